r"""Clothoid paths for point H (AmigoBot-v1): exact geometry and a projection that keeps progress.

A :class:`ClothoidPath` chains :class:`ClothoidSegment` s (curvature linear in arc length) from a start pose,
optionally closed (laps). On a piece of curvature ``kappa(u) = k0 + c u`` from ``(x0, y0, theta0)``:

.. math::
    \theta(u) = \theta_0 + k_0 u + \tfrac12 c u^2, \qquad
    \mathbf{p}(u) = \mathbf{p}_0 + \int_0^u (\cos\theta(\tau), \sin\theta(\tau))\,d\tau,

by :func:`amigo_gym.model.fresnel.advance`'s 10-node rule on pieces of ``|k0| u + |c| u^2 / 2 <= MAX_PHASE_PER_SUB``
(within 5e-14 of ``u``, 4e-16 up to 1 rad). Conventions as :mod:`amigo_gym.paths.classic` (``theta`` continuous: laps
add the total turn); an open path goes on straight beyond its ends, a closed one repeats with period ``length``. A flat
float vector (:data:`PATH_HEADER`, each piece's ``s0, x0, y0, th0, k0, c`` in turn, the coarse samples' ``x``, ``y``),
in numba's subset; a closed path of arcs of one curvature (a circle) also stores its curvature and centre: its
projection starts at the foot in closed form instead of the coarse search.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import InitVar, dataclass, field
from functools import cached_property
from itertools import accumulate
from typing import Any, NamedTuple, Protocol, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.fresnel import NODES, Buffer, node_table, subinterval_count, unit_speed_nodes, unit_speed_poses
from amigo_gym.model.kinematics import Real, pack
from amigo_gym.model.params import check_real
from amigo_gym.paths.classic import ClosestPoint, PathPoint, PathPose, _Projecting

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
TWO_PI = 2.0 * math.pi

#: the closest point is an orthogonal foot point inside the searched range
STATUS_INTERIOR = 0
#: the projection is clamped at the start of an open path (the point lies before it)
STATUS_START = 1
#: the projection is clamped at the end of an open path (the point lies beyond it)
STATUS_END = 2
#: the projection is clamped at an edge of the search window around the hint ``s_prev``
STATUS_WINDOW = 3

#: Newton iterations of the projection (at most; it stops at a fixed point)
NEWTON_ITERATIONS = 5
#: a Newton step ``u`` [m] with ``|u| (1 + |kappa| + |c u|)`` below this is the last one (the next would be below
#: rounding), its pose the first-order one from the last pose (its error ``kappa u^2 / 2`` below rounding too)
NEWTON_TAYLOR_STEP = 1e-8
#: the Newton denominator ``1 - kappa e`` is bounded below by this (points near a centre of curvature)
MIN_NEWTON_DENOMINATOR = 0.05
#: largest length [m] and curvature [1/m] of a segment
MAX_SEGMENT_LENGTH = 1.0e5
MAX_CURVATURE = 1.0e4
#: the default largest spacing [m] of a path's coarse projection samples
SAMPLE_SPACING = 0.02
#: closure tolerance of a closed path: position gap relative to max(1 m, length), and heading gap [rad]
CLOSURE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class ClothoidSegment:
    """One clothoid segment: curvature ``kappa(u) = curvature + curvature_rate u`` [1/m] for ``0 <= u <= length``
    [m] in (0, 1e5]; ``curvature`` (positive left) and the end curvature in [-1e4, 1e4], ``curvature_rate``
    [1/m^2] finite (a line: both 0; an arc: rate 0)."""

    length: float
    curvature: float = 0.0
    curvature_rate: float = 0.0

    def __post_init__(self) -> None:
        g, k, c = self.length, self.curvature, self.curvature_rate
        floats = type(g) is type(k) is type(c) is float and 0.0 < g <= MAX_SEGMENT_LENGTH and c - c == 0.0
        if floats and abs(k) <= MAX_CURVATURE and abs(k + c * g) <= MAX_CURVATURE:
            return  # floats in range: what the checks below keep (the family paths build many segments)
        o = "ClothoidSegment"
        object.__setattr__(self, "length", check_real(o, "length", self.length, 0.0, MAX_SEGMENT_LENGTH, low_open=True))
        object.__setattr__(self, "curvature", check_real(o, "curvature", self.curvature, -MAX_CURVATURE, MAX_CURVATURE))
        object.__setattr__(self, "curvature_rate", check_real(o, "curvature_rate", self.curvature_rate))
        check_real("ClothoidSegment", "curvature_end", self.curvature_end, -MAX_CURVATURE, MAX_CURVATURE)

    @classmethod
    def line(cls, length: float) -> ClothoidSegment:
        """A straight segment of ``length`` [m]."""
        return cls(length, 0.0, 0.0)

    @classmethod
    def arc(cls, length: float, curvature: float) -> ClothoidSegment:
        """A circular arc of ``length`` [m] and signed ``curvature`` [1/m]."""
        return cls(length, curvature, 0.0)

    @classmethod
    def transition(cls, length: float, curvature_start: float, curvature_end: float) -> ClothoidSegment:
        """A clothoid from ``curvature_start`` to ``curvature_end`` [1/m] over ``length`` [m]."""
        check_real("ClothoidSegment", "length", length, 0.0, MAX_SEGMENT_LENGTH, low_open=True)
        return cls(length, curvature_start, (curvature_end - curvature_start) / length)

    @property
    def curvature_end(self) -> float:
        """Curvature at the end, ``curvature + curvature_rate length`` [1/m]."""
        return float(self.curvature) + float(self.curvature_rate) * float(self.length)

    @property
    def turn(self) -> float:
        """Change of tangent angle, ``k0 L + c L^2 / 2`` [rad]."""
        length = float(self.length)
        return length * (float(self.curvature) + 0.5 * float(self.curvature_rate) * length)


class PathSpec(Protocol):
    """The interface AmigoBot-v1 uses of a path (:class:`ClothoidPath` implements it): ``length`` of one traversal
    [m] (one lap), ``closed`` (repeats with period ``length``), ``pose_columns(s)`` (a :class:`PathPose` of columns
    at arc lengths ``s`` [m]) and ``locate`` (the closest :class:`PathPoint` to ``(x, y)`` [m], within
    ``[s_prev - max_retreat, s_prev + max_advance]`` given a hint). A path of your own needs only the first three;
    :mod:`amigo_gym.paths.user` completes the rest."""

    @property
    def length(self) -> float: ...

    @property
    def closed(self) -> bool: ...

    def pose_columns(self, s: Real) -> PathPose: ...

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint: ...


def check_hint(sp: Real) -> None:
    """Raise :func:`check_real`'s error for the first NaN or infinite hint ``s_prev`` (float or array)."""
    a = np.asarray(sp, dtype=np.float64)
    if (bad := a[~np.isfinite(a)]).size:
        check_real("locate", "s_prev", float(bad.flat[0]))


