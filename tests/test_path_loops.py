"""The compiled path-building loops (amigo_gym.paths.clothoid.PathLoops, amigo_gym.sim.fast_v1.path_loops) against
the float route, bit for bit.

The float route runs ``clothoid.chain_pieces``, ``families.run_segments`` and ``families.lane_change_shape`` as
Python and takes the coarse samples from ``clothoid._poses_flat`` (``pose_flat``'s bits); the compiled route compiles
the same functions (and ``clothoid.sample_points``: ``pose_flat`` at each sample) with the C library's cosines and
sines of the nodes. On many random paths of every family, with the ranges of ``path="mixed"`` and beyond them, every
table of the path (the flat vector, the pieces' lists, the length, turn, spacing and largest curvature) is equal bit
for bit, and so are the environments' episodes with and without the compiled loops.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

from amigo_gym.paths import families
from amigo_gym.paths.clothoid import ClothoidPath, ClothoidSegment, PathLoops
from amigo_gym.sim import fast_v1
from amigo_gym.task import v1 as tracking

pytest.importorskip("numba", reason="the compiled path loops need numba (the extra amigo_gym[fast])")


@pytest.fixture(scope="module")
def loops() -> PathLoops:
    got = fast_v1.path_loops()
    if got is None:
        pytest.skip("the C library's cos/sin differ from numpy's here: no compiled path loops")
    return got


def _bits(v: Any) -> bytes:
    return np.asarray(v, dtype=np.float64).tobytes()


def assert_same_path(a: ClothoidPath, b: ClothoidPath) -> None:
    """Every table of the two paths equal bit for bit (and the lists of Python floats)."""
    ta, tb = a._t, b._t
    assert _bits(ta.flat) == _bits(tb.flat)
    for name in ("s0", "x0", "y0", "th0", "k0", "c"):
        la, lb = getattr(ta, name), getattr(tb, name)
        assert type(la) is list and type(lb) is list and all(type(v) is float for v in lb)
        assert _bits(la) == _bits(lb), name
    for name in ("s0_a", "x0_a", "y0_a", "th0_a", "k0_a", "c_a", "sample_x", "sample_y"):
        assert _bits(getattr(ta, name)) == _bits(getattr(tb, name)), name
    for name in ("length", "turn", "spacing", "max_abs_curvature"):
        va, vb = getattr(ta, name), getattr(tb, name)
        assert type(va) is type(vb) is float
        assert _bits(va) == _bits(vb), name
    assert a == b


def _draws(g: np.random.Generator, family: str) -> dict[str, Any]:
    """Parameters of ``family``: mostly ``path="mixed"``'s ranges, also the families' whole ranges."""
    if family == "circle":
        return {"radius": float(g.uniform(0.05, 20.0)), "direction": int(g.choice([-1, 1]))}
    if family == "manoeuvre":
        return {
            "radius": float(g.uniform(0.1, 5.0)),
            "straight_length": float(g.choice([0.0, g.uniform(0.0, 5.0)])),
            "laps": float(g.uniform(0.1, 4.0)),
            "direction": int(g.choice([-1, 1])),
        }
    if family == "figure8":
        return {
            "size": float(g.uniform(0.5, 12.0)),
            "crossing_angle": float(g.uniform(0.3, 2.0)),
            "transition": float(g.choice([0.0, g.uniform(0.0, 1.5)])),
        }
    length = float(g.uniform(0.5, 10.0))
    return {
        "offset": float(g.choice([0.0, g.uniform(-0.7, 0.7) * length])),
        "length": length,
        "lead": float(g.choice([0.0, g.uniform(0.0, 3.0)])),
    }


@pytest.mark.parametrize("family", ["circle", "manoeuvre", "figure8", "lane_change"])
def test_families_bit_for_bit(loops: PathLoops, family: str) -> None:
    g = np.random.default_rng(["circle", "manoeuvre", "figure8", "lane_change"].index(family))
    built = 0
    for _ in range(60):
        kw = _draws(g, family)
        try:
            a = families.make_family_path(family, None, **kw)
        except ValueError as e:  # both routes refuse the same settings with the same message
            with pytest.raises(ValueError) as got:
                families.make_family_path(family, None, loops=loops, **kw)
            assert str(got.value) == str(e)
            continue
        assert_same_path(a, families.make_family_path(family, None, loops=loops, **kw))
        built += 1
    assert built >= 40


def test_mixed_draws_bit_for_bit(loops: PathLoops) -> None:
    """``draw_path`` of ``path="mixed"`` (and its random pool's paths, built anew) with and without the loops."""
    p = tracking.TrackingParams(path="mixed")
    for seed in range(120):
        a, info_a = tracking.draw_path(np.random.default_rng(seed), p)
        b, info_b = tracking.draw_path(np.random.default_rng(seed), p, loops)
        assert info_a == info_b
        if info_a["family"] == "random":  # the pool is cached per process: build this one anew both ways
            a = families.random_path(np.random.default_rng(info_a["id"]))
            b = families.random_path(np.random.default_rng(info_a["id"]), loops=loops)
        assert_same_path(a, b)


def test_random_paths_bit_for_bit(loops: PathLoops) -> None:
    g = np.random.default_rng(7)
    for seed in range(40):
        kw = {
            "length": float(g.uniform(1.0, 40.0)),
            "max_curvature": float(g.uniform(0.2, 4.0)),
            "max_curvature_rate": float(g.uniform(0.2, 8.0)),
        }
        a = families.random_path(np.random.default_rng(seed), **kw)
        assert_same_path(a, families.random_path(np.random.default_rng(seed), loops=loops, **kw))


def test_segments_bit_for_bit(loops: PathLoops) -> None:
    """A path of random segments, open and with a start pose, split into many pieces (large turns)."""
    g = np.random.default_rng(3)
    for _ in range(30):
        segs = tuple(
            ClothoidSegment(float(g.uniform(0.05, 8.0)), float(g.uniform(-3.0, 3.0)), float(g.uniform(-2.0, 2.0)))
            for _ in range(int(g.integers(1, 8)))
        )
        start = (float(g.uniform(-5.0, 5.0)), float(g.uniform(-5.0, 5.0)))
        angle = float(g.uniform(-40.0, 40.0))
        spacing = float(g.uniform(1e-3, 0.2))
        a = ClothoidPath(segs, start, angle, sample_spacing=spacing)
        assert_same_path(a, ClothoidPath(segs, start, angle, sample_spacing=spacing, loops=loops))


def test_run_segments_and_lane_shape(loops: PathLoops) -> None:
    """``run_segments`` of 1 to ``RUN_MAX_SUB`` sub-intervals and ``lane_change_shape`` of any ratio, both routes;
    a segment turning too far is refused by both."""
    g = np.random.default_rng(11)
    for _ in range(200):
        n = int(g.integers(1, 5))
        segs = [float(v) for _ in range(n) for v in (g.uniform(0.01, 1.2), g.uniform(-2.0, 2.0), g.uniform(-2.0, 2.0))]
        pose = (float(g.uniform(-3, 3)), float(g.uniform(-3, 3)), float(g.uniform(-7, 7)))
        want = families.run_segments([0.0] * families.RUN_SCRATCH, families.RUN_NODES, segs, n, *pose)
        assert _bits(loops.run(np.array(segs), n, *pose)) == _bits(want)
    # every number of sub-intervals: a single arc turning by up to 8 rad
    for turn in (0.5, 2.5, 4.5, 6.5, 8.0):
        segs = [2.0, turn / 2.0, 0.0]
        want = families.run_segments([0.0] * families.RUN_SCRATCH, families.RUN_NODES, segs, 1, 0.1, 0.2, 0.3)
        assert _bits(loops.run(np.array(segs), 1, 0.1, 0.2, 0.3)) == _bits(want)
    for segs in ([2.0, 4.5, 0.0], [1.0, math.nan, 0.0]):
        with pytest.raises(ValueError, match="turns by more than"):
            families.run_segments([0.0] * families.RUN_SCRATCH, families.RUN_NODES, segs, 1, 0.0, 0.0, 0.0)
        with pytest.raises(ValueError, match="turns by more than"):
            loops.run(np.array(segs), 1, 0.0, 0.0, 0.0)
    for ratio in [0.0, 1e-9, 0.3, 0.6, 0.68, 0.69, 2.0, *g.uniform(0.0, 0.7, 40).tolist()]:
        want = families.lane_change_shape([0.0] * families.RUN_SCRATCH, families.RUN_NODES, [0.0] * 6, ratio)
        assert _bits(loops.lane(ratio)) == _bits(want)


@pytest.mark.parametrize("vector", [False, True])
def test_env_episodes_with_and_without_loops(loops: PathLoops, vector: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """The compiled step's environments on ``path="mixed"`` give the same episodes when their resets build the paths
    by the float route (``fast_v1.path_loops`` returning None) and by the compiled loops (their default)."""
    kw: dict[str, Any] = {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard", "max_episode_steps": 25}

    def run() -> list[bytes]:
        if vector:
            env: Any = gym.make_vec("AmigoBot-v1", num_envs=6, vectorization_mode="vector_entry_point", **kw)
        else:
            env = gym.make("AmigoBot-v1", **kw)
        out = []
        obs, _ = env.reset(seed=5)
        out.append(np.asarray(obs).tobytes())
        g = np.random.default_rng(0)
        for _ in range(80):
            a = g.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32)
            obs, reward, term, trunc, _info = env.step(a)
            out += [np.asarray(obs).tobytes(), np.asarray(reward, dtype=np.float64).tobytes()]
            out += [np.asarray(term).tobytes(), np.asarray(trunc).tobytes()]
            if not vector and (term or trunc):
                obs, _ = env.reset()
                out.append(np.asarray(obs).tobytes())
        env.close()
        return out

    compiled = run()
    monkeypatch.setattr(fast_v1, "path_loops", lambda: None)
    assert run() == compiled
