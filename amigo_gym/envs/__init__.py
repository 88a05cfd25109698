"""The AmigoBot environments: :class:`AmigoBotEnv` (one robot) and :class:`AmigoBotVectorEnv` (N robots).

Each task version is a pair of classes that hold only its task's hooks, over one base each
(:mod:`amigo_gym.envs.base`, the Gymnasium machinery written once): ``AmigoBot-v0`` (:class:`AmigoBotEnv`,
:class:`AmigoBotVectorEnv`) and ``AmigoBot-v1`` (:class:`AmigoBotV1Env`, :class:`AmigoBotV1VectorEnv`).
Both are registered by ``import amigo_gym``::

    env = gym.make("AmigoBot-v0")
    envs = gym.make_vec("AmigoBot-v0", num_envs=64)  # native numpy-batched AmigoBotVectorEnv
"""

from __future__ import annotations

from amigo_gym.envs.amigobot import AmigoBotEnv, make_env_params
from amigo_gym.envs.amigobot_v1 import AmigoBotV1Env
from amigo_gym.envs.vector import AmigoBotVectorEnv
from amigo_gym.envs.vector_v1 import AmigoBotV1VectorEnv

__all__ = ["AmigoBotEnv", "AmigoBotV1Env", "AmigoBotV1VectorEnv", "AmigoBotVectorEnv", "make_env_params"]
