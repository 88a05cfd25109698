"""The compiled steps called without numba's dispatch (amigo_gym.sim.fast.direct_call, issue 19 item 5).

The entries are compiled for one set of argument types; these tests hold the callers to what they promise: the same
bits as numba's dispatcher (which finds the types at each call), actions of any layout and dtype made C-contiguous
float64 before an entry reads them, and environments that still pickle (an entry is not picklable).
"""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.model.params import EnvParams
from amigo_gym.paths import make_path
from amigo_gym.sim import fast, numpy_loops
from amigo_gym.task import v0 as task

pytest.importorskip("numba")


def _workspace(n: int) -> tuple[fast.Workspace, np.ndarray]:
    params = EnvParams()
    ws = fast.workspace(task.task_constants(params), make_path(params), n)
    g = np.random.default_rng(3)
    rows = np.column_stack((g.normal(0.0, 0.05, n), g.normal(0.0, 0.05, n), g.normal(0.0, 0.1, n), np.zeros((n, 3)),
                            np.full(n, 4.0), np.full(n, 4.0)))  # fmt: skip
    return ws, np.ascontiguousarray(rows)


def test_direct_call_is_not_the_dispatcher_and_gives_its_bits() -> None:
    k = fast.kernels()
    ws, rows = _workspace(5)
    a = np.random.default_rng(4).uniform(-1.2, 1.2, (5, 2))
    no = np.zeros(5, dtype=np.bool_)
    entry = fast.direct_call(k.move_arguments, ws.consts, rows, a, no, ws.tans, ws.turn)
    assert entry is not k.move_arguments and not hasattr(entry, "py_func")
    tans_d, turn_d = np.zeros_like(ws.tans), np.zeros_like(ws.turn)
    k.move_arguments(ws.consts, rows, a, no, tans_d, turn_d)
    entry(ws.consts, rows, a, no, ws.tans, ws.turn)
    assert ws.tans.tobytes() == tans_d.tobytes() and ws.turn.tobytes() == turn_d.tobytes()


@pytest.mark.parametrize("layout", ["C", "F", "strided", "float32"])
def test_step_env_rows_takes_actions_of_any_layout(layout: str) -> None:
    """The entries assume C-contiguous float64 actions: step_env_rows makes them so (a Fortran-ordered array, a
    strided view or float32 values give the bits of the C-contiguous float64 copy)."""
    n = 7
    a = np.random.default_rng(5).uniform(-1.0, 1.0, (n, 2)).astype(np.float32).astype(np.float64)
    given = {
        "C": a,
        "F": np.asfortranarray(a),
        "strided": np.repeat(a, 2, axis=1)[:, ::2],
        "float32": a.astype(np.float32),
    }[layout]
    outs = []
    for actions in (a, given):
        ws, rows = _workspace(n)
        steps = np.zeros(n, dtype=np.int64)
        r = fast.step_env_rows(ws, rows, actions, np.zeros(n, dtype=np.bool_), None, False, steps, None, 400, 0.1)
        outs.append((rows.tobytes(), r.obs.tobytes(), r.reward.tobytes(), r.terminated.tobytes(), r.infos["time"]))
    assert outs[0][:4] == outs[1][:4]
    np.testing.assert_array_equal(outs[0][4], outs[1][4])


@pytest.mark.parametrize("env_id", ["AmigoBot-v0", "AmigoBot-v1"])
def test_single_envs_pickle_and_step_alike_after(env_id: str) -> None:
    env = gym.make(env_id).unwrapped
    env.reset(seed=1)
    a = np.array([0.4, 0.3], dtype=np.float32)
    env.step(a)
    twin = pickle.loads(pickle.dumps(env))
    for _ in range(5):
        o1, r1, t1, _, i1 = env.step(a)
        o2, r2, t2, _, i2 = twin.step(a)
        assert o1.tobytes() == o2.tobytes() and r1 == r2 and t1 == t2
        assert i1["h_position"].tobytes() == i2["h_position"].tobytes()


@pytest.mark.parametrize(
    "settings",
    [{}, {"direction": -1, "radius": 0.5, "dt": 0.05}, {"path": "manoeuvre", "dt": 0.3}, {"preview": (), "dt": 1.5}],
)
def test_single_step_in_one_call_gives_the_three_passes_bits(settings: dict[str, object]) -> None:
    """The single step in one call (kernels.single_step: numpy's own tan loop inside, sim/numpy_loops.py, found on
    CPython) against the three passes with numpy's tan between them, on one machine (two code paths): random states,
    actions beyond [-1, 1] too, 300 steps each."""
    params = EnvParams(**settings)  # type: ignore[arg-type]
    assert numpy_loops.numpy_loops() is not None  # CPython's numpy: the loops are found and give numpy's bits
    whole = fast.SingleStep(task.task_constants(params), make_path(params))
    assert whole._whole is not None and whole._loops is not None
    passes = fast.SingleStep(task.task_constants(params), make_path(params))
    passes._whole = passes._loops = None
    _same_steps(whole, passes)


