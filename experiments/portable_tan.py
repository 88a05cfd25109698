"""``tan`` in plain arithmetic, compiled in a numba loop, against numpy's ``np.tan``: speed and agreement.

    PYTHONPATH=. python experiments/portable_tan.py                 # speed, this CPU's code and AVX2 code
    PYTHONPATH=. python experiments/portable_tan.py --agree 10000000 # agreement with math.tan and np.tan

A lead for issue 19's AVX2 target (docs/architecture.md, "Speed"): AmigoBot-v0's compiled step takes numpy's ``tan``
twice per robot (its bits define the reference's), and numpy's float64 ``tan`` is its own SIMD code on AVX-512 but the
C library's, one value at a time, on AVX2. Timed on 4096 arguments (``time.thread_time`` minima over 300 repeats), in
a new process each with a numba cache of its own: with this CPU's code, and with AVX2 code (``NPY_DISABLE_CPU_FEATURES``
for numpy; for numba ``NUMBA_CPU_NAME=haswell`` **and** ``NUMBA_CPU_FEATURES=""``: with the name alone numba keeps
the host's features, AVX-512 included, and emits ``zmm`` code). The candidates, each compiled in a loop LLVM
vectorises:

- ``ulp tan``: Cody–Waite reduction by pi/4 in three parts, Cephes' rational approximation (as Go's ``math.Tan``),
  about 1 ulp; numpy's bits on about 96 % of arguments (its errors printed against a 120-bit ``mpmath`` tangent);
- ``tan_dd``, ``tan_fast``, ``tan_cr`` of ``experiments/cr_tan.py``: correctly rounded almost always
  (double-double; ``tan_fast`` with a rounding test, ``tan_cr`` = ``tan_fast`` then ``tan_dd`` for the arguments whose
  test fails, in a second loop).

``--agree N``: ``tan_cr`` (compiled) against ``math.tan`` (the C library) and ``np.tan`` on ``N`` random arguments
(uniform on ``|x| < 0.5``, ``20``, ``1e4``, a third each); every disagreement is checked against ``mpmath`` at 160 bits:
the counts of disagreements and of those where each side is the correctly rounded one.
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


def loops() -> dict[str, Callable[[np.ndarray, np.ndarray], None]]:
    """The compiled loops ``f(xs, out)``: ``tangent``'s functions registered as the kernels register theirs."""
    import cr_tan as tangent
    import numba

    from amigo_gym.model import numeric
    from amigo_gym.sim.layout import shared_compiler

    own = (tangent.two_sum, tangent.two_prod, tangent.quotient_parts, tangent.tan_fast, tangent.tan_dd)
    forms = {**numeric.SCALAR_FORMS, **tangent.SCALAR_FORMS}
    shared = (*forms.values(), *own, *tangent.INTRINSICS.values())
    shared_compiler("experiments.portable_tan", shared, numba.njit, own, forms, tangent.INTRINSICS)
    ulp = numba.njit(error_model="numpy", inline="always")(plain_tan)
    fast, slow = tangent.tan_fast, tangent.tan_dd
    jit = numba.njit(error_model="numpy")

    @jit
    def ulp_loop(xs: np.ndarray, out: np.ndarray) -> None:
        for i in range(xs.shape[0]):
            out[i] = ulp(xs[i])

    @jit
    def dd_loop(xs: np.ndarray, out: np.ndarray) -> None:
        for i in range(xs.shape[0]):
            out[i] = slow(xs[i])

    @jit
    def fast_loop(xs: np.ndarray, out: np.ndarray, bad: np.ndarray) -> None:
        for i in range(xs.shape[0]):
            out[i], bad[i] = fast(xs[i])

    @jit
    def cr_loop(xs: np.ndarray, out: np.ndarray, bad: np.ndarray) -> None:
        fast_loop(xs, out, bad)
        for i in np.nonzero(bad)[0]:  # over the few failing ones only (AVX-512 would mask a loop over all)
            out[i] = slow(xs[i])

    def with_flags(f: Any) -> Callable[[np.ndarray, np.ndarray], None]:
        flags = np.empty(4096, dtype=np.bool_)
        return lambda xs, out: f(xs, out, flags[: xs.size] if xs.size <= flags.size else np.empty(xs.size, np.bool_))

    return {"ulp tan": ulp_loop, "tan_dd": dd_loop, "tan_fast": with_flags(fast_loop), "tan_cr": with_flags(cr_loop)}


