"""The compiled single-robot step (amigo_gym.sim.fast_v1, amigo_gym.sim._kernels_v1) against the reference, to
tolerance.

The reference is the Python float code of amigo_gym.task.v1 (``kernel="numpy"``). Whole episodes run side by
side in both, with the same seeds and actions, on every path family (the circle both ways, the manoeuvre, the
figure-8, the lane change to its end, random and mixed paths), without and with randomisation, speed ranges and
the trapezoid profile, fixed delays, a true robot that differs from the nominal one, other control periods,
start poses, steps past termination, ideal actuators and AmigoBot-v0's observation, reward and paths: observations,
rewards, terminations, truncations and every info entry agree within :data:`RTOL` (the golden tolerance,
tests/golden_compare.py; float32 observations within two float32 roundings), of the same types, and booleans,
integers and strings exactly.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from test_v0_as_v1 import V0_CONFIG

from amigo_gym.envs import AmigoBotV1Env
from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.sim import fast_v1
from amigo_gym.task import v1 as tracking

pytest.importorskip("numba", reason="the compiled v1 step needs numba (the extra amigo_gym[fast])")

#: AmigoBot-v0's settings of AmigoBot-v1 (tests/test_v0_as_v1.py), without the path
V0: dict[str, Any] = {k: v for k, v in V0_CONFIG.items() if k != "path"}
#: the tolerance relative to ``1 + |value|`` (float64); float32 values: :data:`RTOL32`
RTOL = 1e-9
RTOL32 = 2.5e-7
#: name -> settings of AmigoBotV1Env
CONFIGS: dict[str, dict[str, Any]] = {
    "circle": {},
    "circle_right": {"direction": -1, "radius": 0.7},
    "manoeuvre": {"path": "manoeuvre"},
    "manoeuvre_right_mild": {"path": "manoeuvre", "direction": -1, "randomize": "mild"},
    "figure8": {"path": "figure8", "speed": 0.3},
    "lane_change": {"path": "lane_change", "speed": 0.4},
    "lane_change_trapezoid": {"path": "lane_change", "speed_profile": "trapezoid", "profile_duration": 8.0, "dt": 0.05},
    "random": {"path": "random", "speed": (0.1, 0.4)},
    "random_delay_mild": {"path": "random", "speed": 0.3, "actuators": {"delay": 0.13}, "randomize": "mild"},
    "mixed_hard": {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"},
    "mixed_hard_trapezoid": {
        "path": "mixed",
        "randomize": "hard",
        "speed_profile": "trapezoid",
        "profile_duration": 6.0,
    },
    "long_delay": {"path": "figure8", "actuators": {"delay": 0.35}, "start_at_rest": False},
    "true_robot_l3": {"path": "circle", "true_robot": {"l3": 0.09, "r1": 0.051}},
    "slow_dt": {"path": "mixed", "dt": 0.3, "speed": 0.15, "preview": (0.3, 0.7, 1.5, 3.0)},
    "slip_only": {"path": "circle", "randomize": {"slip": (0.0, 0.2), "delay": (0.0, 0.5)}, "preview": (0.4,)},
    "no_preview_heading_noise": {"path": "figure8", "preview": (), "randomize": {"heading_noise": 0.05}},
    "wheel_noise_only": {"path": "lane_change", "randomize": {"wheel_rate_noise": 0.5}, "speed": (0.05, 0.3)},
    "dt_1s": {"path": "random", "dt": 1.0, "speed": 0.1, "randomize": "hard"},
    "ideal": {"path": "figure8", "ideal_actuators": True},
    "ideal_noise_v0_layouts": {
        "path": "lane_change",
        "ideal_actuators": True,
        "observation": "v0",
        "reward": "v0",
        "randomize": {"position_noise": 0.01, "heading_noise": 0.02},
    },
    "v0_circle": {**V0, "path": CirclePath(radius=1.0, direction=1)},
    "v0_circle_right_v1_reward": {**V0, "reward": "v1", "path": CirclePath(radius=0.8, direction=-1)},
    "v0_manoeuvre": {**V0, "path": ManoeuvrePath(radius=1.2, straight_length=0.5, direction=-1), "dt": 0.05},
}
SEEDS = (0, 1, 2)
STEPS = 120


def _same(a: Any, b: Any, where: str) -> None:
    """``a`` and ``b`` of the same types (dicts, arrays, floats, bools, ints, strings), floats within the tolerance
    (:data:`RTOL`, :data:`RTOL32`), the rest equal."""
    both_floats = isinstance(a, float) and isinstance(b, float)  # float or np.float64
    assert both_floats or type(a) is type(b), f"{where}: {type(a).__name__} != {type(b).__name__}"
    if isinstance(a, dict):
        assert list(a) == list(b), where
        for k in a:
            _same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, where
        if a.dtype.kind == "f":
            rtol = RTOL32 if a.dtype == np.float32 else RTOL
            bound = rtol * (1.0 + np.abs(b.astype(np.float64)))
            err = np.abs(a.astype(np.float64) - b.astype(np.float64))
            assert np.array_equal(np.isnan(a), np.isnan(b)) and np.all(err[~np.isnan(err)] <= bound[~np.isnan(err)]), (
                f"{where}: {a!r} != {b!r}"
            )
        else:
            np.testing.assert_array_equal(a, b, err_msg=where)
    elif isinstance(a, tuple | list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{where}[{i}]")
    elif isinstance(a, float):
        assert a == b or (a != a and b != b) or abs(a - b) <= RTOL * (1.0 + abs(b)), f"{where}: {a!r} != {b!r}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def _pair(settings: dict[str, Any]) -> tuple[AmigoBotV1Env, AmigoBotV1Env]:
    return AmigoBotV1Env(kernel="numpy", **settings), AmigoBotV1Env(kernel="numba", **settings)


def _actions(kind: str, rng: np.random.Generator, policy: AnalyticTrackingPolicy, obs: Any, t: int, state: Any) -> Any:
    """An action of ``kind``: the analytic policy (perturbed), random in [-1.3, 1.3], or a mix; varied types."""
    a, state = policy.predict(obs[None, :], state, np.array([t == 0]))
    act = np.asarray(a[0], dtype=np.float64)
    if kind == "random" or (kind == "mixed" and rng.random() < 0.3):
        act = rng.uniform(-1.3, 1.3, size=2)
    elif kind == "noisy":
        act = act + rng.normal(0.0, 0.15, size=2)
    form = t % 4
    if form == 1:
        return act.astype(np.float32), state
    if form == 2:
        return [float(act[0]), float(act[1])], state
    if form == 3 and t % 8 == 3:
        return (np.float32(act[0]), round(float(act[1]))), state
    return act, state


def _run_pair(settings: dict[str, Any], seed: int, kind: str, pose: Any = None, past_end: int = 5) -> int:
    """Run both envs side by side; returns the number of steps compared."""
    ref, fast = _pair(settings)
    assert fast._kernel is not None and ref._kernel is None
    options = None if pose is None else {"pose": pose}
    o1, i1 = ref.reset(seed=seed, options=options)
    o2, i2 = fast.reset(seed=seed, options=options)
    assert fast._in_kernel
    _same(o1, o2, "reset obs")
    _same(i1, i2, "reset info")
    policy = AnalyticTrackingPolicy(ref.params)
    rng = np.random.default_rng(1000 + seed)
    state = None
    obs = o1
    n = 0
    after = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # stepping past termination warns
        for t in range(STEPS):
            action, state = _actions(kind, rng, policy, obs, t, state)
            r1 = ref.step(action)
            r2 = fast.step(action)
            n += 1
            for name, a, b in zip(("obs", "reward", "terminated", "truncated", "info"), r1, r2, strict=True):
                _same(a, b, f"{settings} seed {seed} {kind} step {t}: {name}")
            obs = r1[0]
            if r1[2]:
                after += 1
                if after > past_end:
                    break
    st_ref = ref._current_state()
    st_fast = fast._current_state()
    for name, a, b in zip(tracking.State._fields, st_ref, st_fast, strict=True):
        _same(a, b, f"state {name}")
    return n


@pytest.mark.parametrize("name", list(CONFIGS))
def test_kernel_episodes_agree(name: str) -> None:
    total = 0
    for seed in SEEDS:
        for kind in ("noisy", "random", "mixed"):
            total += _run_pair(CONFIGS[name], seed, kind)
    assert total > 100


def test_lane_change_reaches_its_end() -> None:
    """The open path's end (a success): both implementations terminate there, with end_of_path set."""
    settings = {"path": "lane_change", "speed": 0.4}
    ref, fast = _pair(settings)
    for env in (ref, fast):
        env.reset(seed=4)
    policy = AnalyticTrackingPolicy(ref.params)
    state = None
    obs, _ = ref.reset(seed=4)
    fast.reset(seed=4)
    ended = False
    for t in range(2000):
        a, state = policy.predict(obs[None, :], state, np.array([t == 0]))
        r1 = ref.step(a[0])
        r2 = fast.step(a[0])
        for name, x, y in zip(("obs", "reward", "terminated", "truncated", "info"), r1, r2, strict=True):
            _same(x, y, f"step {t}: {name}")
        obs = r1[0]
        if r1[2]:
            ended = bool(r1[4]["end_of_path"])
            break
    assert ended
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(5):  # past the end
            r1 = ref.step(np.zeros(2))
            r2 = fast.step(np.zeros(2))
            for name, x, y in zip(("obs", "reward", "terminated", "truncated", "info"), r1, r2, strict=True):
                _same(x, y, f"past the end: {name}")


