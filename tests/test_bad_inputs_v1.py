"""AmigoBot-v1's bad inputs of issue 21 get a clear one-line error at construction (or reset), never a traceback from
inside numpy, garbage or silence; the fixes around them (feasibility of drawn paths, the render trail's ring, the
byte-bounded path cache, v0 not deprecated, the spec's JSON round trip) checked against independent references.
"""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
import tracemalloc
import warnings
from collections import OrderedDict
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec

import amigo_gym
from amigo_gym.envs import AmigoBotV1Env, AmigoBotV1VectorEnv, vector_v1
from amigo_gym.model import actuators
from amigo_gym.paths import feasibility, make_family_path
from amigo_gym.task import v1 as tracking

NUMPY_DIR = str(Path(np.__file__).resolve().parent)
ROOT = Path(__file__).resolve().parents[1]


def assert_clear(exc: pytest.ExceptionInfo[BaseException], *needles: str) -> None:
    """One line naming every needle; raised by our code, not from inside numpy."""
    msg = str(exc.value)
    assert "\n" not in msg, msg
    for n in needles:
        assert n in msg, (n, msg)
    tb = exc.tb
    while tb.tb_next is not None:
        tb = tb.tb_next
    assert not str(Path(tb.tb_frame.f_code.co_filename).resolve()).startswith(NUMPY_DIR), msg


# ---------------------------------------------------------------- family parameters, at gym.make
BAD_PATH_PARAMS: list[tuple[dict[str, Any], type[Exception], tuple[str, ...]]] = [
    ({"path": "random", "path_params": {"bogus": 1}}, ValueError, ("path_params", "'bogus'", "max_curvature")),
    ({"path": "random", "path_params": {"max_curvature": -1}}, ValueError, ("max_curvature", "-1", "(0, 100]")),
    ({"path": "random", "path_params": {"max_curvature": math.nan}}, ValueError, ("max_curvature", "nan")),
    ({"path": "random", "path_params": {"length": "10"}}, ValueError, ("length", "'10'")),
    ({"path": "random", "path_params": {"min_piece": 2.0, "max_piece": 1.0}}, ValueError, ("min_piece", "max_piece")),
    ({"path": "mixed", "path_params": {"size": 4.0}}, ValueError, ("path_params", "mixed", "'size'", "unused")),
    ({"path": "circle", "path_params": {"radius": 2.0}}, ValueError, ("path_params", "radius=")),
    ({"path": "figure8", "path_params": {"bogus": 1}}, ValueError, ("'bogus'", "size")),
    ({"path": "figure8", "path_params": {"size": -4.0}}, ValueError, ("size", "-4")),
    ({"path": "random", "path_params": 5}, ValueError, ("path_params", "mapping", "5")),
]


@pytest.mark.parametrize(("kwargs", "error", "needles"), BAD_PATH_PARAMS)
def test_path_params_refused_at_make(kwargs: dict[str, Any], error: type[Exception], needles: tuple[str, ...]) -> None:
    with pytest.raises(error) as exc:
        gym.make("AmigoBot-v1", **kwargs)
    assert_clear(exc, *needles)
    with pytest.raises(error) as exc:
        gym.make_vec("AmigoBot-v1", num_envs=2, **kwargs)
    assert_clear(exc, *needles)


def test_good_path_params_still_work() -> None:
    env = gym.make("AmigoBot-v1", path="random", path_params={"max_curvature": 1.5, "max_curvature_rate": 1.5})
    _, info = env.reset(seed=0)
    assert info["path"]["family"] == "random"
    p = env.unwrapped.params  # type: ignore[attr-defined]
    assert p.path_params == (("max_curvature", 1.5), ("max_curvature_rate", 1.5))
    # the pairs (what a JSON round trip of them gives) mean the same as the mapping
    assert (
        tracking.TrackingParams(path="random", path_params=[["max_curvature", 1.5], ["max_curvature_rate", 1.5]]) == p
    )


# ---------------------------------------------------------------- dt and the delay ring
@pytest.mark.parametrize("dt", [1e-9, 5e-4, 0.0, -0.1, 1.5, math.inf])
def test_dt_bounded(dt: float) -> None:
    with pytest.raises(ValueError) as exc:
        gym.make("AmigoBot-v1", dt=dt)
    assert_clear(exc, "dt", repr(dt), "[0.001, 1]")


