"""SB3 ``VecEnv`` over the native vector env (``SAME_STEP`` autoreset): the rollouts of ``DummyVecEnv``.

``reset()`` uses the pending seeds (sub-env ``i``: ``seed + i``) and options once; ``step`` gives ``dones =
terminated | truncated``, float32 rewards, one info dict per env with ``terminal_observation`` and
``TimeLimit.truncated`` on a reset in the same step (the reset's info in ``reset_infos[i]``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from amigo_gym import MAX_EPISODE_STEPS, MAX_EPISODE_STEPS_V1
from amigo_gym.envs.amigobot import AmigoBotVectorEnv
from amigo_gym.envs.base import info_row
from amigo_gym.envs.vector_v1 import AmigoBotV1VectorEnv

VECTOR_ENVS: dict[str, Any] = {"AmigoBot-v0": AmigoBotVectorEnv, "AmigoBot-v1": AmigoBotV1VectorEnv}


class AmigoBotSB3VecEnv(VecEnv):
    """``num_envs`` robots of ``env_id`` (AmigoBot-v0 or -v1: then ``max_episode_steps`` defaults to 600);
    ``settings``: keywords of ``gym.make(env_id, ...)``."""

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = MAX_EPISODE_STEPS,
        render_mode: str | None = None,
        env_id: str = "AmigoBot-v0",
        **settings: Any,
    ) -> None:
        if env_id not in VECTOR_ENVS:
            raise ValueError(f"env_id must be one of {sorted(VECTOR_ENVS)}, got {env_id!r}")
        self.env_id = env_id
        if max_episode_steps == MAX_EPISODE_STEPS and env_id == "AmigoBot-v1":
            max_episode_steps = MAX_EPISODE_STEPS_V1
        self.venv: Any = VECTOR_ENVS[env_id](
            num_envs=num_envs,
            max_episode_steps=max_episode_steps,
            render_mode=render_mode,
            autoreset_mode=AutoresetMode.SAME_STEP,
            **settings,
        )
        self.render_mode = render_mode
        super().__init__(self.venv.num_envs, self.venv.single_observation_space, self.venv.single_action_space)
        self.params = self.venv.params
        self._actions: NDArray[Any] | None = None

    def reset(self) -> VecEnvObs:
        seeds = list(self._seeds)
        options: dict[str, Any] | None = None
        if any(self._options):
            if not all(self._options) or any(set(o) != {"pose"} for o in self._options):
                raise ValueError('options: only {"pose": (x_A, y_A, beta)} for every env is supported')
            options = {"pose": np.stack([np.asarray(o["pose"], dtype=np.float64) for o in self._options])}
        obs, infos = self.venv.reset(seed=None if all(s is None for s in seeds) else seeds, options=options)
        self.reset_infos = [info_row(infos, i) for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        out: NDArray[Any] = obs
        return out

    def step_async(self, actions: NDArray[Any]) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        if self._actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        obs, rewards, terminated, truncated, vinfo = self.venv.step(self._actions)
        self._actions = None
        dones = terminated | truncated
        infos = [info_row(vinfo, i) for i in range(self.num_envs)]
        for j in np.flatnonzero(dones).tolist():
            self.reset_infos[j] = infos[j]
            infos[j] = info_row(vinfo["final_info"], j) | {"terminal_observation": vinfo["final_obs"][j]}
        for i in range(self.num_envs):
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    def get_images(self) -> Sequence[NDArray[Any] | None]:
        frames = self.venv.render()
        return [None] * self.num_envs if frames is None else list(frames)

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        if sorted(self._get_indices(indices)) != list(range(self.num_envs)):
            raise ValueError("set_attr: the robots share one native env; set attributes for all indices")
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **kw: Any) -> list[Any]:
        result = getattr(self.venv, method_name)(*method_args, **kw)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]
