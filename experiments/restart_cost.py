"""What a restart of AmigoBot-v1's native vector env costs: CPU time per restarted robot, and a whole episode's steps.

    python experiments/restart_cost.py mixed            # path family (mixed, random, circle, ...), the training kwargs
    python experiments/restart_cost.py circle --ideal   # without randomisation
    python experiments/restart_cost.py mixed --episode  # 600 steps of the analytic controller, per 100 and step 600

The env: N = 2048 robots of the training distribution (``benchmark.TRAINING_DISTRIBUTION``'s kwargs with ``path``
replaced), 600-step episodes, reset with seeds 0-2047. Restarts: ``env._reset_rows(np.arange(N))`` once (first
builds), then the mean CPU time of three more, per robot. ``--episode``: the CPU time of the steps in windows of 100
and of step 600 alone (every robot whose episode lasted restarts there), with the number of episode ends.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.policies.tracking import AnalyticTrackingPolicy
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else "")
ap.add_argument("path", help="the env's path family")
ap.add_argument("--ideal", action="store_true", help="no randomisation")
ap.add_argument("--episode", action="store_true", help="step 600 steps with the analytic controller")
ap.add_argument("--n", type=int, default=2048, help="robots N")
args = ap.parse_args()
kw = {**TRAINING_DISTRIBUTION["env_kwargs"], "path": args.path}
if args.ideal:
    kw.pop("randomize")
n = args.n
env = gym.make_vec("AmigoBot-v1", num_envs=n, max_episode_steps=600, autoreset_mode="SameStep", **kw)
obs, _ = env.reset(seed=list(range(n)))
print(machine_line(), kw)
if not args.episode:
    idx = np.arange(n)
    env._reset_rows(idx)  # type: ignore[attr-defined]
    t = time.process_time()
    for _ in range(3):
        env._reset_rows(idx)  # type: ignore[attr-defined]
    print(f"{(time.process_time() - t) / 3 / n * 1e6:.1f} us of CPU per restarted robot")
    raise SystemExit(0)
policy = AnalyticTrackingPolicy(env.params)  # type: ignore[attr-defined]
state, start, spent, ends = None, np.ones(n, dtype=bool), 0.0, 0
for k in range(1, 601):
    a, state = policy.predict(obs, state, start, deterministic=True)
    t = time.process_time()
    obs, _, term, trunc, _ = env.step(a)
    dt = time.process_time() - t
    spent, start = spent + dt, term | trunc
    ends += int(start.sum())
    if k == 600:
        print(f"step 600: {dt * 1e3:.1f} ms, {int(start.sum())} episode ends")
    if k % 100 == 0:
        print(f"steps {k - 99}-{k}: {spent / 100 * 1e3:.2f} ms a step, {ends} episode ends")
        spent, ends = 0.0, 0
