"""Start states drawn inside the compiled step (amigo_gym.sim.fast.step_rows with a GeneratorTable's bitgens).

The reference is the Python loop the vector env runs without them (and the single env's reset): per
restarting robot, AmigoBot-v1's start with v0's settings (:func:`amigo_gym.task.v1.start_episode` of
:func:`amigo_gym.task.v1.v0_configuration`) from its own generator. The compiled draws must give the same start
states bit for bit and leave every generator in the same state (compared as ``bit_generator.state`` dicts and by
the numbers drawn next), with masks, partial resets, reseeding, generators drawn from outside, non-PCG64
generators, pickling and deep copies (a copy computes its own generators' addresses and never touches the original's).
"""

from __future__ import annotations

import copy
import pickle
from typing import Any

import numpy as np
import pytest
from gymnasium.utils import seeding
from numpy.typing import NDArray

from amigo_gym.model.params import EnvParams
from amigo_gym.paths import make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking

pytest.importorskip("numba")

Array = NDArray[np.float64]


def _same_state(a: Any, b: Any, where: str) -> None:
    """Equal ``bit_generator.state`` dicts (MT19937's holds an array)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            _same_state(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, np.ndarray):
        np.testing.assert_array_equal(a, b, err_msg=where)
    else:
        assert a == b, where


def _same_generators(a: Any, b: Any) -> None:
    """Same bit generator states, and the same numbers drawn next (from copies: the originals stay)."""
    assert len(a) == len(b)
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        assert (x is None) == (y is None), i
        if x is None:
            continue
        _same_state(x.bit_generator.state, y.bit_generator.state, str(i))
        np.testing.assert_array_equal(copy.deepcopy(x).random(5), copy.deepcopy(y).random(5))


def _reference_starts(params: EnvParams, gens: list[np.random.Generator], idx: NDArray[np.intp], rows: Array) -> Array:
    """The vector env's Python loop: :func:`amigo_gym.task.v1.start_episode` per robot, from its generator."""
    k = tracking.constants(tracking.v0_configuration(params))
    out = rows.copy()
    for i in idx.tolist():
        st = tracking.start_episode(gens[i], k)[3]
        out[i] = (st.x, st.y, st.beta, st.alpha1, st.alpha2, 0.0, st.w1, st.w2)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 17, 123456789])
@pytest.mark.parametrize("path", ["circle", "manoeuvre"])
def test_kernel_draws_equal_the_python_loop(seed: int, path: str) -> None:
    params = EnvParams(path=path, init_position_noise=0.05, init_heading_noise=0.7)
    n = 300
    g = np.random.default_rng(seed)
    restart = g.random(n) < 0.3
    restart[:3] = True  # neighbours and the first row
    ref_gens = [seeding.np_random(seed * 1000 + i)[0] for i in range(n)]
    for x in ref_gens[::7]:  # generators part-way through their streams
        x.random(int(g.integers(1, 9)))
    table = fast.GeneratorTable(copy.deepcopy(ref_gens))
    assert table.drawable
    state = np.ascontiguousarray(g.normal(size=(n, 8)))
    actions = np.ascontiguousarray(g.uniform(-1, 1, (n, 2)))
    ws = fast.workspace(task.task_constants(params), make_path(params), n)
    out = (np.empty((n, ws.obs_dim), np.float32), np.empty(n), np.empty(n, np.bool_), np.empty((n, 16)))
    st = state.copy()
    fast.step_rows(ws, st, actions, restart, *out, bitgens=table.bitgens)

    # the reference: the Python loop's start states, then the same step with the caller's start states
    idx = np.flatnonzero(restart)
    ref_state = _reference_starts(params, ref_gens, idx, state)
    np.testing.assert_array_equal(st[restart], ref_state[restart])  # restart rows do not move
    ref_out = (np.empty((n, ws.obs_dim), np.float32), np.empty(n), np.empty(n, np.bool_), np.empty((n, 16)))
    ref_st = ref_state.copy()
    fast.step_rows(ws, ref_st, actions, restart, *ref_out)
    np.testing.assert_array_equal(st, ref_st)
    for x, y in zip(out, ref_out, strict=True):
        np.testing.assert_array_equal(x, y)
    _same_generators(list(table), ref_gens)

    # a second round with other rows: the streams go on from where they are
    again = g.random(n) < 0.5
    st2 = st.copy()
    fast.step_rows(ws, st2, actions, again, *out, bitgens=table.bitgens)
    ref2 = _reference_starts(params, ref_gens, np.flatnonzero(again), st)
    np.testing.assert_array_equal(st2[again], ref2[again])
    _same_generators(list(table), ref_gens)


