"""The AmigoBot-v1 vector env's compiled step (kernel="numba", :mod:`amigo_gym.sim.fast_v1_batch`) agrees with its
reference column code (kernel="numpy") and with Gymnasium's SyncVectorEnv of single envs (the reference float code)
within the golden tolerance (:data:`RTOL`: tests/golden_compare.py): observations, rewards, terminations,
truncations and every info (keys, dtypes, values, masks), over many steps with autoresets in the three autoreset
modes, partial resets, reseeding and pickling. On one route (a pickled copy; the serial and parallel loops, but for
the ideal step's tangents and exponentials) the bits are equal."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import amigo_gym  # noqa: F401
from amigo_gym.envs import AmigoBotV1VectorEnv
from amigo_gym.sim import fast_v1, fast_v1_batch

numba = pytest.importorskip("numba")

#: tolerance relative to ``1 + |value|`` between routes (float64; float32 observations: :data:`RTOL32`)
RTOL = 1e-9
RTOL32 = 2.5e-7


def _eq(a: Any, b: Any, err_msg: str = "", exact: bool = False) -> None:
    """``a`` equals ``b``: floats within the tolerance (bit for bit when ``exact``: one route), the rest exactly."""
    a, b = np.asarray(a), np.asarray(b)
    if exact or a.dtype.kind != "f" or b.dtype.kind != "f":
        np.testing.assert_array_equal(a, b, err_msg=err_msg)
        return
    rtol = RTOL32 if np.float32 in (a.dtype, b.dtype) else RTOL
    np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol, err_msg=err_msg)


MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED)
#: the tasks compared (episodes end: short time limits, open paths, hard randomisation)
TASKS: dict[str, dict[str, Any]] = {
    "circle": {"max_episode_steps": 35},
    "figure8-mild": {"path": "figure8", "randomize": "mild", "max_episode_steps": 40},
    # a short open path, driven forward: episodes end at its end (end_of_path)
    "lane_change-delay": {
        "path": "lane_change",
        "path_params": {"offset": 0.02, "length": 0.8, "lead": 0.1},
        "actuators": {"delay": 0.25},
        "speed": 0.35,
    },
    "random-hard": {"path": "random", "randomize": "hard", "random_pool": 8, "max_episode_steps": 30},
    "mixed-hard-speeds": {"path": "mixed", "randomize": "hard", "speed": (0.1, 0.4), "max_episode_steps": 45},
    "mixed-trapezoid": {
        "path": "mixed",
        "speed_profile": "trapezoid",
        "profile_duration": 3.0,
        "speed": (0.15, 0.3),
        "max_episode_steps": 50,
    },
    "noise-slip-l3": {
        "path": "circle",
        "randomize": {"slip": (0.0, 0.2), "delay": (0.0, 0.3), "wheel_rate_noise": 0.5, "heading_noise": 0.05},
        "true_robot": {"l3": 0.1},
        "max_episode_steps": 30,
    },
}


def _make(n: int, mode: AutoresetMode, kernel: str, **kw: Any) -> gym.vector.VectorEnv:
    return gym.make_vec(
        "AmigoBot-v1", n, vectorization_mode="vector_entry_point", autoreset_mode=mode, kernel=kernel, **kw
    )


def _sync(n: int, mode: AutoresetMode, **kw: Any) -> gym.vector.VectorEnv:
    # the single envs run their reference float code
    return gym.make_vec(
        "AmigoBot-v1", n, vectorization_mode="sync", vector_kwargs={"autoreset_mode": mode}, kernel="numpy", **kw
    )


def _equal_infos(
    a: dict[str, Any], b: dict[str, Any], what: str, exact_types: bool = True, exact: bool = False
) -> None:
    """``a`` (a native env's infos) equals ``b``: every key of ``a`` (all of ``b``'s when ``exact_types``, with
    the same dtypes and shapes), recursively; ``final_obs`` row by row."""
    if exact_types:
        assert list(a) == list(b), (what, list(a), list(b))
    for key, va in a.items():
        vb = b[key]
        if key == "final_obs":
            assert va.shape == vb.shape
            for i, (ra, rb) in enumerate(zip(va, vb, strict=True)):
                assert (ra is None) == (rb is None), (what, key, i)
                if ra is not None:
                    _eq(ra, rb, f"{what}: final_obs[{i}]", exact)
        elif isinstance(va, dict):
            _equal_infos(va, vb, f"{what}: {key}", exact_types, exact)
        elif va.dtype == object:
            np.testing.assert_array_equal(va, vb, err_msg=f"{what}: {key}")
        else:
            _eq(va, vb, f"{what}: {key}", exact)
            if exact_types:
                assert va.dtype == vb.dtype and va.shape == vb.shape, (what, key, va.dtype, vb.dtype)


def _equal_results(
    a: tuple[Any, ...], b: tuple[Any, ...], what: str, exact_types: bool = True, exact: bool = False
) -> None:
    for j, name in enumerate(("obs", "reward", "terminated", "truncated")):
        _eq(a[j], b[j], f"{what}: {name}", exact)
        if exact_types:
            assert a[j].dtype == b[j].dtype, (what, name)
    _equal_infos(a[4], b[4], what, exact_types, exact)


def _actions(rng: np.random.Generator, n: int, forward: bool = False) -> np.ndarray:
    a = rng.uniform(-1.0, 1.0, (n, 2))
    a[:, 1] = 0.5 * a[:, 1] + 0.5 * a[:, 0]  # correlated wheels, so that episodes also last
    if forward:  # straight ahead at about 0.4 m/s, wobbling
        a = 0.55 + 0.1 * a
    return a


def _run(
    envs: list[gym.vector.VectorEnv], n: int, mode: AutoresetMode, steps: int, seed: int, forward: bool = False
) -> tuple[int, int]:
    """Step ``envs`` (kernel, numpy, sync) with the same actions and compare them.

    Returns:
        the episodes ended, and those ended at the end of an open path.
    """
    outs = [e.reset(seed=seed) for e in envs]
    _eq(outs[0][0], outs[1][0])
    _eq(outs[0][0], outs[2][0])
    _equal_infos(outs[0][1], outs[1][1], "reset")
    _equal_infos(outs[0][1], outs[2][1], "reset vs sync", exact_types=False)
    rng = np.random.default_rng(seed)
    ended = at_end = 0
    for t in range(steps):
        a = _actions(rng, n, forward)
        r = [e.step(a) for e in envs]
        _equal_results(r[0], r[1], f"step {t}")
        _equal_results(r[0], r[2], f"step {t} vs sync", exact_types=False)
        done = r[0][2] | r[0][3]
        ended += int(done.sum())
        last = r[0][4].get("final_info", r[0][4])  # SameStep: the ended episodes' infos
        at_end += int((done & (last["end_of_path"] != 0.0)).sum())
        if mode == AutoresetMode.DISABLED and done.any():
            got = [e.reset(options={"reset_mask": done}) for e in envs]
            _eq(got[0][0], got[1][0])
            _eq(got[0][0], got[2][0])
            _equal_infos(got[0][1], got[1][1], f"partial reset {t}")
            _equal_infos(got[0][1], got[2][1], f"partial reset {t} vs sync", exact_types=False)
    return ended, at_end


@pytest.mark.parametrize("task", list(TASKS))
@pytest.mark.parametrize("mode", MODES, ids=[m.value for m in MODES])
@pytest.mark.parametrize("n", [1, 5, 13, 64])
def test_kernel_equals_numpy_and_sync(task: str, mode: AutoresetMode, n: int) -> None:
    kw = TASKS[task]
    envs = [_make(n, mode, "numba", **kw), _make(n, mode, "numpy", **kw), _sync(n, mode, **kw)]
    assert envs[0].unwrapped._batch is not None  # type: ignore[attr-defined]
    assert envs[1].unwrapped._batch is None  # type: ignore[attr-defined]
    steps = 120 if n < 64 else 70
    ended, at_end = _run(envs, n, mode, steps, seed=7 + n, forward=task.startswith("lane_change"))
    assert ended > 0 or n == 1, "the comparison covered no autoreset"
    if task.startswith("lane_change") and n > 1:
        assert at_end > 0, "no episode reached the end of its path"


def test_parallel_twin_equals_serial() -> None:
    kw = TASKS["mixed-hard-speeds"]
    n = 32
    envs = [_make(n, AutoresetMode.NEXT_STEP, k, **kw) for k in ("numba-parallel", "numba")]
    assert envs[0].unwrapped._batch.parallel  # type: ignore[attr-defined]
    outs = [e.reset(seed=5) for e in envs]
    np.testing.assert_array_equal(outs[0][0], outs[1][0])
    rng = np.random.default_rng(5)
    for t in range(60):
        a = _actions(rng, n)
        r = [e.step(a) for e in envs]
        _equal_results(r[0], r[1], f"step {t}", exact=True)


_WAIT_SCRIPT = """
import os, gymnasium as gym, numpy as np, numba, amigo_gym
e = gym.make_vec("AmigoBot-v0", 8, vectorization_mode="vector_entry_point", kernel="numba-parallel")
e.reset(seed=0)
e.step(np.zeros((8, 2)))
print("layer", numba.threading_layer(), "env", os.environ.get("OMP_WAIT_POLICY"), os.environ.get("GOMP_SPINCOUNT"))
"""


@pytest.mark.parametrize("given", [None, "ACTIVE"])
def test_parallel_threads_wait_passively(given: str | None) -> None:
    """The parallel kernel's OpenMP threads spin 1,000 pauses after a parallel loop, then sleep
    (``OMP_WAIT_POLICY=PASSIVE``, ``GOMP_SPINCOUNT=1000``, as libgomp itself reports them with ``OMP_DISPLAY_ENV``),
    unless the user set the policy (then neither is touched); libgomp's default spin made a 2-thread step 8-10x slower
    than one thread on a busy 2-core machine (docs/performance.md)."""
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    env |= {"OMP_DISPLAY_ENV": "VERBOSE", "NUMBA_NUM_THREADS": "2"} | ({"OMP_WAIT_POLICY": given} if given else {})
    out = subprocess.run([sys.executable, "-c", _WAIT_SCRIPT], env=env, capture_output=True, text=True, check=True)
    want, spin = (given, None) if given else ("PASSIVE", "1000")
    assert f"env {want} {spin}" in out.stdout
    if "layer omp" in out.stdout:  # libgomp read them when numba started its threads
        assert f"OMP_WAIT_POLICY = '{want}'" in out.stdout + out.stderr
        if spin:
            assert f"GOMP_SPINCOUNT = '{spin}'" in out.stdout + out.stderr


@pytest.mark.parametrize(("simd", "threads", "take"), [(False, 2, True), (True, 2, False), (True, 8, True)])
@pytest.mark.parametrize("path", ["circle", "manoeuvre"])
def test_parallel_twin_equals_serial_ideal(
    path: str, simd: bool, threads: int, take: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """AmigoBot-v0's ideal step (blocks of ``ideal_rows`` and the record pass) on numba's threads equals the serial
    one within the golden tolerance, with some rows flagged ``l3_differs`` (the row loop) every other step, both ways
    the threads may take ``tan`` and ``exp`` whatever this CPU and its threads: libm's on the threads
    (``NUMPY_SIMD`` false, or 8 threads or more), which differ from numpy's SIMD versions in the last bits, or numpy's
    on the calling thread as the serial loops (SIMD and fewer threads)."""
    monkeypatch.setattr(fast_v1_batch, "NUMPY_SIMD", simd)
    monkeypatch.setattr(numba, "get_num_threads", lambda: threads)  # what the step's choice reads, not the threads
    n = 300
    envs = [
        gym.make_vec("AmigoBot-v0", n, vectorization_mode="vector_entry_point", kernel=k, path=path,
                     max_episode_steps=25)
        for k in ("numba-parallel", "numba")
    ]  # fmt: skip
    outs = [e.reset(seed=3) for e in envs]
    np.testing.assert_array_equal(outs[0][0], outs[1][0])
    rng = np.random.default_rng(3)
    for t in range(40):
        a = rng.uniform(-1.0, 1.0, (n, 2))
        for e in envs:
            e.unwrapped._batch.rows.l3_differs[130:200] = float(t % 2)  # type: ignore[attr-defined]
        r = [e.step(a) for e in envs]
        _equal_results(r[0], r[1], f"step {t}")
    assert envs[0].unwrapped._batch._take is take  # type: ignore[attr-defined]


def test_partial_resets_reseeding_and_poses() -> None:
    n = 13
    kw = {"path": "mixed", "randomize": "mild", "speed": (0.1, 0.3)}
    mode = AutoresetMode.NEXT_STEP
    envs = [_make(n, mode, "numba", **kw), _make(n, mode, "numpy", **kw), _sync(n, mode, **kw)]
    seeds: list[int | None] = list(range(100, 100 + n))
    for e in envs:
        e.reset(seed=seeds)
    rng = np.random.default_rng(0)
    for t in range(90):
        a = _actions(rng, n)
        r = [e.step(a) for e in envs]
        _equal_results(r[0], r[1], f"step {t}")
        _equal_results(r[0], r[2], f"step {t} vs sync", exact_types=False)
        if t % 15 == 7:  # a partial reset, some rows reseeded, the kernel's rows reloaded mid-episode
            mask = rng.random(n) < 0.4
            mask[t % n] = True
            new = [int(s) if mask[i] and i % 2 else None for i, s in enumerate(rng.integers(0, 10**6, n))]
            got = [e.reset(seed=new, options={"reset_mask": mask}) for e in envs]
            _eq(got[0][0], got[1][0])
            _eq(got[0][0], got[2][0])
            _equal_infos(got[0][1], got[1][1], f"partial reset {t}")
        if t == 50:  # start poses: one per robot (the native envs), one for all (and SyncVectorEnv)
            poses = np.column_stack((rng.uniform(-0.5, 0.5, n), rng.uniform(0.8, 1.2, n), rng.uniform(-0.2, 0.2, n)))
            got = [e.reset(seed=3, options={"pose": poses}) for e in envs[:2]]
            _eq(got[0][0], got[1][0])
            _equal_infos(got[0][1], got[1][1], "reset with poses")
            pose = (0.05, -0.02, 0.1)
            got = [e.reset(seed=4, options={"pose": pose}) for e in envs]
            _eq(got[0][0], got[1][0])
            _eq(got[0][0], got[2][0])
            _equal_infos(got[0][1], got[1][1], "reset with a pose")
            _equal_infos(got[0][1], got[2][1], "reset with a pose vs sync", exact_types=False)


def test_pickled_env_continues_identically() -> None:
    n = 13
    kw = TASKS["mixed-hard-speeds"]
    env = _make(n, AutoresetMode.SAME_STEP, "numba", **kw)
    ref = _make(n, AutoresetMode.SAME_STEP, "numpy", **kw)
    env.reset(seed=21)
    ref.reset(seed=21)
    rng = np.random.default_rng(21)
    for _ in range(40):
        a = _actions(rng, n)
        env.step(a)
        ref.step(a)
    clone = pickle.loads(pickle.dumps(env))
    u = clone.unwrapped
    assert np.shares_memory(u._state.x, u._batch.ws)  # type: ignore[attr-defined]  # views again
    for t in range(80):
        a = _actions(rng, n)
        r = [clone.step(a), env.step(a), ref.step(a)]
        _equal_results(r[0], r[1], f"clone step {t}", exact=True)
        _equal_results(r[0], r[2], f"clone step {t} vs numpy")


def test_kernel_keyword(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("AMIGO_GYM_KERNEL", raising=False)  # "auto" as without the variable
    with pytest.raises(ValueError, match=r"kernel must be 'auto', 'numpy', 'numba' or 'numba-parallel', got 'fast'"):
        AmigoBotV1VectorEnv(2, kernel="fast")
    with pytest.raises(ValueError, match="kernel must be"):
        AmigoBotV1VectorEnv(2, kernel=1)  # type: ignore[arg-type]
    assert AmigoBotV1VectorEnv(2, kernel="auto")._batch is not None
    assert AmigoBotV1VectorEnv(2, kernel="numpy")._batch is None
    envs = gym.make_vec("AmigoBot-v1", 3, vectorization_mode="vector_entry_point", kernel="numpy")
    assert envs.unwrapped._batch is None  # type: ignore[attr-defined]


def test_environment_variable_numpy(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("AMIGO_GYM_KERNEL", "numpy")
    assert AmigoBotV1VectorEnv(2)._batch is None
    assert AmigoBotV1VectorEnv(2, kernel="numba")._batch is not None


class _Wrapped:
    """A path object of another class (the PathSpec protocol by delegation): runs the reference code."""

    def __init__(self, inner: Any) -> None:
        self._inner = inner

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)


def test_path_object_of_another_class_runs_the_reference() -> None:
    from amigo_gym.task import v1 as tracking

    inner = tracking.fixed_path(tracking.make_tracking_params("t", None, path="figure8"))
    path = _Wrapped(inner)
    n = 5
    mode = AutoresetMode.NEXT_STEP
    env = _make(n, mode, "numba", path=path, max_episode_steps=30)
    assert env.unwrapped._batch is None  # type: ignore[attr-defined]
    envs = [env, _make(n, mode, "numba", path=inner, max_episode_steps=30), _sync(n, mode, path=inner)]
    envs[2] = _sync(n, mode, path=inner, max_episode_steps=30)
    assert envs[1].unwrapped._batch is not None  # type: ignore[attr-defined]
    _run(envs, n, mode, 70, seed=2)


def _random_pool(count: int) -> list[Any]:
    # the first ``count`` paths of the default random pool
    from amigo_gym.task import v1 as tracking

    p = tracking.make_tracking_params("t", None, path="random")
    return [tracking.random_pool_path(p, i) for i in range(count)]


def test_path_arena_rows_read_their_paths() -> None:
    from amigo_gym.sim.fast_v1_batch import PathArena

    pool = _random_pool(40)
    n = 16
    arena = PathArena(n)
    rows: list[Any] = [None] * n
    rng = np.random.default_rng(0)
    compacted = False
    peak, biggest = 0, max(fast_v1.flat_path(q).size for q in pool)  # the array stays within 8/3 of the most floats
    for _ in range(300):
        idx = sorted(set(rng.integers(0, n, 5).tolist()))
        paths = [pool[int(j)] for j in rng.integers(0, len(pool), len(idx))]
        used = arena.used
        arena.assign(idx, paths)
        compacted |= arena.used < used
        peak = max(peak, arena.used - arena._dead + biggest)  # live at once, plus a path (the docstring's rule)
        assert arena.flat.size <= 8 / 3 * peak
        for i, q in zip(idx, paths, strict=True):
            rows[i] = q
        for i, q in enumerate(rows):
            if q is not None:
                np.testing.assert_array_equal(arena.flat[arena.starts[i] : arena.stops[i]], fast_v1.flat_path(q))
    assert compacted
    live = {id(q): q for q in rows if q is not None}
    assert arena.used - arena._dead == sum(fast_v1.flat_path(q).size for q in live.values())


def _family_rows(rng: np.random.Generator, m: int) -> tuple[list[str], Any, Any]:
    # m random family descriptions (mixed's families and more: the figure-8's angle and transition, the lead)
    from amigo_gym.paths.families import SEGMENT_FAMILIES

    names = [SEGMENT_FAMILIES[int(j)] for j in rng.integers(0, 3, m)]
    u = rng.uniform
    values = {"circle": lambda: (u(0.3, 3.0), float(rng.choice([-1.0, 1.0])), 0.0),
              "figure8": lambda: (u(1.0, 8.0), u(0.3, 2.0), u(0.0, 1.0)),
              "lane_change": lambda: (u(-2.0, 2.0), u(3.0, 6.0), u(0.0, 2.0))}  # fmt: skip
    params = np.array([values[f]() for f in names])
    return names, np.array([SEGMENT_FAMILIES.index(f) for f in names], dtype=np.int64), params


def _family_path(name: str, v: Any) -> Any:
    # the family constructor's path of _family_rows' description (compiled loops)
    from amigo_gym.paths import families

    keys = {"circle": ("radius", "direction"), "figure8": ("size", "crossing_angle", "transition"),
            "lane_change": ("offset", "length", "lead")}[name]  # fmt: skip
    given = dict(zip(keys, v.tolist(), strict=False))
    given.update({"direction": int(given["direction"])} if name == "circle" else {})
    return families.FAMILIES[name].build(loops=fast_v1.path_loops(), **given)


def test_path_arena_builds_family_paths_in_place() -> None:
    """Rows whose family paths the arena builds (``PathArena.build``, compiled) read the constructors' own flat
    vectors bit for bit (the same compiled functions), among rows holding path objects, through compactions."""
    from amigo_gym.sim.fast_v1_batch import PathArena

    pool = _random_pool(10)
    n = 12
    arena = PathArena(n)
    want: list[Any] = [None] * n
    rng = np.random.default_rng(4)
    compacted = False
    for _ in range(120):
        idx = sorted(set(rng.integers(0, n, 5).tolist()))
        held, built = idx[: len(idx) // 2], idx[len(idx) // 2 :]
        objs = [pool[int(j)] for j in rng.integers(0, len(pool), len(held))]
        names, kinds, params = _family_rows(rng, len(built))
        used = arena.used
        arena.assign(held, objs)
        arena.build(built, kinds, params)
        compacted |= arena.used < used
        for i, q in zip(held, objs, strict=True):
            want[i] = fast_v1.flat_path(q)
        for i, name, v in zip(built, names, params, strict=True):
            want[i] = _family_path(name, v)._t.flat
        for i, f in enumerate(want):
            if f is not None:
                np.testing.assert_array_equal(arena.flat[arena.starts[i] : arena.stops[i]], f)
    assert compacted
    clone = pickle.loads(pickle.dumps(arena))  # the built rows' keys survive (no object behind them)
    for i, f in enumerate(want):
        np.testing.assert_array_equal(clone.flat[clone.starts[i] : clone.stops[i]], f)
    with pytest.raises(ValueError, match=r"row 3's lane_change parameters \[5.0, 3.0, 1.0\] build no path"):
        arena.build([3], np.array([2]), np.array([[5.0, 3.0, 1.0]]))  # |offset| > 0.68 length


def test_drawn_paths_are_the_arenas_and_their_descriptions() -> None:
    """The native vector env's drawn family paths (built in the arena) are, when asked for (``env.paths``), the
    family constructors' paths of ``path_infos``, the arena's vectors bit for bit; through restarts and pickling."""
    from amigo_gym.paths import FAMILIES

    n = 48
    env = _make(n, AutoresetMode.NEXT_STEP, "numba", **TASKS["mixed-hard-speeds"])
    env.reset(seed=5)
    rng = np.random.default_rng(5)
    for t in range(150):
        env.step(_actions(rng, n))
        if t in (60, 149):
            u = pickle.loads(pickle.dumps(env)).unwrapped if t == 149 else env.unwrapped
            a = u._batch.arena  # type: ignore[attr-defined]
            for i in range(n):
                info, path = u.path_infos[i], u.paths[i]  # type: ignore[attr-defined]
                np.testing.assert_array_equal(a.flat[a.starts[i] : a.stops[i]], path._t.flat)
                if info["family"] != "random":  # the Python constructor's (another route: to rounding)
                    want = FAMILIES[info["family"]].build(**{k: v for k, v in info.items() if k != "family"})
                    assert (path.start, path.start_angle, path.closed) == (want.start, want.start_angle, want.closed)
                    segs = [[(g.length, g.curvature, g.curvature_rate) for g in q.segments] for q in (path, want)]
                    np.testing.assert_allclose(segs[0], segs[1], rtol=1e-13, atol=1e-13)
    assert {d["family"] for d in u.path_infos} == {"circle", "figure8", "lane_change", "random"}


def test_path_arena_survives_pickling() -> None:
    from amigo_gym.sim.fast_v1_batch import PathArena

    pool = _random_pool(6)
    arena = PathArena(4)
    arena.assign([0, 1, 2, 3], [pool[0], pool[1], pool[0], pool[2]])
    clone, paths = pickle.loads(pickle.dumps((arena, pool)))
    assert sorted(clone._live) == sorted({id(paths[0]), id(paths[1]), id(paths[2])})
    clone.assign([1, 3], [paths[0], paths[5]])  # row 1 joins a live path, row 3 takes a new one
    for i, q in enumerate([paths[0], paths[0], paths[0], paths[5]]):
        np.testing.assert_array_equal(clone.flat[clone.starts[i] : clone.stops[i]], fast_v1.flat_path(q))
    assert clone._live[id(paths[0])][3] == 3 and id(paths[1]) not in clone._live


def test_warm_cache_start_compiles_nothing() -> None:
    """A second process loads the batch loops from numba's disk cache: building the env, the first reset and the
    first step compile nothing (every compiled function called is a cache hit; the start's duration is measured by
    ``amigo-gym bench-core``, not here)."""
    import subprocess
    import sys

    code = (
        "import numpy as np; from numba.core.registry import CPUDispatcher\n"
        "from amigo_gym.envs import AmigoBotV1VectorEnv\n"
        "e = AmigoBotV1VectorEnv(4, kernel='numba', randomize='hard'); e.reset(seed=0); e.step(np.zeros((4, 2)))\n"
        "import amigo_gym.sim._kernels_v1 as k\n"
        "ds = [v for v in vars(k).values() if isinstance(v, CPUDispatcher)]\n"
        "print(sum(sum(d.stats.cache_misses.values()) for d in ds), sum(sum(d.stats.cache_hits.values()) for d in ds))"
    )
    warm = AmigoBotV1VectorEnv(4, kernel="numba", randomize="hard")  # compiled (and cached) here at the latest
    warm.reset(seed=0)
    warm.step(np.zeros((4, 2)))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    misses, hits = (int(x) for x in out.stdout.split()[-2:])
    assert misses == 0 and hits > 0, (misses, hits)


def test_pickled_env_continues_identically_in_another_process(tmp_path: Path) -> None:
    """A pickled native vector env unpickled in a new process (where numpy's loops sit at other addresses: the
    compiled step calls them by address) continues with the same results as the original here."""
    n = 5
    env = _make(n, AutoresetMode.NEXT_STEP, "numba")
    env.reset(seed=4)
    rng = np.random.default_rng(4)
    actions = [_actions(rng, n) for _ in range(60)]
    for a in actions[:20]:
        env.step(a)
    blob = tmp_path / "env.pkl"
    blob.write_bytes(pickle.dumps((env, actions[20:])))
    out = tmp_path / "out.npz"
    script = (
        "import pickle, sys, numpy as np, amigo_gym\n"
        "env, actions = pickle.loads(open(sys.argv[1], 'rb').read())\n"
        "res = [env.step(a) for a in actions]\n"
        "stack = lambda f: np.stack([f(r) for r in res])\n"
        "np.savez(sys.argv[2], obs=stack(lambda r: r[0]), reward=stack(lambda r: r[1]),\n"
        "         pose=stack(lambda r: r[4]['pose']), track=stack(lambda r: r[4]['reward_terms']['track']))\n"
    )
    subprocess.run([sys.executable, "-c", script, str(blob), str(out)], check=True, timeout=300)
    got = np.load(out)
    res = [env.step(a) for a in actions[20:]]
    assert got["obs"].tobytes() == np.stack([r[0] for r in res]).tobytes()
    assert got["reward"].tobytes() == np.stack([r[1] for r in res]).tobytes()
    assert got["pose"].tobytes() == np.stack([r[4]["pose"] for r in res]).tobytes()
    assert got["track"].tobytes() == np.stack([r[4]["reward_terms"]["track"] for r in res]).tobytes()


@pytest.mark.parametrize("path", ["circle", "manoeuvre"])
@pytest.mark.parametrize("n", [1, 7, 300])
def test_ideal_blocks_equal_the_row_step(path: str, n: int) -> None:
    """AmigoBot-v0's step by blocks (``_kernels_v1._ideal_block``) equals ``ideal_rows``' row loop bit for bit (rows
    flagged ``l3_differs`` with the nominal ``l3`` take it; the same values) and the general row step (``step_rows``,
    the C library's ``tan``) to 1e-12 relative to ``1 + |value|``, over random actions with restarts."""
    envs = [
        gym.make_vec("AmigoBot-v0", n, vectorization_mode="vector_entry_point", path=path, max_episode_steps=25)
        for _ in range(3)
    ]
    envs[1].unwrapped._batch.ideal = False  # type: ignore[attr-defined]
    outs = [e.reset(seed=n) for e in envs]
    np.testing.assert_array_equal(outs[0][0], outs[1][0])
    rng = np.random.default_rng(n)
    ended = 0
    for t in range(60):
        a = rng.uniform(-1.0, 1.0, (n, 2))
        envs[2].unwrapped._batch.rows.l3_differs[:] = 1.0  # type: ignore[attr-defined]
        r = [e.step(a) for e in envs]
        envs[2].unwrapped._batch.rows.l3_differs[:] = 0.0  # type: ignore[attr-defined]
        _equal_results(r[0], r[2], f"step {t}: rows", exact=True)
        for name, x, y in zip(("obs", "reward", "terminated", "truncated"), r[0], r[1], strict=False):
            np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12, err_msg=f"step {t}: {name}")
        for key, x in r[0][4].items():
            if key != "final_obs" and not isinstance(x, dict) and x.dtype != object:
                np.testing.assert_allclose(x, r[1][4][key], rtol=1e-12, atol=1e-12, err_msg=f"step {t}: {key}")
        ended += int((r[0][2] | r[0][3]).sum())
    assert ended > 0