@pytest.mark.parametrize("pose", [(0.05, -0.02, 1.4), (1.2, 0.3, 2.5), (-3.0, 0.0, -0.5)])
def test_kernel_start_pose(pose: tuple[float, float, float]) -> None:
    for settings in ({}, {"path": "figure8", "randomize": "hard"}, {"path": "lane_change"}):
        _run_pair(settings, 7, "mixed", pose=pose)


def test_kernel_reset_sequences_and_pickle() -> None:
    """Several episodes per env (no reseeding), and an env pickled mid-episode goes on as before."""
    settings = {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"}
    ref, fast = _pair(settings)
    ref.reset(seed=11)
    fast.reset(seed=11)
    rng = np.random.default_rng(3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for episode in range(6):
            if episode:
                _same(ref.reset(), fast.reset(), f"reset {episode}")
            for t in range(40):
                a = rng.uniform(-1, 1, 2)
                if episode == 3 and t == 20:
                    fast = pickle.loads(pickle.dumps(fast))
                _same(ref.step(a), fast.step(a), f"episode {episode} step {t}")


def test_kernel_keyword_and_fallback(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("AMIGO_GYM_KERNEL", raising=False)  # "auto" as without the variable
    with pytest.raises(ValueError, match="kernel must be 'auto', 'numpy' or 'numba'"):
        AmigoBotV1Env(kernel="fast")
    assert AmigoBotV1Env()._kernel is not None  # auto, numba installed
    assert AmigoBotV1Env(kernel="numpy")._kernel is None
    monkeypatch.setenv("AMIGO_GYM_KERNEL", "numpy")
    assert AmigoBotV1Env()._kernel is None
    assert AmigoBotV1Env(kernel="numba")._kernel is not None
    monkeypatch.delenv("AMIGO_GYM_KERNEL")
    env = gym.make("AmigoBot-v1", kernel="numpy")
    assert env.unwrapped._kernel is None  # type: ignore[attr-defined]

    class Wrapped:
        """A path object of the user's own (not a ClothoidPath): the reference code runs."""

        def __init__(self, inner: Any) -> None:
            self.inner = inner
            self.length = inner.length
            self.closed = inner.closed

        def pose_columns(self, s: Any) -> Any:
            return self.inner.pose_columns(s)

        def locate(self, *args: Any, **kw: Any) -> Any:
            return self.inner.locate(*args, **kw)

    base = tracking.fixed_path(tracking.make_tracking_params("t", path="figure8"))
    fast = AmigoBotV1Env(path=Wrapped(base))
    ref = AmigoBotV1Env(path="figure8", kernel="numba")
    o1, _ = fast.reset(seed=2)
    o2, _ = ref.reset(seed=2)
    assert not fast._in_kernel and ref._in_kernel
    _same(o1, o2, "reset obs")
    for t in range(30):
        a = np.array([0.5, 0.45 + 0.01 * t])
        r1, r2 = fast.step(a), ref.step(a)
        for name, x, y in zip(("obs", "reward", "terminated", "truncated"), r1[:4], r2[:4], strict=True):
            _same(x, y, f"step {t}: {name}")


def test_fast_action_validation() -> None:
    env = AmigoBotV1Env(kernel="numba")
    env.reset(seed=0)
    for bad in (np.array([np.nan, 0.0]), np.array([0.0, np.inf], dtype=np.float32)):
        with pytest.raises(ValueError, match="finite"):
            env.step(bad)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(3))
    with pytest.raises(TypeError):
        env.step(np.array(["a", "b"]))
    fresh = AmigoBotV1Env(kernel="numba")
    with pytest.raises(gym.error.ResetNeeded):
        fresh.step(np.zeros(2))


def test_flat_path_cached() -> None:
    path = tracking.fixed_path(tracking.make_tracking_params("t", path="figure8"))
    assert fast_v1.flat_path(path) is fast_v1.flat_path(path)


def test_warm_cache_start_compiles_nothing() -> None:
    """A second process loads the compiled step from numba's disk cache: building the env, the first reset and the
    first step compile nothing (every compiled function it calls is a cache hit). (How long that start takes is the
    benchmark's business: ``amigo-gym bench-core``.)"""
    AmigoBotV1Env(kernel="numba").reset(seed=0)  # compiled (and cached) in this process at the latest
    code = (
        "import numpy as np; from numba.core.registry import CPUDispatcher; from amigo_gym.envs import AmigoBotV1Env\n"
        "e = AmigoBotV1Env(kernel='numba'); e.reset(seed=0); e.step(np.zeros(2))\n"
        "import amigo_gym.sim._kernels_v1 as k\n"
        "ds = [v for v in vars(k).values() if isinstance(v, CPUDispatcher)]\n"
        "print(sum(sum(d.stats.cache_misses.values()) for d in ds), sum(sum(d.stats.cache_hits.values()) for d in ds))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    misses, hits = (int(x) for x in out.stdout.split()[-2:])
    assert misses == 0 and hits > 0, (misses, hits)


def test_kernel_cache_is_keyed_by_the_source_bytes(tmp_path: Path) -> None:
    """numba keys a cached function on its own file only; the kernels' cache folder is named by a hash of every
    source file's bytes (the same on every Python), so a change of a shared function in another file (here one byte
    of model/fresnel.py in a copy of the package) gives another folder, and the kernels compile into it."""
    import shutil

    from amigo_gym.sim import layout

    copy = tmp_path / "amigo_gym"
    shutil.copytree(Path(layout.__file__).parents[1], copy, ignore=shutil.ignore_patterns("__pycache__"))
    code = "from amigo_gym.sim.layout import source_digest; print(source_digest())"
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    run = {"env": env, "cwd": tmp_path, "capture_output": True, "text": True, "check": True}
    digest = subprocess.run([sys.executable, "-c", code], **run).stdout  # type: ignore[call-overload]
    assert digest.strip() == layout.source_digest()
    fresnel = copy / "model" / "fresnel.py"
    fresnel.write_text(fresnel.read_text() + "\n")
    changed = subprocess.run([sys.executable, "-c", code], **run).stdout  # type: ignore[call-overload]
    assert changed.strip() != digest.strip()
    cache = tmp_path / "cache"
    fast_v1.kernels()
    code = (
        "from amigo_gym.sim import fast_v1, layout; kv = fast_v1.kernels(); import numba\n"
        "print(kv.step._cache._cache_path); print(layout.source_digest()); print(numba.config.CACHE_DIR)"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    path, digest, restored = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout.split()
    assert Path(path).is_relative_to(cache / "amigo_gym" / digest), path
    assert restored == str(cache)  # the user's setting, restored for their own functions


@pytest.mark.parametrize("family", ["circle", "manoeuvre", "figure8", "lane_change", "random"])
def test_compiled_path_loops_build_the_same_paths(family: str) -> None:
    """The compiled path-building loops (``fast_v1.path_loops``, handed to the constructors at resets) build the
    float route's paths to the tolerance: every piece, sample and length within 1e-12 of its scale."""
    from amigo_gym.paths import families

    loops = fast_v1.path_loops()
    for seed in range(5):
        a = families.make_family_path(family, np.random.default_rng(seed))
        b = families.make_family_path(family, np.random.default_rng(seed), loops=loops)
        for k in range(8):  # the pieces' columns, then the samples'
            x, y = a._t.column(k), b._t.column(k)
            assert x.shape == y.shape and np.allclose(x, y, rtol=0, atol=1e-12 * max(1.0, np.abs(x).max())), k
        assert a._t.length == pytest.approx(b._t.length, rel=1e-12)


@pytest.mark.parametrize("path", ["figure8", "lane_change", "random"])
def test_measured_projection_from_the_true_foot_is_the_searched_one(path: str) -> None:
    """The compiled step projects the measured H by Newton from H's foot, without the coarse search, where that foot
    is interior, ``|kappa e| <= 0.5`` and the two points are within a sample spacing (``_evaluate``): for such pairs
    of points on each family's path, the same foot and cross-track error to 1e-12 m as the search."""
    from amigo_gym.paths import STATUS_INTERIOR
    from amigo_gym.paths import clothoid as C

    kv = fast_v1.kernels()
    env = gym.make_vec("AmigoBot-v1", 1, vectorization_mode="vector_entry_point", path=path)
    env.reset(seed=0)
    b = env.unwrapped._batch  # type: ignore[attr-defined]
    c, pv = b.consts, b.arena.flat[b.arena.starts[0] : b.arena.stops[0]]
    h, rng, compared = float(pv[C.P_SPACING]), np.random.default_rng(1), 0
    for _ in range(3000):
        s = rng.uniform(0.0, float(pv[C.P_LENGTH]))
        x, y, _th, _k, _c, ct, st = C.pose_flat([0.0] * C._SCRATCH, C._PATH_TABLE, 0, pv, s)
        off = rng.uniform(-0.2, 0.2)
        hx, hy = x - off * st, y + off * ct
        s_h, kappa, e, *_, status = kv._locate(c, pv, hx, hy, s + rng.uniform(-0.05, 0.05))
        mx, my = hx + rng.uniform(-h, h), hy + rng.uniform(-h, h)
        if status != STATUS_INTERIOR or abs(kappa * e) > 0.5 or (mx - hx) ** 2 + (my - hy) ** 2 > h * h:
            continue
        searched, newton = kv._locate(c, pv, mx, my, s_h, True), kv._locate(c, pv, mx, my, s_h, False)
        assert abs(searched[0] - newton[0]) <= 1e-12 and abs(searched[2] - newton[2]) <= 1e-12, (s, off, mx, my)
        compared += 1
    assert compared > 1000