def test_generator_table_addresses_and_refusals() -> None:
    gens = [seeding.np_random(i)[0] for i in range(4)]
    table = fast.GeneratorTable([None, *gens[1:]])
    assert not table.drawable and table.bitgens[0] == 0 and table[0] is None
    table[0] = gens[0]
    assert table.drawable and list(table) == gens and len(table) == 4
    assert len(set(table.bitgens.tolist())) == 4 and 0 not in table.bitgens.tolist()
    table[2] = np.random.Generator(np.random.MT19937(3))  # not PCG64: the Python loop draws
    assert not table.drawable and table.bitgens[2] == 0
    table[2] = gens[2]
    assert table.drawable
    table[1] = None
    assert not table.drawable
    # a zero address for a restarting row is refused (nothing is drawn from the others after it)
    params = EnvParams()
    ws = fast.workspace(task.task_constants(params), make_path(params), 4)
    out = (np.empty((4, ws.obs_dim), np.float32), np.empty(4), np.empty(4, np.bool_), np.empty((4, 16)))
    restart = np.array([False, True, False, False])
    with pytest.raises(ValueError, match="address 0"):
        fast.step_rows(ws, np.zeros((4, 8)), np.zeros((4, 2)), restart, *out, bitgens=table.bitgens)
    with pytest.raises(ValueError, match="bitgens must be"):
        fast.step_rows(ws, np.zeros((4, 8)), np.zeros((4, 2)), restart, *out, bitgens=np.zeros(4, np.int64))


def _pair(mode: str = "NextStep", n: int = 24, **kw: Any) -> tuple[Any, Any]:
    """A kernel env that draws in the kernel and the numpy env (the Python loop), same settings."""
    from amigo_gym.envs import AmigoBotVectorEnv

    args: dict[str, Any] = {"num_envs": n, "max_episode_steps": 9, "autoreset_mode": mode, **kw}
    return AmigoBotVectorEnv(kernel="numba", **args), AmigoBotVectorEnv(kernel="numpy", **args)


def _same_step(a: tuple[Any, ...], b: tuple[Any, ...], where: str) -> None:
    for x, y in zip(a[:4], b[:4], strict=True):
        np.testing.assert_array_equal(x, y, err_msg=where)
    np.testing.assert_array_equal(a[4]["pose"], b[4]["pose"], err_msg=where)


def _actions(g: np.random.Generator, n: int) -> Array:
    return np.clip(0.3 + 0.8 * g.normal(size=(n, 2)), -1.0, 1.0)


def test_env_with_partial_resets_reseeding_and_outside_draws() -> None:
    fast_env, ref = _pair("Disabled", path="manoeuvre")
    n = fast_env.num_envs
    g = np.random.default_rng(5)
    for e in (fast_env, ref):
        e.reset(seed=11)
    assert fast_env._rngs.drawable
    for t in range(60):
        if ref._autoreset.any():
            mask = ref._autoreset.copy()
            seeds: list[int | None] = [None] * n
            if t % 3 == 0:  # reseed some of the robots being reset
                for i in np.flatnonzero(mask)[::2].tolist():
                    seeds[i] = 1000 + t + i
            outs = [e.reset(seed=seeds, options={"reset_mask": mask}) for e in (fast_env, ref)]
            np.testing.assert_array_equal(outs[0][0], outs[1][0])
        if t == 20:  # the generators handed out are the live ones: drawing from them moves the env's streams
            for e in (fast_env, ref):
                e.np_randoms[3].random(2)
        a = _actions(g, n)
        _same_step(fast_env.step(a), ref.step(a), f"step {t}")
        _same_generators(fast_env.np_randoms, ref.np_randoms)
    for i, x in enumerate(fast_env.np_randoms):
        assert x is fast_env._rngs[i]


