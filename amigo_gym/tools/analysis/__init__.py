"""Analyses behind the ``amigo-gym`` command: exactness checks, the paper's figures, convergence.

May import the core, ``amigo_gym.policies``, ``amigo_gym.envs`` and ``amigo_gym.io``; heavy
packages (matplotlib, sympy) only inside the functions that need them.
"""