@dataclass(frozen=True)
class _Tables:
    """A built path: its flat vector, largest ``|curvature|`` [1/m], length [m] and total turn [rad]."""

    flat: Array
    max_abs_curvature: float
    length: float
    turn: float

    def column(self, k: int) -> Array:
        # column k (a view): 0 ... 5 the pieces' s0, x0, y0, th0, k0, c; 6, 7 the samples' x, y
        n, m = int(self.flat[P_N]), int(self.flat[P_M])
        if k < 6:
            return self.flat[P_TAIL + k : P_TAIL + 6 * n : 6]
        return self.flat[P_TAIL + 6 * n + (k - 6) * m :][:m]

    s0 = property(lambda self: self.column(0).tolist())


class PathLoops(NamedTuple):
    """The compiled :func:`~amigo_gym.paths.families.family_segments` (``family(kind, a, b, c)``: the segments and
    their number last), :func:`build_flat` with the samples (``flat(pv, segs, n_segs, n, m, total, spacing, x, y,
    theta, closed)``), :func:`sample_points`, :func:`locate_rows`, :func:`pose_rows` (scratch and nodes supplied): the
    ``loops=`` of the path constructors (:func:`amigo_gym.sim.fast_v1.path_loops`)."""

    family: Callable[..., Array]
    flat: Callable[..., tuple[float, float]]
    samples: Callable[..., None]
    locate: Callable[..., None]
    pose: Callable[..., None]


