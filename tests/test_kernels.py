"""The compiled step of AmigoBot-v0 (amigo_gym.sim.fast.step_rows) against AmigoBot-v1's reference with v0's settings.

The reference is the route ``kernel="numpy"`` runs: :func:`amigo_gym.task.v1.step_columns` with ideal actuators
(``_ideal_step``; the observation by :func:`amigo_gym.task.v0.observe_columns`) and
:func:`amigo_gym.task.v1.reset_columns` of :func:`amigo_gym.task.v1.v0_configuration`, on ``(N,)`` columns: another
code path than the kernel's loops (it projects H by ``path.locate`` and evaluates by ``evaluate_columns``). Random
states and actions (actions beyond [-1, 1] too, straight motion, turning on the spot) on the circle and the
manoeuvre path, both directions, several dt: every output agrees to 1e-12 (the contract) and is in fact
bit-identical on this machine (the same numpy ``tan`` and ``exp``); the parallel variant gives the serial one's bits;
restart rows are evaluated as the reference's reset evaluates a start state (the reference: ``tests/v0_reference.py``).
The golden episodes (``tests/test_golden.py``) hold both routes to recorded numbers.
"""

from __future__ import annotations

import functools
import math
import os
import subprocess
import sys
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray
from v0_reference import Reference

from amigo_gym.model.params import EnvParams
from amigo_gym.paths import classic, make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking

pytest.importorskip("numba")

ATOL = 1e-12
Array = NDArray[np.float64]

SETTINGS = [
    {"path": "circle", "direction": 1},
    {"path": "circle", "direction": -1, "radius": 0.5, "dt": 0.05},
    {"path": "manoeuvre", "direction": 1, "dt": 0.3},
    {"path": "manoeuvre", "direction": -1, "straight_length": 0.0, "radius": 1.7, "dt": 1.5},
    {"path": "manoeuvre", "direction": 1, "preview": (), "dt": 0.01},
    {"path": "circle", "direction": 1, "preview": (0.1, 0.5, 2.0), "dt": 2.0},
]


def _states(params: EnvParams, n: int, seed: int) -> tuple[Array, Array]:
    """``(state (n, 8), actions (n, 2))``: poses around the path, some special actions."""
    g = np.random.default_rng(seed)
    r = params.radius
    s = g.uniform(-0.5, params.straight_length + 2 * np.pi * r, n)
    # points near the straight part (x <= L), near the circle, and anywhere in between
    x = np.where(g.random(n) < 0.5, s, g.uniform(-1.0, params.straight_length + r + 1.0, n))
    y = np.where(g.random(n) < 0.5, g.normal(0.0, 0.3, n), params.direction * g.uniform(-0.5, 2 * r + 0.5, n))
    state = np.column_stack(
        (
            x,
            y,
            g.uniform(-20.0, 20.0, n),
            g.normal(0.0, 50.0, n),
            g.normal(0.0, 50.0, n),
            g.normal(0.0, 50.0, n),
            g.uniform(-15.0, 15.0, n),
            g.uniform(-15.0, 15.0, n),
        )
    )
    actions = g.uniform(-1.3, 1.3, (n, 2))
    actions[:20, 1] = actions[:20, 0]  # straight: h = 0
    actions[20:30, 1] = -actions[20:30, 0]  # on the spot: v = 0
    actions[30:35] = 0.0
    actions[35:40] = -0.0
    actions[40:45] = (1.0, -1.0)
    state[45:50, 6:8] = actions[45:50] * params.robot.max_wheel_rate  # no change of the rates
    return np.ascontiguousarray(state), np.ascontiguousarray(actions)


