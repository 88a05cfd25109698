"""Adapter from the native Gymnasium vector env (:class:`amigo_gym.envs.AmigoBotVectorEnv`) to SB3's ``VecEnv``.

SB3's API over Gymnasium's ``SAME_STEP`` autoreset: ``reset()`` uses the seeds / options of :meth:`VecEnv.seed` /
:meth:`VecEnv.set_options` once (sub-env ``i`` gets ``seed + i``); ``step`` returns ``(obs, rewards, dones, infos)``
with ``dones = terminated | truncated``, float32 rewards and one info dict per env with the single env's keys and
types; a finished sub-env is reset in the same step, its last observation in ``infos[i]["terminal_observation"]``,
``infos[i]["TimeLimit.truncated"] = truncated and not terminated``, the reset's info in ``reset_infos[i]``. Rollouts
equal ``DummyVecEnv([lambda: gym.make(env_id)] * N)``'s (docs/baselines.md).
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

#: the native vector env of each id (the registrations' ``vector_entry_point``)
VECTOR_ENVS: dict[str, Any] = {"AmigoBot-v0": AmigoBotVectorEnv, "AmigoBot-v1": AmigoBotV1VectorEnv}


class AmigoBotSB3VecEnv(VecEnv):
    """SB3 ``VecEnv`` over one native :class:`AmigoBotVectorEnv` of ``num_envs`` robots.

    Args:
        num_envs: number of robots (>= 1).
        max_episode_steps: truncation after this many steps (default 400, the registration's).
        render_mode: ``None`` or ``"rgb_array"``.
        env_id: ``"AmigoBot-v0"`` (default) or ``"AmigoBot-v1"`` (then ``max_episode_steps`` defaults to 600).
        **settings: task settings, as keywords of ``gym.make(env_id, ...)`` (``dt``, ``radius``,
            ``kernel`` (both ids): ``"auto"`` by default, the compiled step when numba is installed,
            ``params``, ``robot``, ...).
    """

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
        """Reset every robot with the pending seeds/options (used once, as in ``DummyVecEnv``)."""
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

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        if self._actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        obs, rewards, terminated, truncated, vinfo = self.venv.step(self._actions)
        self._actions = None
        dones = terminated | truncated
        infos = [info_row(vinfo, i) for i in range(self.num_envs)]
        for j in np.flatnonzero(dones).tolist():  # reset in this step: the finished episode's info and observation
            self.reset_infos[j] = infos[j]
            infos[j] = info_row(vinfo["final_info"], j) | {"terminal_observation": vinfo["final_obs"][j]}
        for i in range(self.num_envs):
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return [None] * self.num_envs if frames is None else list(frames)

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The native env's attribute (``params``, ``path``, ``render_mode``, ...), once per index."""
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute of the native env (shared by every robot: all indices must be selected)."""
        if sorted(self._get_indices(indices)) != list(range(self.num_envs)):
            raise ValueError("set_attr: the robots share one native env; set attributes for all indices")
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None, **kw: Any) -> list[Any]:
        """Call a method of the native env once and return its result for each index."""
        result = getattr(self.venv, method_name)(*method_args, **kw)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper], indices: VecEnvIndices = None) -> list[bool]:
        """The robots are not wrapped in Gymnasium wrappers (use ``VecMonitor`` for episode statistics)."""
        return [False for _ in self._get_indices(indices)]
