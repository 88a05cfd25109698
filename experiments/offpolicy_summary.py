"""Validation H RMS at equal CPU seconds of training, from the curves of experiments/offpolicy_quality.py.

    python experiments/offpolicy_summary.py docs/figures/offpolicy/*.curve.csv --at 30 60 90 120

For each curve and each mark ``t``: the last evaluation whose training time ``cpu_s`` is at most ``t`` (the policy
one would hold after ``t`` CPU seconds of training), as ``H RMS [mm] (settled chatter [rad/s])``, and the env-steps
it had seen. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("curves", nargs="+")
    p.add_argument("--at", type=float, nargs="+", default=[30.0, 60.0, 90.0, 120.0], help="CPU seconds")
    a = p.parse_args()
    print("| run | " + " | ".join(f"{t:g} CPU s" for t in a.at) + " |")
    print("|---|" + "---:|" * len(a.at))
    for path in a.curves:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        cells = []
        for t in a.at:
            held = [r for r in rows if float(r["cpu_s"]) <= t]
            if not held or float(rows[-1]["cpu_s"]) < t:
                cells.append("(not reached)" if held else "")
                continue
            r = held[-1]
            cells.append(
                f"{1e3 * float(r['eval_h_rms_m']):.2f} ({float(r['eval_chatter_settled_rms']):.1f}; "
                f"{int(float(r['env_steps'])):,} steps)"
            )
        print(f"| {Path(path).name.removesuffix('.curve.csv')} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