def test_smallest_dt_keeps_the_ring_small() -> None:
    env = AmigoBotV1Env(dt=tracking.MIN_DT)
    assert env._ring.shape == (501, 2) == (actuators.ring_length(tracking.MIN_DT), 2)
    env.reset(seed=0)
    _, r, *_ = env.step(np.array([0.1, 0.1]))
    assert math.isfinite(float(r))


# ---------------------------------------------------------------- conflicting combined settings
def test_delay_above_the_maximum_is_refused_not_clipped() -> None:
    with pytest.raises(ValueError) as exc:
        gym.make("AmigoBot-v1", actuators={"delay": 0.4}, randomize={"delay": (0.3, 0.5)})
    assert_clear(exc, "actuators.delay", "0.4", "randomize.delay", "0.5", "MAX_DELAY")
    # at the maximum exactly: accepted, and the drawn delay is the sum (nothing clipped)
    env = gym.make("AmigoBot-v1", actuators={"delay": 0.3}, randomize={"delay": (0.2, 0.2)})
    _, info = env.reset(seed=0)
    _, _, _, _, info = env.step(np.zeros(2))
    assert info["delay"] == pytest.approx(0.5, abs=1e-12)


def test_trapezoid_that_cannot_reach_its_speed_is_refused() -> None:
    with pytest.raises(ValueError) as exc:
        gym.make("AmigoBot-v1", speed_profile="trapezoid", speed=0.4, profile_duration=1.0)
    assert_clear(exc, "profile_duration", "1 s", "0.4 m/s", "2.8 s")
    gym.make("AmigoBot-v1", speed_profile="trapezoid", speed=0.4, profile_duration=2.8)  # 0.4/0.2 + 0.4/0.5


# ---------------------------------------------------------------- drawn tasks' feasibility
def test_infeasible_random_paths_refused_at_make() -> None:
    # 0.4^2 * 70.5 / (1 - 0.08^2)^2 = 11.4 rad/s^2 of rotational acceleration (min_piece 0.01 lets the rate reach
    # 70.5 1/m^2; tracking.envelope_needs)
    kw = {"path": "random", "speed": 0.4, "path_params": {"max_curvature_rate": 70.5, "min_piece": 0.01}}
    with pytest.raises(ValueError) as exc:
        gym.make("AmigoBot-v1", **kw)
    assert_clear(exc, "random", "11.4 rad/s^2", "0.87 rad/s^2", "0.4 m/s")
    with pytest.raises(ValueError) as exc:
        gym.make("AmigoBot-v1", path="random", speed=0.75)
    assert_clear(exc, "random", "16.8 rad/s", "15 rad/s")
    with pytest.raises(ValueError) as exc:
        gym.make("AmigoBot-v1", path="mixed", speed=(0.1, 0.75))
    assert_clear(exc, "mixed", "0.75 m/s", "limit")
    with pytest.raises(ValueError) as exc:
        gym.make_vec("AmigoBot-v1", num_envs=2, path="random", path_params={"max_curvature": 13.0}, speed=0.05)
    assert_clear(exc, "90 degrees", "max_curvature 13")


@pytest.mark.parametrize(
    "kw",
    [
        {"path": "random", "speed": 0.2},
        {"path": "random", "speed": 0.2, "path_params": {"max_curvature": 1.5, "max_curvature_rate": 1.5}},
        {"path": "mixed", "speed": (0.1, 0.4)},
        {"path": "random", "speed": 0.6},
    ],
)
def test_feasible_drawn_tasks_accepted(kw: dict[str, Any]) -> None:
    gym.make("AmigoBot-v1", **kw)


def test_envelope_bounds_the_exact_needs_of_drawn_paths() -> None:
    """Soundness of :func:`tracking.envelope_needs` against :func:`amigo_gym.paths.feasibility` (RK4 on the lag
    profile) on pool paths, and tightness of the wheel-rate bound (reached on their longest arcs)."""
    sharp = {"max_curvature": 3.0, "max_curvature_rate": 4.0}
    cases = [
        (tracking.TrackingParams(path="random", speed=0.6), [0, 1, 2]),
        (tracking.TrackingParams(path="random", speed=0.2, path_params=sharp), [0, 1]),
    ]
    for p, ids in cases:
        (env,) = tracking.drawn_envelopes(p)
        wheel, rot = tracking.envelope_needs(env, p.speed_range[1], p.robot)
        peaks = []
        for i in ids:
            f = feasibility(tracking.random_pool_path(p, i), p.speed_range[1], p.robot, "A")
            assert f.peaks["wheel_rate"] <= wheel * (1 + 1e-9)
            assert f.peaks["rotational_acceleration"] <= rot * (1 + 1e-9)
            peaks.append(f.peaks["wheel_rate"])
        assert max(peaks) >= 0.9 * wheel  # not a loose bound


