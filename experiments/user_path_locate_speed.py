"""CPU time of a path object of your own's projection (``UserPath.locate`` without the object's own ``locate``).

    PYTHONPATH=. python experiments/user_path_locate_speed.py [--num-points 1024] [--repeats 5]

The object forwards ``length``, ``closed`` and ``pose_columns`` to a figure-8 ``ClothoidPath``; prints the least
``time.thread_time`` of ``--repeats`` calls on ``--num-points`` points near the path with hints (arrays, as a vector
env's rows), and of one point of floats (as the single env), in milliseconds.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from amigo_gym.paths import UserPath, figure8


class _Mine:
    def __init__(self, path: Any) -> None:
        self.path, self.length, self.closed = path, path.length, path.closed

    def pose_columns(self, s: Any) -> Any:
        return self.path.pose_columns(s)


def _least(f: Callable[[], object], repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.thread_time()
        f()
        best = min(best, time.thread_time() - t0)
    return best * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--num-points", type=int, default=1024)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    path = figure8()
    user = UserPath(_Mine(path))
    g = np.random.default_rng(0)
    s = g.uniform(0.0, path.length, args.num_points)
    q = path.pose_columns(s)
    x, y = q.x + 0.05, q.y - 0.03
    ms = _least(lambda: user.locate(x, y, s, 0.5, 0.5), args.repeats)
    print(f"UserPath.locate, {args.num_points} points: {ms:8.2f} ms", flush=True)
    one = (float(x[0]), float(y[0]), float(s[0]))
    ms = _least(lambda: user.locate(*one, 0.5, 0.5), 10 * args.repeats)
    print(f"UserPath.locate, one point of floats: {ms:8.3f} ms", flush=True)


if __name__ == "__main__":
    main()
