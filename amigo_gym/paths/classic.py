"""AmigoBot-v0 paths for point H: the paper's circle (eq. 6) and its manoeuvre path (straight, then circle).

Arc lengths ``s`` [m] from the start point, points ``(..., 2)`` [m], tangent angle ``theta(s)`` [rad] continuous,
signed curvature ``kappa(s) = dtheta/ds`` [1/m] positive turning left, cross-track error ``e = (p - closest) . n``
[m] with ``n = (-sin theta, cos theta)`` (positive left). ``project`` takes points ``(..., 2)``, ``project_xy``
columns (floats or arrays). The foot functions are in numba's subset (compiled by :mod:`amigo_gym.sim`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import Real, pack
from amigo_gym.model.numeric import where
from amigo_gym.model.params import check_real

Array = NDArray[np.float64]
TWO_PI = 2.0 * math.pi
#: an int status (one point) or an int64 column
IntColumn = int | NDArray[np.int64]


def wrap_angle(x: ArrayLike) -> Array:
    """Wrap angles to ``[-pi, pi)`` [rad], elementwise."""
    return np.mod(np.asarray(x, dtype=np.float64) + math.pi, TWO_PI) - math.pi


class Projection(NamedTuple):
    """Closest point of a path to query points, fields with the query's leading axes: its arc length ``s`` [m],
    the ``point`` ``(..., 2)`` [m], the path's ``tangent_angle`` [rad] and signed ``curvature`` [1/m] there, the
    ``cross_track_error`` [m] (positive left of the path direction) and the unit tangent ``cos_theta, sin_theta``."""

    s: Array
    point: Array
    tangent_angle: Array
    curvature: Array
    cross_track_error: Array
    cos_theta: Array
    sin_theta: Array


class ClosestPoint(NamedTuple):
    """Column form of :class:`Projection` (from ``project_xy``): the point as ``x``, ``y`` columns of the query's
    shape; ``curvature`` a float on a circle; the fields a ``minimal`` projection skips are NaN."""

    s: Real
    x: Real
    y: Real
    tangent_angle: Real
    curvature: Real
    cross_track_error: Real
    cos_theta: Real
    sin_theta: Real

    def projection(self) -> Projection:
        """The :class:`Projection` of these columns (point stacked ``(..., 2)``, curvature broadcast)."""
        s = np.asarray(self.s)
        k = np.asarray(np.broadcast_to(self.curvature, s.shape)).copy()
        rest = (np.asarray(v) for v in (self.cross_track_error, self.cos_theta, self.sin_theta))
        return Projection(s, pack(self.x, self.y), np.asarray(self.tangent_angle), k, *rest)


class PathPose(NamedTuple):
    """The path at arc lengths ``s`` (``pose_columns`` of every path), columns of the shape of ``s``: the point
    ``x, y`` [m], the tangent angle ``theta`` [rad] (continuous: laps of a closed path add its total turn), the
    signed ``curvature`` [1/m], ``curvature_rate = dkappa/ds`` [1/m^2], the unit tangent ``cos_theta, sin_theta``."""

    x: Real
    y: Real
    theta: Real
    curvature: Real
    curvature_rate: Real
    cos_theta: Real
    sin_theta: Real


def _pose(x: Any, y: Any, th: Any, k: Any, s: Real) -> PathPose:
    # a PathPose of arrays, or of floats for a float s
    c, sn = np.cos(th), np.sin(th)
    if not isinstance(s, np.ndarray):
        return PathPose(float(x), float(y), float(th), float(k), 0.0, float(c), float(sn))
    return PathPose(x, y, th, k, np.zeros(np.shape(th)), c, sn)


class PathPoint(NamedTuple):
    """The closest path point ``c`` to query points ``p`` (``locate`` of every path), as columns: ``s`` [m] within
    one traversal (``[0, length)`` closed, ``[0, length]`` open), ``progress`` [m] unwrapped (``s`` plus whole laps
    from the hint ``s_prev``), ``x, y`` [m], ``tangent_angle`` [rad] unwrapped, ``curvature`` [1/m],
    ``curvature_rate`` [1/m^2], ``cross_track_error = (p - c) . n`` [m] (positive left; at a clamped end the
    lateral part), ``cos_theta, sin_theta``, ``distance = |p - c|`` [m] and ``status`` (``STATUS_INTERIOR`` 0,
    ``STATUS_START``, ``STATUS_END``, ``STATUS_WINDOW`` of :mod:`amigo_gym.paths.clothoid`)."""

    s: Real
    progress: Real
    x: Real
    y: Real
    tangent_angle: Real
    curvature: Real
    curvature_rate: Real
    cross_track_error: Real
    cos_theta: Real
    sin_theta: Real
    distance: Real
    status: IntColumn

    def closest_point(self) -> ClosestPoint:
        """The :class:`ClosestPoint` of these columns (``s`` within one lap)."""
        e, c, sn = self.cross_track_error, self.cos_theta, self.sin_theta
        return ClosestPoint(self.s, self.x, self.y, self.tangent_angle, self.curvature, e, c, sn)


class _Projecting:
    def project(self, p: ArrayLike) -> Projection:
        """Closest point to ``p`` ``(..., 2)`` [m] (:meth:`project_xy` of its columns)."""
        q = np.asarray(p, dtype=np.float64)
        cp: ClosestPoint = self.project_xy(q[..., 0], q[..., 1])  # type: ignore[attr-defined]
        return cp.projection()


@dataclass(frozen=True)
class CirclePath(_Projecting):
    r"""Circle of radius ``radius`` entered at ``start`` with heading ``start_angle``, turning left
    (``direction = +1``) or right (``-1``). The defaults give the paper's eq. (6):

    .. math:: x_H = R \sin\phi, \quad y_H = R(1 - \cos\phi), \quad \phi = s / R.

    In general ``theta(s) = theta0 + d s / R``, ``p(s) = c + d R (sin theta, -cos theta)``, centre
    ``c = p0 + d R (-sin theta0, cos theta0)``, with ``R = radius`` [m] > 0, ``p0 = start`` [m], ``theta0 =
    start_angle`` [rad], ``d = direction``. Projections' arc lengths lie in ``[0, 2 pi R)``; laps repeat."""

    radius: float = 1.0
    start: tuple[float, float] = (0.0, 0.0)
    start_angle: float = 0.0
    direction: int = 1

    def __post_init__(self) -> None:
        check_real("CirclePath", "radius", self.radius, 0.0, low_open=True)
        check_real("CirclePath", "start_angle", self.start_angle)
        for i, c in enumerate(self.start):
            check_real("CirclePath", f"start[{i}]", c)
        if self.direction not in (1, -1):
            raise ValueError(f"CirclePath.direction must be +1 or -1, got {self.direction!r}")

    @property
    def center(self) -> tuple[float, float]:
        """Centre of the circle [m]."""
        d, r, t0 = self.direction, self.radius, self.start_angle
        return (self.start[0] - d * r * math.sin(t0), self.start[1] + d * r * math.cos(t0))

    @property
    def length(self) -> float:
        """Circumference ``2 pi R`` [m]."""
        return TWO_PI * self.radius

    def tangent_angle(self, s: ArrayLike) -> Array:
        return self.start_angle + self.direction * np.asarray(s, dtype=np.float64) / self.radius

    def curvature(self, s: ArrayLike) -> Array:
        return np.full(np.shape(s), self.direction / self.radius)

    def point(self, s: ArrayLike) -> Array:
        p = self.pose_columns(np.asarray(s, dtype=np.float64))
        return pack(p.x, p.y)

    def curvature_columns(self, s: Real) -> Real:
        return self.direction / self.radius

    #: a circle repeats with period :attr:`length`
    closed = True

    def pose_columns(self, s: Real) -> PathPose:
        """``x``, ``y`` [m], ``theta`` [rad], ``curvature`` [1/m] at arc lengths ``s`` [m] (floats for a float)."""
        th = self.tangent_angle(s)
        cx, cy = self.center
        dr = self.direction * self.radius
        return _pose(cx + dr * np.sin(th), cy - dr * np.cos(th), th, self.curvature(th), s)

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        """:class:`PathPoint` of ``(x, y)`` [m] by :meth:`project_xy`; ``progress`` is ``s`` plus the whole laps
        nearest to ``s_prev`` (``s`` without a hint); the window is not used (the projection is unique); status 0."""
        cp = self.project_xy(x, y)
        s = progress = cp.s
        if s_prev is not None:
            progress = s + self.length * np.round((s_prev - s) / self.length)
            if not isinstance(progress, np.ndarray) or progress.ndim == 0:
                progress = float(progress)
        return _located(cp, progress)

    @cached_property
    def _frame(self) -> tuple[float, float, float, float]:
        # the centre and the unit vector from it to the start point
        d, t0 = self.direction, self.start_angle
        return (*self.center, d * math.sin(t0), -d * math.cos(t0))

    def project_xy(self, x: Real, y: Real, minimal: bool = False) -> ClosestPoint:
        """Closest point of the circle to ``(x, y)`` [m].

        With ``u = (x, y) - c``, ``rho = |u|``, ``n = u / rho``: the point ``c + R n``, the tangent ``d (-n_y, n_x)``,
        ``e = d (R - rho)``, ``s = R a`` with ``a = atan2(d (r0 x u), r0 . u)`` in ``[0, 2 pi)`` from the start
        radius ``r0``. At the centre: the start point. ``minimal=True``: ``s``, point and tangent angle are NaN."""
        cx, cy, r0x, r0y = self._frame
        d, r = self.direction, self.radius
        e, cos_theta, sin_theta, ux, uy = circle_foot(x, y, cx, cy, r0x, r0y, float(d), r)
        if minimal:
            return ClosestPoint(math.nan, math.nan, math.nan, math.nan, d / r, e, cos_theta, sin_theta)
        s = circle_arc(ux, uy, r0x, r0y, float(d), r)
        return ClosestPoint(s, *self._on_arc(s, cos_theta, sin_theta), d / r, e, cos_theta, sin_theta)

    def _on_arc(self, s: Real, cos_theta: Real, sin_theta: Real) -> tuple[Real, Real, Real]:
        # the foot c + r n (n from the unit tangent d (-n_y, n_x): a negation is exact) and theta at arc length s
        cx, cy, _, _ = self._frame
        d, r = self.direction, self.radius
        nx, ny = (sin_theta, -cos_theta) if d > 0 else (-sin_theta, cos_theta)
        return cx + r * nx, cy + r * ny, self.start_angle + (s if d > 0 else -s) / r