def test_envelope_bounds_the_sharpest_mixed_paths() -> None:
    """The exact needs of the corners of MIXED_RANGES at 0.4 m/s within :func:`tracking.envelope_needs`."""
    p = tracking.TrackingParams(path="mixed", speed=0.4)
    env = {e.family: e for e in tracking.drawn_envelopes(p)}
    for name, kw in (("figure8", {"size": 3.0}), ("lane_change", {"offset": -1.0, "length": 3.0})):
        wheel, rot = tracking.envelope_needs(env[name], 0.4, p.robot)
        f = feasibility(make_family_path(name, None, **kw), 0.4, p.robot, "A")
        assert f.peaks["wheel_rate"] <= wheel * (1 + 1e-9) and f.peaks["rotational_acceleration"] <= rot * (1 + 1e-9)
        assert f.peaks["rotational_acceleration"] >= 0.8 * rot  # the bound is near the exact need


def test_mixed_draws_stay_inside_their_envelopes() -> None:
    p = tracking.TrackingParams(path="mixed")
    env = {e.family: e for e in tracking.drawn_envelopes(p)}
    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(120):
        path, info = tracking.draw_path(rng, p)
        seen.add(info["family"])
        k, c = tracking._segment_bounds(path)
        e = env[info["family"]]
        assert k <= e.max_curvature * (1 + 1e-12) and c <= e.max_curvature_rate * (1 + 1e-12), info
    assert seen == set(tracking.MIXED_FAMILIES)


# ---------------------------------------------------------------- num_envs and memory
def test_huge_num_envs_refused_before_allocating() -> None:
    tracemalloc.start()
    try:
        with pytest.raises(ValueError) as exc:
            gym.make_vec("AmigoBot-v1", num_envs=10**12)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert_clear(exc, "num_envs=1000000000000", "bytes", "per robot")
    assert peak < 50 * 2**20


def test_memory_estimate_matches_tracemalloc(monkeypatch: pytest.MonkeyPatch) -> None:
    """:func:`vector_v1.memory_needed` per robot against tracemalloc's count (N = 96 minus N = 32, over 64), each count
    from an empty family-path cache (paths an earlier test built would otherwise not be counted)."""

    def count(n: int, **kw: Any) -> int:
        monkeypatch.setattr(tracking, "_FAMILY_CACHE", OrderedDict())
        monkeypatch.setattr(tracking, "_cache_bytes", 0)
        tracemalloc.start()
        try:
            e = AmigoBotV1VectorEnv(num_envs=n, **kw)
            e.reset(seed=0)
            for _ in range(3):
                e.step(np.zeros((n, 2)))
            return tracemalloc.get_traced_memory()[0]
        finally:
            tracemalloc.stop()

    for kw in ({"path": "circle"}, {"path": "circle", "dt": 0.001}, {"path": "mixed"}):
        count(8, **kw)  # warm-up: caches, compiled code
        per = (count(96, **kw) - count(32, **kw)) / 64
        est = vector_v1.memory_needed(1, tracking.make_tracking_params("t", **kw))
        assert 0.5 * per <= est <= 3.0 * per, (kw, per, est)


# ---------------------------------------------------------------- vector reset seeds
@pytest.mark.parametrize(
    ("seed", "error", "needles"),
    [
        (1.5, TypeError, ("seed", "1.5")),
        ("abc", TypeError, ("seed", "'abc'")),
        (True, TypeError, ("seed", "True")),
        (-1, ValueError, ("seed", "-1")),
        ([0, 1.5, 2], TypeError, ("seed[1]", "1.5")),
        ([0, "a", 2], TypeError, ("seed[1]", "'a'")),
        ([0, -3, 2], ValueError, ("seed[1]", "-3")),
        ([0, 1], ValueError, ("num_envs=3", "length 2")),
        (np.array([0, 1, 2]), TypeError, ("seed",)),
    ],
)
def test_vector_seeds_typed(seed: Any, error: type[Exception], needles: tuple[str, ...]) -> None:
    envs = gym.make_vec("AmigoBot-v1", num_envs=3)
    with pytest.raises(error) as exc:
        envs.reset(seed=seed)
    assert_clear(exc, *needles)
    if seed is True:
        return  # Gymnasium takes a bool for an int; refused here as by AmigoBot-v0's vector env
    # Gymnasium's SyncVectorEnv refuses each of them too (with its own errors)
    sync = gym.make_vec("AmigoBot-v1", num_envs=3, vectorization_mode="sync")
    with pytest.raises(Exception):  # noqa: B017
        sync.reset(seed=seed)


