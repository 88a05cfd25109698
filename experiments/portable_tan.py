"""A ``tan`` in plain arithmetic, compiled in a numba loop, against numpy's ``np.tan``: speed and accuracy.

    PYTHONPATH=. python experiments/portable_tan.py

A lead for issue 19's AVX2 target (docs/architecture.md, "Speed"): AmigoBot-v0's compiled step takes numpy's ``tan``
twice per robot (its bits define the reference's), and numpy's float64 ``tan`` is its own SIMD code on AVX-512 but the
C library's, one value at a time, on AVX2. This times, on 4096 arguments, a ``tan`` written in plain arithmetic
(Cody–Waite reduction by pi/4 in three parts, Cephes' rational approximation, as Go's ``math.Tan``) in a compiled
loop, which LLVM vectorises, against ``np.tan``, each run in a new process twice: with this CPU's code, and with AVX2
code (``NPY_DISABLE_CPU_FEATURES`` for numpy, ``NUMBA_CPU_NAME=haswell`` for numba). Its error against a 120-bit
``mpmath`` tangent is printed in ulps beside numpy's, and the share of arguments where its bits are numpy's.
Nothing in the package uses it (a plain ``tan`` would give every CPU the same bits, but it moves v0's results by ulps).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from typing import Any

import numpy as np

P = (-1.30936939181383777646e4, 1.15351664838587416140e6, -1.79565251976484877988e7)
Q = (1.36812963470692954678e4, -1.32089234440210967447e6, 2.50083801823357915839e7, -5.38695755929454629881e7)
PI4 = (7.85398125648498535156e-1, 3.77489470793079817668e-8, 2.69515142907905952645e-15)  # pi/4 in three parts
FOUR_OVER_PI = 1.273239544735162542821171882678754627704620361328125


def plain_tan(x: float) -> float:
    """``tan(x)`` for ``|x| < 2**29`` in plain float64 arithmetic, without branches (selects), as Go's ``math.Tan``."""
    a = abs(x)
    y = np.floor(a * FOUR_OVER_PI)
    y = y + (y - 2.0 * np.floor(0.5 * y))  # the even octant at or above
    z = ((a - y * PI4[0]) - y * PI4[1]) - y * PI4[2]
    zz = z * z
    t = z + z * (zz * ((P[0] * zz + P[1]) * zz + P[2]) / ((((zz + Q[0]) * zz + Q[1]) * zz + Q[2]) * zz + Q[3]))
    r = -1.0 / t
    t = r if y - 4.0 * np.floor(0.25 * y) == 2.0 else t
    return -t if x < 0.0 else t


def measure() -> None:
    """In this process: ns per value of the compiled loop and of ``np.tan``, and their errors."""
    import mpmath
    import numba

    from amigo_gym.bench.machine import machine_line

    own = numba.njit(error_model="numpy", inline="always")(plain_tan)

    @numba.njit(error_model="numpy")
    def loop(xs: np.ndarray, out: np.ndarray) -> None:
        for i in range(xs.shape[0]):
            out[i] = own(xs[i])

    def best(f: Callable[..., object], *args: np.ndarray, n: int = 300) -> float:
        b = math.inf
        for _ in range(n):
            t = time.perf_counter()
            f(*args)
            b = min(b, time.perf_counter() - t)
        return b

    def ulps(v: np.ndarray, ref: list[Any]) -> float:
        return max(abs(float((mpmath.mpf(float(v[i])) - r) / np.spacing(abs(float(r))))) for i, r in enumerate(ref))

    mpmath.mp.prec = 120
    rng = np.random.default_rng(1)
    print(f"{machine_line()}; numba target {numba.config.CPU_NAME or 'host'}")
    for lo, hi in ((-0.2, 0.2), (-20.0, 20.0), (-2000.0, 2000.0)):
        xs = rng.uniform(lo, hi, 4096)
        mine, theirs = np.empty_like(xs), np.empty_like(xs)
        loop(xs, mine)
        t_own = best(loop, xs, mine) / xs.size * 1e9
        t_np = best(np.tan, xs, theirs) / xs.size * 1e9
        ref = [mpmath.tan(mpmath.mpf(float(v))) for v in xs[:2000]]
        same = float(np.mean(mine == theirs))
        e_own, e_np = ulps(mine, ref), ulps(theirs, ref)
        print(
            f"  x in [{lo:g}, {hi:g}]: plain tan {t_own:.2f} ns/value, np.tan {t_np:.2f} ns/value; largest error "
            f"{e_own:.2f} against {e_np:.2f} ulp; numpy's bits in {100 * same:.1f} % of values"
        )


if __name__ == "__main__":
    if sys.argv[1:] == ["--here"]:
        measure()
        sys.exit(0)
    avx2 = {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR", "NUMBA_CPU_NAME": "haswell"}
    for label, extra in (("this CPU's code", {}), ("AVX2 code", avx2)):
        with tempfile.TemporaryDirectory() as cache:
            print(f"{label}:", flush=True)
            env = {**os.environ, **extra, "NUMBA_CACHE_DIR": cache}
            subprocess.run([sys.executable, __file__, "--here"], env=env, check=True)