@dataclass(frozen=True)
class ClothoidPath(_Projecting):
    """A path of clothoid ``segments`` (a non-empty tuple) from ``start`` ``(x, y)`` [m] at ``start_angle`` [rad];
    exact geometry, batched evaluation and projection. ``closed``: it repeats, its end pose equal to its start pose
    (to 1e-9 relative to ``max(1 m, length)`` and 1e-9 rad modulo ``2 pi``). ``sample_spacing`` [m] in [1e-4, 1]:
    of the coarse projection samples (also at most ``0.1 / max|kappa|``). ``loops`` (not stored):
    :class:`PathLoops` or None (Python), the same path either way.
    """

    segments: tuple[ClothoidSegment, ...]
    start: tuple[float, float] = (0.0, 0.0)
    start_angle: float = 0.0
    closed: bool = False
    sample_spacing: float = SAMPLE_SPACING
    _t: _Tables = field(init=False, repr=False, compare=False)
    loops: InitVar[PathLoops | None] = None

    def __post_init__(self, loops: PathLoops | None) -> None:
        segs = self.segments
        if isinstance(segs, list):
            segs = tuple(segs)
            object.__setattr__(self, "segments", segs)
        if not isinstance(segs, tuple) or not segs or not all(isinstance(g, ClothoidSegment) for g in segs):
            raise ValueError(f"ClothoidPath.segments must be a non-empty tuple of ClothoidSegment, got {segs!r}")
        if not isinstance(self.start, tuple) or len(self.start) != 2:
            raise ValueError(f"ClothoidPath.start must be a pair (x, y), got {self.start!r}")
        start = tuple(check_real("ClothoidPath", f"start[{i}]", v) for i, v in enumerate(self.start))
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "start_angle", check_real("ClothoidPath", "start_angle", self.start_angle))
        if not isinstance(self.closed, bool):
            raise ValueError(f"ClothoidPath.closed must be True or False, got {self.closed!r}")
        spacing = check_real("ClothoidPath", "sample_spacing", self.sample_spacing, 1e-4, 1.0)
        object.__setattr__(self, "sample_spacing", spacing)
        object.__setattr__(self, "_t", self._build(loops))

    def _build(self, loops: PathLoops | None = None) -> _Tables:
        segs = [v for g in self.segments for v in (g.length, g.curvature, g.curvature_rate, 0.0)]  # checked floats
        n_segs, closed = len(self.segments), self.closed
        n, m, total, kmax, spacing = path_layout(segs, n_segs, float(self.sample_spacing), closed)
        x, y, th = float(self.start[0]), float(self.start[1]), float(self.start_angle)
        if loops is None:
            pv: Any = [0.0] * (P_TAIL + 6 * n + 2 * m)
            gap, turn_gap = build_flat(pv, segs, n_segs, n, m, total, spacing, x, y, th, closed, [0.0] * _SCRATCH,
                                       _PATH_TABLE)  # fmt: skip
            flat, o = np.array(pv), P_TAIL + 6 * n
            if _COMPILED:  # (the compiled pose either way)
                _COMPILED[0].samples(flat, o, m, spacing)
            else:
                poses = _poses_flat(pv, (np.arange(m, dtype=np.float64) * spacing).tolist())
                flat[o : o + m], flat[o + m :] = [q[0] for q in poses], [q[1] for q in poses]
        else:
            flat = np.empty(P_TAIL + 6 * n + 2 * m)
            gap, turn_gap = loops.flat(flat, np.array(segs), n_segs, n, m, total, spacing, x, y, th, closed)
        if gap > CLOSURE_TOLERANCE * max(1.0, total) or abs(turn_gap) > CLOSURE_TOLERANCE:
            raise ValueError(
                f"ClothoidPath.closed: the segments end {gap:.3g} m from the start with a heading "
                f"{turn_gap:.3g} rad off, but a closed path must end at its start pose"
            )
        return _Tables(flat, kmax, total, float(flat[P_TURN]))

    @cached_property
    def _flat_list(self) -> list[float]:
        out: list[float] = self._t.flat.tolist()  # faster to index than the array
        return out

    @property
    def length(self) -> float:
        """Arc length of one traversal [m] (one lap if closed)."""
        return self._t.length

    @property
    def max_abs_curvature(self) -> float:
        """``max |kappa|`` over the path [1/m]."""
        return self._t.max_abs_curvature

    def breakpoints(self) -> tuple[float, ...]:
        """Arc lengths of the segment joints, with 0 and :attr:`length` [m] (where the curvature may have a kink)."""
        return (0.0, *accumulate(float(g.length) for g in self.segments))

    def pose_columns(self, s: Real) -> PathPose:
        """Point, tangent angle, curvature and curvature rate at arc lengths ``s`` [m] (columns, any shape)."""
        if not isinstance(s, np.ndarray):
            sf = s if type(s) is float else float(s)
            return PathPose(*pose_flat([0.0] * _SCRATCH, _PATH_TABLE, 0, self._flat_list, sf))
        a = np.ascontiguousarray(s, dtype=np.float64).reshape(-1)
        p = pose_columns_of(self._t.flat, np.zeros(a.size, dtype=np.int64), a)
        return PathPose(*(np.reshape(v, np.shape(s)) for v in p))

    def pose_floats(self, ss: list[float]) -> list[PathPose]:
        """:meth:`pose_columns` of each float in ``ss``, computed together."""
        return [PathPose(*q) for q in _poses_flat(self._flat_list, ss)]

    def _array_pose(self, s: ArrayLike) -> PathPose:
        a = np.asarray(s, dtype=np.float64)
        p = self.pose_columns(a.reshape(-1))
        return PathPose(*(np.broadcast_to(v, (a.size,)).reshape(a.shape) for v in p))

    def point(self, s: ArrayLike) -> Array:
        """Point at arc length ``s``: ``(..., 2)`` [m]."""
        p = self._array_pose(s)
        return pack(p.x, p.y)

    def tangent_angle(self, s: ArrayLike) -> Array:
        """Tangent angle ``theta(s)`` [rad], continuous in ``s`` (not wrapped)."""
        return np.asarray(self._array_pose(s).theta)

    def curvature(self, s: ArrayLike) -> Array:
        """Signed curvature ``kappa(s)`` [1/m]."""
        return np.asarray(self._array_pose(s).curvature)

    def curvature_rate(self, s: ArrayLike) -> Array:
        """``dkappa/ds`` [1/m^2] (right-continuous at segment joints)."""
        return np.asarray(self._array_pose(s).curvature_rate)

    def curvature_columns(self, s: Real) -> Real:
        """:meth:`curvature` as a column."""
        return self.pose_columns(s).curvature

    def project_xy(self, x: Real, y: Real, minimal: bool = False) -> ClosestPoint:
        """Closest point (global search; ``minimal`` is ignored)."""
        return self.locate(x, y).closest_point()

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        """Closest path point to the points ``(x, y)`` [m], keeping progress along the path.

        1. Coarse search over the samples ``s_j = j h``: over one lap without a hint ``s_prev`` [m], else over the
           window ``[s_prev - max_retreat, s_prev + max_advance]`` [m] (> 0; ``max_retreat`` defaults to
           ``max_advance``), less than half the arc length between branches that pass near each other; with a
           hint on a circle (arcs of one curvature, closed), the foot in closed form, lap nearest the hint (no step 2).
        2. Newton's method on ``g(s) = (p - c(s)) . t(s)``, ``g'(s) = -(1 - kappa e)``, steps limited to ``h``,
           ``s`` kept in the window (and in ``[0, L]`` on an open path) (:func:`project_flat`).
        3. The status says whether ``s`` was clamped at an end of an open path or at a window edge.

        ``x``, ``y``, ``s_prev``: floats or arrays, broadcast; a :class:`PathPoint` of their shape.
        """
        if not (isinstance(x, np.ndarray) or isinstance(y, np.ndarray) or isinstance(s_prev, np.ndarray)):
            sp = None if s_prev is None else float(s_prev)
            return _locate_float(self._flat_list, float(x), float(y), sp, max_advance, max_retreat)
        return locate_points(self._t.flat, x, y, s_prev, max_advance, max_retreat)


