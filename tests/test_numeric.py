"""The elementwise helpers of amigo_gym.model.numeric: a float and a column give the same bits (numpy's rules for
NaN, ties and signed zeros), and the compiled steps' float forms give what the helpers give as Python."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from amigo_gym.model import numeric

EDGES = (-0.0, 0.0, -1.0, 1.0, -2.0, 2.0, 0.5, -0.5, 1e-300, -1e-300, math.inf, -math.inf, math.nan)
BOUNDS = ((-1.0, 1.0), (0.0, 1.0), (-1.0, 0.0), (-0.0, 1.0), (-1.0, -0.0), (-2.0, 2.0))


def _bits(x: object) -> bytes:
    return np.asarray(x, dtype=np.float64).tobytes()


def _same(got: object, want: object) -> bool:
    """The same bits, but for the sign of a zero: which of two zeros numpy's SIMD minimum/maximum return is the CPU's
    (x86-64 and ARM differ), not a rule the float forms can follow on every machine."""
    g = np.asarray(got, dtype=np.float64)
    w = np.asarray(want, dtype=np.float64)
    zeros = (g == 0.0) & (w == 0.0)
    return bool(np.array_equal(np.where(zeros, 0.0, g).view(np.uint64), np.where(zeros, 0.0, w).view(np.uint64)))


def test_clip_of_a_float_has_the_column_clips_bits() -> None:
    """clip_float equals np.minimum(np.maximum(x, low), high) bit for bit (NaN, infinities, exact bounds, values
    inside), zeros of either sign at bounds of either sign as values (their sign: the CPU's, :func:`_same`)."""
    rng = np.random.default_rng(0)
    xs = np.concatenate([np.array(EDGES), rng.normal(0.0, 2.0, 200)])
    for low, high in BOUNDS:
        column = numeric.clip_real(xs, low, high)
        assert isinstance(column, np.ndarray)
        floats = np.array([numeric.clip_real(float(x), low, high) for x in xs])
        assert _same(floats, column), (low, high)
        assert all(type(numeric.clip_real(float(x), low, high)) is float for x in xs)


def test_clip_float_keeps_nan_and_takes_the_bound_on_a_tie() -> None:
    assert math.isnan(numeric.clip_float(math.nan, -1.0, 1.0))
    assert math.copysign(1.0, numeric.clip_float(-0.0, 0.0, 1.0)) == 1.0  # the bound on a tie
    assert numeric.clip_float(5.0, -1.0, 1.0) == 1.0
    assert numeric.clip_float(-5.0, -1.0, 1.0) == -1.0


@pytest.mark.parametrize(
    ("real", "column"),
    [(numeric.min_real, np.minimum), (numeric.max_real, np.maximum), (numeric.copysign_real, np.copysign)],
)
def test_two_argument_helpers_of_floats_match_columns_on_finite_values(real: object, column: object) -> None:
    """min, max and copysign of floats against numpy's on finite values with ties and signed zeros (NaN differs by
    design, documented: the float forms compare once)."""
    finite = [v for v in EDGES if math.isfinite(v)]
    pairs = [(a, b) for a, b in itertools.product(finite, finite) if not (a == b and a == 0.0)]
    a = np.array([p[0] for p in pairs])
    b = np.array([p[1] for p in pairs])
    want = column(a, b)  # type: ignore[operator]
    got = np.array([real(x, y) for x, y in pairs])  # type: ignore[operator]
    assert _same(got, want)


def test_max0_and_abs_of_floats_match_columns() -> None:
    xs = np.array([v for v in EDGES if not math.isnan(v)])
    assert _same([numeric.max0_real(float(x)) for x in xs], numeric.max0_real(xs))
    assert _same([numeric.abs_real(float(x)) for x in xs], numeric.abs_real(xs))
    assert numeric.max0_float(math.nan) == 0.0


def test_sqrt_and_any_of_floats_match_columns() -> None:
    xs = np.array([v for v in EDGES if not v < 0.0])
    assert _same([numeric.sqrt_real(float(x)) for x in xs], numeric.sqrt_real(xs))
    with np.errstate(invalid="ignore"):  # below 0: NaN (its sign bit is the CPU's)
        assert np.isnan(numeric.sqrt_real(np.array([-1.0, -math.inf]))).all()
    assert math.isnan(numeric.sqrt_real(-1.0)) and math.isnan(numeric.sqrt_real(-math.inf))
    assert numeric.any_real(np.array([False, True])) is True
    assert numeric.any_real(np.array([False, False])) is False
    assert numeric.any_real(True) and not numeric.any_real(False)


def test_arctan2_and_hypot_of_floats_match_columns_and_stay_python_floats() -> None:
    pairs = list(itertools.product(EDGES, EDGES))
    a = np.array([p[0] for p in pairs])
    b = np.array([p[1] for p in pairs])
    for real in (numeric.arctan2_real, numeric.hypot_real):
        floats = [real(x, y) for x, y in pairs]
        assert all(type(v) is float for v in floats)
        assert _same(floats, real(a, b))


def test_where_of_floats_and_columns() -> None:
    assert numeric.where_real(True, 1.0, 2.0) == 1.0
    assert numeric.where_real(False, 1.0, 2.0) == 2.0
    got = numeric.where_real(np.array([True, False]), 1.0, np.array([3.0, 4.0]))
    assert np.array_equal(got, [1.0, 4.0])


def test_compiled_float_forms_give_the_helpers_bits() -> None:
    """The compiled steps run each helper's float form (SCALAR_FORMS, registered by sim.layout.shared_compiler): a
    function calling the helpers, compiled, against the same function run as Python, at the edges."""
    import numba

    from amigo_gym.sim import fast_v1

    fast_v1.kernels()  # registers the float forms

    def piece(x: float, y: float) -> tuple[float, ...]:
        return (
            numeric.clip_real(x, -1.0, 1.0),
            numeric.min_real(x, y),
            numeric.max_real(x, y),
            numeric.max0_real(x),
            numeric.abs_real(y),
            numeric.sqrt_real(x) if numeric.any_real(x > y) else -1.0,
            numeric.where_real(x < y, x, y),
            numeric.arctan2_real(y, x),
            numeric.hypot_real(x, y),
        )

    compiled = numba.njit(piece)
    for x, y in itertools.product(EDGES, EDGES):
        assert _bits(compiled(x, y)) == _bits(piece(x, y)), (x, y)


def test_every_helper_has_a_float_form_listed_in_the_kernel() -> None:
    """The kernel compiles the float forms (its SHARED tuple lists them)."""
    from amigo_gym.sim import layout_v1

    for form in numeric.SCALAR_FORMS.values():
        assert form in layout_v1.SHARED
