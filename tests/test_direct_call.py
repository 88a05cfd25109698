"""The compiled step called without numba's dispatch (:func:`amigo_gym.sim.fast_v1.direct_call`), on one route:
the same bits as numba's dispatcher, environments that still pickle (an entry is not picklable) and step as before,
and infos that share no memory with the env.
"""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.sim import fast_v1

pytest.importorskip("numba")


def test_direct_call_is_not_the_dispatcher_and_gives_its_bits() -> None:
    env = gym.make("AmigoBot-v1").unwrapped
    env.reset(seed=3)
    kern = env._kernel
    kv = fast_v1.kernels()
    entry = fast_v1.direct_call(kv.step_record, 1, 0.3, 0.2, *kern.args)
    assert entry is not kv.step_record
    ws, ring = kern.ws.copy(), kern.ring.copy()
    entry(1, 0.3, 0.2, *kern.args)
    got = (kern.obs.copy(), kern.record.copy())
    kern.ws[:], kern.ring[:] = ws, ring
    kv.step_record(1, 0.3, 0.2, *kern.args)
    np.testing.assert_array_equal(got[0], kern.obs)
    np.testing.assert_array_equal(got[1], kern.record)


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
