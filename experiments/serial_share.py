"""How much of AmigoBot-v1's vector step is outside its parallel loop, and what that leaves to many threads (Amdahl).

    NUMBA_NUM_THREADS=1 python experiments/serial_share.py 65536            # N (default 16384)
    NUMBA_NUM_THREADS=1 python experiments/serial_share.py 16384 training   # as train-fast steps it in a long run

The defaults with random actions on one thread (``kernel="numba"``): the wall time of the step and of the compiled
row loop ``step_rows`` inside it (the loop ``numba-parallel`` divides; timed by a wrapper), least of 4 repeats of 15
steps; the rest runs on one thread whatever the thread count, so ``t / (rest + loop / 16)`` bounds 16 threads.

``training``: the env as ``train-fast`` makes it (the training distribution, ``autoreset_mode="SameStep"``, 600-step
episodes) in the steady state of a long run: the episodes' step counts spread uniformly over 0..599 (so about N/600
robots restart each step), 400 steps first (the random-path pool then built, as after a few minutes of training),
then 100 steps timed, zero actions; also the time in the restarts (``_reset_rows``) and the infos' scatter
(``scatter_infos``), the two largest parts of the rest.
"""

from __future__ import annotations

import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
import amigo_gym.envs.vector_v1 as vector_v1
from amigo_gym.tools.machine import machine_line

n = int(sys.argv[1]) if len(sys.argv) > 1 else 16384
training = "training" in sys.argv[2:]
spent = {"step_rows": 0.0, "restarts": 0.0, "scatter_infos": 0.0}


def timed(f: Any, name: str) -> Any:
    def call(*args: Any) -> Any:
        t = time.perf_counter()
        out = f(*args)
        spent[name] += time.perf_counter() - t
        return out

    return call


if training:
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

    kw: dict[str, Any] = {"max_episode_steps": 600, "autoreset_mode": "SameStep", **TRAINING_DISTRIBUTION["env_kwargs"]}
else:
    kw = {}
env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", kernel="numba", **kw)
env.reset(seed=0)
u: Any = env.unwrapped
batch = u._batch
batch._step_rows = timed(batch._step_rows, "step_rows")
if training:
    u._state.steps[:] = np.random.default_rng(0).integers(0, 600, n)  # a long run's spread of episode ages
    u._reset_rows = timed(u._reset_rows, "restarts")
    vector_v1.scatter_infos = timed(vector_v1.scatter_infos, "scatter_infos")
    zero = np.zeros((n, 2))
    for _ in range(400):
        env.step(zero)
    runs = [[zero] * 100]
else:
    acts = np.random.default_rng(0).uniform(-1.0, 1.0, (15, n, 2))
    env.step(acts[0])
    runs = [list(acts)] * 4
best: tuple[float, ...] = (float("inf"),)
for r, actions in enumerate(runs):
    if not training:
        env.reset(seed=r)
    spent.update(dict.fromkeys(spent, 0.0))
    t0 = time.perf_counter()
    for a in actions:
        env.step(a)
    k = len(actions)
    best = min(best, ((time.perf_counter() - t0) / k, *(v / k for v in spent.values())))
w, inside, restarts, scatter = best
cap = w / (w - inside + inside / 16)
parts = f" (restarts {restarts * 1e3:.2f} ms, infos' scatter {scatter * 1e3:.2f} ms)" if training else ""
label = f"N={n}{' training' if training else ''}"
print(f"{label}: step {w * 1e3:.2f} ms, step_rows {inside * 1e3:.2f} ms, outside {1e3 * (w - inside):.2f} ms "
      f"({(w - inside) / w:.1%}){parts}; 16 threads at most {cap:.1f}x [{machine_line()}]")  # fmt: skip