def _same_steps(whole: fast.SingleStep, passes: fast.SingleStep) -> None:
    g = np.random.default_rng(11)
    for _ in range(20):
        state = np.concatenate((g.normal(0.0, 0.5, 2), g.uniform(-50.0, 50.0, 1), g.normal(0.0, 30.0, 3),
                                g.uniform(-15.0, 15.0, 2)))  # fmt: skip
        whole.set_state(state)
        passes.set_state(state)
        for a1, a2 in g.uniform(-1.3, 1.3, (15, 2)).tolist():
            assert whole.step(a1, a2) == passes.step(a1, a2)
            assert whole.buf.tobytes() == passes.buf.tobytes() and whole.obs.tobytes() == passes.obs.tobytes()
            assert whole.past_limit == passes.past_limit


def test_without_numpys_loops_the_single_env_runs_the_passes(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fast, "numpy_loops", lambda: None)  # numpy's loops not found
    env = gym.make("AmigoBot-v0").unwrapped
    assert env._v0._whole is None and env._v0._loops is None
    ref = gym.make("AmigoBot-v0", kernel="numpy").unwrapped
    env.reset(seed=2)
    ref.reset(seed=2)
    for a in np.random.default_rng(6).uniform(-1.0, 1.0, (30, 2)):
        o1, r1, t1, _, _ = env.step(a)
        o2, r2, t2, _, _ = ref.step(a)
        assert o1.tobytes() == o2.tobytes() and r1 == r2 and t1 == t2


@pytest.mark.parametrize("settings", [{}, {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"}])
def test_v1_reward_exponentials_in_the_step_give_the_references_bits(settings: dict[str, object]) -> None:
    """AmigoBot-v1's single step with the reward's exponentials, smoothness term and reward in the compiled call
    (kernels_v1.step_record: kinematics.col_exp compiled) against the reference (kernel="numpy"), same seeds: the
    same bits, resets included."""
    envs = [
        gym.make("AmigoBot-v1", **settings).unwrapped,
        gym.make("AmigoBot-v1", kernel="numpy", **settings).unwrapped,
    ]
    assert envs[0]._kernel is not None and envs[1]._kernel is None
    infos = [e.reset(seed=8)[1] for e in envs]
    assert _same_info(*infos)
    for a in np.random.default_rng(9).uniform(-1.0, 1.0, (200, 2)):
        out = [e.step(a) for e in envs]
        (o1, r1, t1, _, i1), (o2, r2, t2, _, i2) = out
        assert o1.tobytes() == o2.tobytes() and r1 == r2 and t1 == t2
        assert _same_info(i1, i2)
        if t1:
            for e in envs:
                e.reset()


def _same_info(a: dict[str, object], b: dict[str, object]) -> bool:
    """The same keys, arrays of the same bits, the same other values."""
    if a.keys() != b.keys():
        return False
    for k, va in a.items():
        vb = b[k]
        if isinstance(va, np.ndarray):
            if not (isinstance(vb, np.ndarray) and va.dtype == vb.dtype and va.tobytes() == vb.tobytes()):
                return False
        elif va != vb:
            return False
    return True


def _same_tree(a: object, b: object) -> bool:
    """:func:`_same_info` of nested dicts (vector infos): the same keys, arrays of the same dtype and bits (object
    arrays compared by value), the same other values."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same_tree(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        if not (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape):
            return False
        return bool(np.array_equal(a, b)) if a.dtype == object else a.tobytes() == b.tobytes()
    return bool(a == b)


def test_v1_vector_infos_are_new_memory_at_every_step() -> None:
    """The vector infos' arrays are views of a record made for the step: nothing of one step's infos is shared with
    the next step's or with the env's state, so writing into them changes nothing the env does."""
    n = 4
    env = gym.make_vec("AmigoBot-v1", num_envs=n, vectorization_mode="vector_entry_point")
    ref = gym.make_vec("AmigoBot-v1", num_envs=n, vectorization_mode="vector_entry_point")
    env.reset(seed=3)
    ref.reset(seed=3)
    a = np.full((n, 2), 0.3)
    _, reward, _, _, first = env.step(a)
    ref.step(a)
    arrays = [v for v in first.values() if isinstance(v, np.ndarray) and v.dtype != np.bool_ and v.dtype != object]
    arrays += [v for d in (first["reward_terms"], first["true_robot"]) for v in d.values()]
    assert len(arrays) >= 20
    for v in arrays:
        assert not np.shares_memory(v, env.unwrapped._batch.ws) and not np.shares_memory(v, reward)
        v[...] = np.nan  # a user's scribbles
    reward[...] = np.nan
    _, r2, _, _, second = env.step(a)
    _, r_ref, _, _, second_ref = ref.step(a)
    assert r2.tobytes() == r_ref.tobytes() and _same_tree(second, second_ref)
    assert not any(np.shares_memory(v, w) for v in arrays for w in (second["pose"], second["reward_terms"]["track"]))
