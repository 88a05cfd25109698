"""Time and peak memory of fitting the most points from_points accepts (amigo_gym.paths.points.MAX_POINTS), with the
CPU they were measured on (docs/amigobot_v1.md, "Paths of your own", quotes it).

    PYTHONPATH=. python experiments/bench_points.py [--n 1000000] [--length 1000] [--smoothing 0.02]

The points: a wavy open path y = 2 sin(x / 5) over ``--length`` metres of x (987 m of path by default; curvature at
most 0.08 1/m), evenly sampled; with ``--smoothing`` Gaussian noise of that size is added and the smoothing fit
runs. Prints the fit's wall time, the process's peak resident memory before and after, the segments and the
measured bound.
"""

from __future__ import annotations

import argparse
import platform
import resource
import time

import numpy as np


def cpu() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--length", type=float, default=950.0)
    ap.add_argument("--smoothing", type=float, default=None)
    args = ap.parse_args()
    from amigo_gym.paths import fit_points

    x = np.linspace(0.0, args.length, args.n)
    pts = np.c_[x, 2.0 * np.sin(x / 5.0)]
    if args.smoothing:
        pts += np.random.default_rng(0).normal(size=pts.shape) * args.smoothing
    fit_points(pts[:: max(1, args.n // 100)])  # imports (scipy) outside the timing
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10
    t0 = time.perf_counter()
    fit = fit_points(pts, smoothing=args.smoothing)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10
    print(f"cpu: {cpu()} ({platform.machine()}), python {platform.python_version()}, numpy {np.__version__}")
    print(
        f"points {args.n}, path {fit.path.length:.1f} m, smoothing {args.smoothing}: fit {wall:.2f} s, "
        f"peak RSS {peak:.0f} MiB (before the fit {before:.0f} MiB), {len(fit.path.segments)} segments, "
        f"max_error {fit.max_error:.3g} m"
    )


if __name__ == "__main__":
    main()