def test_vector_seeds_accepted_as_sync() -> None:
    for seed in (5, np.int64(5), [5, None, 7], (5, 6, 7)):
        native = gym.make_vec("AmigoBot-v1", num_envs=3, kernel="numpy")
        sync = gym.make_vec("AmigoBot-v1", num_envs=3, vectorization_mode="sync")
        a, _ = native.reset(seed=seed)
        sync_seed = [None if s is None else int(s) for s in seed] if isinstance(seed, (list, tuple)) else int(seed)
        b, _ = sync.reset(seed=sync_seed)
        rows = [i for i in range(3) if not (isinstance(seed, list) and seed[i] is None)]
        np.testing.assert_array_equal(a[rows], b[rows])


# ---------------------------------------------------------------- the render trail
@pytest.mark.parametrize(("mode", "kernel"), [("NextStep", "auto"), ("SameStep", "auto"), ("NextStep", "numpy")])
def test_render_trail_is_the_h_of_the_infos(mode: str, kernel: str) -> None:
    """The ring's trail of each robot is H of its infos since its episode started (the last trail_length ones)."""
    n = 5
    envs = AmigoBotV1VectorEnv(
        num_envs=n, render_mode="rgb_array", max_episode_steps=9, autoreset_mode=mode, kernel=kernel, path="mixed"
    )
    envs.trail_length = 12
    _, info = envs.reset(seed=1)
    want: list[list[tuple[float, float]]] = [[tuple(h)] for h in info["h_position"].tolist()]
    done = np.zeros(n, dtype=bool)
    rng = np.random.default_rng(0)
    for _ in range(40):
        _, _, term, trunc, info = envs.step(rng.uniform(-1, 1, (n, 2)))
        new = done if mode == "NextStep" else term | trunc
        for i, h in enumerate(info["h_position"].tolist()):
            want[i] = [tuple(h)] if new[i] else [*want[i], tuple(h)]
        done = term | trunc
    for i in range(n):
        assert envs._trail_of(i) == want[i][-12:]
    assert envs._trail is not None and envs._trail.shape == (12, n, 2)
    frames = envs.render()
    assert frames is not None and len(frames) == n


def test_render_trail_memory_is_flat() -> None:
    # a fixed path: the memory of the paths drawn at resets (kept in the compiled step's arena) is not measured here
    envs = AmigoBotV1VectorEnv(num_envs=16, render_mode="rgb_array", max_episode_steps=None)
    envs.trail_length = 50
    envs.reset(seed=0)
    action = np.tile([0.27, 0.24], (16, 1))
    for _ in range(60):
        envs.step(action)
    tracemalloc.start()
    try:
        for _ in range(60):
            envs.step(action)
        first, _ = tracemalloc.get_traced_memory()
        for _ in range(600):
            envs.step(action)
        second, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the former lists grew by 16 positions (a tuple and two floats each, ~150 bytes) per step: ~1.4 MiB here
    assert second - first < 256 * 1024, (first, second)


# ---------------------------------------------------------------- the path cache
def test_path_cache_bounded_by_bytes(monkeypatch: pytest.MonkeyPatch) -> None:
    p = tracking.TrackingParams(path="random", path_params={"length": 5.0})
    first = tracking.random_pool_path(p, 900)
    monkeypatch.setattr(tracking, "PATH_CACHE_BYTES", 100_000)
    for i in range(60):
        tracking.random_pool_path(p, 1000 + i)
        assert tracking._cache_bytes <= 100_000
    assert sum(size for _, size in tracking._FAMILY_CACHE.values()) == tracking._cache_bytes
    again = tracking.random_pool_path(p, 900)  # evicted and rebuilt: the same path
    assert again is not first and again.segments == first.segments


