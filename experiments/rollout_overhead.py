"""CPU time per env step of ``train-fast``'s rollout outside the env step and the networks' forward passes (the
features, their normaliser, the actions, the bookkeeping), on the CPU with one torch thread and one env thread.

    python experiments/rollout_overhead.py --n 16384 --iters 4

Settings: ``agents/hyperparams/fastppo_gpu.yml`` without the curriculum at ``num_envs = --n``. One rollout warms up;
then ``--iters`` rollouts, each timed by this thread's CPU clock and the wall clock less the time inside
``env.step`` and the actor's and critic's ``forward``. Prints the least and the median per env step [µs] and the load.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from amigo_gym.policies.learned import FeatureBuilder
from amigo_gym.tools.training import fastppo as fp

ROOT = Path(__file__).resolve().parent.parent
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else "")
ap.add_argument("--n", type=int, default=16384, help="robots N")
ap.add_argument("--iters", type=int, default=4, help="rollouts timed")
args = ap.parse_args()
hp: dict[str, Any] = fp.load_settings_yaml(ROOT / "agents" / "hyperparams" / "fastppo_gpu.yml")
hp |= {"curriculum_max_curvature": 0.0, "hidden": tuple(hp["hidden"]), "num_envs": args.n, "env_threads": 1}
hp |= {"minibatch_size": max(1, args.n * hp["rollout_steps"] // 8), "device": "cpu", "threads": 1}
s = fp.FastPPOSettings(**hp | {"total_steps": 10**9, "seed": 0})
torch.set_num_threads(1)
builder = FeatureBuilder(s.spec())
run = fp._new_run(s, builder, "cpu")
buf = fp._Buffers.allocate(s.rollout_steps, s.num_envs, builder.dim, "cpu")
excluded = [0.0, 0.0]  # this thread's CPU time and wall time inside the wrapped calls


def timed(f: Any) -> Any:
    def call(*a: Any) -> Any:
        c0, w0 = time.thread_time(), time.perf_counter()
        y = f(*a)
        excluded[0] += time.thread_time() - c0
        excluded[1] += time.perf_counter() - w0
        return y

    return call


run.env.step = timed(run.env.step)
run.net.actor.forward = timed(run.net.actor.forward)
run.net.critic.forward = timed(run.net.critic.forward)
fp.rollout(s, run, builder, buf, "cpu")
res = []
for _ in range(args.iters):
    excluded[:] = [0.0, 0.0]
    c0, w0 = time.thread_time(), time.perf_counter()
    fp.rollout(s, run, builder, buf, "cpu")
    c, w = time.thread_time() - c0, time.perf_counter() - w0
    res.append([(c - excluded[0]) / s.rollout_steps * 1e6, (w - excluded[1]) / s.rollout_steps * 1e6])
r = np.array(res)
print(f"N = {args.n}: outside the env and the networks, per env step: CPU least {r[:, 0].min():.0f} median "
      f"{np.median(r[:, 0]):.0f} us, wall least {r[:, 1].min():.0f} median {np.median(r[:, 1]):.0f} us; "
      f"load {os.getloadavg()[0]:.2f}")  # fmt: skip