# --------------------------------------------------------------------------- one point (numba's subset)


def py_min(a: float, b: float) -> float:
    """Python's ``min(a, b)`` of two floats (``a`` on ties and NaN), for compiled code."""
    return b if b < a else a


def py_max(a: float, b: float) -> float:
    """Python's ``max(a, b)`` of two floats (``a`` on ties and NaN), for compiled code."""
    return b if b > a else a


FloatPose = tuple[float, float, float, float, float, float, float]
#: a path's pose on floats, ``(buf, nodes, nb, pv, s) -> FloatPose`` (:func:`pose_flat`'s arguments)
PoseOf = Callable[[Buffer, Buffer, int, Any, float], FloatPose]
#: :func:`locate_flat`'s result: ``(progress, x, y, theta, kappa, dkappa/ds, e, cos theta, sin theta, distance,
#: status)``
FlatPoint = tuple[float, float, float, float, float, float, float, float, float, float, int]

# --------------------------------------------------------------------------- the flat path vector

#: the head of a flat path vector (then the arrays)
PATH_HEADER: tuple[str, ...] = (
    "n_pieces", "n_samples", "length", "turn", "spacing", "closed", "circle_curvature", "circle_x", "circle_y"
)  # fmt: skip
P_N, P_M, P_LENGTH, P_TURN, P_SPACING, P_CLOSED, P_CIRCLE_K, P_CIRCLE_X, P_CIRCLE_Y = range(len(PATH_HEADER))
#: where the pieces' arrays start
P_TAIL = len(PATH_HEADER)
#: a flat path vector: a float64 array or a list of Python floats
FlatPath = list[float] | NDArray[np.float64]


def piece_at(pv: FlatPath, s: float) -> tuple[int, float, float, float]:
    """``(j, du, lap, extra)``: the last piece ``j`` with ``s0 <= u`` (clamped to the pieces; NaN: the last) for
    ``s`` [m] wrapped to ``u`` in ``[0, length]``, the distance ``du = u - s0`` into it [m], the lap (closed) and
    the length ``extra = s - u`` past an open path's ends [m]."""
    length = pv[P_LENGTH]
    if pv[P_CLOSED] != 0.0:
        lap = _floor_float(s / length)
        u = s - lap * length
        extra = 0.0
    else:
        u = py_min(py_max(s, 0.0), length)
        lap = 0.0
        extra = s - u
    n = int(pv[P_N])
    lo = 0
    hi = n
    while lo < hi:
        mid = (lo + hi) // 2
        if u < pv[P_TAIL + 6 * mid]:
            hi = mid
        else:
            lo = mid + 1
    j = min(max(lo - 1, 0), n - 1)
    return j, u - pv[P_TAIL + 6 * j], lap, extra


def place(
    pv: FlatPath, j: int, du: float, lap: float, extra: float, x: float, y: float, th: float, ct: float, st: float
) -> FloatPose:
    """The pose on the whole path from the unit-speed pose ``x, y, th, ct, st`` at ``du`` [m] into piece ``j``:
    curvature ``k0 + c du``; laps add ``lap * turn`` [rad] to the heading; past an open path's ends it goes
    straight (curvature 0)."""
    c = pv[P_TAIL + 6 * j + 5]
    kappa = pv[P_TAIL + 6 * j + 4] + c * du
    if pv[P_CLOSED] != 0.0:
        return x, y, th + lap * pv[P_TURN], kappa, c, ct, st
    if extra != 0.0:
        return x + extra * ct, y + extra * st, th, 0.0, 0.0, ct, st
    return x + extra * ct, y + extra * st, th, kappa, c, ct, st