def _run(
    params: EnvParams, state: Array, actions: Array, restart: NDArray[np.bool_], parallel: bool = False
) -> tuple[Array, Array, Array, NDArray[np.bool_], Array]:
    n = len(state)
    st = state.copy()
    obs = np.full((n, task.obs_dim(params)), np.nan)
    reward = np.full(n, np.nan)
    terminated = np.zeros(n, dtype=np.bool_)
    record = np.full((n, len(fast.kernels().RECORD_FIELDS)), np.nan)
    ws = fast.workspace(task.task_constants(params), make_path(params), n)
    fast.step_rows(ws, st, actions, restart, obs, reward, terminated, record, parallel=parallel)
    return st, obs, reward, terminated, record


def _obs(out: tracking.Outcome, n: int) -> Array:
    return np.column_stack([np.broadcast_to(np.asarray(c, dtype=np.float64), (n,)) for c in out.obs])


@pytest.mark.parametrize("settings", SETTINGS, ids=lambda s: "-".join(f"{k}={v}" for k, v in s.items()))
def test_kernel_step_agrees_with_the_reference(settings: dict[str, Any]) -> None:
    params = EnvParams(**settings)
    n = 3000
    state, actions = _states(params, n, seed=len(str(settings)))
    ref_state, ref_record, out = Reference(params, state).step(actions)
    st, obs, reward, terminated, record = _run(params, state, actions, np.zeros(n, dtype=np.bool_))

    np.testing.assert_allclose(st, ref_state, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(st[:, 3:5], ref_state[:, 3:5])  # wheel angles and rates: no transcendentals
    np.testing.assert_array_equal(st[:, 6:], ref_state[:, 6:])
    np.testing.assert_allclose(obs, _obs(out, n), rtol=0, atol=ATOL)
    np.testing.assert_allclose(reward, out.reward, rtol=0, atol=ATOL)
    np.testing.assert_allclose(record, ref_record, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(terminated, out.terminated)
    assert terminated.any() and not terminated.all()
    # the same numpy tan and exp, the same IEEE operations: the same bits on this machine. (The manoeuvre's arc
    # length comes from the C library's atan2 in the kernel, numpy's arctan2 in the reference, which may differ by
    # an ulp; it only decides whether a preview point lies before the end of the straight part.)
    np.testing.assert_array_equal(st, ref_state)
    np.testing.assert_array_equal(obs, _obs(out, n))
    np.testing.assert_array_equal(record, ref_record)


@pytest.mark.parametrize("settings", SETTINGS[:4], ids=lambda s: "-".join(f"{k}={v}" for k, v in s.items()))
def test_kernel_restart_rows_agree_with_the_reference_start(settings: dict[str, Any]) -> None:
    params = EnvParams(**settings)
    n = 500
    state, actions = _states(params, n, seed=5)
    restart = np.random.default_rng(1).random(n) < 0.5
    st, obs, _, terminated, record = _run(params, state, actions, restart)
    ref_record, out = Reference(params, state[restart]).start()
    m = int(restart.sum())
    np.testing.assert_array_equal(st[restart], state[restart])  # not moved
    np.testing.assert_allclose(obs[restart], _obs(out, m), rtol=0, atol=ATOL)
    np.testing.assert_allclose(record[restart], ref_record, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(record[restart], ref_record)
    np.testing.assert_array_equal(terminated[restart], out.terminated)
    assert np.all(record[restart, 14] == 1.0)  # no smoothness loss at a start
    # the other rows stepped as without restarts
    st2, obs2, *_ = _run(params, state, actions, np.zeros(n, dtype=np.bool_))
    np.testing.assert_array_equal(st[~restart], st2[~restart])
    np.testing.assert_array_equal(obs[~restart], obs2[~restart])


def test_parallel_variant_gives_the_same_bits() -> None:
    params = EnvParams(path="manoeuvre")
    state, actions = _states(params, 4096, seed=3)
    restart = np.random.default_rng(2).random(4096) < 0.1
    serial = _run(params, state, actions, restart)
    par = _run(params, state, actions, restart, parallel=True)
    for a, b in zip(serial, par, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("settings", SETTINGS, ids=lambda s: "-".join(f"{k}={v}" for k, v in s.items()))
def test_blocked_evaluate_gives_the_row_loops_bits(settings: dict[str, Any]) -> None:
    """The evaluate pass by blocks of rows in vectorised stages (``evaluate``, serial with one scratch slot and parallel
    with one per block) writes the row loop's bits (``evaluate_rows``, the single env's and small batches'), at sizes
    around the block's, with restart rows among the others."""
    k = fast.kernels()
    params = EnvParams(**settings)
    for n in (1, k.BLOCK - 1, k.BLOCK, k.BLOCK + 1, 3 * k.BLOCK + 5):
        state, actions = _states(params, max(n, 60), seed=n)
        state, actions = np.ascontiguousarray(state[:n]), np.ascontiguousarray(actions[:n])
        restart = np.random.default_rng(n).random(n) < 0.3
        ws = fast.workspace(task.task_constants(params), make_path(params), n)
        k.move_arguments(ws.consts, state, actions, restart, ws.tans, ws.turn)
        np.tan(ws.tans, out=ws.tans)
        ws.tans[restart, 0] = np.cos(state[restart, 2])
        ws.tans[restart, 1] = np.sin(state[restart, 2])
        outs = []
        per_block = np.zeros(k.scratch_size(n))  # the parallel pass: a slot per block
        runs = ((k.evaluate_rows, None), (k.evaluate, ws.block_cols), (k.evaluate_parallel, per_block))
        for run, cols in runs:
            st = state.copy()
            out = (st, np.full((n, ws.obs_dim), np.nan, np.float32), np.zeros(n, np.bool_), np.full((n, 16), np.nan),
                   np.full((n, 3), np.nan))  # fmt: skip
            args: tuple[Any, ...] = (ws.consts, ws.preview, st, actions, restart, ws.tans, ws.turn, *out[1:])
            if cols is not None:
                args += (cols,)
            run(*args)
            outs.append(out)
        for other in outs[1:]:
            for a, b in zip(outs[0], other, strict=True):
                assert a.tobytes() == b.tobytes()


def test_float32_observations_are_the_float64_ones_rounded() -> None:
    params = EnvParams()
    state, actions = _states(params, 1000, seed=4)
    _, obs64, *_ = _run(params, state, actions, np.zeros(1000, dtype=np.bool_))
    obs32 = np.empty(obs64.shape, dtype=np.float32)
    ws = fast.workspace(task.task_constants(params), make_path(params), 1000)
    no = np.zeros(1000, np.bool_)
    fast.step_rows(ws, state.copy(), actions, no, obs32, np.empty(1000), no.copy(), np.empty((1000, 16)))
    np.testing.assert_array_equal(obs32, obs64.astype(np.float32))


def test_bad_buffers_are_refused() -> None:
    params = EnvParams()
    ws = fast.workspace(task.task_constants(params), make_path(params), 4)
    good: list[Any] = [
        np.zeros((4, 8)),
        np.zeros((4, 2)),
        np.zeros(4, np.bool_),
        np.zeros((4, 10), np.float32),
        np.zeros(4),
        np.zeros(4, np.bool_),
        np.zeros((4, 16)),
    ]
    fast.step_rows(ws, *good)
    bad = [np.zeros((5, 8)), np.zeros((4, 2), np.float32), np.zeros(4), np.zeros((4, 9), np.float32)]
    for i, b in enumerate(bad):
        args = list(good)
        args[i] = b
        with pytest.raises(ValueError, match="C-contiguous"):
            fast.step_rows(ws, *args)
    args = list(good)
    args[0] = np.zeros((8, 4)).T
    with pytest.raises(ValueError, match="state"):
        fast.step_rows(ws, *args)


def test_a_trajectory_stays_with_the_reference() -> None:
    """200 steps fed back into themselves: rounding differences do not grow beyond 1e-12."""
    params = EnvParams(path="manoeuvre", dt=0.1)
    n = 64
    state, _ = _states(params, n, seed=6)
    state[:, 0:3] = np.random.default_rng(0).normal(0.0, [0.02, 0.02, 0.1], (n, 3))
    g = np.random.default_rng(7)
    ref = Reference(params, state)
    st = state.copy()
    for _ in range(200):
        a = np.ascontiguousarray(0.27 + 0.05 * g.normal(size=(n, 2)))
        _, _, out = ref.step(a)
        st, _, reward, *_ = _run(params, st, a, np.zeros(n, dtype=np.bool_))
        np.testing.assert_allclose(reward, out.reward, rtol=0, atol=ATOL)
    np.testing.assert_allclose(st, ref.rows(), rtol=0, atol=1e-11)


def test_which_path_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(fast.KERNEL_ENV, "numpy")
    assert fast.use_fast_path() is False
    monkeypatch.setenv(fast.KERNEL_ENV, "numba")
    assert fast.use_fast_path() is True
    monkeypatch.setenv(fast.KERNEL_ENV, "auto")
    assert fast.use_fast_path() is True
    assert fast.use_fast_path(False) is False
    monkeypatch.setenv(fast.KERNEL_ENV, "fortran")
    with pytest.raises(ValueError, match="AMIGO_GYM_KERNEL"):
        fast.use_fast_path()
    monkeypatch.delenv(fast.KERNEL_ENV)
    monkeypatch.setattr(fast, "numba_available", lambda: False)
    assert fast.use_fast_path() is False
    with pytest.raises(ImportError, match=r"amigo[-_]gym\[fast\]"):
        fast.use_fast_path(True)


def test_import_amigo_gym_does_not_load_numba() -> None:
    """``import amigo_gym`` and the numpy step never load numba (the kernel loads it when first built)."""
    code = (
        "import sys, gymnasium as gym, amigo_gym, amigo_gym.sim.fast\n"
        "print('numba' in sys.modules)\n"
        "env = gym.make('AmigoBot-v0', kernel='numpy'); env.reset(seed=0); env.step(env.action_space.sample())\n"
        "print('numba' in sys.modules)\n"
        "env = gym.make('AmigoBot-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
        "print('numba' in sys.modules)"
    )
    env = {k: v for k, v in os.environ.items() if k != fast.KERNEL_ENV}  # "auto" as without the variable
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    ).stdout.split()
    assert out == ["False", "False", "True"]


def _same(a: Any, b: Any, where: str) -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            _same(a[key], b[key], f"{where}.{key}")
    elif isinstance(a, tuple | list) or (isinstance(a, np.ndarray) and a.dtype == object):
        for x, y in zip(a, b, strict=True):
            _same(x, y, where)
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, where
        np.testing.assert_array_equal(a, b, err_msg=where)
    else:
        assert a == b, where


@pytest.mark.parametrize("mode", ["NextStep", "SameStep", "Disabled"])
@pytest.mark.parametrize("path", ["circle", "manoeuvre"])
def test_vector_env_with_the_kernel_gives_the_same_bits(mode: str, path: str) -> None:
    """AmigoBotVectorEnv(kernel="numba") against the numpy path: every output, across autoresets."""
    from amigo_gym.envs import AmigoBotVectorEnv

    n = 16
    kw: dict[str, Any] = {"num_envs": n, "max_episode_steps": 25, "autoreset_mode": mode, "path": path}
    ref = AmigoBotVectorEnv(**kw)
    envs = [AmigoBotVectorEnv(kernel="numba", **kw), AmigoBotVectorEnv(kernel="numba-parallel", **kw)]
    g = np.random.default_rng(3)
    outs = [e.reset(seed=7) for e in (ref, *envs)]
    for o in outs[1:]:
        _same(o, outs[0], "reset")
    for t in range(80):
        a = np.clip(0.27 + 0.6 * g.normal(size=(n, 2)), -1.2, 1.2)
        if mode == "Disabled" and ref._autoreset.any():
            mask = ref._autoreset.copy()
            outs = [e.reset(options={"reset_mask": mask}) for e in (ref, *envs)]
            for o in outs[1:]:
                _same(o, outs[0], f"partial reset {t}")
        outs = [e.step(a.astype(np.float32) if t % 2 else a) for e in (ref, *envs)]
        for o in outs[1:]:
            _same(o, outs[0], f"step {t}")
    assert ref._step_counts().max() < 25  # episodes ended (terminated or truncated) and restarted


def test_vector_env_kernel_argument(monkeypatch: pytest.MonkeyPatch) -> None:
    from amigo_gym.envs import AmigoBotVectorEnv

    monkeypatch.delenv(fast.KERNEL_ENV, raising=False)  # "auto" as without the variable
    with pytest.raises(ValueError, match="kernel"):
        AmigoBotVectorEnv(num_envs=2, kernel="cuda")
    assert AmigoBotVectorEnv(num_envs=2, kernel="numpy")._v0 is None
    assert AmigoBotVectorEnv(num_envs=2, kernel="numba")._v0 is not None
    # the default is "auto": the kernel when numba is installed (it is, here), unless AMIGO_GYM_KERNEL=numpy
    assert AmigoBotVectorEnv(num_envs=2)._v0 is not None
    monkeypatch.setenv("AMIGO_GYM_KERNEL", "numpy")
    assert AmigoBotVectorEnv(num_envs=2)._v0 is None


# ---------------------------------------------------------------------------------------------- single env


@functools.cache
def _compiled_atan2() -> Any:
    """numba's ``math.atan2`` (the C library's), compiled once."""
    import numba

    return numba.njit(lambda y, x: math.atan2(y, x))


def _atan2_explains(args: tuple[float, ...], got: tuple[Any, ...], want: tuple[Any, ...]) -> None:
    """The one difference the compiled ``manoeuvre_foot`` may show from the Python one: numba compiles ``np.arctan2``
    on floats to the C library's ``atan2``, and numpy's float64 ``arctan2`` is vectorised on some CPUs (numpy's SVML on
    AVX-512) and then differs from it by an ulp on some arguments. So: the two ``atan2`` differ on this point's
    arguments, the error, the tangent and the choice of the line are the same bits, and the arc lengths ``s`` and
    ``s_circ`` differ by at most a few ulps (NaN for a NaN point, its sign bit aside)."""
    x, y, cx, cy, r0x, r0y, d, r, _ = args
    _, _, _, ux, uy = classic.circle_foot(x, y, cx, cy, r0x, r0y, d, r)
    cross = r0x * uy - r0y * ux
    ya, xa = (cross if d > 0.0 else -cross), r0x * ux + r0y * uy
    assert not _bits_equal(_compiled_atan2()(ya, xa), float(np.arctan2(ya, xa))), (args, got, want)
    assert _bits_equal((got[0], got[1], got[2], got[5]), (want[0], want[1], want[2], want[5])), (args, got, want)
    for j in (3, 4):  # a NaN argument: NaN, of either sign
        nan = math.isnan(got[j]) and math.isnan(want[j])
        assert nan or abs(got[j] - want[j]) <= 4.0 * np.spacing(abs(want[j])), (args, j, got[j], want[j])


def _bits_equal(a: Any, b: Any) -> bool:
    """Equal bit for bit and of the same type (dicts recursively)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_bits_equal(a[k], b[k]) for k in a)
    if type(a) is not type(b):
        return False
    if isinstance(a, tuple | list):
        return len(a) == len(b) and all(_bits_equal(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return bool(np.asarray(a).tobytes() == np.asarray(b).tobytes())


@pytest.mark.parametrize("settings", SETTINGS, ids=lambda s: "-".join(f"{k}={v}" for k, v in s.items()))
def test_single_env_kernel_gives_the_reference_bits(settings: dict[str, Any]) -> None:
    """``AmigoBotEnv(kernel="numba")`` (fast.SingleStep) returns what ``kernel="numpy"`` (task.v1's ideal step) returns:
    observations, rewards, flags and every info entry bit for bit and of the same types, over whole episodes
    with random actions (beyond [-1, 1] too), straight runs and turns on the spot, past termination."""
    import warnings

    import gymnasium as gym

    fast_env = gym.make("AmigoBot-v0", kernel="numba", max_episode_steps=300, **settings)
    ref_env = gym.make("AmigoBot-v0", kernel="numpy", max_episode_steps=300, **settings)
    assert fast_env.unwrapped._v0 is not None and ref_env.unwrapped._v0 is None
    for seed in range(3):
        g = np.random.default_rng(seed)
        assert _bits_equal(fast_env.reset(seed=seed), ref_env.reset(seed=seed))
        for t in range(300):
            kind = t % 4
            if kind == 0:
                a = g.uniform(-1.3, 1.3, 2)
            elif kind == 1:
                a = np.array([0.6, 0.6])
            elif kind == 2:
                a = np.array([0.8, -0.8])
            else:
                a = g.uniform(-1.0, 1.0, 2).astype(np.float32)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # stepping past termination warns (both envs)
                out_f = fast_env.unwrapped.step(a)
                out_r = ref_env.unwrapped.step(a)
            for x, y in zip(out_f, out_r, strict=True):
                assert _bits_equal(x, y), (t, x, y)
        np.testing.assert_array_equal(fast_env.unwrapped.pose, ref_env.unwrapped.pose)
        np.testing.assert_array_equal(fast_env.unwrapped.wheel_rates, ref_env.unwrapped.wheel_rates)


def test_single_env_kernel_equals_the_vector_env_row() -> None:
    """One robot stepped by the single env's kernel and by the vector env (N = 1) gives the same bits."""
    import gymnasium as gym

    from amigo_gym.envs import AmigoBotVectorEnv

    single = gym.make("AmigoBot-v0", kernel="numba").unwrapped
    vec = AmigoBotVectorEnv(1, kernel="numba", max_episode_steps=None)
    o1, _ = single.reset(seed=5)
    ov, _ = vec.reset(seed=5)
    np.testing.assert_array_equal(o1, ov[0])
    g = np.random.default_rng(1)
    for _ in range(200):
        a = g.uniform(-1, 1, 2)
        o1, r1, t1, _, i1 = single.step(a)
        ov, rv, _, _, iv = vec.step(a[None])
        if t1:
            break
        np.testing.assert_array_equal(o1, ov[0])
        assert r1 == rv[0]
        np.testing.assert_array_equal(i1["pose"], iv["pose"][0])


def test_single_env_kernel_survives_pickling_and_bounds_the_heading() -> None:
    """A pickled env steps on identically (its own buffer); a heading past the limit is reduced as the reference
    reduces it (task.v0.bound_angle)."""
    import pickle

    import gymnasium as gym

    env = gym.make("AmigoBot-v0", kernel="numba", termination_distance=10.0).unwrapped
    ref = gym.make("AmigoBot-v0", kernel="numpy", termination_distance=10.0).unwrapped
    for e in (env, ref):
        e.reset(seed=0, options={"pose": (0.0, 0.0, 1e6 - 0.05)})
    for _ in range(3):
        a = np.array([1.0, -1.0])  # spin: the heading crosses 1e6 rad
        assert _bits_equal(env.step(a), ref.step(a))
    copy = pickle.loads(pickle.dumps(env))
    for _ in range(5):
        a = np.array([0.3, -0.2])
        out_c, out_e = copy.step(a), env.step(a)
        assert _bits_equal(out_c, out_e)
    assert copy._v0 is not None and copy._v0.buf is not env._v0.buf


def test_single_env_kernel_argument(monkeypatch: pytest.MonkeyPatch) -> None:
    """``kernel`` selects the step; ``"auto"`` follows AMIGO_GYM_KERNEL; a bad value is refused in one line."""
    import gymnasium as gym

    monkeypatch.delenv(fast.KERNEL_ENV, raising=False)
    assert gym.make("AmigoBot-v0").unwrapped._v0 is not None  # auto, numba installed
    monkeypatch.setenv(fast.KERNEL_ENV, "numpy")
    assert gym.make("AmigoBot-v0").unwrapped._v0 is None
    for bad in ("fast", 1, None, "numba-parallel"):
        with pytest.raises(ValueError, match=r"^AmigoBotEnv\.kernel must be 'auto', 'numpy' or 'numba', got .*$"):
            gym.make("AmigoBot-v0", kernel=bad)


def test_compiled_shared_pieces_give_the_python_bits() -> None:
    """The functions the kernel compiles from ``paths/classic.py`` and ``task/v0.py`` (its :data:`SHARED`), called
    compiled and as Python on the same floats: the same bits. For ``manoeuvre_foot`` this compares numba's ``atan2``
    and ``hypot`` (the C library's) with numpy's ``arctan2`` and ``hypot`` (the reference's) on points around the path,
    ties between the line and the circle, the centre and NaN included; for the observation's pieces, the kernel's
    ``clip_real`` (an overload: ``clip_float``) with the Python one on values beyond the bounds and NaN."""
    from amigo_gym.paths import ManoeuvrePath

    k = fast.kernels()
    g = np.random.default_rng(12)
    atan2_differs = 0
    for path in (ManoeuvrePath(1.0, 1.0, 1), ManoeuvrePath(0.6, 0.0, -1), ManoeuvrePath(1.7, 2.5, -1)):
        big_l, r, d = path.straight_length, path.radius, float(path.direction)
        frame = path.circle._frame
        n = 4000
        x = g.uniform(-2.0, big_l + 2.5 * r, n)
        y = g.uniform(-2.5 * r, 2.5 * r, n)
        x[:40], y[:40] = big_l, d * g.uniform(0.5 * r, r, 40)  # ties: d_line = |e_circle| = |y|
        x[40:44], y[40:44] = frame[0], frame[1]  # the centre
        x[44], y[45], x[46] = np.nan, np.nan, -0.0
        for i in range(n):
            args = (float(x[i]), float(y[i]), *frame, d, r, big_l)
            got, want = k._manoeuvre_foot(*args), classic.manoeuvre_foot(*args)
            if not _bits_equal(got, want):
                _atan2_explains(args, got, want)
                atan2_differs += 1
            s = float(x[i]) + 0.5
            assert _bits_equal(k._manoeuvre_curvature(s, big_l, d / r), classic.manoeuvre_curvature(s, big_l, d / r))
    # where numpy's arctan2 is the C library's (x86-64 without AVX-512, here on 2026-11-26), no point differs
    sample = g.uniform(-3.0, 3.0, (2, 20_000))
    same = all(_bits_equal(_compiled_atan2()(a, b), float(np.arctan2(a, b))) for a, b in sample.T.tolist())
    assert atan2_differs == 0 or not same
    v = g.normal(size=(n, 8)) * 3.0
    v[::9, 3] = np.nan
    for row in v.tolist():
        args = (row[0], row[1], row[2], row[3], 0.3, 0.25, 1.6)
        assert _bits_equal(k._observe_head(*args), task.observe_head(*args)), args
        args = (row[4], row[5], row[6], row[7], 1.7, 0.8)
        assert _bits_equal(k._observe_rates(*args), task.observe_rates(*args)), args
        assert _bits_equal(k._observe_reference(row[7], 0.8), task.observe_reference(row[7], 0.8))
        assert _bits_equal(k._curvature_feature(row[3], 0.3), task.curvature_feature(row[3], 0.3))
        args = (abs(row[0]), abs(row[6]), row[4] * row[4] + row[5] * row[5], 0.2, 0.4, 3.5)
        assert _bits_equal(k._reward_arguments(*args), task.reward_arguments(*args)), args
        assert k._off_path(abs(row[0]), 2.0) == task.off_path(abs(row[0]), 2.0)