@pytest.mark.parametrize(
    ("name", "rng", "kw"),
    [
        ("circle", None, {"radius": 0.7}),
        ("figure8", None, {"size": 4.3}),
        ("lane_change", None, {"offset": 0.3, "length": 4.0}),
        ("random", 5, {}),
    ],
)
def test_path_nbytes_against_tracemalloc(name: str, rng: int | None, kw: dict[str, Any]) -> None:
    gen = None if rng is None else np.random.default_rng(rng)
    make_family_path(name, None if gen is None else np.random.default_rng(rng), **kw)  # warm-up
    tracemalloc.start()
    try:
        path = make_family_path(name, gen, **kw)
        counted = tracemalloc.get_traced_memory()[0]
    finally:
        tracemalloc.stop()
    assert 0.5 * counted <= tracking.path_nbytes(path) <= 2.0 * counted


# ---------------------------------------------------------------- v0 is not deprecated; the spec's JSON round trip
def test_v0_no_deprecation_warning_without_a_global_filter(tmp_path: Path) -> None:
    code = textwrap.dedent(
        """
        import warnings
        import gymnasium as gym
        import amigo_gym

        def test_make():
            assert not [f for f in warnings.filters if "AmigoBot" in str(f[1])]
            gym.make("AmigoBot-v0")
            gym.make("AmigoBot-v1")
            gym.make_vec("AmigoBot-v0", num_envs=2)
            gym.make_vec("AmigoBot-v1", num_envs=2)
        """
    )
    (tmp_path / "test_user.py").write_text(code)
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-W",
            "error::DeprecationWarning",
            "-p",
            "no:cacheprovider",
            "test_user.py",
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert r.returncode == 0, r.stdout + r.stderr


def test_v0_and_v1_ids_and_in_process_warnings() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert isinstance(gym.make("AmigoBot-v0").unwrapped, amigo_gym.envs.AmigoBotEnv)
        assert isinstance(gym.make("AmigoBot-v1").unwrapped, AmigoBotV1Env)
    assert not [w for w in caught if issubclass(w.category, DeprecationWarning)], [str(w.message) for w in caught]
    assert gym.spec("AmigoBot-v1").max_episode_steps == 600
    with pytest.raises(gym.error.Error):
        gym.make("AmigoBot-v2")


def _specs() -> list[EnvSpec]:
    return [
        gym.spec("AmigoBot-v0"),
        gym.spec("AmigoBot-v1"),
        gym.make("AmigoBot-v0", params=tracking.TrackingParams.v0(dt=0.05, radius=1.5)).spec,
        gym.make("AmigoBot-v0", params=tracking.TrackingParams.v0(dt=0.05)).unwrapped.spec,
        gym.make(
            "AmigoBot-v1", params=tracking.TrackingParams(dt=0.05, path="figure8", path_params={"size": 5.0})
        ).spec,
        gym.make("AmigoBot-v1", speed=(0.1, 0.3), randomize="mild", true_robot={"r1": 0.051}).spec,
        gym.make_vec("AmigoBot-v1", num_envs=2, params=tracking.TrackingParams(path="mixed")).spec,
        gym.make_vec("AmigoBot-v0", num_envs=2, params=tracking.TrackingParams.v0(speed=0.3)).spec,
    ]


@pytest.mark.parametrize("i", range(8))
def test_spec_json_round_trip_equal(i: int) -> None:
    """Gymnasium's ``test_env_spec_to_from_json`` on our specs, params given as dataclasses."""
    spec = _specs()[i]
    assert spec is not None
    again = EnvSpec.from_json(spec.to_json())
    assert again == spec and spec == again


def test_spec_json_round_trip_rebuilds_v1() -> None:
    env = gym.make(
        "AmigoBot-v1", params=tracking.TrackingParams(dt=0.05, path="lane_change", path_params={"lead": 2.0})
    )
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))  # type: ignore[union-attr]
    assert again.unwrapped.params == env.unwrapped.params  # type: ignore[attr-defined]
    a, _ = env.reset(seed=4)
    b, _ = again.reset(seed=4)
    np.testing.assert_array_equal(a, b)


def test_a_missing_robot_file_names_the_keyword(tmp_path: Any) -> None:
    """``true_robot`` given as a path to a robot file that does not exist (or is not one): one line that names the
    keyword and the file."""
    with pytest.raises(FileNotFoundError, match=r"^AmigoBotV1Env: true_robot: robot file 'abc' does not exist") as e:
        gym.make("AmigoBot-v1", true_robot="abc")
    assert "\n" not in str(e.value)
    bad = tmp_path / "robot.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match=r"true_robot: .*robot\.json") as e2:
        gym.make("AmigoBot-v1", true_robot=str(bad))
    assert "\n" not in str(e2.value)
