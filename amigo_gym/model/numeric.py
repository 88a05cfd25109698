"""Elementwise helpers for bodies written once for floats (compiled by numba) and numpy columns: clipping
(``np.clip`` of a float does not compile) and selection (``np.where`` of floats gives a 0-d array; compiled code
runs :func:`where_float` in its place). May import numpy and the standard library only.
"""

from __future__ import annotations

from typing import Any, TypeAlias

import numpy as np
from numpy.typing import NDArray

#: a float or a column of floats
Real: TypeAlias = float | NDArray[np.float64]


def any_array(*cols: object) -> bool:
    """Whether any argument is a numpy array."""
    return any(isinstance(c, np.ndarray) for c in cols)


def clip(x: Real, low: float, high: float) -> Real:
    """``x`` clipped to ``[low, high]`` (``low <= high``), elementwise."""
    out: Real = np.minimum(np.maximum(x, low), high)
    return out


def where_float(cond: bool, a: float, b: float) -> float:
    """``a`` if ``cond`` else ``b``."""
    return a if cond else b


def where(cond: Any, a: Any, b: Any) -> Any:
    """``a`` where ``cond`` else ``b``: ``np.where`` when any argument is an array, else :func:`where_float`."""
    if any_array(cond, a, b):
        return np.where(cond, a, b)
    return a if cond else b
