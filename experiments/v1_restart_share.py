"""Where AmigoBot-v1's native vector env spends a step in the steady state of random actions: the compiled step
against the episode restarts (autoreset) and the parts of a restart, by CPU time.

    NUMBA_NUM_THREADS=1 python experiments/v1_restart_share.py [training|defaults|hard] [N] [steps]

``gym.make_vec("AmigoBot-v1", N, vectorization_mode="vector_entry_point", **kwargs)`` (default: the training
distribution, N = 4096) stepped 300 times with uniform random actions in [-1, 1] (10 drawn, in turn), then
``steps`` (default 1000) more timed: ``time.thread_time_ns`` around the whole step and around each named function
of a restart (wrapped in this process only). Prints µs a step for each, the restarted rows a step, the size of the
path arena (the rows' flat paths) against its live paths at the end, and the CPU.
"""

from __future__ import annotations

import collections
import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.envs import vector_v1
from amigo_gym.paths import batch as path_batch
from amigo_gym.sim import fast_v1_batch
from amigo_gym.task import v1 as tracking
from amigo_gym.tools.bench.env import V1_HARD
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

spent: collections.Counter[str] = collections.Counter()
rows_restarted = [0]


def timed(owner: Any, name: str, label: str) -> None:
    """Wrap ``owner.name`` to add its CPU time to ``spent[label]``."""
    f = getattr(owner, name)

    def wrapper(*a: Any, **k: Any) -> Any:
        t = time.thread_time_ns()
        try:
            return f(*a, **k)
        finally:
            spent[label] += time.thread_time_ns() - t

    setattr(owner, name, wrapper)


env_cls = vector_v1.AmigoBotV1VectorEnv
restart = env_cls._begin_rows_kernel


def counted(self: Any, idx: Any, *a: Any) -> Any:
    rows_restarted[0] += len(idx)
    return restart(self, idx, *a)


env_cls._begin_rows_kernel = counted  # type: ignore[method-assign]
parts = [
    (env_cls, "_begin_rows_kernel", "restarts, all"),
    (tracking, "draw_family", "  draw the path's family and parameters"),
    (tracking, "random_pool_path", "  the random pool's paths (cached)"),
    (fast_v1_batch.PathArena, "build", "  the family paths built in the arena (compiled)"),
    (fast_v1_batch.PathArena, "assign", "  the path arena (flat copies)"),
    (path_batch.PathBatch, "replace", "  the path batch (Python objects; built when asked for)"),
    (fast_v1_batch.BatchKernel, "start", "  the start records (compiled)"),
    (tracking, "start_state", "  the start states"),
    (env_cls, "_draws", "  the episode draws (compiled)"),
    (tracking, "episode_of", "  the episode columns"),
    (fast_v1_batch.BatchKernel, "step", "the compiled step"),
]
for owner, name, label in parts:
    timed(owner, name, label)

config = sys.argv[1] if len(sys.argv) > 1 else "training"
n = int(sys.argv[2]) if len(sys.argv) > 2 else 4096
steps = int(sys.argv[3]) if len(sys.argv) > 3 else 1000
kw = {"training": dict(TRAINING_DISTRIBUTION["env_kwargs"]), "defaults": {}, "hard": V1_HARD}[config]
env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", **kw)
env.reset(seed=0)
acts = np.random.default_rng(0).uniform(-1.0, 1.0, (10, n, 2))
for k in range(300):
    env.step(acts[k % 10])
spent.clear()
rows_restarted[0] = 0
t0 = time.thread_time_ns()
for k in range(steps):
    env.step(acts[k % 10])
total = time.thread_time_ns() - t0
print(f"{config}, N = {n}, {steps} steps: {total / steps / 1e3:,.0f} µs a step, {rows_restarted[0] / steps:.1f} rows "
      f"restarted a step [{machine_line()}]")  # fmt: skip
for _, _, label in parts:
    us = spent[label] / steps / 1e3
    print(f"  {label:58s} {us:7,.0f} µs a step ({spent[label] / total:4.0%})")
per_row = spent["restarts, all"] / max(rows_restarted[0], 1) / 1e3
print(
    f"  a restarted row: {per_row:.0f} µs; the rest of the step (Python around the kernel, infos) "
    f"{(total - spent['restarts, all'] - spent['the compiled step']) / steps / 1e3:,.0f} µs"
)
if (batch := env.unwrapped._batch) is not None:
    a = batch.arena
    live = a.used - a._dead
    print(f"  the path arena: {a.flat.size / 1e6:.2f}M floats for {live / 1e6:.2f}M live ({a.flat.size / live:.1f}x)")
