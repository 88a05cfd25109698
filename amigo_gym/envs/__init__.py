"""The AmigoBot environments: ``AmigoBot-v1``'s single and vector envs (:class:`AmigoBotV1Env`,
:class:`AmigoBotV1VectorEnv`) and ``AmigoBot-v0``'s, their configuration (:class:`AmigoBotEnv`,
:class:`AmigoBotVectorEnv`). Registered by ``import amigo_gym``::

    env = gym.make("AmigoBot-v0")
    envs = gym.make_vec("AmigoBot-v0", num_envs=64)  # native numpy-batched AmigoBotVectorEnv
"""

from __future__ import annotations

from amigo_gym.envs.amigobot import AmigoBotEnv, AmigoBotVectorEnv, make_env_params
from amigo_gym.envs.amigobot_v1 import AmigoBotV1Env
from amigo_gym.envs.vector_v1 import AmigoBotV1VectorEnv

__all__ = ["AmigoBotEnv", "AmigoBotV1Env", "AmigoBotV1VectorEnv", "AmigoBotVectorEnv", "make_env_params"]
