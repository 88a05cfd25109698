"""Do two trees step AmigoBot-v1 alike? Record a vector env's observations and cross-track errors, then compare.

    PYTHONPATH=<tree> NUMBA_NUM_THREADS=1 python experiments/v1_trace_compare.py record <out.npz>
    python experiments/v1_trace_compare.py compare <a.npz> <b.npz>

``record``: 2,048 robots of the training distribution and of ``V1_HARD``, reset with seed 0, 200 steps of actions
``0.5 + 0.3 U(-1, 1)`` (seed 1). ``compare``: per array, the largest absolute difference and how many entries differ.
"""

from __future__ import annotations

import sys

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.tools.bench.env import V1_HARD
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

if sys.argv[1] == "record":
    out = {}
    for name, kw in (("train", dict(TRAINING_DISTRIBUTION["env_kwargs"])), ("hard", dict(V1_HARD))):
        env = gym.make_vec("AmigoBot-v1", 2048, vectorization_mode="vector_entry_point", **kw)
        obs, _ = env.reset(seed=0)
        rng = np.random.default_rng(1)
        trace, errors = [obs], []
        for _ in range(200):
            obs, _, _, _, info = env.step(rng.uniform(-1.0, 1.0, (2048, 2)) * 0.3 + 0.5)
            trace.append(obs)
            errors.append(info["cross_track_error"])
        out[name], out[f"{name}_e"] = np.array(trace), np.array(errors)
    np.savez(sys.argv[2], **out)
else:
    a, b = np.load(sys.argv[2]), np.load(sys.argv[3])
    for k in a.files:
        d = np.abs(a[k].astype(np.float64) - b[k].astype(np.float64))
        print(f"{k} {a[k].shape}: max |difference| {d.max():.3g}, {int((d > 0).sum())} of {d.size} entries differ")
