"""What numpy's ``tan`` costs AmigoBot-v0's vector step at N = 4096, with this CPU's code and with AVX2 code.

    PYTHONPATH=. python experiments/tan_share.py [--sizes 4096] [--repeats 5] [--rounds 2]

Issue 19 item 5 asks the native vector env at N = 4096 for >= 1.0 x CartPoleVectorEnv's throughput on AVX2 machines
too. The compiled vector step (``sim/fast.py: _step_rows``) takes numpy's ``tan`` of its ``(N, 2)`` half-angles
between its first two passes, because numpy's bits define the reference's (``kinematics.col_tan``). This replaces that
one call, in this process only, by

- ``numpy``: ``np.tan`` itself (the package as it is);
- ``plain``: a ``tan`` in plain arithmetic compiled in a loop LLVM vectorises (Cephes' rational approximation, about
  2 ulp: ``experiments/portable_tan.py``'s ``plain_tan``; **not** numpy's bits, so the results change);
- ``tan_cr``: the correctly rounded ``tan`` of ``experiments/cr_tan.py`` compiled (the same bits as ``np.tan`` wherever
  numpy's is correctly rounded: all but a few arguments in 1000), plus a copy of the arguments;
- ``free``: nothing (the step's tangents are then wrong: the cost of the rest of the step, a bound no ``tan`` beats),

and times ``gym.make_vec("AmigoBot-v0", N)`` against ``CartPoleVectorEnv`` in interleaved repeats (bench-env's own
``measure_many``), one thread, each code in its own process and numba cache: this CPU's, and AVX2 code
(``NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR"`` for numpy, ``NUMBA_CPU_NAME=haswell
NUMBA_CPU_FEATURES=""`` for numba). Prints the CPU line and one ratio per variant and round.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import types
from typing import Any

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
AVX2 = {
    "NPY_DISABLE_CPU_FEATURES": "X86_V4 AVX512_ICL AVX512_SPR",
    "NUMBA_CPU_NAME": "haswell",
    "NUMBA_CPU_FEATURES": "",
}


def _numpy_with_tan(tan: Any) -> types.SimpleNamespace:
    """A stand-in for the numpy module in ``sim/fast.py`` whose ``tan`` is ``tan`` (everything else numpy's)."""
    ns = types.SimpleNamespace(**{k: getattr(np, k) for k in dir(np) if not k.startswith("__")})
    ns.tan = tan
    return ns


def _variants() -> dict[str, Any]:
    import numba

    sys.path.insert(0, HERE)
    from portable_tan import loops, plain_tan

    cr = loops()["tan_cr"]
    own = numba.njit(error_model="numpy", inline="always")(plain_tan)
    args = np.empty(0)

    @numba.njit(error_model="numpy")
    def in_place(xs: np.ndarray) -> None:  # one array: LLVM vectorises it (two that overlap fail its alias check)
        for i in range(xs.shape[0]):
            xs[i] = own(xs[i])

    def plain(x: np.ndarray, out: np.ndarray) -> np.ndarray:
        in_place(out.reshape(-1))  # x is out: the (N, 2) scratch, C-contiguous
        return out

    def correct(x: np.ndarray, out: np.ndarray) -> np.ndarray:
        nonlocal args
        flat = out.reshape(-1)
        if args.size != flat.size:
            args = np.empty_like(flat)
        np.copyto(args, flat)  # its fallback reads the argument after the fast path wrote the value
        cr(args, flat)
        return out

    def free(x: np.ndarray, out: np.ndarray) -> np.ndarray:
        return out

    return {"numpy": np.tan, "plain": plain, "tan_cr": correct, "free": free}


def here(sizes: list[int], repeats: int, rounds: int) -> None:
    """Measure in this process."""
    import gymnasium as gym
    from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

    import amigo_gym  # noqa: F401  (registers the envs)
    from amigo_gym.sim import fast
    from amigo_gym.tools.bench.env import _vector_stepper, measure_many, numba_state
    from amigo_gym.tools.machine import machine_line

    print(f"{machine_line()}; {numba_state()}", flush=True)
    variants = _variants()
    for n in sizes:
        for r in range(rounds):
            for name, tan in variants.items():
                fast.np = _numpy_with_tan(tan)  # type: ignore[attr-defined]
                try:
                    envs = {
                        "amigo": gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="vector_entry_point"),
                        "cartpole": CartPoleVectorEnv(num_envs=n),
                    }
                    envs["cartpole"].action_space.seed(0)
                    t = measure_many({k: _vector_stepper(e, 0) for k, e in envs.items()}, repeats, 0.2)
                    for e in envs.values():
                        e.close()
                finally:
                    fast.np = np  # type: ignore[attr-defined]
                print(
                    f"  N = {n}, round {r + 1}, tan {name}: AmigoBot-v0 {n / t['amigo']:.3g} env-steps/s, "
                    f"CartPoleVectorEnv {n / t['cartpole']:.3g}, ratio {t['cartpole'] / t['amigo']:.2f}",
                    flush=True,
                )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[4096])
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--here", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.here:
        here(a.sizes, a.repeats, a.rounds)
        return
    args = ["--sizes", *map(str, a.sizes), "--repeats", str(a.repeats), "--rounds", str(a.rounds), "--here"]
    for label, extra in (("this CPU's code", {}), ("AVX2 code", AVX2)):
        with tempfile.TemporaryDirectory() as cache:
            print(f"{label}:", flush=True)
            env = {**os.environ, **extra, "NUMBA_CACHE_DIR": cache, "NUMBA_NUM_THREADS": "1"}
            subprocess.run([sys.executable, __file__, *args], env=env, check=True)


if __name__ == "__main__":
    main()
