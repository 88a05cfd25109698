"""cProfile of 30 steps of AmigoBot-v0's vector env at N = 65,536 with random actions: where a step's time goes, and
how much of it is outside the parallel loops (what numba's threads cannot divide).

    NUMBA_NUM_THREADS=1 python experiments/vector_step_profile.py numba
    NUMBA_NUM_THREADS=2 python experiments/vector_step_profile.py numba-parallel
"""

from __future__ import annotations

import cProfile
import pstats
import sys

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401

n = 65536
env = gym.make_vec("AmigoBot-v0", n, vectorization_mode="vector_entry_point", kernel=sys.argv[1])
env.reset(seed=0)
actions = [np.random.default_rng(k).uniform(-1, 1, (n, 2)).astype(np.float32) for k in range(8)]
for k in range(5):
    env.step(actions[k])
profile = cProfile.Profile()
profile.enable()
for k in range(30):
    env.step(actions[k % 8])
profile.disable()
pstats.Stats(profile).sort_stats("tottime").print_stats(14)
