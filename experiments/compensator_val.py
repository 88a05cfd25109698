"""The validation cells' ratios to the analytic controller (mean H RMS over the validation seeds) of the package's
delay compensator and of a shipped ``compensator_residual`` seed, loaded as a user loads it (``load_pretrained``).

    python experiments/compensator_val.py [agents/pretrained/v1/compensator_residual/compensator_residual_s0.zip]
"""

from __future__ import annotations

import sys

import numpy as np

from amigo_gym.policies import AnalyticTrackingPolicy, DelayCompensatedPolicy, load_pretrained
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import evaluate, make_env
from amigo_gym.tools.training.protocol import validation_cells

path = sys.argv[1] if len(sys.argv) > 1 else "agents/pretrained/v1/compensator_residual/compensator_residual_s0.zip"
model = load_pretrained(path)
print(machine_line())
print(
    f"| cell | analytic [mm] | delay_compensated / analytic | {path.split('/')[-1]} / analytic |\n|---|---:|---:|---:|"
)
for sc in validation_cells("AmigoBot-v1", 20):
    env = make_env(sc)
    p = env.unwrapped.params if hasattr(env, "unwrapped") else env.params
    agents = (AnalyticTrackingPolicy(p), DelayCompensatedPolicy(p), model)
    m = [float(np.mean([1e3 * e["h_rms_m"] for e in evaluate(ag, env, sc)])) for ag in agents]
    print(f"| {sc.name} | {m[0]:.2f} | {m[1] / m[0]:.3f} | {m[2] / m[0]:.3f} |", flush=True)
