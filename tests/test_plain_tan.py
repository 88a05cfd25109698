"""The ``tan`` of ``experiments/cr_tan.py`` (an experiment, not in the package) against ``mpmath`` at 160 bits:
correctly rounded on 10^5 random arguments over the ranges AmigoBot-v0's step sees and on hard cases (near multiples
of pi/2 and pi/4, tiny, subnormal, signed zeros, NaN, infinities, the limit of its reduction); its constants
re-derived; the fast path's value where its rounding test passes; every disagreement with ``math.tan`` (the C library)
and ``np.tan`` on a sample is theirs; the same bits for a float, a column and compiled. The full comparison (10^7
arguments) and its speed: ``experiments/portable_tan.py``.

    python tests/test_plain_tan.py      # prints the module's constants from mpmath (the literals of cr_tan.py)
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import mpmath
import numpy as np
import pytest

from amigo_gym.model import numeric


def _load() -> ModuleType:
    """``experiments/cr_tan.py`` as a module (the experiments are scripts, not a package)."""
    path = Path(__file__).resolve().parents[1] / "experiments" / "cr_tan.py"
    spec = importlib.util.spec_from_file_location("cr_tan", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["cr_tan"] = mod  # numba compiles its functions by their module
    spec.loader.exec_module(mod)
    return mod


tangent = _load()

#: the random arguments of the correct-rounding test, per range (3 x 35000 >= 10^5)
RANGES = {"half turn": 0.5, "heading": 20.0, "many laps": 1e4}
PER_RANGE = 35000


def _cr(xs: np.ndarray) -> np.ndarray:
    """The correctly rounded ``tan`` (mpmath at 160 bits, rounded to nearest; its own precision, whatever another
    test module set mpmath's global one to)."""
    with mpmath.workprec(160):
        return np.array([float(mpmath.tan(mpmath.mpf(x))) for x in xs.tolist()])


def constants() -> dict[str, object]:
    """The module's constants computed with mpmath at 400 bits: ``pi/2`` in 33-bit parts, the series' coefficients,
    ``tan(j / 64)`` as double-doubles."""
    with mpmath.workprec(400):
        rest, parts = mpmath.pi / 2, []
        for _ in range(4):
            e = int(mpmath.floor(mpmath.log(abs(rest), 2)))
            p = mpmath.nint(rest * mpmath.mpf(2) ** (32 - e)) / mpmath.mpf(2) ** (32 - e)
            parts.append(float(p))
            rest -= p
        parts.append(float(rest))

        def dd(v: object) -> tuple[float, float]:
            hi = float(v)  # type: ignore[arg-type]
            return hi, float(v - mpmath.mpf(hi))  # type: ignore[operator]

        table = [dd(mpmath.tan(mpmath.mpf(j) / 64)) for j in range(51)]
        fractions = ((1, 3), (2, 15), (17, 315), (62, 2835), (1382, 155925), (21844, 6081075))
        series = [mpmath.mpf(n) / d for n, d in fractions]
        return {
            "parts": tuple(parts),
            "p3r": float(mpmath.pi / 2 - mpmath.mpf(parts[0]) - mpmath.mpf(parts[1])),
            "two_over_pi": float(2 / mpmath.pi),
            "limit": float(2**20 * mpmath.pi / 2),
            "c1": dd(series[0]),
            "c2": dd(series[1]),
            "series": tuple(float(c) for c in series),
            "hi": tuple(t[0] for t in table),
            "lo": tuple(t[1] for t in table),
        }


def test_constants_are_mpmaths() -> None:
    c = constants()
    t = tangent
    assert c["parts"] == (t._P1, t._P2, t._P3, t._P4, t._P5)
    for p in c["parts"][:4]:  # type: ignore[index]  # 33 bits: times any |k| < 2**20, exact
        assert (p * 2.0 ** (32 - math.floor(math.log2(p)))).is_integer()
    assert (c["p3r"], c["two_over_pi"], c["limit"]) == (t._P3R, t._TWO_OVER_PI, t.TAN_LIMIT)
    assert (*c["c1"], *c["c2"]) == (t._C1, t._C1L, t._C2, t._C2L)  # type: ignore[misc]
    assert c["series"] == (t._C1, t._C2, t._C3, t._C4, t._C5, t._C6)
    assert (c["hi"], c["lo"]) == (t._TAN_HI, t._TAN_LO)


@pytest.mark.parametrize("name", list(RANGES))
def test_correctly_rounded_on_random_arguments(name: str) -> None:
    xs = np.random.default_rng(19).uniform(-RANGES[name], RANGES[name], PER_RANGE)
    want = _cr(xs)
    assert tangent.tan_cr(xs).tobytes() == want.tobytes()
    assert tangent.tan_dd(xs[:5000]).tobytes() == want[:5000].tobytes()


def _hard_cases() -> np.ndarray:
    """The doubles nearest to ``m pi/4`` (odd and even ``m``, so multiples of pi/2 too) for ``m`` up to 2000 and
    some up to ``2**21``, and their neighbours two ulps either way; tiny and subnormal arguments."""
    with mpmath.workprec(200):
        m = np.concatenate((np.arange(1, 2001), np.random.default_rng(4).integers(2001, 2**21, 2000)))
        near = np.array([float(int(k) * mpmath.pi / 4) for k in m])
    around = np.concatenate([np.nextafter(near, np.inf * s) if s else near for s in (0, 1, -1)])
    around = np.concatenate((around, np.nextafter(around, np.inf), np.nextafter(around, -np.inf)))
    tiny = np.array([7.450580596923828e-09, np.nextafter(7.450580596923828e-09, 0.0), 1e-8, 3e-8, 1e-300, 5e-324])
    xs = np.concatenate((around, tiny))
    return np.concatenate((xs, -xs))


def test_correctly_rounded_on_hard_cases() -> None:
    xs = _hard_cases()
    xs = xs[np.abs(xs) < tangent.TAN_LIMIT]
    assert tangent.tan_cr(xs).tobytes() == _cr(xs).tobytes()
    assert tangent.tan_dd(xs).tobytes() == _cr(xs).tobytes()


@pytest.mark.filterwarnings("ignore:invalid value encountered")  # NaN and infinities in columns
def test_edge_cases() -> None:
    """Signed zeros and tiny arguments as they are, NaN for NaN, infinities and beyond the reduction's limit."""
    below = np.nextafter(tangent.TAN_LIMIT, 0.0)
    for x in (0.0, -0.0, 5e-324, -5e-324, 1e-300, 2.0**-28):
        for got in (tangent.tan_cr(x), tangent.tan_cr(np.array([x]))[0]):
            assert got == x and math.copysign(1.0, got) == math.copysign(1.0, x)
    for x in (math.nan, math.inf, -math.inf, tangent.TAN_LIMIT, -tangent.TAN_LIMIT, 1e300):
        assert math.isnan(tangent.tan_cr(x)) and np.isnan(tangent.tan_cr(np.array([x]))).all()
    assert tangent.tan_cr(below) == _cr(np.array([below]))[0]


def test_fast_path_where_its_test_passes() -> None:
    """tan_fast gives tan_dd's bits wherever its rounding test passes (bound 2**-62: fails about 3 in 1000)."""
    xs = np.random.default_rng(7).uniform(-2000.0, 2000.0, 200_000)
    fast, bad = tangent.tan_fast(xs)
    assert isinstance(bad, np.ndarray) and 0 < bad.sum() < 0.005 * xs.size
    assert np.array_equal(fast[~bad], tangent.tan_dd(xs[~bad]))


def test_disagreements_with_the_c_library_and_numpy_are_theirs() -> None:
    """Where ``math.tan`` (glibc) or ``np.tan`` (numpy's SIMD code, the CPU's) differ from tan_cr, tan_cr is the
    correctly rounded one (and they differ: neither is correctly rounded everywhere)."""
    xs = np.random.default_rng(11).uniform(-20.0, 20.0, 20_000)
    ours = tangent.tan_cr(xs)
    for theirs in (np.array([math.tan(x) for x in xs.tolist()]), np.tan(xs)):
        differ = np.nonzero(theirs != ours)[0]
        assert differ.size < 0.02 * xs.size
        assert _cr(xs[differ]).tobytes() == ours[differ].tobytes()


@pytest.mark.filterwarnings("ignore:invalid value encountered", "ignore:overflow encountered")
def test_float_column_and_compiled_give_the_same_bits() -> None:
    """A Python float, a column and compiled (numeric's float forms and its FMA intrinsic registered as the kernels
    register theirs, :func:`amigo_gym.sim.layout.shared_compiler`), in a loop LLVM vectorises."""
    pytest.importorskip("numba")
    import numba

    from amigo_gym.sim.layout import shared_compiler

    t = tangent
    own = (t.two_sum, t.two_prod, t.quotient_parts, t.tan_fast, t.tan_dd)
    forms = {**numeric.SCALAR_FORMS, **tangent.SCALAR_FORMS}
    shared = (*forms.values(), *own, *tangent.INTRINSICS.values())
    shared_compiler("tests.plain_tan", shared, numba.njit, own, forms, tangent.INTRINSICS)
    fast, slow = t.tan_fast, t.tan_dd

    @numba.njit(error_model="numpy")
    def loop(xs: np.ndarray, out: np.ndarray, bad: np.ndarray, dd: np.ndarray) -> None:
        for i in range(xs.shape[0]):
            out[i], bad[i] = fast(xs[i])
            dd[i] = slow(xs[i])

    g = np.random.default_rng(3)
    xs = np.concatenate((g.uniform(-0.5, 0.5, 3000), g.uniform(-1e4, 1e4, 3000), _hard_cases()[::7],
                         [0.0, -0.0, math.nan, math.inf, -math.inf, 1e300]))  # fmt: skip
    out, bad, dd = np.empty_like(xs), np.empty(xs.size, np.bool_), np.empty_like(xs)
    loop(xs, out, bad, dd)
    fast_col, bad_col = t.tan_fast(xs)
    assert out.tobytes() == fast_col.tobytes() and np.array_equal(bad, bad_col)
    assert dd.tobytes() == t.tan_dd(xs).tobytes()
    floats = np.array([t.tan_cr(x) for x in xs[::5].tolist()])
    assert floats.tobytes() == t.tan_cr(xs)[::5].tobytes()


if __name__ == "__main__":
    for key, value in constants().items():
        print(f"{key} = {value!r}")
