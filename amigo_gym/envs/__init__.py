"""The AmigoBot environments: :class:`AmigoBotEnv` (one robot) and :class:`AmigoBotVectorEnv` (N robots).

``AmigoBot-v0`` is registered by ``import amigo_gym``::

    env = gym.make("AmigoBot-v0")
    envs = gym.make_vec("AmigoBot-v0", num_envs=64)  # native numpy-batched AmigoBotVectorEnv
"""

from __future__ import annotations

from amigo_gym.envs.amigobot import AmigoBotEnv, make_env_params

__all__ = ["AmigoBotEnv", "AmigoBotVectorEnv", "make_env_params"]


def __getattr__(name: str) -> object:
    # the vector env is imported lazily so that a missing or broken vector module never blocks the single env
    if name == "AmigoBotVectorEnv":
        from amigo_gym.envs.vector import AmigoBotVectorEnv

        return AmigoBotVectorEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
