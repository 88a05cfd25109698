"""AmigoBot-v1's native vector env at N = 4096, defaults, the training distribution and ``V1_HARD`` (mixed paths, hard
randomisation), timed by CPU time: run it on two trees alternately to compare them.

    PYTHONPATH=<tree> NUMBA_NUM_THREADS=1 python experiments/v1_vector_speed.py [label] [N] [steps] [warmup] [configs] \
        [kernel]

Prints, per configuration (``configs``: some of ``defaults,training,hard``, default all), the least over 5 repeats of
``steps`` steps (default 10; ``time.thread_time_ns``: a busy host's stolen time does not count) of
``gym.make_vec("AmigoBot-v1", N, vectorization_mode="vector_entry_point", **kwargs)`` stepped with uniform random
actions in [-1, 1] (10 drawn, in turn) after ``reset(seed=repeat)`` and ``warmup`` untimed steps (default 0), in µs a
step and env-steps/s, and the CPU. The robots start at rest and their episodes reach their steady rate of restarts
after about 200 steps (``vector_warmup.py``): ``warmup`` 300 times the steady state of random actions. ``kernel``
``numba-parallel`` (default ``numba``) runs the loops on ``NUMBA_NUM_THREADS`` threads and times by wall clock.
"""

from __future__ import annotations

import sys
import time

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.bench.env import V1_HARD
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

n = int(sys.argv[2]) if len(sys.argv) > 2 else 4096
steps = int(sys.argv[3]) if len(sys.argv) > 3 else 10
warmup = int(sys.argv[4]) if len(sys.argv) > 4 else 0
chosen = sys.argv[5].split(",") if len(sys.argv) > 5 else ["defaults", "training", "hard"]
kernel = sys.argv[6] if len(sys.argv) > 6 else "numba"
clock = time.perf_counter_ns if kernel == "numba-parallel" else time.thread_time_ns
out = []
configs = (("defaults", {}), ("training", dict(TRAINING_DISTRIBUTION["env_kwargs"])), ("hard", V1_HARD))
for label, kw in [c for c in configs if c[0] in chosen]:
    env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", kernel=kernel, **kw)
    env.reset(seed=0)
    acts = np.random.default_rng(0).uniform(-1.0, 1.0, (10, n, 2))
    env.step(acts[0])  # compiled
    best = float("inf")
    for r in range(5):
        env.reset(seed=r)
        for k in range(warmup):
            env.step(acts[k % 10])
        t = clock()
        for k in range(steps):
            env.step(acts[k % 10])
        best = min(best, (clock() - t) / steps)
    env.close()
    out.append(f"{label} {best / 1e3:.0f} us/step ({n / best * 1e3:.2f}M env-steps/s)")
print(f"{sys.argv[1] if len(sys.argv) > 1 else ''} N={n}: " + " | ".join(out) + f" [{machine_line()}]")
