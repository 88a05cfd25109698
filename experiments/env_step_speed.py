"""The environments' step through the public API, timed by CPU time: run it on two trees alternately to compare them.

    PYTHONPATH=<tree> NUMBA_NUM_THREADS=1 python experiments/env_step_speed.py [label] [repeats]

Prints the least (``time.thread_time_ns``: a busy host's stolen time does not count) over ``repeats`` (default 7) of:
one ``step`` of ``gym.make_vec("AmigoBot-v0", 4096, vectorization_mode="vector_entry_point")`` (20 steps a repeat),
of ``gym.make("AmigoBot-v0")`` and ``gym.make("AmigoBot-v1")`` (2000 steps a repeat, reset when an episode ends) and
of ``gym.make_vec("AmigoBot-v1", 1024, ...)`` (10 steps a repeat), all with uniform random actions in [-1, 1] (so
episodes end and restart), and the CPU model.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)


def least(fn: Callable[[], object], calls: int, repeats: int) -> float:
    """The least CPU time [ns] per call over ``repeats`` repeats of ``calls`` calls."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.thread_time_ns()
        for _ in range(calls):
            fn()
        best = min(best, (time.thread_time_ns() - t0) / calls)
    return best


def vector_stepper(env: Any, n: int) -> Callable[[], object]:
    env.reset(seed=0)
    g = np.random.default_rng(0)
    actions = [g.uniform(-1.0, 1.0, (n, 2)).astype(np.float32) for _ in range(16)]
    i = [0]

    def step() -> object:
        i[0] = (i[0] + 1) % 16
        return env.step(actions[i[0]])

    return step


def single_stepper(env: Any) -> Callable[[], object]:
    env.reset(seed=0)
    g = np.random.default_rng(0)
    actions = [g.uniform(-1.0, 1.0, 2).astype(np.float32) for _ in range(64)]
    i = [0]

    def step() -> object:
        i[0] = (i[0] + 1) % 64
        _, _, terminated, truncated, _ = env.step(actions[i[0]])
        if terminated or truncated:
            env.reset()
        return None

    return step


def cpu_model() -> str:
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return "unknown"


def main() -> None:
    label = sys.argv[1] if len(sys.argv) > 1 else ""
    r = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    v0 = vector_stepper(gym.make_vec("AmigoBot-v0", num_envs=4096, vectorization_mode="vector_entry_point"), 4096)
    v0()
    t_v0 = least(v0, 20, r)
    s0 = single_stepper(gym.make("AmigoBot-v0"))
    s1 = single_stepper(gym.make("AmigoBot-v1"))
    for _ in range(100):
        s0()
        s1()
    t_s0, t_s1 = least(s0, 2000, r), least(s1, 2000, r)
    v1 = vector_stepper(gym.make_vec("AmigoBot-v1", num_envs=1024, vectorization_mode="vector_entry_point"), 1024)
    v1()
    t_v1 = least(v1, 10, r)
    print(
        f"{label} [{cpu_model()}]: v0 vec N=4096 {t_v0 / 1e3:.1f} us/step | v0 single {t_s0 / 1e3:.2f} us | "
        f"v1 single {t_s1 / 1e3:.2f} us | v1 vec N=1024 {t_v1 / 1e3:.1f} us/step",
        flush=True,
    )


if __name__ == "__main__":
    main()
