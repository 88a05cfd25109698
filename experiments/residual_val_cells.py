"""The protocol's validation cells for choosing between agents (never a test cell or seed).

    python experiments/residual_val_cells.py --models res=experiments/candidates/residual_s0.zip \
        [--cells val_delay_0.1 val_delay_0.25 ...] [--seeds 20] [--json out.json]

For each AmigoBot-v1 cell of :func:`amigo_gym.tools.training.protocol.validation_cells` named in ``--cells``
(default: all), on the first ``--seeds`` validation seeds (one episode each,
:func:`amigo_gym.tools.training.benchmark.evaluate`, deterministic), the analytic controller
(:class:`amigo_gym.policies.AnalyticTrackingPolicy`, nominal robot) and every ``NAME=ZIP`` fast-PPO model.
Prints one Markdown row per cell: the mean H cross-track RMS over the episodes [mm] with a 95 % bootstrap interval
over episodes (2 000 resamples, seed 0), and the ratio of each model's mean to the analytic's.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from amigo_gym.tools.training.benchmark import AgentSpec, evaluate, make_env
from amigo_gym.tools.training.protocol import validation_cells


def ci(x: np.ndarray, reps: int = 2000) -> tuple[float, float]:
    """95 % percentile bootstrap interval of the mean of ``x``."""
    rng = np.random.default_rng(0)
    means = x[rng.integers(0, x.size, (reps, x.size))].mean(axis=1)
    return float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="*", default=[], help="NAME=ZIP fast-PPO models")
    p.add_argument("--cells", nargs="*", default=None, help="validation cell names (default: every v1 cell)")
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--json", default=None)
    a = p.parse_args()
    by = {sc.name: sc for sc in validation_cells("AmigoBot-v1", a.seeds)}
    unknown = sorted(set(a.cells or ()) - set(by))
    if unknown:
        p.error(f"--cells must be validation cells {sorted(by)}, got {unknown}")
    specs = [AgentSpec("analytic")]
    for m in a.models:
        name, path = m.split("=", 1)
        specs.append(AgentSpec(name, 0, path, "fastppo_residual"))
    out: dict[str, dict[str, list[float]]] = {}
    print("| cell | " + " | ".join(f"{s.name} H RMS [mm]" for s in specs) + " | " +
          " | ".join(f"{s.name}/analytic" for s in specs[1:]) + " |")  # fmt: skip
    print("|---" * (2 * len(specs)) + "|")
    for cell in a.cells or list(by):
        sc = by[cell]
        env = make_env(sc)
        row = {}
        for s in specs:
            eps = evaluate(s.instantiate(env), env, sc)
            row[s.name] = [1e3 * e["h_rms_m"] for e in eps]
        env.close()
        out[cell] = row
        base = float(np.mean(row["analytic"]))
        cells = []
        for s in specs:
            x = np.array(row[s.name])
            lo, hi = ci(x)
            cells.append(f"{x.mean():.2f} [{lo:.2f}, {hi:.2f}]")
        ratios = [f"{np.mean(row[s.name]) / base:.2f}" for s in specs[1:]]
        print(f"| {cell} | " + " | ".join(cells) + " | " + " | ".join(ratios) + " |", flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
