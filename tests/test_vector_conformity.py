"""The native vector env behaves as Gymnasium's ``SyncVectorEnv`` where users and wrappers rely on it.

Each case runs both on the same inputs and compares what happens: the value, or the exception's
type and message. Gymnasium's behaviour is the reference, not a copy of ours.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)

N = 3


def both() -> tuple[Any, Any]:
    sync = gym.make_vec("AmigoBot-v0", num_envs=N, vectorization_mode="sync")
    native = gym.make_vec("AmigoBot-v0", num_envs=N, vectorization_mode="vector_entry_point")
    assert type(native.unwrapped).__name__ == "AmigoBotVectorEnv"
    return sync, native


def outcome(fn: Callable[[], Any]) -> tuple[str, str]:
    try:
        fn()
    except Exception as exc:
        return type(exc).__name__, str(exc)
    return "ok", ""


def test_np_random_seed_before_the_first_reset() -> None:
    sync, native = both()
    for envs in (sync, native):
        seeds = envs.np_random_seed
        assert isinstance(seeds, tuple) and len(seeds) == N
        assert all(isinstance(s, int) and s >= 0 for s in seeds), seeds
        assert len(set(seeds)) == N  # drawn at random, one per sub-env
        assert envs.np_random_seed == seeds  # drawn once
    # the reported seed is the one a reset without a seed then uses: reseeding with it repeats the start
    for envs in (sync, native):
        seeds = list(envs.np_random_seed)
        obs_random, _ = envs.reset()
        obs_seeded, _ = envs.reset(seed=seeds)
        np.testing.assert_array_equal(obs_random, obs_seeded)
    assert sync.reset(seed=5)[0].tolist() == native.reset(seed=5)[0].tolist()
    assert sync.np_random_seed == native.np_random_seed == (5, 6, 7)


@pytest.mark.parametrize(
    "mask",
    [
        [True, False, True],
        np.array([1, 0, 1]),
        np.array([1.0, 0.0, 1.0]),
        np.array([True, False]),
        np.array([[True, False, True]]),
        np.zeros(N, dtype=bool),
        "TFT",
        None,
    ],
    ids=["list", "int", "float", "short", "2d", "all-false", "str", "none"],
)
def test_bad_reset_mask_raises_as_sync(mask: Any) -> None:
    sync, native = both()
    sync.reset(seed=0)
    native.reset(seed=0)
    want = outcome(lambda: sync.reset(options={"reset_mask": mask}))
    got = outcome(lambda: native.reset(options={"reset_mask": mask}))
    assert want[0] != "ok"
    assert got == want


@pytest.mark.parametrize(
    "action",
    [0.5, np.float32(0.5), np.array(0.5), 3, None, True],
    ids=["float", "np-scalar", "0d-array", "int", "none", "bool"],
)
def test_scalar_action_raises_as_sync(action: Any) -> None:
    sync, native = both()
    sync.reset(seed=0)
    native.reset(seed=0)
    want = outcome(lambda: sync.step(action))
    got = outcome(lambda: native.step(action))
    assert want[0] == "TypeError", want
    assert got[0] == want[0]
    assert got[1].startswith(want[1]), (got, want)  # Sync's message, then what the actions must be


@pytest.mark.parametrize(
    "action",
    [np.zeros((N + 1, 2)), np.zeros((N, 3)), np.zeros(2), np.full((N, 2), np.nan)],
    ids=["rows", "cols", "1d", "nan"],
)
def test_bad_action_exception_type_as_sync(action: Any) -> None:
    sync, native = both()
    sync.reset(seed=0)
    native.reset(seed=0)
    assert outcome(lambda: native.step(action))[0] == outcome(lambda: sync.step(action))[0] == "ValueError"


def test_string_actions_are_a_type_error() -> None:
    """Sync fails inside each env's float conversion (ValueError); the native env refuses strings up front as a
    type error in one line (tests/test_bad_inputs.py): a deliberate difference."""
    _, native = both()
    native.reset(seed=0)
    assert outcome(lambda: native.step([["a", "b"]] * N))[0] == "TypeError"


def test_list_actions_accepted_as_sync() -> None:
    sync, native = both()
    a = [[0.3, 0.2]] * N
    sync.reset(seed=1)
    native.reset(seed=1)
    s, n = sync.step(a), native.step(a)
    np.testing.assert_array_equal(s[0], n[0])
    np.testing.assert_array_equal(s[1], n[1])