def test_env_next_step_restarts_in_the_kernel() -> None:
    fast_env, ref = _pair(n=64)
    g = np.random.default_rng(2)
    for e in (fast_env, ref):
        e.reset(seed=[40 + i for i in range(64)])
    restarted = 0
    for t in range(50):
        a = _actions(g, 64)
        restarted += int(ref._autoreset.sum())
        _same_step(fast_env.step(a), ref.step(a), f"step {t}")
        _same_generators(fast_env.np_randoms, ref.np_randoms)
        if t == 10:  # a later reset reseeding some robots (None: the generator goes on)
            outs = [e.reset(seed=[None if i % 5 == 0 else 7 * i for i in range(64)]) for e in (fast_env, ref)]
            np.testing.assert_array_equal(outs[0][0], outs[1][0])
    assert restarted > 100


def test_env_falls_back_to_the_python_loop_for_other_bit_generators() -> None:
    fast_env, ref = _pair()
    for e in (fast_env, ref):
        e.reset(seed=1)
        e._rngs[4] = np.random.Generator(np.random.MT19937(9))
    assert not fast_env._rngs.drawable
    g = np.random.default_rng(0)
    for t in range(30):
        a = _actions(g, fast_env.num_envs)
        _same_step(fast_env.step(a), ref.step(a), f"step {t}")
        _same_generators(fast_env.np_randoms, ref.np_randoms)


@pytest.mark.parametrize("clone", ["pickle", "deepcopy"])
def test_copies_draw_from_their_own_generators(clone: str) -> None:
    env, _ = _pair(n=32)
    env.reset(seed=8)
    g = np.random.default_rng(1)
    for _ in range(12):
        env.step(_actions(g, 32))
    twin = pickle.loads(pickle.dumps(env)) if clone == "pickle" else copy.deepcopy(env)
    other = copy.deepcopy(env)
    # new addresses: those of the copy's own generators, none of the original's
    assert twin._rngs.drawable
    mine = set(env._rngs.bitgens.tolist())
    assert not mine & set(twin._rngs.bitgens.tolist())
    for i, x in enumerate(twin.np_randoms):
        assert x is not env.np_randoms[i]
        assert twin._rngs.bitgens[i] == fast._bitgen_address(x)
    before = [x.bit_generator.state for x in env.np_randoms]
    frozen = env._rows.copy()
    actions = [_actions(g, 32) for _ in range(30)]
    twin_steps = []
    for t, a in enumerate(actions):
        twin_steps.append(twin.step(a))
        _same_step(twin_steps[-1], other.step(a), f"step {t}")
    assert [x.bit_generator.state for x in env.np_randoms] == before  # the original's generators untouched
    np.testing.assert_array_equal(env._rows, frozen)
    _same_generators(twin.np_randoms, other.np_randoms)
    # and the original goes on exactly as its copies did
    for t, a in enumerate(actions):
        _same_step(env.step(a), twin_steps[t], f"original {t}")
    _same_generators(env.np_randoms, twin.np_randoms)


@pytest.mark.parametrize("parallel", [False, True])
def test_step_report_counts_headings_past_the_limit(parallel: bool) -> None:
    """step_rows reports the rows task.bound_angle would change (|beta| > HEADING_LIMIT; NaN is not)."""
    from amigo_gym.model.params import HEADING_LIMIT

    params = EnvParams()
    n = 64
    state = np.zeros((n, 8))
    state[:, 2] = np.linspace(-3.0, 3.0, n)
    state[[3, 10, 50], 2] = [HEADING_LIMIT + 5.0, -HEADING_LIMIT - 5.0, np.nan]
    state[11, 2] = HEADING_LIMIT  # at the limit: kept
    actions = np.zeros((n, 2))  # a zero action keeps the heading
    ws = fast.workspace(task.task_constants(params), make_path(params), n)
    out = (np.empty((n, ws.obs_dim), np.float32), np.empty(n), np.empty(n, np.bool_), np.empty((n, 16)))
    report = fast.step_rows(ws, state, actions, np.zeros(n, np.bool_), *out, parallel=parallel)
    assert report == fast.StepReport(drawn=0, past_limit=2)
    changed = task.bound_angle(state[:, 2].copy()) != state[:, 2]
    assert int(np.sum(changed & ~np.isnan(state[:, 2]))) == 2


def test_generator_table_addresses_are_read_only() -> None:
    table = fast.GeneratorTable([seeding.np_random(1)[0]])
    with pytest.raises(ValueError, match="read-only"):
        table.bitgens[0] = 1