def circle_foot(
    x: Real, y: Real, cx: float, cy: float, r0x: float, r0y: float, d: float, r: float
) -> tuple[Real, Real, Real, Real, Real]:
    """Foot of ``(x, y)`` [m] on the circle of centre ``(cx, cy)``, radius ``r`` [m], direction ``d`` (+1
    left, -1 right): ``(e, cos theta, sin theta, u_x, u_y)`` with ``u = (x, y) - c`` (``r0`` at the centre),
    ``e = d (r - |u|)`` and the tangent ``d (-n_y, n_x)``, ``n = u / |u|``."""
    ux = x - cx
    uy = y - cy
    rho = np.sqrt(ux * ux + uy * uy)
    norm = rho
    at_centre = rho == 0.0
    if np.any(at_centre):  # at the centre: the start point
        ux = where(at_centre, r0x, ux)
        uy = where(at_centre, r0y, uy)
        norm = where(at_centre, 1.0, rho)
    nx = ux / norm
    ny = uy / norm
    if d > 0.0:
        return r - rho, -ny, nx, ux, uy
    return rho - r, ny, -nx, ux, uy


def angle_of(y: Real, x: Real) -> Real:
    """``atan2(y, x)`` [rad]: numpy's on columns; the compiled step takes :func:`atan2_float` in its place."""
    return np.arctan2(y, x)


