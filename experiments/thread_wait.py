"""The vector env's step on numba's threads under the OpenMP wait policy the caller sets: wall and process CPU time.

    NUMBA_NUM_THREADS=2 [OMP_WAIT_POLICY=ACTIVE|PASSIVE] python experiments/thread_wait.py AmigoBot-v0 16384 2
    NUMBA_NUM_THREADS=16 python experiments/thread_wait.py AmigoBot-v1 65536 16 0 training

Arguments: env id, N, threads (1: ``kernel="numba"``; more: ``"numba-parallel"``), then optionally ``work`` 1 or 0
(default 1: each step is followed by about 200 µs of numpy work in the calling thread, where a learner would run, the
time when spinning workers compete with it; 0: the step alone, for the scaling with threads) and ``training``
(AmigoBot-v1 with the training distribution's ``env_kwargs``, ``benchmark.TRAINING_DISTRIBUTION``). Prints the least
wall time per step over 3 repeats, the process CPU time of that repeat, the threading layer and the wait policy
libgomp was given (the env sets PASSIVE and a spin count of 1000 unless the caller set a policy), the minor page
faults a step of that repeat (0: the step reuses its memory), and the CPU.
"""

from __future__ import annotations

import os
import resource
import sys
import time

import gymnasium as gym
import numba
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.tools.machine import cpu_model

env_id, n, threads = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
work = len(sys.argv) < 5 or sys.argv[4] != "0"
kwargs = {}
if "training" in sys.argv[5:]:
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

    kwargs = dict(TRAINING_DISTRIBUTION["env_kwargs"])
kernel = "numba-parallel" if threads > 1 else "numba"
env = gym.make_vec(env_id, n, vectorization_mode="vector_entry_point", kernel=kernel, **kwargs)
env.reset(seed=0)
numba.set_num_threads(threads)
actions = [np.random.default_rng(k).uniform(-1, 1, (n, 2)).astype(np.float32) for k in range(8)]
for k in range(5):
    env.step(actions[k])
steps = max(10, int(2e6 // n))
best = (float("inf"), 0.0, 0.0)
for _ in range(3):
    w0, c0, f0 = time.perf_counter(), time.process_time(), resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for k in range(steps):
        env.step(actions[k % 8])
        if work:
            np.sin(np.arange(20000.0)).sum()  # the caller's own work between steps
    w, c = (time.perf_counter() - w0) / steps, (time.process_time() - c0) / steps
    best = min(best, (w, c, (resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0) / steps))
wait, spin = os.environ.get("OMP_WAIT_POLICY", "default"), os.environ.get("GOMP_SPINCOUNT", "default")
print(
    f"{env_id}{' training' if kwargs else ''} N={n} threads={threads} work={int(work)} "
    f"layer={numba.threading_layer()} OMP_WAIT_POLICY={wait} GOMP_SPINCOUNT={spin}: "
    f"wall {best[0] * 1e6:.0f} us, CPU {best[1] * 1e6:.0f} us, {best[2]:.0f} minor faults a step; {cpu_model()}, "
    f"load {os.getloadavg()[0]:.1f}"
)
