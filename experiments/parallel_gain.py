"""What numba's threads gain for the native vector envs (issue 19 item 5, "both cores"; docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=2 python experiments/parallel_gain.py [--env AmigoBot-v1] [--sizes 64 256 1024]

For each N, one vector env with ``kernel="numba"`` (the serial compiled step, the default) and one with
``kernel="numba-parallel"`` (the same loops on numba's threads, the same bits) step the same actions; the two are
timed in interleaved repeats (``--repeats`` of at least ``--min-time`` seconds each, so that a change of the
machine's load touches both) and the median of the per-repeat ratios parallel / serial is printed with its range.
The header names the CPU, numba's threads and threading layer, and the load average (again at the end): the gain
depends on all four, and on a machine whose cores are busy numba's OpenMP threads spin at each barrier and lose.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the ids)
from amigo_gym.tools.machine import cpu_model, simd_level


def _make(env_id: str, n: int, kernel: str) -> tuple[Any, np.ndarray]:
    env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", kernel=kernel)
    env.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (n, 2)).astype(np.float32)
    for _ in range(3):  # compile, warm the caches
        env.step(actions)
    return env, actions


def _rate(env: Any, actions: np.ndarray, min_time: float) -> float:
    """Env-steps per second over at least ``min_time`` seconds of steps."""
    k = 0
    t0 = time.perf_counter()
    while True:
        env.step(actions)
        k += 1
        elapsed = time.perf_counter() - t0
        if elapsed >= min_time:
            return k * actions.shape[0] / elapsed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="AmigoBot-v0", help="env id (default: AmigoBot-v0)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024, 4096, 16384], help="vector sizes [envs]")
    ap.add_argument("--repeats", type=int, default=7, help="interleaved repeats per size (default: 7)")
    ap.add_argument("--min-time", type=float, default=0.3, help="least duration of one repeat [s] (default: 0.3)")
    args = ap.parse_args(argv)
    if args.repeats < 1 or args.min_time <= 0 or min(args.sizes) < 1:
        ap.error("--repeats and --sizes must be >= 1 and --min-time > 0")
    import numba

    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    machine = f"{cpu_model()} ({platform.machine()}, SIMD {simd_level()})"
    print(f"# {machine}, numba {numba.__version__}, {numba.get_num_threads()} threads, load {load}")
    print("| env | N | serial env-steps/s | parallel env-steps/s | parallel / serial, median (range) |")
    print("|---|---:|---:|---:|---|")
    for n in args.sizes:
        serial, a = _make(args.env, n, "numba")
        parallel, _ = _make(args.env, n, "numba-parallel")
        rs, rp = [], []
        for _ in range(args.repeats):
            rs.append(_rate(serial, a, args.min_time))
            rp.append(_rate(parallel, a, args.min_time))
        serial.close()
        parallel.close()
        ratio = np.array(rp) / np.array(rs)
        print(
            f"| {args.env} | {n} | {np.median(rs):.3g} | {np.median(rp):.3g} | "
            f"{np.median(ratio):.2f} ({ratio.min():.2f}–{ratio.max():.2f}) |",
            flush=True,
        )
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(f"# threading layer {numba.threading_layer()}, load at the end {load}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
