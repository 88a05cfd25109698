"""Speed of the vector env's numpy route (``kernel="numpy"``: the column code) at one N, per task (issue 19, the column
code written once: a change of it must keep this route within ~1.5x).

    PYTHONPATH=. python experiments/numpy_route_speed.py [--num-envs 1024] [--steps 60] [--repeats 5] [--single]

For each task: ``--steps`` vector steps with uniform random actions in [-1, 1] (fixed seed), repeated; prints the
median CPU time per call (``time.thread_time``) in milliseconds. ``--single``: instead, the single env's reference
(``gym.make(..., kernel="numpy")``: the float route, which a path object of the user's own runs), ``--steps`` steps
(resets included) per repeat, in microseconds per step.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the ids)

TASKS: dict[str, tuple[str, dict[str, Any]]] = {
    "v0 circle": ("AmigoBot-v0", {}),
    "v0 manoeuvre": ("AmigoBot-v0", {"path": "manoeuvre"}),
    "v1 default": ("AmigoBot-v1", {}),
    "v1 mixed, randomize=hard": ("AmigoBot-v1", {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"}),
}


def measure(env_id: str, kwargs: dict[str, Any], n: int, steps: int, repeats: int) -> float:
    """Median CPU ms per vector step of ``env_id`` with ``kernel="numpy"``."""
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", kernel="numpy", **kwargs)
    env.reset(seed=0)
    g = np.random.default_rng(1)
    actions = g.uniform(-1.0, 1.0, (steps, n, 2)).astype(np.float32)
    for a in actions[:3]:
        env.step(a)
    times = []
    for _ in range(repeats):
        t0 = time.thread_time()
        for a in actions:
            env.step(a)
        times.append((time.thread_time() - t0) / steps * 1e3)
    env.close()
    return statistics.median(times)


def measure_single(env_id: str, kwargs: dict[str, Any], steps: int, repeats: int) -> float:
    """Median CPU us per step of ``gym.make(env_id, kernel="numpy")`` (resets on termination or truncation)."""
    env = gym.make(env_id, kernel="numpy", **kwargs)
    env.reset(seed=0)
    actions = np.random.default_rng(1).uniform(-1.0, 1.0, (steps, 2)).astype(np.float32)
    times = []
    for _ in range(repeats):
        t0 = time.thread_time()
        for a in actions:
            _, _, terminated, truncated, _ = env.step(a)
            if terminated or truncated:
                env.reset()
        times.append((time.thread_time() - t0) / steps * 1e6)
    env.close()
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--num-envs", type=int, default=1024)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--only", nargs="*", default=None, help="task names (default: all)")
    ap.add_argument("--single", action="store_true", help="the single env's float route instead")
    args = ap.parse_args()
    for name, (env_id, kwargs) in TASKS.items():
        if args.only and name not in args.only:
            continue
        if args.single:
            us = measure_single(env_id, kwargs, args.steps, args.repeats)
            print(f"{name:28s} single: {us:8.1f} us per step (kernel=numpy)", flush=True)
            continue
        ms = measure(env_id, kwargs, args.num_envs, args.steps, args.repeats)
        print(f"{name:28s} N={args.num_envs}: {ms:8.3f} ms per call (kernel=numpy)", flush=True)


if __name__ == "__main__":
    main()
