"""How much of AmigoBot-v1's vector step its autoresets take (issue 19: the restarting robots are started in a Python
loop, ``envs/vector_v1.py: _begin_rows_kernel``), by CPU time (``time.thread_time``).

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v1_reset_share.py [--num-envs 1024] [--steps 700] [--paths 300]

For each task (the default AmigoBot-v1, and tasks whose episodes end often), ``--steps`` vector steps with uniform
random actions in [-1, 1] (a fixed seed): the CPU time per step, the robots restarted per step, and the share of the
step's CPU time spent in ``_begin_rows`` (timed by wrapping that method of the env), with the time per restarted robot.

With ``--paths N`` (and a tree that has them, ``amigo_gym.sim.fast_v1.path_loops``), also the CPU time of building one
path of each family ``path="mixed"`` builds anew (N parameter sets drawn from its ranges, ``task/v1.py``'s
``MIXED_RANGES``; random paths of the default settings, seeds 0 to N - 1) by the float route and by the compiled loops,
with the compiled coarse samples' share.
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


def build_times(n: int) -> None:
    """The table of ``--paths``: CPU µs per path, float route and compiled loops (their coarse samples timed apart)."""
    from amigo_gym.paths import families
    from amigo_gym.sim import fast_v1
    from amigo_gym.task.v1 import MIXED_RANGES

    loops = getattr(fast_v1, "path_loops", lambda: None)()
    if loops is None:
        print("no compiled path loops in this tree (or the C library's cos/sin differ from numpy's)")
        return
    spent = [0.0]
    samples = loops.samples

    def timed_samples(*args: Any) -> None:
        t0 = time.thread_time()
        samples(*args)
        spent[0] += time.thread_time() - t0

    timed = loops._replace(samples=timed_samples)
    g = np.random.default_rng(2)
    print(f"\nbuilding one path, CPU µs (mean of {n}): float route | compiled loops | of which the coarse samples")
    print("| family | float route | compiled | compiled: coarse samples | coarse samples per path |")
    print("|---|---:|---:|---:|---:|")
    for fam in ("circle", "figure8", "lane_change", "random"):
        if fam == "random":
            draws: list[dict[str, Any]] = [{} for _ in range(n)]
        else:
            draws = [{k: float(g.uniform(lo, hi)) for k, (lo, hi) in MIXED_RANGES[fam].items()} for _ in range(n)]
        warm = np.random.default_rng(n) if fam == "random" else None
        families.make_family_path(fam, warm, loops=loops, **draws[0])  # compiled code loaded (or compiled) first
        row = []
        for lp in (None, timed):
            spent[0] = 0.0
            count = 0
            t0 = time.thread_time()
            for i, kw in enumerate(draws):
                rng = np.random.default_rng(i) if fam == "random" else None
                path = families.make_family_path(fam, rng, loops=lp, **kw)
                count += len(path._t.sample_x)
            row.append((time.thread_time() - t0) / n * 1e6)
        print(f"| {fam} | {row[0]:.0f} | {row[1]:.0f} | {spent[0] / n * 1e6:.0f} | {count / n:.0f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num-envs", type=int, default=1024, help="robots in the vector env (default 1024)")
    ap.add_argument(
        "--steps", type=int, default=700, help="vector steps per task (default 700: past the time limit, 600)"
    )
    ap.add_argument("--paths", type=int, default=0, help="also time building N paths per family (default 0: not)")
    args = ap.parse_args()
    print(f"CPU: {_cpu_model()}; N = {args.num_envs}, {args.steps} steps, uniform random actions, CPU time")
    print("| task | µs per step | robots restarted per step | share of the step in resets | µs per restarted robot |")
    print("|---|---:|---:|---:|---:|")
    for name, kwargs in TASKS.items():
        per_step, restarted, share, per_row = measure(kwargs, args.num_envs, args.steps)
        print(f"| {name} | {per_step:.0f} | {restarted:.1f} | {100 * share:.1f} % | {per_row:.1f} |", flush=True)
    if args.paths:
        build_times(args.paths)


if __name__ == "__main__":
    main()
