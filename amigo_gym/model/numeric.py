r"""Elementwise helpers written once for Python floats, numpy columns and the compiled steps.

The reference's pieces of physics and of the task are *polymorphic*: one function computes one robot on Python
floats (the single env) and ``N`` robots on ``(N,)`` columns (the vector env), and the compiled steps
(:mod:`amigo_gym.sim._kernels_v1`) compile the very same function
(docs/architecture.md, "One robot, one step"). What differs between floats and columns is confined to the helpers
below: each ``*_real`` function dispatches on the type (numpy's ufunc on an array, its ``*_float`` form on a
float), and each ``*_float`` form is plain float code in numba's subset with **numpy's rules** (NaN, ties, signed
zeros), so that a float and a column give the same bits.

numba cannot dispatch on ``isinstance``; the compiled steps replace each ``*_real`` function by its ``*_float``
form (:data:`SCALAR_FORMS`, registered once per process by :func:`amigo_gym.sim.layout.shared_compiler`).

Shapes: floats, or arrays of any shape (broadcast as numpy does). Units: those of the arguments.

May import numpy and the standard library only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, TypeAlias

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Real",
    "any_array",
    "clip_float",
    "clip_real",
    "min_float",
    "min_real",
    "max_float",
    "max_real",
    "max0_float",
    "max0_real",
    "abs_float",
    "abs_real",
    "where_float",
    "where_real",
    "copysign_float",
    "copysign_real",
    "arctan2_float",
    "arctan2_real",
    "hypot_float",
    "hypot_real",
    "sqrt_float",
    "sqrt_real",
    "any_float",
    "any_real",
    "pow2_real",
    "pow2_typing",
    "SCALAR_FORMS",
]

#: a float or a column of floats
Real: TypeAlias = float | NDArray[np.float64]

_ndarray = np.ndarray  # a module global: isinstance against it is cheaper than against np.ndarray


def any_array(*cols: object) -> bool:
    """Whether any argument is a numpy array."""
    for c in cols:  # noqa: SIM110  (a loop: a third of the time of any() over a generator)
        if isinstance(c, _ndarray):
            return True
    return False


def clip_float(x: float, low: float, high: float) -> float:
    """``np.minimum(np.maximum(x, low), high)`` of one float (``low <= high``), by two comparisons: NaN stays NaN, a
    tie takes the bound (``clip_float(-0.0, 0.0, 1.0)`` is ``0.0``, as numpy's on x86-64; which zero numpy returns
    for two zeros is its SIMD loop's choice and may differ on other CPUs)."""
    return low if x <= low else (high if x >= high else x)


def clip_real(x: Real, low: float, high: float) -> Real:
    """``x`` clipped to ``[low, high]``: ``np.minimum(np.maximum(x, low), high)`` of an array (``np.clip``'s values,
    less overhead), :func:`clip_float` of a float."""
    if isinstance(x, _ndarray):
        out: Real = np.minimum(np.maximum(x, low), high)
        return out
    return clip_float(x, low, high)


def min_float(a: float, b: float) -> float:
    """The smaller of two floats by one comparison, ``a`` on a tie (``b`` when either is NaN but ``a`` alone)."""
    return a if a <= b else b


def min_real(a: Real, b: Real) -> Real:
    """``np.minimum(a, b)`` of arrays, :func:`min_float` of floats."""
    if any_array(a, b):
        out: Real = np.minimum(a, b)
        return out
    return min_float(a, b)  # type: ignore[arg-type]


def max_float(a: float, b: float) -> float:
    """The larger of two floats by one comparison, ``a`` on a tie (``b`` when either is NaN but ``a`` alone)."""
    return a if a >= b else b


def max_real(a: Real, b: Real) -> Real:
    """``np.maximum(a, b)`` of arrays, :func:`max_float` of floats."""
    if any_array(a, b):
        out: Real = np.maximum(a, b)
        return out
    return max_float(a, b)  # type: ignore[arg-type]


def max0_float(x: float) -> float:
    """``max(x, 0)`` of one float by a comparison: ``0.0`` for ``-0.0`` and for NaN."""
    return x if x > 0.0 else 0.0


def max0_real(x: Real) -> Real:
    """``np.maximum(x, 0.0)`` of an array, :func:`max0_float` of a float."""
    if isinstance(x, _ndarray):
        out: Real = np.maximum(x, 0.0)
        return out
    return max0_float(x)


def abs_float(x: float) -> float:
    """``|x|`` of one float."""
    return abs(x)


def abs_real(x: Real) -> Real:
    """``np.abs`` of an array, ``abs`` of a float."""
    return np.abs(x) if isinstance(x, _ndarray) else abs(x)


def where_float(cond: bool, a: float, b: float) -> float:
    """``a`` if ``cond`` else ``b``, of floats (:func:`where_real`)."""
    return a if cond else b


def where_real(cond: bool | NDArray[np.bool_], a: Real, b: Real) -> Real:
    """``a`` where ``cond`` else ``b`` (``np.where`` when any argument is an array, else :func:`where_float`'s
    expression, inline: the float path calls this often)."""
    if isinstance(cond, _ndarray) or isinstance(a, _ndarray) or isinstance(b, _ndarray):
        out: Real = np.where(cond, a, b)
        return out
    return a if cond else b


def copysign_float(x: float, y: float) -> float:
    """``|x|`` with the sign of ``y``, of floats (``math.copysign``)."""
    return math.copysign(x, y)


def copysign_real(x: Real, y: Real) -> Real:
    """``|x|`` with the sign of ``y`` (``np.copysign`` of arrays, :func:`copysign_float` of floats)."""
    if any_array(x, y):
        out: Real = np.copysign(x, y)
        return out
    return copysign_float(x, y)  # type: ignore[arg-type]


def arctan2_float(y: float, x: float) -> float:
    """``np.arctan2`` of two floats as a Python float (numpy's function; compiled, the C library's ``atan2``, which
    numpy calls where it does not vectorise: AVX-512 builds of numpy vectorise it and may differ by an ulp)."""
    return float(np.arctan2(y, x))


def arctan2_real(y: Real, x: Real) -> Real:
    """``np.arctan2(y, x)`` of arrays, :func:`arctan2_float` of floats."""
    if any_array(y, x):
        out: Real = np.arctan2(y, x)
        return out
    return arctan2_float(y, x)  # type: ignore[arg-type]


def hypot_float(x: float, y: float) -> float:
    """``np.hypot`` of two floats as a Python float (numpy's, the C library's ``hypot``; Python's ``math.hypot`` is its
    own algorithm)."""
    return float(np.hypot(x, y))


def hypot_real(x: Real, y: Real) -> Real:
    """``np.hypot(x, y)`` of arrays, :func:`hypot_float` of floats."""
    if any_array(x, y):
        out: Real = np.hypot(x, y)
        return out
    return hypot_float(x, y)  # type: ignore[arg-type]


def sqrt_float(x: float) -> float:
    """``np.sqrt`` of one float: ``math.sqrt`` (IEEE 754 rounds square roots exactly: numpy's bits), NaN below 0
    (where ``math.sqrt`` would raise; the sign bit of that NaN may differ from numpy's, which is the CPU's)."""
    return math.sqrt(x) if (x >= 0.0 or x != x) else math.nan


def sqrt_real(x: Real) -> Real:
    """``np.sqrt`` of an array, :func:`sqrt_float` of a float."""
    if isinstance(x, _ndarray):
        out: Real = np.sqrt(x)
        return out
    return sqrt_float(x)


def any_float(cond: bool) -> bool:
    """Whether the one condition ``cond`` holds (:func:`any_real` of a bool)."""
    return cond


def any_real(cond: bool | NDArray[np.bool_]) -> bool:
    """Whether any element of ``cond`` holds (``np.any`` of an array, the bool itself): a branch that a column takes
    when any of its rows would."""
    if isinstance(cond, _ndarray):
        return bool(cond.any())
    return any_float(cond)


def pow2_real(k: Real) -> Real:
    """``2**k`` of a whole number ``k`` in ``[-1022, 1023]`` held in a float or a column, exactly: ``np.ldexp`` of a
    column, ``math.ldexp`` of a float; compiled, the bits ``(k + 1023) << 52`` of a float64 (:func:`pow2_typing`)."""
    if isinstance(k, _ndarray):
        out: Real = np.ldexp(1.0, k.astype(np.int64))
        return out
    return math.ldexp(1.0, int(k))


def pow2_typing(typingctx: object, k: Any) -> Any:
    """The typing and code of :func:`pow2_real` on a float in compiled code (numba's ``intrinsic``, which the kernels
    register in its place: :func:`amigo_gym.sim.layout.shared_compiler`'s ``intrinsics``): the float ``k`` to an
    integer, plus 1023, shifted into a float64's exponent field. numba imported here, when a kernel is compiled."""
    from llvmlite import ir
    from numba.core import types

    if not isinstance(k, types.Float):
        return None

    def codegen(context: object, builder: Any, signature: object, values: list[Any]) -> Any:
        i64 = ir.IntType(64)
        bits = builder.shl(builder.add(builder.fptosi(values[0], i64), ir.Constant(i64, 1023)), ir.Constant(i64, 52))
        return builder.bitcast(bits, ir.DoubleType())

    return types.float64(k), codegen


#: the polymorphic helpers the compiled steps' shared pieces call, each with the float form numba compiles in its
#: place (:func:`amigo_gym.sim.layout.shared_compiler` registers them)
SCALAR_FORMS: dict[Callable[..., Any], Callable[..., Any]] = {
    clip_real: clip_float,
    min_real: min_float,
    max_real: max_float,
    max0_real: max0_float,
    abs_real: abs_float,
    sqrt_real: sqrt_float,
    any_real: any_float,
    where_real: where_float,
    copysign_real: copysign_float,
    arctan2_real: arctan2_float,
    hypot_real: hypot_float,
}
