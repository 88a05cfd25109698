"""Training, evaluation and the main comparison: functions of typed settings dataclasses.

The modules here import torch and stable-baselines3 lazily or at their top (install the ``train``
extra); ``import amigo_gym.tools.training`` itself imports nothing heavy. They may import the core,
``amigo_gym.policies``, ``amigo_gym.envs`` and ``amigo_gym.io``; never the CLI parser of another
module and never the repository's ``experiments/`` scripts.
"""

from __future__ import annotations
