"""amigo_gym: a Gymnasium environment for the AmigoBot differential-drive robot.

``import amigo_gym`` registers ``AmigoBot-v0`` and ``AmigoBot-v1`` and needs only numpy and gymnasium; the symbolic
derivation (sympy), rendering (pygame), plots (matplotlib) and agents (torch, stable-baselines3)
are imported only where they are used.
"""

from __future__ import annotations

import warnings

from gymnasium.envs.registration import register, registry

from amigo_gym.params import EnvParams, RobotParams

__version__ = "0.1.0"
__all__ = ["EnvParams", "RobotParams", "__version__"]

#: steps of one episode at the default dt = 0.1 s: 40 s, more than one lap (31.3 s) of the
#: default circle. Pass ``max_episode_steps`` to ``gym.make`` with other settings.
MAX_EPISODE_STEPS = 400

#: steps of one AmigoBot-v1 episode at the default dt = 0.1 s: 60 s
MAX_EPISODE_STEPS_V1 = 600

if "AmigoBot-v0" not in registry:
    register(
        id="AmigoBot-v0",
        entry_point="amigo_gym.envs:AmigoBotEnv",
        vector_entry_point="amigo_gym.envs:AmigoBotVectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
    )

# AmigoBot-v0 is not deprecated by v1: it stays the ideal robot of the paper comparison (docs/amigobot_v1.md).
# Gymnasium warns whenever an older version of an id is made; silence that one message, nothing else.
warnings.filterwarnings("ignore", message=r".*The environment AmigoBot-v0 is out of date", category=DeprecationWarning)

if "AmigoBot-v1" not in registry:
    register(
        id="AmigoBot-v1",
        entry_point="amigo_gym.envs:AmigoBotV1Env",
        vector_entry_point="amigo_gym.envs:AmigoBotV1VectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS_V1,
    )
