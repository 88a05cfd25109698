"""Per-cell 95 % intervals over training seeds from an ``amigo-gym benchmark`` JSON, against a baseline agent.

    python experiments/bench_cell_intervals.py <out>/benchmark.json --agent residual2 [--baseline analytic]

For every scenario: the baseline's H RMS (mean over its seeds; the classical controllers are deterministic, one
seed), the agent's mean over its training seeds with a 95 % percentile bootstrap interval over those seeds
(10 000 resamples, seed 0), the per-seed values, the ratio of the means, and whether the agent's interval lies
entirely below the baseline's (for a one-seed baseline: below its value). Markdown, H RMS in mm.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np


def interval(x: np.ndarray, reps: int = 10_000) -> tuple[float, float]:
    """95 % percentile bootstrap interval of the mean of ``x`` (resampling its entries)."""
    rng = np.random.default_rng(0)
    means = x[rng.integers(0, x.size, (reps, x.size))].mean(axis=1)
    return float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("benchmark_json")
    p.add_argument("--agent", required=True)
    p.add_argument("--baseline", default="analytic")
    a = p.parse_args()
    with open(a.benchmark_json) as f:
        res = json.load(f)["results"]
    cells = list(dict.fromkeys(r["scenario"] for r in res))
    print(f"| cell | {a.baseline} | {a.agent}: mean [95 % over seeds] | per seed | ratio | interval below |")
    print("|---|---:|---:|---|---:|---|")
    for c in cells:
        rows = {n: sorted((r for r in res if r["scenario"] == c and r["agent"] == n), key=lambda r: r["seed"])
                for n in (a.baseline, a.agent)}  # fmt: skip
        b = 1e3 * np.array([r["h_rms_m"] for r in rows[a.baseline]])
        x = 1e3 * np.array([r["h_rms_m"] for r in rows[a.agent]])
        blo, bhi = interval(b)
        lo, hi = interval(x)
        verdict = "yes" if hi < blo else ("no (above)" if lo > bhi else "no (overlaps)")
        print(f"| {c} | {b.mean():.2f} | {x.mean():.2f} [{lo:.2f}, {hi:.2f}] | {' '.join(f'{v:.2f}' for v in x)} | "
              f"{x.mean() / b.mean():.2f} | {verdict} |")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
