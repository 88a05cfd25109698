"""amigo_gym: a Gymnasium environment for the AmigoBot differential-drive robot.

``import amigo_gym`` registers ``AmigoBot-v0`` and ``AmigoBot-v1`` and needs only numpy and gymnasium; sympy,
pygame, matplotlib, torch and stable-baselines3 are imported only where used.
"""

from __future__ import annotations

import dataclasses

from gymnasium.envs.registration import EnvSpec, register, registry

from amigo_gym.model.params import RobotParams

__version__ = "0.1.0"
__all__ = ["RobotParams", "SeparateEnvSpec", "__version__"]

#: steps of one AmigoBot-v0 episode at the default dt = 0.1 s: 40 s, more than one lap of the default circle
MAX_EPISODE_STEPS = 400

#: steps of one AmigoBot-v1 episode at the default dt = 0.1 s: 60 s
MAX_EPISODE_STEPS_V1 = 600


class SeparateEnvSpec(EnvSpec):
    """The spec of ``AmigoBot-v1``, a task of its own name (``name = id``, ``version = None``), so that
    ``gym.make("AmigoBot-v0")`` does not warn that v0 is out of date; equal to the plain :class:`EnvSpec` of the same
    fields."""

    def __post_init__(self) -> None:
        super().__post_init__()
        self.name = self.id
        self.version = None

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, EnvSpec):
            return NotImplemented
        names = [f.name for f in dataclasses.fields(EnvSpec) if f.init]
        return [getattr(self, n) for n in names] == [getattr(other, n) for n in names]

    __hash__ = None  # type: ignore[assignment]  # unhashable, as EnvSpec


if "AmigoBot-v0" not in registry:
    register(
        id="AmigoBot-v0",
        entry_point="amigo_gym.envs:AmigoBotEnv",
        vector_entry_point="amigo_gym.envs:AmigoBotVectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
    )

if "AmigoBot-v1" not in registry:
    # register() builds a plain EnvSpec
    registry["AmigoBot-v1"] = SeparateEnvSpec(
        id="AmigoBot-v1",
        entry_point="amigo_gym.envs:AmigoBotV1Env",
        vector_entry_point="amigo_gym.envs:AmigoBotV1VectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS_V1,
    )