def nearest_sample(pv: FlatPath, x: float, y: float, j0: float, count: int) -> float:
    """``s = j h`` [m] of the coarse sample nearest to ``(x, y)`` among ``j = j0 + k``, ``k < count`` (``count >= 1``;
    a closed path reads sample ``j mod m``, an open one ``clip(j, 0, m - 1)``); the first minimum wins (the first NaN
    if any, as ``np.argmin``). The samples read are runs of consecutive ones, each scanned by :func:`nearest_in_run`:
    an open path's clipped repeats are equal to the first, which wins."""
    h = pv[P_SPACING]
    n = int(pv[P_N])
    m = int(pv[P_M])
    sx = P_TAIL + 6 * n
    m_f = float(m)
    if pv[P_CLOSED] == 0.0:
        top = m_f - 1.0
        i0 = int(min(max(j0, 0.0), top))
        i1 = int(min(max(j0 + float(count - 1), 0.0), top)) + 1
        return float(nearest_in_run(pv, sx, sx + m, x, y, i0, i1, math.inf, i0)[1]) * h
    if abs(j0) + float(count) >= 9007199254740992.0:  # beyond 2^53 the sample numbers are not whole: one by one
        best = math.inf
        best_j = j0
        for k in range(count):
            jj = j0 + float(k)
            idx = int(jj % m_f)
            best, at = nearest_in_run(pv, sx, sx + m, x, y, idx, idx + 1, best, -1)
            best_j = jj if at >= 0 else best_j
        return best_j * h
    # j mod m steps by one: runs from j0 mod m to the end of the samples, then from 0
    i0 = int(j0 % m_f)
    best = math.inf
    best_k = 0
    k = 0
    while k < count:
        i1 = min(m, i0 + count - k)
        best, at = nearest_in_run(pv, sx, sx + m, x, y, i0, i1, best, -1)
        best_k = k + at - i0 if at >= 0 else best_k
        k += i1 - i0
        i0 = 0
    return (j0 + float(best_k)) * h


def nearest_in_run(
    pv: FlatPath, sx: int, sy: int, x: float, y: float, i0: int, i1: int, best: float, at: int
) -> tuple[float, int]:
    """``(best, at)`` after the samples ``i0 <= i < i1`` (``pv[sx + i]``, ``pv[sy + i]``): a squared distance to
    ``(x, y)`` below ``best``, or the first NaN, replaces ``best`` and ``at`` by it and its ``i``."""
    xs = pv[sx + i0 : sx + i1]  # indexed from 0: no negative index to wrap
    ys = pv[sy + i0 : sy + i1]
    for j in range(len(xs)):
        ddx = xs[j] - x
        ddy = ys[j] - y
        d2 = ddx * ddx + ddy * ddy
        if d2 < best or (d2 != d2 and best == best):
            best = d2
            at = i0 + j
    return best, at


def locate_flat(
    pose: PoseOf, buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, x: float, y: float, sp: float, ahead: float,
    behind: float, scan: bool = True,
) -> FlatPoint:  # fmt: skip
    """:meth:`ClothoidPath.locate` of one point ``(x, y)`` [m] with hint ``sp`` [m] and window ``ahead``,
    ``behind`` [m] (> 0) on the flat path ``pv``; ``pose(buf, nodes, nb, pv, s)``: :func:`pose_flat` or alike.
    ``scan=False``: Newton's steps start at ``sp`` itself (a foot within a sample spacing of ``(x, y)``'s)."""
    lo = sp - behind
    hi = sp + ahead
    if pv[P_CLOSED] == 0.0:
        lo = min(max(lo, 0.0), pv[P_LENGTH])
        hi = min(max(hi, 0.0), pv[P_LENGTH])
    if pv[P_CIRCLE_K] != 0.0:  # the foot in closed form: no Newton step
        return project_flat(pose, buf, nodes, nb, pv, x, y, min(max(circle_foot(pv, x, y, sp), lo), hi), lo, hi, 0)
    h = pv[P_SPACING]
    s = sp
    if scan:
        s = nearest_sample(pv, x, y, float(np.floor((sp - behind) / h)), math.ceil((ahead + behind) / h) + 2)
    return project_flat(pose, buf, nodes, nb, pv, x, y, min(max(s, lo), hi), lo, hi, NEWTON_ITERATIONS)


def circle_foot(pv: FlatPath, x: float, y: float, sp: float) -> float:
    """On a circle (``pv[P_CIRCLE_K] != 0``): the arc length [m] of the foot of ``(x, y)`` [m] on the lap nearest
    ``sp`` [m], ``s = Delta / k`` with ``Delta`` the signed angle at the centre from the start point to ``(x, y)``."""
    cx = pv[P_CIRCLE_X]
    cy = pv[P_CIRCLE_Y]
    ax = pv[P_TAIL + 1] - cx  # the start point (piece 0's), s = 0
    ay = pv[P_TAIL + 2] - cy
    bx = x - cx
    by = y - cy
    s = math.atan2(ax * by - ay * bx, ax * bx + ay * by) / pv[P_CIRCLE_K]
    length = pv[P_LENGTH]
    return s + length * _floor_float((sp - s) / length + 0.5)


def locate_global(pose: PoseOf, buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, x: float, y: float) -> FlatPoint:
    """:func:`locate_flat` without a hint: from the nearest of all samples, in ``[0, length]`` (open) or
    unbounded (closed)."""
    s = nearest_sample(pv, x, y, 0.0, int(pv[P_M]))
    if pv[P_CLOSED] != 0.0:
        return project_flat(pose, buf, nodes, nb, pv, x, y, s, -math.inf, math.inf, NEWTON_ITERATIONS)
    return project_flat(pose, buf, nodes, nb, pv, x, y, s, 0.0, pv[P_LENGTH], NEWTON_ITERATIONS)


def foot_terms(x: float, y: float, px: float, py: float, ct: float, st: float) -> tuple[float, float, float, float]:
    """``(dx, dy, g, e)``: ``d = (x, y) - (px, py)``, ``g = d . t``, ``e = d . n`` for the tangent ``t = (ct, st)``."""
    dx = x - px
    dy = y - py
    return dx, dy, dx * ct + dy * st, dy * ct - dx * st


