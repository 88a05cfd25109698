"""amigo_gym: a Gymnasium environment for the AmigoBot differential-drive robot.

``import amigo_gym`` registers ``AmigoBot-v0`` and ``AmigoBot-v1`` and needs only numpy and gymnasium; sympy,
pygame, matplotlib, torch and stable-baselines3 are imported only where used.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from gymnasium.envs.registration import EnvSpec, register, registry

from amigo_gym.model.params import EnvParams, RobotParams

__version__ = "0.1.0"
__all__ = ["EnvParams", "RobotParams", "SeparateEnvSpec", "__version__"]

#: steps of one AmigoBot-v0 episode at the default dt = 0.1 s: 40 s, more than one lap of the default circle
MAX_EPISODE_STEPS = 400

#: steps of one AmigoBot-v1 episode at the default dt = 0.1 s: 60 s
MAX_EPISODE_STEPS_V1 = 600


class SeparateEnvSpec(EnvSpec):
    """The registered spec of ``AmigoBot-v1``: an environment of its own name, not a newer version of ``AmigoBot-v0``.

    It reports ``name = id`` and ``version = None``, so that ``gym.make("AmigoBot-v0")`` does not warn that v0 is
    out of date (v1 is a different task, docs/amigobot_v1.md); ``gym.make("AmigoBot-v1")`` finds it by id. It compares
    equal to the plain :class:`EnvSpec` of the same fields, and pickles and copies as one.
    """

    def __post_init__(self) -> None:
        super().__post_init__()
        self.name = self.id
        self.version = None

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, EnvSpec):
            return NotImplemented
        return _init_fields(self) == _init_fields(other)

    # unhashable, as EnvSpec (a mutable dataclass)
    __hash__ = None  # type: ignore[assignment]


def _init_fields(spec: EnvSpec) -> tuple[Any, ...]:
    return tuple(getattr(spec, f.name) for f in dataclasses.fields(EnvSpec) if f.init)


if "AmigoBot-v0" not in registry:
    register(
        id="AmigoBot-v0",
        entry_point="amigo_gym.envs:AmigoBotEnv",
        vector_entry_point="amigo_gym.envs:AmigoBotVectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
    )

if "AmigoBot-v1" not in registry:
    # gymnasium.register builds a plain EnvSpec: write the registry's entry directly
    registry["AmigoBot-v1"] = SeparateEnvSpec(
        id="AmigoBot-v1",
        entry_point="amigo_gym.envs:AmigoBotV1Env",
        vector_entry_point="amigo_gym.envs:AmigoBotV1VectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS_V1,
    )
