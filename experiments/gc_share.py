"""What Python's garbage collector costs AmigoBot-v1's native vector env in the steady state of random actions.

    PYTHONPATH=<tree> NUMBA_NUM_THREADS=1 python experiments/gc_share.py [N] [steps]

``gym.make_vec("AmigoBot-v1", N, vectorization_mode="vector_entry_point", **TRAINING_DISTRIBUTION["env_kwargs"])``
(default N = 4096) stepped 300 times with uniform random actions in [-1, 1] (10 drawn, in turn), then ``steps``
(default 600) more timed: the CPU time a step, and per generation the collections, their CPU time each
(``gc.callbacks``) and their share a step; the CPU.
"""

from __future__ import annotations

import collections
import gc
import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

n = int(sys.argv[1]) if len(sys.argv) > 1 else 4096
steps = int(sys.argv[2]) if len(sys.argv) > 2 else 600
env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", **TRAINING_DISTRIBUTION["env_kwargs"])
env.reset(seed=0)
acts = np.random.default_rng(0).uniform(-1.0, 1.0, (10, n, 2))
for k in range(300):
    env.step(acts[k % 10])
spent: collections.Counter[int] = collections.Counter()
count: collections.Counter[int] = collections.Counter()
began = [0]


def timed(phase: str, info: dict[str, Any]) -> None:
    if phase == "start":
        began[0] = time.thread_time_ns()
    else:
        spent[info["generation"]] += time.thread_time_ns() - began[0]
        count[info["generation"]] += 1


gc.callbacks.append(timed)
t0 = time.thread_time_ns()
for k in range(steps):
    env.step(acts[k % 10])
total = time.thread_time_ns() - t0
print(f"N = {n}, {steps} steps: {total / steps / 1e3:,.0f} µs a step [{machine_line()}]")
for g in range(3):
    each = spent[g] / count[g] / 1e3 if count[g] else 0.0
    print(f"  generation {g}: {count[g]} collections, {each:,.0f} µs each, {spent[g] / steps / 1e3:,.0f} µs a step")
