"""One AmigoBot-v1 step against one AmigoBot-v0 step through ``gym.make`` (issue 35's "single step <= 1.2"), timed as
``bench-env`` times single envs, with two envs and with the four that ``amigo-gym bench-env --v1`` times together.

    NUMBA_NUM_THREADS=1 python experiments/single_ratio.py [runs] [warmup]

``amigo_gym.tools.bench.time_envs`` (median of 7 round-robin repeats of >= 0.2 s, random actions, a reset when an
episode ends) of v1 and v0 alone, then of v1, ``V1_HARD``, the training distribution and v0 (``bench-env``'s set),
``runs`` times each (default 2), after ``warmup`` untimed steps (default 0); prints the v1 / v0 ratios and the CPU.
"""

from __future__ import annotations

import sys

import gymnasium as gym

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.bench import time_envs
from amigo_gym.tools.bench.env import V1_HARD
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

runs = int(sys.argv[1]) if len(sys.argv) > 1 else 2
warmup = int(sys.argv[2]) if len(sys.argv) > 2 else 0
sets = {
    "v1 and v0": {"v1": ("AmigoBot-v1", {}), "v0": ("AmigoBot-v0", {})},
    "bench-env's four": {"v1": ("AmigoBot-v1", {}), "hard": ("AmigoBot-v1", V1_HARD),
                         "training": ("AmigoBot-v1", dict(TRAINING_DISTRIBUTION["env_kwargs"])),
                         "v0": ("AmigoBot-v0", {})},
}  # fmt: skip
print(machine_line())
for _ in range(runs):
    for label, envs in sets.items():
        t = time_envs({k: gym.make(e, **kw) for k, (e, kw) in envs.items()}, 7, 0.2, 0, warmup)
        print(f"{label}: v1 {t['v1'] * 1e6:.2f} us, v0 {t['v0'] * 1e6:.2f} us, v1 / v0 {t['v1'] / t['v0']:.3f}")