def project_flat(
    pose: PoseOf, buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, x: float, y: float, s: float, lo: float,
    hi: float, iterations: int,
) -> FlatPoint:  # fmt: skip
    """Steps 2 and 3 of :meth:`ClothoidPath.locate` from ``s`` [m] in ``[lo, hi]``: at most ``iterations``
    steps ``s <- clip(s + clip(d, -h, h), lo, hi)`` (the last below
    :data:`NEWTON_TAYLOR_STEP`, its pose to first order), ``d = g / q``, ``q = max(1 - kappa e,
    MIN_NEWTON_DENOMINATOR)`` (on an arc exactly ``atan2(kappa g, q) / kappa``); then the foot terms and status."""
    h = pv[P_SPACING]
    px, py, th, kappa, c, ct, st = pose(buf, nodes, nb, pv, s)
    for _ in range(iterations):
        _dx, _dy, g, e = foot_terms(x, y, px, py, ct, st)
        den = py_max(1.0 - kappa * e, MIN_NEWTON_DENOMINATOR)
        d = math.atan2(kappa * g, den) / kappa if c == 0.0 and kappa != 0.0 else g / den
        s_new = py_min(py_max(s + py_min(py_max(d, -h), h), lo), hi)
        u = s_new - s
        s = s_new
        if abs(u) * (1.0 + abs(kappa) + abs(c * u)) <= NEWTON_TAYLOR_STEP:
            px, py, th, ct, st = px + u * ct, py + u * st, th + kappa * u, ct - kappa * u * st, st + kappa * u * ct
            kappa += c * u
            break
        px, py, th, kappa, c, ct, st = pose(buf, nodes, nb, pv, s)
    dx, dy, g, e = foot_terms(x, y, px, py, ct, st)
    status = STATUS_INTERIOR
    if (s <= lo and g < 0.0) or (s >= hi and g > 0.0):
        status = STATUS_WINDOW
    if pv[P_CLOSED] == 0.0:
        if s <= 0.0 and g < 0.0:
            status = STATUS_START
        if s >= pv[P_LENGTH] and g > 0.0:
            status = STATUS_END
    return s, px, py, th, kappa, c, e, ct, st, math.sqrt(dx * dx + dy * dy), status


def lap_arc(s: float, length: float, closed: bool) -> float:
    """``s`` [m] reduced to ``[0, length)`` on a closed path, unchanged on an open one."""
    if not closed:
        return s
    s_lap = s - _floor_float(s / length) * length
    if s_lap >= length:
        s_lap = s_lap - length
    return s_lap


def _floor_float(q: float) -> float:
    # np.floor of a float: math.floor where finite, NaN and infinities as they are
    return float(math.floor(q)) if q - q == 0.0 else q


def locate_rows(
    pose: PoseOf, out: Array, buf: Buffer, nodes: Buffer, flat: FlatPath, start: list[int] | IntArray, x: FlatPath,
    y: FlatPath, sp: FlatPath, ahead: float, behind: float, hinted: bool,
) -> None:  # fmt: skip
    """:func:`locate_flat` (``hinted``) or :func:`locate_global` of the points ``(x[i], y[i])`` [m] on the flat
    paths at ``flat[start[i]:]``, into column ``i`` of ``out`` ``(12, N)`` (the fields of :class:`PathPoint`)."""
    for i in range(len(x)):
        pv = flat[start[i] :]
        if hinted:
            r = locate_flat(pose, buf, nodes, 0, pv, x[i], y[i], sp[i], ahead, behind)
        else:
            r = locate_global(pose, buf, nodes, 0, pv, x[i], y[i])
        out[0, i] = lap_arc(r[0], pv[P_LENGTH], pv[P_CLOSED] != 0.0)
        floats = r[:10]  # (the status, r[10], an int: a tuple of one type to index)
        for k in range(10):
            out[k + 1, i] = floats[k]
        out[11, i] = r[10]


def pose_rows(out: Array, buf: Buffer, nodes: Buffer, flat: FlatPath, start: list[int] | IntArray, s: FlatPath) -> None:
    """:func:`pose_flat` at ``s[i]`` [m] on the flat paths at ``flat[start[i]:]``, into column ``i`` of ``out``
    ``(7, N)``."""
    for i in range(len(s)):
        r = pose_flat(buf, nodes, 0, flat[start[i] :], s[i])
        for k in range(7):
            out[k, i] = r[k]


def pose_flat(buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, s: float) -> FloatPose:
    """Pose at arc length ``s`` [m] on the flat path ``pv``:
    ``(x, y, theta, kappa, dkappa/ds, cos theta, sin theta)`` [m, m, rad, 1/m, 1/m^2, -, -].

    ``buf``: scratch of ``3 (NODES + 1)`` floats; ``nodes[nb:]``: :func:`amigo_gym.model.fresnel.node_table` of 1.
    On a circle (``pv[P_CIRCLE_K] = k != 0``) in closed form: ``theta = theta_0 + k s``, the point
    ``c + (sin theta, -cos theta) / k``.
    """
    k = pv[P_CIRCLE_K]
    if k != 0.0:
        th = pv[P_TAIL + 3] + k * s
        ct = math.cos(th)
        st = math.sin(th)
        return pv[P_CIRCLE_X] + st / k, pv[P_CIRCLE_Y] - ct / k, th, k, 0.0, ct, st
    j, du, lap, extra = piece_at(pv, s)
    b = P_TAIL + 6 * j
    x, y, th, ct, st = unit_speed_nodes(
        buf, pv[b + 1], pv[b + 2], pv[b + 3], pv[b + 4], pv[b + 5], du, nodes, nb, NODES
    )
    return place(pv, j, du, lap, extra, x, y, th, ct, st)


