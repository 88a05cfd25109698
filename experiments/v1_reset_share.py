"""How much of AmigoBot-v1's vector step its autoresets take (issue 19: the restarting robots are started in a Python
loop, ``envs/vector_v1.py: _begin_rows_kernel``), by CPU time (``time.thread_time``).

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v1_reset_share.py [--num-envs 1024] [--steps 700]

For each task (the default AmigoBot-v1, and tasks whose episodes end often), ``--steps`` vector steps with uniform
random actions in [-1, 1] (a fixed seed): the CPU time per step, the robots restarted per step, and the share of the
step's CPU time spent in ``_begin_rows`` (timed by wrapping that method of the env), with the time per restarted robot.
"""

from __future__ import annotations

import argparse
import platform
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the ids)

TASKS: dict[str, dict[str, Any]] = {
    "default": {},
    "max_episode_steps=35": {"max_episode_steps": 35},
    "lane_change": {"path": "lane_change"},
    "mixed, randomize=hard": {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"},
}


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def measure(kwargs: dict[str, Any], n: int, steps: int) -> tuple[float, float, float, float]:
    """(CPU µs per step, robots restarted per step, share of the step in resets, CPU µs per restarted robot)."""
    env = gym.make_vec("AmigoBot-v1", num_envs=n, vectorization_mode="vector_entry_point", **kwargs)
    u: Any = env.unwrapped
    env.reset(seed=0)
    g = np.random.default_rng(1)
    actions = g.uniform(-1.0, 1.0, (steps, n, 2)).astype(np.float32)
    for a in actions[:5]:  # warm: compiled code loaded
        env.step(a)
    spent = [0.0]
    rows = [0]
    begin = u._begin_rows

    def timed(idx: Any, pose_opt: Any = None) -> Any:
        t0 = time.thread_time()
        out = begin(idx, pose_opt)
        spent[0] += time.thread_time() - t0
        rows[0] += len(idx)
        return out

    u._begin_rows = timed
    t0 = time.thread_time()
    for a in actions:
        env.step(a)
    total = time.thread_time() - t0
    env.close()
    per_row = spent[0] / rows[0] * 1e6 if rows[0] else float("nan")
    return total / steps * 1e6, rows[0] / steps, spent[0] / total, per_row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num-envs", type=int, default=1024, help="robots in the vector env (default 1024)")
    ap.add_argument(
        "--steps", type=int, default=700, help="vector steps per task (default 700: past the time limit, 600)"
    )
    args = ap.parse_args()
    print(f"CPU: {_cpu_model()}; N = {args.num_envs}, {args.steps} steps, uniform random actions, CPU time")
    print("| task | µs per step | robots restarted per step | share of the step in resets | µs per restarted robot |")
    print("|---|---:|---:|---:|---:|")
    for name, kwargs in TASKS.items():
        per_step, restarted, share, per_row = measure(kwargs, args.num_envs, args.steps)
        print(f"| {name} | {per_step:.0f} | {restarted:.1f} | {100 * share:.1f} % | {per_row:.1f} |", flush=True)


if __name__ == "__main__":
    main()