#: Cephes' rational approximation of ``atan(u) - u = u z P(z) / Q(z)``, ``z = u^2``, ``|u| <= 0.66`` (Q monic), and
#: the part of pi / 4 below its float's last bit
_ATAN_P = (-8.750608600031904122785e-1, -1.615753718733365076637e1, -7.500855792314704667340e1,
           -1.228866684490136173410e2, -6.485021904942025371773e1)  # fmt: skip
_ATAN_Q = (2.485846490142306297962e1, 1.650270098316988542046e2, 4.328810604912902668951e2,
           4.853903996359136964868e2, 1.945506571482613964425e2)  # fmt: skip
_PI4_LOW = 3.061616997868382943065e-17


def atan2_float(y: float, x: float) -> float:
    """``atan2(y, x)`` [rad] of two floats, within 2 ulp of the C library's, without calls or branches (a compiled
    loop of it vectorises): ``t = min(|x|, |y|) / max(|x|, |y|)`` in [0, 1], ``a = atan t`` by Cephes' approximation
    (above 0.66 as ``pi / 4 + atan((t - 1) / (t + 1))``), then ``pi / 2 - a`` where ``|y| > |x|``, ``pi - a`` where
    ``x`` is negative (``-0.0`` too), the multiples of pi / 4 added last, and the sign of ``y``. NaN for a NaN or two
    infinite arguments."""
    ax = abs(x)
    ay = abs(y)
    steep = ay > ax
    hi = ay if steep else ax
    lo = ax if steep else ay
    t = lo / (hi if hi != 0.0 else 1.0)
    big = t > 0.66
    u = (t - 1.0) / (t + 1.0) if big else t
    z = u * u
    p = (((_ATAN_P[0] * z + _ATAN_P[1]) * z + _ATAN_P[2]) * z + _ATAN_P[3]) * z + _ATAN_P[4]
    q = ((((z + _ATAN_Q[0]) * z + _ATAN_Q[1]) * z + _ATAN_Q[2]) * z + _ATAN_Q[3]) * z + _ATAN_Q[4]
    a = u + u * (z * p / q)
    k = 1.0 if big else 0.0  # the angle: k pi / 4 + sign a
    k, sign = (2.0 - k, -1.0) if steep else (k, 1.0)
    k, sign = (4.0 - k, -sign) if math.copysign(1.0, x) < 0.0 else (k, sign)
    return math.copysign(k * (0.25 * math.pi) + (sign * a + k * _PI4_LOW), y)


