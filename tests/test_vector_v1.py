"""The native AmigoBot-v1 vector env: partial resets as Gymnasium's SyncVectorEnv of single envs (the reference,
``kernel="numpy"``, within the golden tolerance; tests/test_vector_v1_kernel.py compares whole runs), heterogeneous
batches, bad actions, pickling."""

from __future__ import annotations

import pickle
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import amigo_gym  # noqa: F401
from amigo_gym.envs import AmigoBotV1VectorEnv

INFO_KEYS = ("pose", "h_position", "cross_track_error", "progress", "speed", "speed_error", "wheel_rates", "command")
INFO_KEYS += ("measured_pose", "slip", "time", "delay")


def _pair(n: int, mode: AutoresetMode, **kw: Any) -> tuple[gym.vector.VectorEnv, gym.vector.VectorEnv]:
    steps = kw.pop("max_episode_steps", None)
    extra = {} if steps is None else {"max_episode_steps": steps}
    native = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", autoreset_mode=mode, **extra, **kw)
    sync = gym.make_vec(  # the reference: single envs on the Python float path
        "AmigoBot-v1",
        n,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": mode},
        **extra,
        **{**kw, "kernel": "numpy"},
    )
    assert isinstance(native.unwrapped, AmigoBotV1VectorEnv)
    return native, sync


def _same(a: Any, b: Any, what: str) -> None:
    """Equal shapes and dtypes; floats within the tolerance of their scale, the rest equal."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype, what
    if a.dtype.kind != "f":
        assert np.array_equal(a, b), what
        return
    rtol = 2.5e-7 if a.dtype == np.float32 else 1e-9
    scale = max(1.0, float(np.max(np.abs(b), initial=0.0)))
    np.testing.assert_allclose(a, b, rtol=0.0, atol=rtol * scale, err_msg=what)


def test_disabled_mode_and_reset_mask_equal_sync() -> None:
    n = 4
    native, sync = _pair(n, AutoresetMode.DISABLED, path="mixed", randomize="mild", max_episode_steps=20)
    _same(native.reset(seed=3)[0], sync.reset(seed=3)[0], "reset")
    for t in range(60):
        a = np.full((n, 2), 0.4)
        r1, r2 = native.step(a), sync.step(a)
        _same(r1[0], r2[0], f"obs {t}")
        done = r1[2] | r1[3]
        if done.any():
            o1, _ = native.reset(options={"reset_mask": done})
            o2, _ = sync.reset(options={"reset_mask": done})
            _same(o1, o2, "partial reset")


def test_heterogeneous_batch_holds_several_families() -> None:
    envs = gym.make_vec("AmigoBot-v1", 16, vectorization_mode="vector_entry_point", path="mixed")
    envs.reset(seed=0)
    fams = {d["family"] for d in envs.unwrapped.path_infos}  # type: ignore[attr-defined]
    assert len(fams) >= 3


def test_bad_actions_and_order() -> None:
    envs = AmigoBotV1VectorEnv(num_envs=3)
    with pytest.raises(gym.error.ResetNeeded):
        envs.step(np.zeros((3, 2)))
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        envs.step(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="finite"):
        envs.step(np.full((3, 2), np.nan))
    with pytest.raises(TypeError):
        envs.step(np.full((3, 2), "a"))


def test_pickle_after_render() -> None:
    envs = AmigoBotV1VectorEnv(num_envs=2, render_mode="rgb_array")
    envs.reset(seed=0)
    envs.step(np.zeros((2, 2)))
    frames = envs.render()
    assert frames is not None and frames[0].shape[2] == 3
    clone = pickle.loads(pickle.dumps(envs))
    a = np.full((2, 2), 0.3)
    assert np.array_equal(clone.step(a)[0], envs.step(a)[0]), "clone steps like the original"
