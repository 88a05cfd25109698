"""How long a vector env takes to reach the steady state of restarts under random actions, the state a benchmark
should time (``amigo-gym bench-env --warmup``): episodes ended a step and CPU time a step, by windows of steps after
``reset``.

    NUMBA_NUM_THREADS=1 python experiments/vector_warmup.py [N] [steps]

``gym.make_vec(..., N, vectorization_mode="vector_entry_point")`` (default N = 4096) of AmigoBot-v1 with the training
distribution's keywords and with its defaults, AmigoBot-v0 and Gymnasium's ``CartPoleVectorEnv``, each reset with seed
0 and stepped ``steps`` times (default 800) with bench-env's actions (a pool of 16 ``action_space.sample()``, seed 0);
prints, per window, the mean episodes ended a step and the median ``time.thread_time_ns`` of a step, and the CPU.
"""

from __future__ import annotations

import itertools
import sys
import time

import gymnasium as gym
import numpy as np
from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

n = int(sys.argv[1]) if len(sys.argv) > 1 else 4096
steps = int(sys.argv[2]) if len(sys.argv) > 2 else 800
edges = (0, 50, 100, 200, 300, 400, 800, 1600)
windows = [(a, b) for a, b in itertools.pairwise(edges) if b <= steps]
print(machine_line())
print("| env | " + " | ".join(f"steps {a}-{b}" for a, b in windows) + " |\n|---|" + "---:|" * len(windows))
makers = {
    "AmigoBot-v1, the training distribution": lambda: gym.make_vec(
        "AmigoBot-v1", n, vectorization_mode="vector_entry_point", **TRAINING_DISTRIBUTION["env_kwargs"]
    ),
    "AmigoBot-v1, defaults": lambda: gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point"),
    "AmigoBot-v0": lambda: gym.make_vec("AmigoBot-v0", n, vectorization_mode="vector_entry_point"),
    "CartPoleVectorEnv": lambda: CartPoleVectorEnv(num_envs=n),
}
for label, make in makers.items():
    env = make()
    env.action_space.seed(0)
    actions = itertools.cycle([env.action_space.sample() for _ in range(16)])
    env.reset(seed=0)
    ends, spent = np.zeros(steps), np.zeros(steps)
    for i in range(steps):
        t = time.thread_time_ns()
        _, _, terminated, truncated, _ = env.step(next(actions))
        spent[i] = (time.thread_time_ns() - t) / 1e3
        ends[i] = np.count_nonzero(terminated | truncated)
    cells = [f"{ends[a:b].mean():.1f} ended, {np.median(spent[a:b]):,.0f} µs" for a, b in windows]
    print(f"| {label} | " + " | ".join(cells) + " |", flush=True)
    env.close()
