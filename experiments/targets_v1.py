"""Issue 18's targets read off a benchmark.json: IQM of H RMS on the ideal-robot cells with 95 % intervals, the
ratio to the analytic controller, settled figures, chatter, speed error, and seeds against their algorithm's median.

    amigo-gym benchmark --agents analytic 'ppo_fast=agents/pretrained/v1/ppo_fast/*.zip' ... --out runs/bench
    python experiments/targets_v1.py runs/bench/benchmark.json [--markdown out.md]

The ideal-robot cells are the suite's v1 scenarios with the nominal robot, no delay, no noise and dt 0.1 s (the
11 of :data:`IDEAL`); intervals are the benchmark's own stratified bootstrap over training seeds
(:func:`amigo_gym.tools.training.intervals.stratified_bootstrap`, 10 000 replications, seed 0). Nothing is tuned here:
the cells are fixed by the suite and the figures are those of the test seeds the benchmark ran.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from amigo_gym.tools.training.intervals import iqm, stratified_bootstrap

IDEAL = (
    "circle_r1_ccw",
    "circle_r0.5_ccw",
    "circle_r0.5_cw",
    "circle_r2_cw",
    "circle_v0.1",
    "circle_v0.4",
    "circle_v_random",
    "figure8",
    "random_paths",
    "lane_change",
    "mixed",
)
DELAY_AND_MISMATCH = ("delay_0.1", "delay_0.25", "wheels_plus5", "wheels_minus5", "wheels_unequal")


def _matrix(rows: list[dict], agent: str, cells: tuple[str, ...], key: str) -> np.ndarray:
    by = {(r["seed"], r["scenario"]): r[key] for r in rows if r["agent"] == agent and r["scenario"] in cells}
    seeds = sorted({s for s, _ in by})
    return np.array([[by[(s, c)] for c in cells] for s in seeds], dtype=np.float64)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("benchmark", type=Path, help="a benchmark.json [file]")
    ap.add_argument("--markdown", type=Path, help="also write the tables here [file]")
    args = ap.parse_args(argv)
    doc = json.loads(args.benchmark.read_text())
    rows = [r for r in doc["results"] if r.get("h_rms_m") is not None]
    agents = list(dict.fromkeys(r["agent"] for r in rows))
    lines = [
        f"From `{args.benchmark}` (command: `{doc.get('command', '?')}`).",
        "",
        "Ideal-robot cells (11): IQM over (seed, cell) [95 % interval], ratio to the analytic controller's IQM;",
        "medians over the cells of the seed-mean settled chatter and settled speed error.",
        "",
        "| agent | seeds | H RMS IQM [mm] | ratio | settled H RMS IQM [mm] | ratio "
        "| chatter settled [rad/s] median (max) | speed err settled [mm/s] median (max) |",
        "|---|---:|---|---:|---|---:|---|---|",
    ]
    ref: dict[str, float] = {}
    # agents the run did not evaluate on every ideal cell (AmigoBot-v0's specialists in a full run) are left out
    agents = [a for a in agents if {r["scenario"] for r in rows if r["agent"] == a} >= set(IDEAL)]
    for agent in agents:
        out = []
        for key in ("h_rms_m", "h_rms_settled_m"):
            x = _matrix(rows, agent, IDEAL, key) * 1e3
            point, (lo, hi) = stratified_bootstrap(x, iqm, reps=10_000, seed=0)
            if agent == "analytic":
                ref[key] = float(point)
            ratio = float(point) / ref[key] if key in ref else float("nan")
            out.append(f"{float(point):.2f} [{float(lo):.2f}, {float(hi):.2f}] | {ratio:.2f}")
        ch = _matrix(rows, agent, IDEAL, "chatter_settled_rms").mean(axis=0)
        sp = _matrix(rows, agent, IDEAL, "speed_err_settled_rms").mean(axis=0) * 1e3
        n = _matrix(rows, agent, IDEAL, "h_rms_m").shape[0]
        lines.append(
            f"| {agent} | {n} | {out[0]} | {out[1]} | {np.median(ch):.2f} ({ch.max():.2f}) | "
            f"{np.median(sp):.1f} ({sp.max():.1f}) |"
        )
    v1 = tuple(dict.fromkeys(r["scenario"] for r in rows if not r["scenario"].startswith("v0_")))
    held = tuple(s["name"] for s in doc["scenarios"] if s.get("held_out") and s["name"] in v1)
    for label, cells in ((f"All {len(v1)} v1 cells", v1), (f"The {len(held)} held-out v1 cells", held)):
        scores = {a: float(iqm(_matrix(rows, a, cells, "h_rms_m") * 1e3)) for a in agents}
        lines += ["", f"{label} (the v0 cells left out): IQM of H RMS over (seed, cell) [mm]: "
                  + ", ".join(f"{a} {v:.2f}" for a, v in scores.items())]  # fmt: skip
    lines += [
        "",
        "Delay and wheel-mismatch cells: mean H RMS over the episodes [mm], per training seed.",
        "",
        "| agent | " + " | ".join(DELAY_AND_MISMATCH) + " |",
        "|---|" + "---|" * len(DELAY_AND_MISMATCH),
    ]
    for agent in agents:
        x = _matrix(rows, agent, DELAY_AND_MISMATCH, "h_rms_m") * 1e3
        cells = [" / ".join(f"{v:.2f}" for v in x[:, j]) for j in range(x.shape[1])]
        lines.append(f"| {agent} | " + " | ".join(cells) + " |")
    lines += ["", "Seeds against their algorithm's median (IQM of H RMS over all cells of the run) [mm]:", ""]
    for agent in agents:
        per_seed = defaultdict(list)
        for r in rows:
            if r["agent"] == agent:
                per_seed[r["seed"]].append(r["h_rms_m"] * 1e3)
        score = {s: float(iqm(np.array([v]))) for s, v in sorted(per_seed.items())}
        med = float(np.median(list(score.values())))
        worst = max(score.values()) / med
        shown = ", ".join(f"s{s} {v:.2f}" for s, v in score.items())
        lines.append(f"- {agent}: {shown}; worst/median {worst:.2f} ({'ok' if worst <= 2 else 'a failed seed'})")
    text = "\n".join(lines) + "\n"
    print(text, end="")
    if args.markdown:
        args.markdown.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
