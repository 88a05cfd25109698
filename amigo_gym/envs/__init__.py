"""The AmigoBot environments: :class:`AmigoBotEnv` (one robot) and :class:`AmigoBotVectorEnv` (N robots).

One single env class and one vector env class (their shared checks: :mod:`amigo_gym.envs.base`): ``AmigoBot-v1``'s
(:class:`AmigoBotV1Env`, :class:`AmigoBotV1VectorEnv`), and ``AmigoBot-v0`` as their configuration
(:class:`AmigoBotEnv`, :class:`AmigoBotVectorEnv`: the same classes built with AmigoBot-v0's settings from its
keywords, :mod:`amigo_gym.envs.amigobot`).
Both are registered by ``import amigo_gym``::

    env = gym.make("AmigoBot-v0")
    envs = gym.make_vec("AmigoBot-v0", num_envs=64)  # native numpy-batched AmigoBotVectorEnv
"""

from __future__ import annotations

from amigo_gym.envs.amigobot import AmigoBotEnv, AmigoBotVectorEnv, make_env_params
from amigo_gym.envs.amigobot_v1 import AmigoBotV1Env
from amigo_gym.envs.vector_v1 import AmigoBotV1VectorEnv

__all__ = ["AmigoBotEnv", "AmigoBotV1Env", "AmigoBotV1VectorEnv", "AmigoBotVectorEnv", "make_env_params"]
