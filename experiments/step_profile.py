"""Where a vector env's step spends its time, by function (``cProfile``): the compiled loops against the rest.

    NUMBA_NUM_THREADS=1 python experiments/step_profile.py AmigoBot-v0 65536 numba
    NUMBA_NUM_THREADS=2 python experiments/step_profile.py AmigoBot-v0 65536 numba-parallel [steps] [rows]

``gym.make_vec(env_id, N, vectorization_mode="vector_entry_point", kernel=kernel)``, ``reset(seed=0)``, stepped with
16 uniform random action arrays in [-1, 1] (seed 0, in turn): ``steps`` (default 100) untimed, ``steps`` timed by the
wall clock (ms a step, no profiler), ``steps`` under ``cProfile``. Prints the wall time a step and the ``rows``
(default 14) functions of most own time, in µs a step; a compiled function's own time is its whole call (numba's
threads included), so the rest of the step is what stays on the calling thread whatever the threads. The CPU is
printed: the shares move with it and the host's load.
"""

from __future__ import annotations

import cProfile
import pstats
import sys
import time

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.machine import machine_line

env_id, n, kernel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
steps = int(sys.argv[4]) if len(sys.argv) > 4 else 100
rows = int(sys.argv[5]) if len(sys.argv) > 5 else 14
env = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", kernel=kernel)
env.reset(seed=0)
rng = np.random.default_rng(0)
actions = [rng.uniform(-1.0, 1.0, (n, 2)) for _ in range(16)]
for i in range(steps):
    env.step(actions[i % 16])
t = time.perf_counter()
for i in range(steps):
    env.step(actions[i % 16])
wall = (time.perf_counter() - t) / steps
profile = cProfile.Profile()
profile.enable()
for i in range(steps):
    env.step(actions[i % 16])
profile.disable()
stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
own = sorted(((v[2], f"{k[2]} ({k[0].rsplit('/', 1)[-1]}:{k[1]})") for k, v in stats.items()), reverse=True)
total = sum(t for t, _ in own)
print(f"{env_id} N={n} kernel={kernel}: {wall * 1e6:,.0f} us a step (wall, unprofiled); {machine_line()}")
for t, name in own[:rows]:
    print(f"  {t / steps * 1e6:8,.0f} us a step ({t / total:4.0%})  {name}")
