"""Per test cell: an agent's H cross-track RMS against the analytic controller's, paired by episode seed.

    python experiments/paired_cells.py docs/benchmark/robust/benchmark.json --agent robust

A reader of ``benchmark.json``'s ``paired`` (``amigo_gym.tools.training.benchmark.paired_differences``, its fields in
that module's docstring); a document written before ``paired`` existed, or without ``--agent`` in it, is paired here
by the same function with 10,000 resamples and seed 0. Prints one Markdown row per cell: the analytic controller's
mean H RMS [mm], the agent's per training seed, the ratio of the means, and the paired difference (agent minus
analytic, per reset seed, averaged over the training seeds) with its 95 % percentile bootstrap interval over the
reset seeds, the failed episodes and the settled chatter [rad/s]. ``--marginal``: then one row per cell with each
side's own 95 % percentile bootstrap interval of its mean H RMS over its episodes (the agent's episodes of all
training seeds pooled) and whether the two overlap. Last, the trimmed mean (25 % cut each side) of the per-cell
means of both over the cells of the table.
"""

from __future__ import annotations

import argparse
import json

from amigo_gym.tools.training.benchmark import paired_differences


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("json")
    p.add_argument("--agent", required=True)
    p.add_argument("--marginal", action="store_true", help="also each side's own interval over its episodes")
    a = p.parse_args()
    with open(a.json, encoding="utf-8") as f:
        doc = json.load(f)
    paired = doc.get("paired") or {}
    if a.agent not in paired.get("agents", {}):
        paired = paired_differences(doc, reps=10_000, seed=0)
    if a.agent not in paired["agents"]:
        raise SystemExit(f"{a.json}: no cell where both {a.agent!r} and {paired['baseline']!r} ran")
    entry = paired["agents"][a.agent]
    print(
        "| cell | held out | analytic [mm] | " + a.agent + " per seed [mm] | ratio | paired diff [mm] (95 % CI) "
        "| failed | chatter settled [rad/s] |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for c in entry["cells"]:
        lo, hi = c["diff_ci95_mm"]
        seeds = ", ".join(f"{x:.2f}" for x in c["agent_seeds_mm"])
        ratio = "–" if c["ratio"] is None else f"{c['ratio']:.2f}"
        chatter = "–" if c["chatter_settled_rms"] is None else f"{c['chatter_settled_rms']:.3f}"
        print(
            f"| {c['scenario']} | {'yes' if c['held_out'] else ''} | {c['baseline_mm']:.2f} | {seeds} | {ratio} | "
            f"{c['diff_mm']:+.2f} [{lo:+.2f}, {hi:+.2f}] | {c['failed']} of {c['agent_episodes']} | {chatter} |"
        )
    t = entry["trimmed_mean_mm"]
    print(f"\nTrimmed mean (25 %) of the per-cell means over these {len(entry['cells'])} cells: analytic "
          f"{t['baseline']:.2f} mm, {a.agent} {t['agent']:.2f} mm")  # fmt: skip
    if a.marginal:
        print(f"\n| cell | analytic, 95 % CI [mm] | {a.agent}, 95 % CI [mm] | overlap |\n|---|---:|---:|---|")
        for c in entry["cells"]:
            (b_lo, b_hi), (g_lo, g_hi) = c["baseline_ci95_mm"], c["agent_ci95_mm"]
            print(f"| {c['scenario']} | [{b_lo:.2f}, {b_hi:.2f}] | [{g_lo:.2f}, {g_hi:.2f}] | "
                  f"{'yes' if c['overlap'] else 'no'} |")  # fmt: skip


if __name__ == "__main__":
    main()