def test_compiled_start_draws_equal_the_generators() -> None:
    """The restarts' compiled draws (``draw_uniforms``) are ``2 Generator.random(3) - 1`` and ``draw_key`` bit for
    bit and leave each generator in the same state (one with a buffered 32-bit half included); a reseeded row draws
    from its new generator."""
    from gymnasium.utils import seeding

    from amigo_gym.model.randomization import draw_key

    gens, refs = ([seeding.np_random(s)[0] for s in range(4)] for _ in range(2))
    for g in (gens[1], refs[1]):
        g.random(dtype=np.float32)
    addr = np.array([g.bit_generator.ctypes.bit_generator.value for g in gens], dtype=np.int64)
    out, want = np.empty((4, 3)), np.empty((4, 3))
    keys = np.zeros(4, dtype=np.uint64)
    fast_v1.kernels().draw_uniforms(addr, np.array([(-1.0, 1.0)] * 3), out, keys)
    for j, g in enumerate(refs):
        g.random(out=want[j])
    want *= 2.0
    want -= 1.0
    assert out.tobytes() == want.tobytes()
    assert keys.tolist() == [draw_key(g) for g in refs]
    assert [g.bit_generator.state for g in gens] == [g.bit_generator.state for g in refs]
    assert [g.random() for g in gens] == [g.random() for g in refs]
    env = gym.make_vec("AmigoBot-v0", 3, vectorization_mode="vector_entry_point", kernel="numba")
    assert env.unwrapped._template is not None  # the restarts of one fixed path (the compiled draws)
    env.reset(seed=1)
    again = env.reset(seed=2)[0]
    fresh = gym.make_vec("AmigoBot-v0", 3, vectorization_mode="vector_entry_point", kernel="numba")
    assert again.tobytes() == fresh.reset(seed=2)[0].tobytes()
