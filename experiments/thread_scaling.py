"""AmigoBot-v1's vector step (defaults, random actions) on 1, 2, 8 and 16 of numba's threads in one process, then with
dynamic chunks of 64 rows; the machine's topology first (``lscpu``).

    NUMBA_NUM_THREADS=16 python experiments/thread_scaling.py 65536 15      # N, steps per repeat

Prints the least wall time per step of 3 repeats for each thread count (``kernel="numba-parallel"`` throughout).
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numba
import numpy as np

import amigo_gym  # noqa: F401

n, steps = int(sys.argv[1]), int(sys.argv[2])
lscpu = "lscpu | grep -Ei 'model name|thread|core|socket|numa|mhz|cache'"
print(subprocess.run(lscpu, shell=True, capture_output=True, text=True).stdout)
print("siblings of cpu0:", Path("/sys/devices/system/cpu/cpu0/topology/thread_siblings_list").read_text().strip())
env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", kernel="numba-parallel")
env.reset(seed=0)
acts = [np.random.default_rng(k).uniform(-1, 1, (n, 2)).astype(np.float32) for k in range(8)]
t0 = time.perf_counter()
env.step(acts[0])
print(f"first step (compile) {time.perf_counter() - t0:.1f} s", flush=True)
for chunk, counts in ((0, (1, 2, 8, 16)), (64, (8, 16))):
    numba.set_parallel_chunksize(chunk)
    for t in (t for t in counts if t <= numba.config.NUMBA_NUM_THREADS):
        numba.set_num_threads(t)
        for k in range(2):
            env.step(acts[k])
        best = 1e9
        for _ in range(3):
            t0 = time.perf_counter()
            for k in range(steps):
                env.step(acts[k % 8])
            best = min(best, (time.perf_counter() - t0) / steps)
        print(f"v1 N={n} threads={t} chunksize={chunk}: {best * 1e3:.2f} ms a step", flush=True)