def circle_arc(ux: Real, uy: Real, r0x: float, r0y: float, d: float, r: float) -> Real:
    """Arc length ``s = r a`` [m] from the circle's start to the direction ``u``:
    ``a = atan2(d (r0 x u), r0 . u)`` (:func:`angle_of`), plus ``2 pi`` where negative."""
    cross = r0x * uy - r0y * ux
    a = angle_of(cross if d > 0.0 else -cross, r0x * ux + r0y * uy)
    s: Real = r * (a + where(a < 0.0, TWO_PI, 0.0))
    return s


@dataclass(frozen=True)
class ManoeuvrePath(_Projecting):
    """The paper's manoeuvre path: ``(s, 0)`` with tangent 0 for ``s <= straight_length`` [m] (>= 0; also for
    ``s < 0``), then the circle of ``radius`` [m] (> 0) tangent to the segment's end, turning by ``direction`` (+1
    left, -1 right; laps repeat). Projection takes the closer of the half-line and the circle (ties to the line)."""

    radius: float = 1.0
    straight_length: float = 1.0
    direction: int = 1

    def __post_init__(self) -> None:
        check_real("ManoeuvrePath", "radius", self.radius, 0.0, low_open=True)
        check_real("ManoeuvrePath", "straight_length", self.straight_length, 0.0)
        if self.direction not in (1, -1):
            raise ValueError(f"ManoeuvrePath.direction must be +1 or -1, got {self.direction!r}")

    @cached_property
    def circle(self) -> CirclePath:
        """The circular part, starting at the segment's end."""
        return CirclePath(self.radius, (self.straight_length, 0.0), 0.0, self.direction)

    @property
    def length(self) -> float:
        """Straight part plus one lap [m]."""
        return self.straight_length + self.circle.length

    def tangent_angle(self, s: ArrayLike) -> Array:
        s = np.asarray(s, dtype=np.float64)
        return np.where(s <= self.straight_length, 0.0, self.circle.tangent_angle(s - self.straight_length))

    def curvature(self, s: ArrayLike) -> Array:
        s = np.asarray(s, dtype=np.float64)
        return np.where(s <= self.straight_length, 0.0, self.direction / self.radius)

    def point(self, s: ArrayLike) -> Array:
        s = np.asarray(s, dtype=np.float64)
        straight = np.stack((s, np.zeros_like(s)), axis=-1)
        arc = self.circle.point(s - self.straight_length)
        return np.where((s <= self.straight_length)[..., None], straight, arc)

    def curvature_columns(self, s: Real) -> Real:
        """Curvature [1/m] at ``s`` [m]: 0 for ``s <= straight_length``, else ``direction / radius``."""
        return manoeuvre_curvature(s, self.straight_length, self.direction / self.radius)  # type: ignore[arg-type]

    #: open, but its projection never reports the end (the circle's laps repeat)
    closed = False

    def pose_columns(self, s: Real) -> PathPose:
        """``x``, ``y`` [m], ``theta`` [rad], ``curvature`` [1/m] at ``s`` [m], floats for a float ``s``."""
        xy = self.point(s)
        return _pose(xy[..., 0], xy[..., 1], self.tangent_angle(s), self.curvature(s), s)

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        """:class:`PathPoint` of ``(x, y)`` [m] by :meth:`project_xy`; ``progress = s``; status 0 (the path does
        not end)."""
        cp = self.project_xy(x, y)
        if not isinstance(cp.cross_track_error, np.ndarray) or np.ndim(cp.cross_track_error) == 0:
            cp = ClosestPoint(*(float(v) for v in cp))
        return _located(cp, cp.s)

    def project_xy(self, x: Real, y: Real, minimal: bool = False) -> ClosestPoint:
        """Closest point to ``(x, y)`` [m] (:func:`manoeuvre_foot`); ``minimal=True``: point and tangent
        angle are NaN."""
        circle = self.circle
        d, r = self.direction, self.radius
        e, ct, st, s, s_circ, on_line = manoeuvre_foot(x, y, *circle._frame, float(d), r, self.straight_length)
        curvature = where(on_line, 0.0, d / r)
        if minimal:
            return ClosestPoint(s, math.nan, math.nan, math.nan, curvature, e, ct, st)
        arc = circle._on_arc(s_circ, ct, st)
        px, py, theta = (where(on_line, a, b) for a, b in zip((s, 0.0, 0.0), arc, strict=True))
        return ClosestPoint(s, px, py, theta, curvature, e, ct, st)