#: the path quadrature's nodes and weights (:func:`pose_flat`'s ``nodes``)
_PATH_TABLE: list[float] = node_table(1)
#: the size of :func:`pose_flat`'s scratch ``buf``
_SCRATCH = 3 * NODES + 3


def path_layout(
    segs: Buffer, n_segs: int, sample_spacing: float, closed: bool
) -> tuple[int, int, float, float, float]:  # fmt: skip
    """The layout of a path of the segments ``segs[4 g : 4 g + 3]`` (length [m], curvature [1/m], rate [1/m^2]):
    each one's piece count into ``segs[4 g + 3]`` (the phase of a piece <= ``MAX_PHASE_PER_SUB``), and ``(n pieces,
    m samples, length [m], max |kappa| [1/m], sample spacing [m])``: ``m`` samples ``s_j = j spacing`` up to the end
    (open) or before it (closed), spaced by at most ``sample_spacing`` and ``0.1 / max|kappa|``, at least 8."""
    n = 0
    kmax = 0.0
    total = 0.0
    for g in range(n_segs):
        length = segs[4 * g]
        k = segs[4 * g + 1]
        rate = segs[4 * g + 2]
        kabs = py_max(abs(k), abs(k + rate * length))
        kmax = py_max(kmax, kabs)
        # piece j of n: |k_j| h + |c| h^2 / 2 <= (kabs L + |c| L^2 / 2) / n <= MAX_PHASE_PER_SUB
        count = subinterval_count(kabs * length + 0.5 * abs(rate) * length * length)
        segs[4 * g + 3] = float(count)
        n += count
        total += length
    spacing = py_min(sample_spacing, 0.1 / kmax) if kmax > 0.0 else sample_spacing
    n_samples = max(8, math.ceil(total / spacing))
    return n, n_samples + (0 if closed else 1), total, kmax, total / n_samples


def build_flat(
    pv: Buffer, segs: Buffer, n_segs: int, n: int, m: int, total: float, spacing: float, x: float, y: float,
    th: float, closed: bool, buf: Buffer, nodes: Buffer,
) -> tuple[float, float]:  # fmt: skip
    """The flat vector of the path of :func:`path_layout`'s segments and layout from ``(x, y, th)`` into ``pv``
    (``P_TAIL + 6 n + 2 m`` floats; the samples left to :func:`sample_points`): the header and the pieces chained
    (:func:`chain_pieces`). Returns a closed path's distance [m] and heading difference [rad] from its end pose to its
    start's modulo ``2 pi`` (0, 0 if open)."""
    xe, ye, the = chain_pieces(pv, n, segs, n_segs, x, y, th, buf, nodes)
    turn = TWO_PI * math.floor((the - th) / TWO_PI + 0.5) if closed else the - th
    k = segs[1] if closed else 0.0  # a closed path of arcs of one curvature k (a circle): k and its centre
    for g in range(n_segs):
        k = k if segs[4 * g + 1] == k and segs[4 * g + 2] == 0.0 else 0.0
    cx, cy = (x - math.sin(th) / k, y + math.cos(th) / k) if k != 0.0 else (0.0, 0.0)
    for j, v in enumerate((float(n), float(m), total, turn, spacing, 1.0 if closed else 0.0, k, cx, cy)):
        pv[j] = v  # the header, in PATH_HEADER's order
    return (math.hypot(xe - x, ye - y), the - th - turn) if closed else (0.0, 0.0)


def chain_pieces(
    pv: Buffer, n: int, segs: Buffer, n_segs: int, x: float, y: float, th: float, buf: Buffer, nodes: Buffer
) -> tuple[float, float, float]:
    """Split the segments ``segs[4 g : 4 g + 4]`` (length [m], curvature [1/m], rate [1/m^2], piece count) into
    pieces chained from ``(x, y, th)``: piece ``q``'s ``s0, x0, y0, th0, k0, c`` into ``pv[P_TAIL + 6 q :][:6]``
    (one piece's numbers together: one cache line for a pose), ``n`` pieces in all (``buf``, ``nodes`` as
    :func:`pose_flat`); returns ``(x, y, theta)`` at the end."""
    q = P_TAIL
    s_seg = 0.0
    for g in range(n_segs):
        length = segs[4 * g]
        k = segs[4 * g + 1]
        rate = segs[4 * g + 2]
        m = int(segs[4 * g + 3])
        h = length / m
        for j in range(m):
            kj = k + rate * (j * h)
            hj = h if j < m - 1 else length - (m - 1) * h
            pv[q] = s_seg + j * h
            pv[q + 1] = x
            pv[q + 2] = y
            pv[q + 3] = th
            pv[q + 4] = kj
            pv[q + 5] = rate
            x, y, th, _ct, _st = unit_speed_nodes(buf, x, y, th, kj, rate, hj, nodes, 0, NODES)
            q += 6
        s_seg += length
    return x, y, th


