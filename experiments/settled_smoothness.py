"""Issue 18's smoothness targets per training seed and per episode, read off a benchmark.json.

    python experiments/settled_smoothness.py docs/benchmark/benchmark.json [--markdown out.md]

``experiments/targets_v1.py`` gives, per agent, the median and maximum over the 11 ideal-robot cells of the
seed-mean settled chatter and settled speed error. This script gives the finer grain the targets ("settled chatter
<= 1 rad/s and settled speed error <= 10 mm/s for every shipped agent") can also be read at, for every agent and
three groups of cells: the 11 ideal-robot v1 cells (:data:`targets_v1.IDEAL`), all v1 cells, and the AmigoBot-v0
cells (the v0 specialists' own environment):

* the maximum over (training seed, cell) of the cell's mean over its episodes, and where it is;
* the maximum over single episodes, and how many episodes exceed the target (of how many).

Settled chatter is the RMS step-to-step change of the wheel-rate command over ``t >= 5 s`` [rad/s], settled speed
error the RMS of the speed error over ``t >= 5 s`` [m/s, printed in mm/s]
(:mod:`amigo_gym.tools.training.task_metrics`). Nothing is computed here beyond maxima and counts of the benchmark's own
records (``results[].chatter_settled_rms``, ``speed_err_settled_rms`` and their ``per_episode`` lists).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from targets_v1 import IDEAL

#: the targets of issue 18: settled chatter [rad/s], settled speed error [m/s]
CHATTER_MAX = 1.0
SPEED_ERR_MAX = 0.010


def _group(doc: dict[str, Any], rows: list[dict[str, Any]], group: str) -> list[dict[str, Any]]:
    env = {s["name"]: s["env_id"] for s in doc["scenarios"]}
    if group == "v1 ideal":
        return [r for r in rows if r["scenario"] in IDEAL]
    want = "AmigoBot-v1" if group == "v1 all" else "AmigoBot-v0"
    return [r for r in rows if env.get(r["scenario"]) == want]


def table(doc: dict[str, Any]) -> list[str]:
    """The Markdown table: one line per (agent, group of cells) the agent ran."""
    rows = [r for r in doc["results"] if r.get("chatter_settled_rms") is not None]
    lines = [
        "| agent | cells | runs (seed, cell) | chatter: max of cell means [rad/s] (where) | chatter: max episode, "
        f"episodes > {CHATTER_MAX:g} | speed err: max of cell means [mm/s] (where) | speed err: max episode, "
        f"episodes > {1e3 * SPEED_ERR_MAX:g} |",
        "|---|---|---:|---|---|---|---|",
    ]
    for agent in dict.fromkeys(r["agent"] for r in rows):
        for group in ("v1 ideal", "v1 all", "v0"):
            rs = _group(doc, [r for r in rows if r["agent"] == agent], group)
            if not rs:
                continue
            c = max(rs, key=lambda r: r["chatter_settled_rms"])
            s = max(rs, key=lambda r: r["speed_err_settled_rms"])
            ce = [x for r in rs for x in r["per_episode"]["chatter_settled_rms"]]
            se = [x for r in rs for x in r["per_episode"]["speed_err_settled_rms"]]
            lines.append(
                f"| {agent} | {group} | {len(rs)} | {c['chatter_settled_rms']:.2f} ({c['scenario']}, s{c['seed']}) | "
                f"{max(ce):.2f}, {sum(x > CHATTER_MAX for x in ce)} of {len(ce)} | "
                f"{1e3 * s['speed_err_settled_rms']:.1f} ({s['scenario']}, s{s['seed']}) | "
                f"{1e3 * max(se):.1f}, {sum(x > SPEED_ERR_MAX for x in se)} of {len(se)} |"
            )
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("benchmark", type=Path, help="a benchmark.json [file]")
    ap.add_argument("--markdown", type=Path, help="also write the table here [file]")
    args = ap.parse_args(argv)
    doc = json.loads(args.benchmark.read_text())
    lines = [
        f"From `{args.benchmark}` (command: `{doc.get('command', '?')}`); "
        f"`python experiments/settled_smoothness.py {args.benchmark}`.",
        "",
        *table(doc),
    ]
    text = "\n".join(lines) + "\n"
    print(text, end="")
    if args.markdown is not None:
        tmp = args.markdown.with_suffix(args.markdown.suffix + ".tmp")
        tmp.write_text(text)
        tmp.replace(args.markdown)
    return 0


if __name__ == "__main__":
    sys.exit(main())