def manoeuvre_foot(
    x: Real, y: Real, cx: float, cy: float, r0x: float, r0y: float, d: float, r: float, big_l: float
) -> tuple[Real, Real, Real, Real, Real, bool | NDArray[np.bool_]]:
    """``(e, cos theta, sin theta, s, s_circ, on_line)``: the foot of ``(x, y)`` [m] on the manoeuvre path, the
    half-line ``y = 0, x <= L = big_l`` then the circle of :func:`circle_foot` from ``(L, 0)``. On the line
    ``s = min(x, L)``, ``d_line = hypot(x - s, y)``, ``e = y`` (``sign(y) d_line`` past the end); on the circle
    ``s = L + s_circ`` (:func:`circle_arc`). The line wins where ``d_line <= |e_circle|`` (numpy's NaN and
    signed-zero rules)."""
    e, cos_theta, sin_theta, ux, uy = circle_foot(x, y, cx, cy, r0x, r0y, d, r)
    s_circ = circle_arc(ux, uy, r0x, r0y, d, r)
    s_line = where((x < big_l) | (x != x), x, big_l)  # np.minimum(x, big_l)
    d_line = np.hypot(x - s_line, y)
    on_line = d_line <= np.abs(e)  # the line (ties to it)
    sign_y = where(y > 0.0, 1.0, where(y < 0.0, -1.0, where(y == 0.0, 0.0, y)))  # np.sign(y)
    e_line = where(x <= big_l, y, sign_y * d_line)
    return (
        where(on_line, e_line, e),
        where(on_line, 1.0, cos_theta),
        where(on_line, 0.0, sin_theta),
        where(on_line, s_line, big_l + s_circ),
        s_circ,
        on_line,
    )


def manoeuvre_curvature(s: float, big_l: float, curvature: float) -> float:
    """Curvature [1/m] at ``s`` [m]: 0 where ``s <= big_l``, else ``curvature`` (also for NaN)."""
    k: float = where(s <= big_l, 0.0, curvature)
    return k


def _located(cp: ClosestPoint, progress: Real) -> PathPoint:
    """The :class:`PathPoint` of ``cp`` with ``progress`` [m]: curvature rate 0, ``distance = |e|``, status 0."""
    e = cp.cross_track_error
    zero = 0.0 * e
    dist, status = (np.abs(e), np.zeros(e.shape, np.int64)) if isinstance(e, np.ndarray) else (abs(e), 0)
    k = cp.curvature + zero
    return PathPoint(cp.s, progress, cp.x, cp.y, cp.tangent_angle, k, zero, e, cp.cos_theta, cp.sin_theta, dist, status)
