"""Training, evaluation and the main comparison: functions of typed settings dataclasses (the ``train`` extra).

``import amigo_gym.tools.training`` imports nothing heavy. Its modules may import the core, ``amigo_gym.policies``,
``envs`` and ``io``; never another module's CLI parser, never the repository's ``experiments/`` scripts.
"""
