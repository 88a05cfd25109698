"""Elementwise helpers for function bodies written once for numpy columns (the reference) and floats (compiled).

numpy's ufuncs (``np.minimum``, ``np.abs``, ``np.sqrt``, ``np.arctan2``, ``np.any``, ...) take both and numba
compiles them on floats, so the shared functions call them directly. Two operations need a helper: clipping
(``np.clip`` of a float does not compile) and selection (``np.where`` of floats gives a 0-d array): :func:`where`
dispatches on the type, and the compiled step compiles :func:`where_float` in its place
(``amigo_gym.sim._kernels_v1``).

May import numpy and the standard library only.
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
    """``x`` clipped to ``[low, high]`` (``low <= high``), elementwise: ``np.minimum(np.maximum(x, low), high)``."""
    out: Real = np.minimum(np.maximum(x, low), high)
    return out


def where_float(cond: bool, a: float, b: float) -> float:
    """``a`` if ``cond`` else ``b``: :func:`where` of floats."""
    return a if cond else b


def where(cond: Any, a: Any, b: Any) -> Any:
    """``a`` where ``cond`` else ``b``: ``np.where`` when any argument is an array, else :func:`where_float`."""
    if any_array(cond, a, b):
        return np.where(cond, a, b)
    return a if cond else b