def measure() -> None:
    """In this process: ns per value of the compiled loops and of ``np.tan``, the ulp tan's errors."""
    import cr_tan as tangent
    import mpmath
    import numba

    from amigo_gym.tools.machine import machine_line

    compiled = loops()

    def best(f: Callable[..., object], *args: np.ndarray, n: int = 300) -> float:
        b = math.inf
        for _ in range(n):
            t = time.thread_time()
            f(*args)
            b = min(b, time.thread_time() - t)
        return b

    mpmath.mp.prec = 120
    rng = np.random.default_rng(1)
    print(f"{machine_line()}; numba target {numba.config.CPU_NAME or 'host'}, features {numba.config.CPU_FEATURES!r}")
    for lo, hi in ((-0.2, 0.2), (-20.0, 20.0), (-2000.0, 2000.0)):
        xs = rng.uniform(lo, hi, 4096)
        theirs = np.tan(xs)
        out = np.empty_like(xs)
        times = {"np.tan": best(np.tan, xs, out)}
        for name, f in compiled.items():
            f(xs, out)
            want = {"tan_dd": tangent.tan_dd, "tan_cr": tangent.tan_dd, "tan_fast": lambda v: tangent.tan_fast(v)[0]}
            assert name not in want or out.tobytes() == want[name](xs).tobytes()
            times[name] = best(f, xs, out)
        compiled["ulp tan"](xs, out)
        ref = [mpmath.tan(mpmath.mpf(float(v))) for v in xs[:2000]]
        worst = max(abs(float((mpmath.mpf(float(out[i])) - r) / np.spacing(abs(float(r))))) for i, r in enumerate(ref))
        print(
            f"  x in [{lo:g}, {hi:g}]: ns/value "
            + ", ".join(f"{k} {1e9 * v / xs.size:.2f}" for k, v in times.items())
            + f"; ulp tan: largest error {worst:.2f} ulp, numpy's bits in {100 * np.mean(out == theirs):.1f} %"
        )


def agree(n: int) -> None:
    """``tan_cr`` against ``math.tan`` and ``np.tan`` on ``n`` arguments, disagreements checked with mpmath."""
    import cr_tan as tangent
    import mpmath

    from amigo_gym.tools.machine import machine_line

    mpmath.mp.prec = 160
    cr = loops()["tan_cr"]
    rng = np.random.default_rng(26)
    print(machine_line())
    for scale in (0.5, 20.0, 1e4):
        xs = rng.uniform(-scale, scale, n // 3)
        ours = np.empty_like(xs)
        cr(xs, ours)
        assert ours[:100_000].tobytes() == tangent.tan_cr(xs[:100_000]).tobytes()  # compiled = column
        for name, theirs in (("math.tan", np.array([math.tan(v) for v in xs.tolist()])), ("np.tan", np.tan(xs))):
            differ = np.nonzero(theirs != ours)[0]
            true = np.array([float(mpmath.tan(mpmath.mpf(v))) for v in xs[differ].tolist()])
            print(
                f"  |x| < {scale:g}, {xs.size} arguments, {name}: {differ.size} differ from tan_cr; correctly rounded "
                f"there: tan_cr {int(np.sum(ours[differ] == true))}, {name} {int(np.sum(theirs[differ] == true))}"
            )


if __name__ == "__main__":
    if sys.argv[1:] == ["--here"]:
        measure()
        sys.exit(0)
    if sys.argv[1:2] == ["--agree"]:
        agree(int(sys.argv[2]))
        sys.exit(0)
    avx2 = {"NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR", "NUMBA_CPU_NAME": "haswell"}
    for label, extra in (("this CPU's code", {}), ("AVX2 code", {**avx2, "NUMBA_CPU_FEATURES": ""})):
        with tempfile.TemporaryDirectory() as cache:
            print(f"{label}:", flush=True)
            env = {**os.environ, **extra, "NUMBA_CACHE_DIR": cache}
            subprocess.run([sys.executable, __file__, "--here"], env=env, check=True)
