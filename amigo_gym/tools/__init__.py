"""The tools layer: the ``amigo-gym`` command, training, benchmarks, sweeps, curves, speed benches, paper tooling.

The environment core (``amigo_gym`` outside this subpackage) never imports it. Its heavy dependencies (torch,
stable-baselines3, optuna, matplotlib, sympy) come with the ``train`` and ``bench`` extras and are imported only
by the modules that use them; ``import amigo_gym.tools`` itself imports nothing.
"""
