"""How much of AmigoBot-v1's vector step is outside its parallel loop, and what that leaves to many threads (Amdahl).

    NUMBA_NUM_THREADS=1 python experiments/serial_share.py 65536      # N (default 16384)

The defaults with random actions on one thread (``kernel="numba"``): the wall time of the step and of the compiled
row loop ``step_rows`` inside it (the loop ``numba-parallel`` divides; timed by a wrapper), least of 4 repeats of 15
steps; the rest runs on one thread whatever the thread count, so ``t / (rest + loop / 16)`` bounds 16 threads.
"""

from __future__ import annotations

import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.machine import machine_line

n = int(sys.argv[1]) if len(sys.argv) > 1 else 16384
env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", kernel="numba")
env.reset(seed=0)
batch = env.unwrapped._batch  # type: ignore[attr-defined]
loop, spent = batch._step_rows, [0.0]


def timed(*args: Any) -> None:
    t = time.perf_counter()
    loop(*args)
    spent[0] += time.perf_counter() - t


batch._step_rows = timed
acts = np.random.default_rng(0).uniform(-1.0, 1.0, (15, n, 2))
env.step(acts[0])
best = (float("inf"), 0.0)
for r in range(4):
    env.reset(seed=r)
    spent[0] = 0.0
    t0 = time.perf_counter()
    for k in range(15):
        env.step(acts[k])
    best = min(best, ((time.perf_counter() - t0) / 15, spent[0] / 15))
w, inside = best
cap = w / (w - inside + inside / 16)
print(f"N={n}: step {w * 1e3:.2f} ms, step_rows {inside * 1e3:.2f} ms, outside {1e3 * (w - inside):.2f} ms "
      f"({(w - inside) / w:.1%}); 16 threads at most {cap:.1f}x [{machine_line()}]")  # fmt: skip
