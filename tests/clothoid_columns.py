"""The clothoid projection and pose on columns as the package computed them before they were written once, kept as an
independent reference for the tests (``tests/test_float_paths.py``).

:class:`amigo_gym.paths.ClothoidPath` now evaluates arrays row by row with its float functions
(:func:`amigo_gym.paths.clothoid.locate_rows`, :func:`amigo_gym.paths.clothoid.pose_rows`); this module is the earlier
vectorised code (``searchsorted`` of the piece starts, ``argmin`` over a window matrix of samples, a Newton loop on
whole columns), which gave the float functions' bits. Only the path's tables (``path._t``) are shared.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.fresnel import advance
from amigo_gym.paths import clothoid
from amigo_gym.paths.classic import PathPoint, PathPose

Array = NDArray[np.float64]


def pose(path: Any, s: Array) -> PathPose:
    """The pose at the arc lengths ``s`` [m] (an array) on the ClothoidPath ``path``."""
    t = path._t
    s = np.asarray(s, dtype=np.float64)
    if path.closed:
        lap = np.floor(s / t.length)
        u = s - lap * t.length
        extra = np.zeros_like(s)
    else:
        lap = np.zeros_like(s)
        u = np.minimum(np.maximum(s, 0.0), t.length)
        extra = s - u
    i = np.clip(np.searchsorted(t.s0_a, u, side="right") - 1, 0, len(t.s0) - 1)
    s0, x0, y0, th0, k0, c = t.s0_a[i], t.x0_a[i], t.y0_a[i], t.th0_a[i], t.k0_a[i], t.c_a[i]
    du = u - s0
    x, y, th = advance(x0, y0, th0, 1.0, 0.0, k0, c, du, 1)
    kappa = k0 + c * du
    cos_t, sin_t = np.cos(th), np.sin(th)
    if path.closed:
        return PathPose(x, y, th + lap * t.turn, kappa, c, cos_t, sin_t)
    beyond = extra != 0.0
    return PathPose(
        x + extra * cos_t,
        y + extra * sin_t,
        th,
        np.where(beyond, 0.0, kappa),
        np.where(beyond, 0.0, c),
        cos_t,
        sin_t,
    )


def coarse(path: Any, x: Array, y: Array, s_prev: Array | None, ahead: float, behind: float) -> tuple[Array, Any, Any]:
    """The coarse search: ``s`` [m] of the nearest sample and the Newton bounds ``(lo, hi)``."""
    t = path._t
    h, length, n_samp = t.spacing, t.length, len(t.sample_x)
    if s_prev is None:
        d2 = (t.sample_x - x[..., None]) ** 2 + (t.sample_y - y[..., None]) ** 2
        lo, hi = (-math.inf, math.inf) if path.closed else (0.0, length)
        return np.argmin(d2, axis=-1) * h, lo, hi
    jj = np.floor((s_prev - behind) / h)[..., None] + np.arange(math.ceil((ahead + behind) / h) + 2, dtype=np.float64)
    if path.closed:
        idx = np.mod(jj, n_samp).astype(np.int64)
    else:
        jj = np.clip(jj, 0, n_samp - 1)
        idx = jj.astype(np.int64)
    d2 = (t.sample_x[idx] - x[..., None]) ** 2 + (t.sample_y[idx] - y[..., None]) ** 2
    k = np.argmin(d2, axis=-1)
    s_start = np.take_along_axis(jj, k[..., None], axis=-1)[..., 0] * h
    lo, hi = s_prev - behind, s_prev + ahead
    if not path.closed:
        lo, hi = np.clip(lo, 0.0, length), np.clip(hi, 0.0, length)
    return np.clip(s_start, lo, hi), lo, hi


@np.errstate(invalid="ignore", divide="ignore")
def locate(
    path: Any, x: Array, y: Array, s_prev: Array | None = None, ahead: float = 0.5, behind: float | None = None
) -> PathPoint:
    """``path.locate(x, y, s_prev, ahead, behind)`` on arrays (of one shape) as the column code computed it."""
    t = path._t
    behind = ahead if behind is None else behind
    s, lo, hi = coarse(path, x, y, s_prev, ahead, behind)
    h = t.spacing
    p = pose(path, s)
    for _ in range(clothoid.NEWTON_ITERATIONS):
        dx = x - p.x
        dy = y - p.y
        g = dx * p.cos_theta + dy * p.sin_theta
        e = dy * p.cos_theta - dx * p.sin_theta
        den = 1.0 - p.curvature * e
        den = np.where(den < clothoid.MIN_NEWTON_DENOMINATOR, clothoid.MIN_NEWTON_DENOMINATOR, den)
        s_new = np.minimum(np.maximum(s + np.minimum(np.maximum(g / den, -h), h), lo), hi)
        if np.array_equal(s_new, s) and np.array_equal(np.signbit(s_new), np.signbit(s)):
            break
        s = s_new
        p = pose(path, s)
    dx = x - p.x
    dy = y - p.y
    g = dx * p.cos_theta + dy * p.sin_theta
    e = dy * p.cos_theta - dx * p.sin_theta
    status = np.full(s.shape, clothoid.STATUS_INTERIOR, dtype=np.int64)
    status[((s <= lo) & (g < 0.0)) | ((s >= hi) & (g > 0.0))] = clothoid.STATUS_WINDOW
    if not path.closed:
        status[(s <= 0.0) & (g < 0.0)] = clothoid.STATUS_START
        status[(s >= t.length) & (g > 0.0)] = clothoid.STATUS_END
    s_lap = s
    if path.closed:
        s_c = s - np.floor(s / t.length) * t.length
        s_lap = np.where(s_c >= t.length, s_c - t.length, s_c)
    dist = np.sqrt(dx * dx + dy * dy)
    return PathPoint(
        s_lap, s, p.x, p.y, p.theta, p.curvature, p.curvature_rate, e, p.cos_theta, p.sin_theta, dist, status
    )
