"""Per test cell: an agent's H cross-track RMS against the analytic controller's, paired by episode seed.

    python experiments/paired_cells.py docs/benchmark/robust/benchmark.json --agent robust

Reads a ``benchmark.json`` of ``amigo-gym benchmark`` that ran ``analytic`` and ``--agent`` (any number of training
seeds) on the same cells and reset seeds. Prints one Markdown row per cell: the analytic controller's mean H RMS
[mm], the agent's per training seed and over seeds, the ratio of the means, and the paired difference (agent minus
analytic, per reset seed, averaged over the training seeds) with a 95 % percentile bootstrap interval over the reset
seeds (10,000 resamples, seed 0), the failed episodes and the settled chatter [rad/s]. ``--marginal``: then one row
per cell with each side's own 95 % percentile bootstrap interval of its mean H RMS over its episodes (10,000
resamples, seed 0; the agent's episodes of all training seeds pooled) and whether the two overlap. Last, the trimmed
mean (25 % cut each side, ``scipy.stats.trim_mean``) of the per-cell means of both over the cells of the table.
"""

from __future__ import annotations

import argparse
import json

import numpy as np
from scipy.stats import trim_mean


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("json")
    p.add_argument("--agent", required=True)
    p.add_argument("--marginal", action="store_true", help="also each side's own interval over its episodes")
    a = p.parse_args()
    with open(a.json, encoding="utf-8") as f:
        doc = json.load(f)
    by: dict[tuple[str, str], list[dict]] = {}
    for r in doc["results"]:
        by.setdefault((r["agent"], r["scenario"]), []).append(r)
    rng = np.random.default_rng(0)
    print(
        "| cell | held out | analytic [mm] | " + a.agent + " per seed [mm] | ratio | paired diff [mm] (95 % CI) "
        "| failed | chatter settled [rad/s] |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    marginal, means = [], []
    for sc in doc["scenarios"]:
        name = sc["name"]
        if (a.agent, name) not in by:
            continue
        base = np.array(by[("analytic", name)][0]["per_episode"]["h_rms_m"]) * 1e3
        runs = sorted(by[(a.agent, name)], key=lambda r: r["seed"])
        ag = np.array([r["per_episode"]["h_rms_m"] for r in runs]) * 1e3
        diff = ag.mean(axis=0) - base
        boot = diff[rng.integers(0, diff.size, (10_000, diff.size))].mean(axis=1)
        lo, hi = np.percentile(boot, [2.5, 97.5])
        means.append((base.mean(), ag.mean()))
        failed = int(sum(np.sum(r["per_episode"]["failure"]) for r in runs))
        chatter = np.mean([r["chatter_settled_rms"] for r in runs])
        seeds = ", ".join(f"{x:.2f}" for x in ag.mean(axis=1))
        print(
            f"| {name} | {'yes' if sc['held_out'] else ''} | {base.mean():.2f} | {seeds} | "
            f"{ag.mean() / base.mean():.2f} | {diff.mean():+.2f} [{lo:+.2f}, {hi:+.2f}] | "
            f"{failed} of {ag.size} | {chatter:.3f} |"
        )
        cis = []
        for x in (base, ag.ravel()):
            lo_hi = np.percentile(x[rng.integers(0, x.size, (10_000, x.size))].mean(axis=1), [2.5, 97.5])
            cis.append((float(lo_hi[0]), float(lo_hi[1])))
        overlap = cis[0][0] <= cis[1][1] and cis[1][0] <= cis[0][1]
        marginal.append(f"| {name} | [{cis[0][0]:.2f}, {cis[0][1]:.2f}] | [{cis[1][0]:.2f}, {cis[1][1]:.2f}] | "
                        f"{'yes' if overlap else 'no'} |")  # fmt: skip
    t_base, t_agent = (float(trim_mean([m[j] for m in means], 0.25)) for j in (0, 1))
    print(f"\nTrimmed mean (25 %) of the per-cell means over these {len(means)} cells: analytic {t_base:.2f} mm, "
          f"{a.agent} {t_agent:.2f} mm")  # fmt: skip
    if a.marginal:
        print(f"\n| cell | analytic, 95 % CI [mm] | {a.agent}, 95 % CI [mm] | overlap |\n|---|---:|---:|---|")
        print("\n".join(marginal))


if __name__ == "__main__":
    main()
