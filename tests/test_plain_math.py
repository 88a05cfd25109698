"""The reward's ``exp`` in plain float64 arithmetic (``amigo_gym/model/kinematics.py``: ``col_exp``) against a 120-bit
``mpmath`` reference: within :data:`BOUND` ulp over the arguments the step sees (the reward's arguments, never
positive, down to underflow; small and positive ones too), the edge cases (zeros, subnormal results, exact zeros
below them, NaN, infinities); the same bits for a float, a column and compiled (numba, as the kernels compile it).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from amigo_gym.model.kinematics import col_exp
from amigo_gym.model.numeric import pow2_real

#: the largest error allowed [ulp of the true value] (measured: 0.85; numpy's AVX-512 ``exp``: 0.68)
BOUND = 1.0
#: the smallest subnormal float64, the ulp of results below the smallest normal
TINY = 5e-324


def _ulps(got: np.ndarray, xs: np.ndarray, fn: object) -> float:
    """The largest ``|got - fn(x)| / ulp(fn(x))`` with ``fn`` evaluated by mpmath at 120 bits."""
    worst = 0.0
    with mpmath.workprec(120):  # its own precision, whatever another test module set mpmath's global one to
        for g, x in zip(got.tolist(), xs.tolist(), strict=True):
            true = fn(mpmath.mpf(x))  # type: ignore[operator]
            ulp = max(float(np.spacing(abs(float(true)))), TINY)
            worst = max(worst, float(abs(mpmath.mpf(g) - true) / ulp))
    return worst


def _exp_args() -> dict[str, np.ndarray]:
    g = np.random.default_rng(20)
    return {
        "reward": -g.exponential(2.0, 6000),
        "wide": g.uniform(-800.0, 0.0, 4000),
        "subnormal results": g.uniform(-745.2, -708.0, 4000),
        "small": g.normal(0.0, 1e-6, 1000),
        "positive": g.uniform(0.0, 709.7, 1000),
    }


@pytest.mark.parametrize("name", list(_exp_args()))
def test_exp_within_the_bound(name: str) -> None:
    xs = _exp_args()[name]
    got = col_exp(xs)
    assert _ulps(got, xs, mpmath.exp) <= BOUND
    assert np.array_equal(np.array([col_exp(x) for x in xs[:400].tolist()]), got[:400])


def test_edge_cases() -> None:
    """Zeros, subnormal results, NaN and infinities as numpy's ``exp`` gives them; exactly 0 below half the smallest
    subnormal."""
    cases = ((0.0, 1.0), (-0.0, 1.0), (TINY, 1.0), (-745.1332191019411, TINY), (-745.1332191019412, 0.0),
             (-746.0, 0.0), (-1e300, 0.0), (-math.inf, 0.0), (709.79, math.inf), (math.inf, math.inf))  # fmt: skip
    with np.errstate(over="ignore"):
        for x, e in cases:
            assert col_exp(x) == e and col_exp(np.array([x]))[0] == e
    assert math.isnan(col_exp(math.nan)) and np.isnan(col_exp(np.array([math.nan]))).all()


def test_pow2_is_exact() -> None:
    k = np.arange(-1022.0, 1024.0)
    two = pow2_real(k)
    assert np.array_equal(two, np.ldexp(1.0, np.arange(-1022, 1024)))
    assert [pow2_real(v) for v in k[::97].tolist()] == two[::97].tolist()


def test_compiled_gives_the_same_bits() -> None:
    """Compiled as the kernels compile it (their registration: ``numeric.where_real`` as its float form,
    ``numeric.pow2_real`` as an intrinsic), in a loop LLVM vectorises: the bits of the Python function."""
    pytest.importorskip("numba")
    import numba

    from amigo_gym.sim import fast_v1

    fast_v1.kernels()  # registers the shared functions with numba

    @numba.njit(error_model="numpy")
    def loop(e: np.ndarray) -> None:
        for i in range(e.shape[0]):
            e[i] = col_exp(e[i])

    xe = np.concatenate([*_exp_args().values(), [0.0, -1e300, -math.inf, math.nan, 800.0]])
    e = xe.copy()
    loop(e)
    with np.errstate(over="ignore"):
        assert e.tobytes() == col_exp(xe).tobytes()
