r"""Paths for point H: the paper's circle (eq. 6) and its manoeuvre path (straight, then circle).

Paths are frozen dataclasses whose methods are pure and batched: arc lengths ``s`` have shape
``(...)`` and points ``(..., 2)``; results keep the leading axes. A path is parametrised by arc
length ``s`` [m] from its start point; its tangent angle ``theta(s)`` [rad] and signed curvature
``kappa(s) = dtheta/ds`` [1/m] (positive turning left) follow.

The signed cross-track error of a point is positive when the point lies to the **left** of the
path direction, i.e. ``e = (p - closest) . n`` with ``n = (-sin theta, cos theta)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.params import EnvParams, check_range

__all__ = ["Projection", "Path", "CirclePath", "ManoeuvrePath", "make_path", "wrap_angle"]

Array = NDArray[np.float64]
TWO_PI = 2.0 * math.pi


def wrap_angle(x: ArrayLike) -> Array:
    """Wrap angles to ``[-pi, pi)`` [rad], elementwise."""
    return np.mod(np.asarray(x, dtype=np.float64) + math.pi, TWO_PI) - math.pi


class Projection(NamedTuple):
    """Closest point of a path to query points; every field has the query's leading axes.

    Attributes:
        s: arc length of the closest point [m].
        point: the closest point ``(..., 2)`` [m].
        tangent_angle: path tangent angle there [rad].
        curvature: signed path curvature there [1/m].
        cross_track_error: signed distance, positive left of the path direction [m].
    """

    s: Array
    point: Array
    tangent_angle: Array
    curvature: Array
    cross_track_error: Array


class Path(Protocol):
    """What the environment, the inverse solution and the agents need of a path."""

    @property
    def length(self) -> float:
        """Arc length of one traversal [m] (one lap for a closed path, ``inf`` if open)."""
        ...

    def point(self, s: ArrayLike) -> Array:
        """Point at arc length ``s``: ``(..., 2)`` [m]."""
        ...

    def tangent_angle(self, s: ArrayLike) -> Array:
        """Tangent angle ``theta(s)`` [rad], continuous in ``s`` (not wrapped)."""
        ...

    def curvature(self, s: ArrayLike) -> Array:
        """Signed curvature ``kappa(s)`` [1/m]."""
        ...

    def project(self, p: ArrayLike) -> Projection:
        """Closest point to ``p`` ``(..., 2)``, with tangent, curvature and signed cross-track error."""
        ...


@dataclass(frozen=True)
class CirclePath:
    r"""Circle of radius ``radius`` entered at ``start`` with heading ``start_angle``.

    ``direction = +1`` turns left (counter-clockwise), ``-1`` right. With the defaults this is the
    paper's eq. (6): through the origin, tangent to x0 there, centre ``(0, R)``:

    .. math:: x_H = R \sin\phi, \quad y_H = R(1 - \cos\phi), \quad \phi = s / R.

    In general ``theta(s) = theta0 + d s / R`` and ``p(s) = c + d R (sin theta, -cos theta)`` with
    centre ``c = p0 + d R (-sin theta0, cos theta0)``. Arc lengths of projections lie in
    ``[0, 2 pi R)``; :meth:`point` and friends accept any ``s`` (laps repeat).

    Attributes:
        radius: R [m], > 0.
        start: start point ``(x, y)`` [m].
        start_angle: tangent angle at the start [rad].
        direction: +1 (left) or -1 (right).
    """

    radius: float = 1.0
    start: tuple[float, float] = (0.0, 0.0)
    start_angle: float = 0.0
    direction: int = 1

    def __post_init__(self) -> None:
        check_range("CirclePath", "radius", self.radius, 0.0, low_open=True)
        check_range("CirclePath", "start_angle", self.start_angle)
        for i, c in enumerate(self.start):
            check_range("CirclePath", f"start[{i}]", c)
        if self.direction not in (1, -1):
            raise ValueError(f"CirclePath.direction must be +1 or -1, got {self.direction!r}")

    @classmethod
    def from_center(
        cls, center: tuple[float, float], radius: float, direction: int = 1, start_phase: float = 0.0
    ) -> CirclePath:
        """Circle given by its centre [m]; the start is at polar angle ``start_phase`` [rad] about it."""
        p0 = (center[0] + radius * math.cos(start_phase), center[1] + radius * math.sin(start_phase))
        return cls(radius=radius, start=p0, start_angle=start_phase + direction * math.pi / 2, direction=direction)

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
        th = self.tangent_angle(s)
        c = self.center
        dr = self.direction * self.radius
        return np.stack((c[0] + dr * np.sin(th), c[1] - dr * np.cos(th)), axis=-1)

    def project(self, p: ArrayLike) -> Projection:
        p = np.asarray(p, dtype=np.float64)
        c = self.center
        d = self.direction
        ux = p[..., 0] - c[0]
        uy = p[..., 1] - c[1]
        rho = np.hypot(ux, uy)
        th = np.arctan2(d * ux, -d * uy)  # tangent angle at the closest point (0 at the centre)
        s = self.radius * np.mod(d * (th - self.start_angle), TWO_PI)
        th = self.tangent_angle(s)
        return Projection(
            s=s,
            point=self.point(s),
            tangent_angle=th,
            curvature=self.curvature(s),
            cross_track_error=d * (self.radius - rho),
        )


@dataclass(frozen=True)
class ManoeuvrePath:
    """The paper's manoeuvre path: a straight segment along x0 from the origin, then a circle.

    For ``0 <= s <= straight_length`` the path is ``(s, 0)`` with tangent 0; beyond, it is the circle
    of ``radius`` tangent to the segment's end, turning by ``direction`` (laps repeat). The straight
    part extends backwards for ``s < 0`` so that points behind the start project onto it.

    Projection takes the closer of the straight half-line and the circle (ties to the straight).

    Attributes:
        radius: circle radius [m], > 0.
        straight_length: straight segment length [m], >= 0.
        direction: +1 (left) or -1 (right).
    """

    radius: float = 1.0
    straight_length: float = 1.0
    direction: int = 1

    def __post_init__(self) -> None:
        check_range("ManoeuvrePath", "radius", self.radius, 0.0, low_open=True)
        check_range("ManoeuvrePath", "straight_length", self.straight_length, 0.0)
        if self.direction not in (1, -1):
            raise ValueError(f"ManoeuvrePath.direction must be +1 or -1, got {self.direction!r}")

    @property
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

    def project(self, p: ArrayLike) -> Projection:
        p = np.asarray(p, dtype=np.float64)
        L = self.straight_length
        s_line = np.minimum(p[..., 0], L)
        d_line = np.hypot(p[..., 0] - s_line, p[..., 1])
        circ = self.circle.project(p)
        use_line = d_line <= np.abs(circ.cross_track_error)
        s = np.where(use_line, s_line, L + circ.s)
        line_point = np.stack((s_line, np.zeros_like(s_line)), axis=-1)
        point = np.where(use_line[..., None], line_point, circ.point)
        th = np.where(use_line, 0.0, circ.tangent_angle)
        # for the line: e = (p - q) . (0, 1) = y (exact beyond the segment end too, as the distance
        # there is measured to the end point only in the rare case it is the closer feature)
        e_line = np.where(p[..., 0] <= L, p[..., 1], np.sign(p[..., 1]) * d_line)
        return Projection(
            s=s,
            point=point,
            tangent_angle=th,
            curvature=np.where(use_line, 0.0, circ.curvature),
            cross_track_error=np.where(use_line, e_line, circ.cross_track_error),
        )


def make_path(params: EnvParams) -> CirclePath | ManoeuvrePath:
    """The path that ``params`` describe (``params.path``, ``radius``, ``direction``, ...)."""
    if params.path == "circle":
        return CirclePath(radius=params.radius, direction=params.direction)
    return ManoeuvrePath(radius=params.radius, straight_length=params.straight_length, direction=params.direction)
