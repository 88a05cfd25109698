"""cProfile of 30 steps of a vector env (default AmigoBot-v0, N = 65,536) with random actions: where a step's time
goes, and how much of it is outside the parallel loops (what numba's threads cannot divide).

    NUMBA_NUM_THREADS=1 python experiments/vector_step_profile.py numba
    NUMBA_NUM_THREADS=2 python experiments/vector_step_profile.py numba-parallel
    NUMBA_NUM_THREADS=1 python experiments/vector_step_profile.py numba AmigoBot-v1 16384 [training]

Arguments: kernel, then optionally env id, N and ``training`` (AmigoBot-v1 with the training distribution's
``env_kwargs``).
"""

from __future__ import annotations

import cProfile
import pstats
import sys

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401

env_id = sys.argv[2] if len(sys.argv) > 2 else "AmigoBot-v0"
n = int(sys.argv[3]) if len(sys.argv) > 3 else 65536
kwargs = {}
if "training" in sys.argv[4:]:
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

    kwargs = dict(TRAINING_DISTRIBUTION["env_kwargs"])
env = gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", kernel=sys.argv[1], **kwargs)
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