def sample_points(buf: Buffer, nodes: Buffer, pv: FlatPath, o: int, count: int, spacing: float) -> None:
    """Write the coarse samples at ``s_j = j spacing`` [m], ``j < count``, into ``pv``: ``x`` at ``pv[o + j]``,
    ``y`` at ``pv[o + count + j]``."""
    for j in range(count):
        x, y, _th, _k, _c, _ct, _st = pose_flat(buf, nodes, 0, pv, j * spacing)
        pv[o + j] = x
        pv[o + count + j] = y


def _poses_flat(pv: FlatPath, ss: list[float]) -> list[FloatPose]:
    """:func:`pose_flat` of several floats ``ss`` [m], the cosines and sines in one numpy call."""
    where = [piece_at(pv, s) for s in ss]
    starts = []
    for j, du, _, _ in where:
        b = P_TAIL + 6 * j
        starts.append((pv[b + 1], pv[b + 2], pv[b + 3], pv[b + 4], pv[b + 5], du))
    return [
        place(pv, j, du, lap, extra, *pose)
        for pose, (j, du, lap, extra) in zip(unit_speed_poses(starts), where, strict=True)
    ]


def check_window(max_advance: float, max_retreat: float | None) -> tuple[float, float]:
    """The window ``ahead``, ``behind`` [m] of :meth:`ClothoidPath.locate`, checked (> 0, finite)."""
    ahead = check_real("locate", "max_advance", max_advance, 0.0, low_open=True)
    return ahead, ahead if max_retreat is None else check_real("locate", "max_retreat", max_retreat, 0.0, low_open=True)


def _locate_float(
    pv: FlatPath, x: float, y: float, sp: float | None, max_advance: float, max_retreat: float | None
) -> PathPoint:
    buf = [0.0] * _SCRATCH
    if sp is None:
        r = locate_global(pose_flat, buf, _PATH_TABLE, 0, pv, x, y)
    else:
        ahead, behind = check_window(max_advance, max_retreat)
        if sp - sp != 0.0:
            check_hint(sp)
        r = locate_flat(pose_flat, buf, _PATH_TABLE, 0, pv, x, y, sp, ahead, behind)
    return PathPoint(lap_arc(r[0], pv[P_LENGTH], pv[P_CLOSED] != 0.0), *r)


#: the compiled rows registered by :func:`use_compiled_rows`
_COMPILED: list[PathLoops] = []


def use_compiled_rows(loops: PathLoops) -> None:
    """Run :func:`locate_columns` and :func:`pose_columns_of` by the compiled rows of ``loops`` from now on."""
    if not _COMPILED:
        _COMPILED.append(loops)


def locate_columns(
    flat: Array, start: IntArray, x: Array, y: Array, sp: Array | None, ahead: float, behind: float,
    pose: PoseOf | None = None,
) -> PathPoint:  # fmt: skip
    """:func:`locate_rows` on ``(N,)`` float64 columns (compiled where registered and ``pose`` is None, else
    Python); a :class:`PathPoint` of columns."""
    out = np.empty((12, x.shape[0]))
    hints = x if sp is None else sp
    if _COMPILED and pose is None:
        _COMPILED[0].locate(out, flat, start, x, y, hints, ahead, behind, sp is not None)
    else:
        rows = (start.tolist(), x.tolist(), y.tolist(), hints.tolist())
        pv = cast(FlatPath, flat.data)  # a memoryview: its slices are views, its entries Python floats
        of = pose_flat if pose is None else pose
        locate_rows(of, out, [0.0] * _SCRATCH, _PATH_TABLE, pv, *rows, ahead, behind, sp is not None)
    return PathPoint._make([*out[:11], out[11].astype(np.int64)])


def locate_points(
    flat: Array, x: Real, y: Real, s_prev: Real | None, max_advance: float, max_retreat: float | None,
    pose: PoseOf | None = None,
) -> PathPoint:  # fmt: skip
    """:meth:`ClothoidPath.locate` of points of any shape (window and hints checked, arguments broadcast)."""
    ahead, behind = (0.0, 0.0) if s_prev is None else check_window(max_advance, max_retreat)
    if s_prev is not None:
        check_hint(s_prev)
    cols = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x, y, 0.0 if s_prev is None else s_prev)))
    xf, yf, sf = (np.ascontiguousarray(v).reshape(-1) for v in cols)
    start = np.zeros(xf.size, dtype=np.int64)
    got = locate_columns(flat, start, xf, yf, None if s_prev is None else sf, ahead, behind, pose)
    return PathPoint._make([np.reshape(v, cols[0].shape) for v in got])


def pose_columns_of(flat: Array, start: IntArray, s: Array) -> PathPose:
    """:func:`pose_rows` on a ``(N,)`` float64 column, compiled as :func:`locate_columns`."""
    out = np.empty((7, s.shape[0]))
    if _COMPILED:
        _COMPILED[0].pose(out, flat, start, s)
    else:
        pose_rows(out, [0.0] * _SCRATCH, _PATH_TABLE, cast(FlatPath, flat.data), start.tolist(), s.tolist())
    return PathPose(*out)
