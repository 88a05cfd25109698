"""CPU time to build one path of each built-in family on the float route (no compiled loops registered).

    PYTHONPATH=. python experiments/path_build_speed.py [--repeats 15]

Prints the least ``time.thread_time`` of ``--repeats`` builds of ``make_family_path(name)`` (the random family with a
fixed seed), in milliseconds.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from amigo_gym.paths import make_family_path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    for name in ("circle", "figure8", "lane_change", "random"):
        best = float("inf")
        for _ in range(args.repeats):
            rng = np.random.default_rng(5) if name == "random" else None
            t0 = time.thread_time()
            make_family_path(name, rng)
            best = min(best, time.thread_time() - t0)
        print(f"{name:12s} {best * 1e3:7.2f} ms per path", flush=True)


if __name__ == "__main__":
    main()
