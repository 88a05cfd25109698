"""AmigoBot-v1's compiled step, vector and single, timed by CPU time (docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v1_step_speed.py [label]

Prints the least of 30 repeats (``time.thread_time``, which a busy host's stolen time does not count) of: the vector
env's step at N = 1024 per robot-step, the vector env's step call at N = 1 (its fixed cost per call), and the single
env's step, all with the steady action 0.5 (few resets: the kernel dominates at N = 1024). Run it on two trees
alternately (``PYTHONPATH``) to compare them.
"""

from __future__ import annotations

import sys
import time
import timeit

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the ids)


def main() -> None:
    n = 1024
    vec = gym.make_vec("AmigoBot-v1", num_envs=n, vectorization_mode="vector_entry_point")
    vec.reset(seed=0)
    a = np.full((n, 2), 0.5, np.float32)
    for _ in range(3):
        vec.step(a)
    per_robot = min(timeit.repeat(lambda: vec.step(a), number=5, repeat=30, timer=time.thread_time)) / 5 / n * 1e6
    one = gym.make_vec("AmigoBot-v1", num_envs=1, vectorization_mode="vector_entry_point")
    one.reset(seed=0)
    a1 = np.full((1, 2), 0.5, np.float32)
    for _ in range(20):
        one.step(a1)
    per_call = min(timeit.repeat(lambda: one.step(a1), number=500, repeat=30, timer=time.thread_time)) / 500 * 1e6
    env = gym.make("AmigoBot-v1")
    env.reset(seed=0)
    b = np.full(2, 0.5, np.float32)

    def one() -> None:
        _, _, terminated, truncated, _ = env.step(b)
        if terminated or truncated:
            env.reset()

    for _ in range(20):
        one()
    single = min(timeit.repeat(one, number=500, repeat=30, timer=time.thread_time)) / 500 * 1e6
    label = sys.argv[1] if len(sys.argv) > 1 else ""
    print(
        f"{label} vector N=1024: {per_robot:.3f} us per robot-step; vector N=1: {per_call:.1f} us per call; "
        f"single: {single:.2f} us".strip(),
        flush=True,
    )


if __name__ == "__main__":
    main()
