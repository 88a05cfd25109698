r"""Clothoid paths for point H (AmigoBot-v1): exact geometry, and a projection that keeps progress.

A :class:`ClothoidPath` is a chain of :class:`ClothoidSegment` s, each with curvature linear in arc length
(lines and circular arcs are the special cases of a zero curvature rate), from a start pose, optionally
closed (it is then traversed in laps). Along one piece of curvature ``kappa(u) = k0 + c u`` starting at
``(x0, y0, theta0)``:

.. math::
    \theta(u) = \theta_0 + k_0 u + \tfrac12 c u^2, \qquad
    \mathbf{p}(u) = \mathbf{p}_0 + \int_0^u (\cos\theta(\tau), \sin\theta(\tau))\,d\tau,

evaluated by :func:`amigo_gym.model.fresnel.advance` (speed 1, turn rate ``k0 + c u``), exact to rounding as long as
``|k0| u + |c| u^2 / 2 <= MAX_PHASE_PER_SUB``. Segments are therefore split into equal *pieces* that satisfy
this bound, and the start pose of every piece is computed once, at construction, by chaining the pieces.
A point then costs one quadrature from its piece's start (no accumulation along the path).

Conventions (as :mod:`amigo_gym.paths.classic`): arc length ``s`` [m] from the start point, tangent angle
``theta(s)`` [rad] continuous (never wrapped, laps add the total turn), signed curvature ``kappa = dtheta/ds``
[1/m] positive turning left, signed cross-track error ``e = (p - c(s)) . n`` [m] with the left normal
``n = (-sin theta, cos theta)``. An open path continues beyond its ends as the straight lines along its end
tangents (curvature 0 there); a closed path repeats (``s`` modulo the lap length). Column arguments are
floats or float64 arrays of any shape; one code serves both, with bit-identical results: the float functions below
(``pose_flat``, ``locate_flat``), on an array entry by entry (``locate_rows``, ``pose_rows``: Python, or compiled by
the v1 kernels once a compiled route registered them, ``use_compiled_rows``).

This module may import numpy, :mod:`amigo_gym.model.params`, :mod:`amigo_gym.model.kinematics` and
:mod:`amigo_gym.model.fresnel`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import InitVar, dataclass, field
from functools import cached_property
from typing import Any, NamedTuple, Protocol, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.fresnel import (
    NODES,
    Buffer,
    node_table,
    subintervals,
    unit_speed_nodes,
    unit_speed_poses,
)
from amigo_gym.model.kinematics import Real, pack
from amigo_gym.model.params import check_range, check_real
from amigo_gym.paths.classic import ClosestPoint, PathPoint, PathPose, Projection

__all__ = [
    "STATUS_INTERIOR",
    "STATUS_START",
    "STATUS_END",
    "STATUS_WINDOW",
    "ClothoidSegment",
    "ClothoidPath",
    "PathPose",
    "PathPoint",
    "PathSpec",
    "PathLoops",
    "check_real",
]

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

#: Newton iterations of the projection (a fixed count, so that one point and a batch give the same bits)
NEWTON_ITERATIONS = 5
#: the Newton denominator ``1 - kappa e`` is bounded below by this (points near a centre of curvature)
MIN_NEWTON_DENOMINATOR = 0.05
#: largest length [m] and curvature [1/m] of a segment
MAX_SEGMENT_LENGTH = 1.0e5
MAX_CURVATURE = 1.0e4
#: closure tolerance of a closed path: position gap relative to max(1 m, length), and heading gap [rad]
CLOSURE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class ClothoidSegment:
    r"""One clothoid segment: curvature ``kappa(u) = curvature + curvature_rate u`` for ``0 <= u <= length``.

    A line has ``curvature = curvature_rate = 0``, a circular arc ``curvature_rate = 0``.

    Attributes:
        length: arc length [m], in (0, 1e5].
        curvature: signed curvature at the segment's start [1/m], in [-1e4, 1e4] (positive turns left).
        curvature_rate: ``dkappa/ds`` [1/m^2], finite; the end curvature must lie in [-1e4, 1e4] too.
    """

    length: float
    curvature: float = 0.0
    curvature_rate: float = 0.0

    def __post_init__(self) -> None:
        # stored as Python floats (check_real also accepts Fractions and 0-d arrays)
        o = "ClothoidSegment"
        object.__setattr__(self, "length", check_real(o, "length", self.length, 0.0, MAX_SEGMENT_LENGTH, low_open=True))
        object.__setattr__(self, "curvature", check_real(o, "curvature", self.curvature, -MAX_CURVATURE, MAX_CURVATURE))
        object.__setattr__(self, "curvature_rate", check_real(o, "curvature_rate", self.curvature_rate))
        check_range("ClothoidSegment", "curvature_end", self.curvature_end, -MAX_CURVATURE, MAX_CURVATURE)

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
        """Curvature at the segment's end, ``curvature + curvature_rate length`` [1/m]."""
        return float(self.curvature) + float(self.curvature_rate) * float(self.length)

    @property
    def turn(self) -> float:
        """Change of tangent angle over the segment, ``k0 L + c L^2 / 2`` [rad]."""
        length = float(self.length)
        return length * (float(self.curvature) + 0.5 * float(self.curvature_rate) * length)


class PathSpec(Protocol):
    """The full interface AmigoBot-v1 uses of a path (:class:`ClothoidPath` implements it).

    A path is parametrised by arc length ``s`` [m] of point H, with a tangent angle continuous in ``s`` and
    a signed curvature (positive turning left). A path object of your own needs only ``length``, ``closed``
    and a ``pose_columns`` returning ``x``, ``y``, ``theta`` and ``curvature``: :mod:`amigo_gym.paths.user`
    checks it and completes the rest (``locate`` is optional).
    """

    @property
    def length(self) -> float:
        """Arc length of one traversal [m] (one lap of a closed path)."""
        ...

    @property
    def closed(self) -> bool:
        """Whether the path repeats with period :attr:`length` (laps)."""
        ...

    def pose_columns(self, s: Real) -> PathPose:
        """Point, tangent angle, curvature and curvature rate at arc lengths ``s`` (columns)."""
        ...

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        """Closest path point to ``(x, y)``; within ``[s_prev - max_retreat, s_prev + max_advance]`` given a hint."""
        ...


def check_hint(sp: Real) -> None:
    """Refuse a NaN or infinite hint ``s_prev`` [m] of :meth:`ClothoidPath.locate` (a float or a column, both
    routes): the one-line error of :func:`check_real` naming the first such value."""
    a = np.asarray(sp, dtype=np.float64)
    bad = a[~np.isfinite(a)]
    if bad.size:
        check_real("locate", "s_prev", float(bad.flat[0]))


@dataclass(frozen=True)
class _Tables:
    """A built :class:`ClothoidPath`: its flat path vector (:data:`PATH_HEADER`, the pieces, the coarse samples) and
    its largest ``|curvature|`` [1/m]; the header's values are read from the vector once, the pieces' and the samples'
    columns are views of it (arrays) or its entries as Python floats (lists)."""

    flat: Array
    max_abs_curvature: float
    length: float
    turn: float
    spacing: float

    @classmethod
    def of(cls, flat: Array, max_abs_curvature: float) -> _Tables:
        return cls(flat, max_abs_curvature, *(float(flat[i]) for i in (P_LENGTH, P_TURN, P_SPACING)))

    def column(self, k: int) -> Array:
        """Column ``k`` (view): ``0 ... 5`` the pieces' ``s0, x0, y0, th0, k0, c``, ``6``, ``7`` the samples' x, y."""
        n, m = int(self.flat[P_N]), int(self.flat[P_M])
        a = P_TAIL + k * n if k < 6 else P_TAIL + 6 * n + (k - 6) * m
        return self.flat[a : a + (n if k < 6 else m)]

    s0_a = property(lambda self: self.column(0))
    x0_a = property(lambda self: self.column(1))
    y0_a = property(lambda self: self.column(2))
    th0_a = property(lambda self: self.column(3))
    k0_a = property(lambda self: self.column(4))
    c_a = property(lambda self: self.column(5))
    sample_x = property(lambda self: self.column(6))
    sample_y = property(lambda self: self.column(7))
    s0 = property(lambda self: self.column(0).tolist())
    x0 = property(lambda self: self.column(1).tolist())
    y0 = property(lambda self: self.column(2).tolist())
    th0 = property(lambda self: self.column(3).tolist())
    k0 = property(lambda self: self.column(4).tolist())
    c = property(lambda self: self.column(5).tolist())


class PathLoops(NamedTuple):
    """The compiled forms of the path-building loops, which a compiled route hands to the path constructors
    (``loops=``; :func:`amigo_gym.sim.fast_v1.path_loops`). Without them the constructors run the same functions as
    Python (the reference); both give the same paths to the tolerance (``tests/test_kernel_v1.py``).

    Attributes:
        chain: :func:`chain_pieces` ``(out, n, segs, n_segs, x, y, theta) -> (x, y, theta, length)`` (its scratch and
            nodes supplied).
        samples: :func:`sample_points` ``(pv, o, count, spacing)``: the coarse samples written into the flat path
            vector ``pv`` itself (the float route takes them from :func:`_poses_flat`, the same poses).
        run: :func:`amigo_gym.paths.families.run_segments` ``(segs, n_segs, x, y, theta) -> (x, y, theta)``.
        lane: :func:`amigo_gym.paths.families.lane_change_shape` ``(ratio) -> (x1, y1, theta_m, x_m)``.
        locate, pose: :func:`locate_rows` and :func:`pose_rows` (their scratch and nodes supplied), the column
            projection and pose of every path once registered (:func:`use_compiled_rows`).
    """

    chain: Callable[..., tuple[float, float, float, float]]
    samples: Callable[..., None]
    run: Callable[..., tuple[float, float, float]]
    lane: Callable[..., tuple[float, float, float, float]]
    locate: Callable[..., None]
    pose: Callable[..., None]


@dataclass(frozen=True)
class ClothoidPath:
    r"""A path of clothoid segments from a start pose; exact geometry, batched evaluation and projection.

    Attributes:
        segments: the segments in order (a non-empty tuple of :class:`ClothoidSegment`).
        start: start point ``(x, y)`` [m].
        start_angle: tangent angle at the start [rad].
        closed: the path repeats; its end pose must then equal its start pose (to 1e-9 relative to
            ``max(1 m, length)`` in position and 1e-9 rad in angle modulo ``2 pi``).
        sample_spacing: largest spacing [m] of the samples of the coarse projection search, in
            [1e-4, 1]; the samples are also at most ``0.1 / max|kappa|`` apart. Default 0.02.
        loops: (an argument of the constructor only, not stored) the compiled path-building loops
            (:class:`PathLoops`), or None (default): the float route; the same path either way.
    """

    segments: tuple[ClothoidSegment, ...]
    start: tuple[float, float] = (0.0, 0.0)
    start_angle: float = 0.0
    closed: bool = False
    sample_spacing: float = 0.02
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
        """Split the segments into pieces of phase change <= MAX_PHASE_PER_SUB and chain their start poses
        (:func:`chain_pieces`), then sample the path for the coarse search; ``loops``: their compiled forms."""
        segs: list[float] = []
        n = 0
        kmax = 0.0
        for g in self.segments:
            length, k, rate = float(g.length), float(g.curvature), float(g.curvature_rate)
            kabs = max(abs(k), abs(g.curvature_end))
            kmax = max(kmax, kabs)
            # piece j of n: |k_j| h + |c| h^2 / 2 <= (kabs L + |c| L^2 / 2) / n <= MAX_PHASE_PER_SUB
            count = subintervals(kabs * length + 0.5 * abs(rate) * length * length)
            segs += (length, k, rate, float(count))
            n += count
        n_segs = len(self.segments)
        x, y, th = float(self.start[0]), float(self.start[1]), float(self.start_angle)
        if loops is None:
            out: Any = [0.0] * (6 * n)
            x, y, th, total = chain_pieces(out, n, segs, n_segs, x, y, th, [0.0] * (3 * NODES + 3), _PATH_TABLE)
        else:
            out = np.empty(6 * n)
            x, y, th, total = loops.chain(out, n, np.array(segs), n_segs, x, y, th)
        raw_turn = th - float(self.start_angle)
        turn = raw_turn
        if self.closed:
            laps = round(raw_turn / TWO_PI)
            turn = TWO_PI * laps
            gap = math.hypot(x - self.start[0], y - self.start[1])
            if gap > CLOSURE_TOLERANCE * max(1.0, total) or abs(raw_turn - turn) > CLOSURE_TOLERANCE:
                raise ValueError(
                    f"ClothoidPath.closed: the segments end {gap:.3g} m from the start with a heading "
                    f"{raw_turn - turn:.3g} rad off, but a closed path must end at its start pose"
                )
        spacing = min(float(self.sample_spacing), 0.1 / kmax if kmax > 0 else math.inf)
        n_samples = max(8, math.ceil(total / spacing))
        spacing = total / n_samples
        # the flat path vector: the header, the pieces, then the coarse samples at s_j = j * spacing, j = 0..n_samples
        # (open) or 0..n_samples - 1 (closed, periodic), the path's own pose at each (pose_flat reads no sample)
        m = n_samples + (0 if self.closed else 1)
        o = P_TAIL + 6 * n
        flat = np.zeros(o + 2 * m)
        flat[:P_TAIL] = (float(n), float(m), total, turn, spacing, 1.0 if self.closed else 0.0)
        flat[P_TAIL:o] = out
        if loops is not None:
            loops.samples(flat, o, m, spacing)
        elif _COMPILED:  # compiled pose_flat at each sample (the same bits)
            q = pose_columns_of(flat, np.zeros(m, dtype=np.int64), np.arange(m, dtype=np.float64) * spacing)
            flat[o : o + m], flat[o + m :] = q.x, q.y
        else:
            poses = _poses_flat(flat.tolist(), (np.arange(m, dtype=np.float64) * spacing).tolist())
            flat[o : o + m], flat[o + m :] = [q[0] for q in poses], [q[1] for q in poses]
        return _Tables.of(flat, kmax)

    @cached_property
    def _flat_list(self) -> list[float]:
        """The flat path vector as a list of Python floats, what the float path reads (indexing a list is faster
        than an array and gives floats); built at its first use (4 times the array's memory)."""
        out: list[float] = self._t.flat.tolist()
        return out

    # --- evaluation -------------------------------------------------------------------------------------

    @property
    def length(self) -> float:
        """Arc length of one traversal [m] (one lap if closed)."""
        return self._t.length

    @property
    def total_turn(self) -> float:
        """Tangent angle change over one traversal [rad] (a multiple of ``2 pi`` if closed: 0 for a figure-8)."""
        return self._t.turn

    @property
    def max_abs_curvature(self) -> float:
        """``max |kappa|`` over the path [1/m]."""
        return self._t.max_abs_curvature

    def breakpoints(self) -> tuple[float, ...]:
        """Arc lengths of the segment joints, with 0 and :attr:`length` [m] (where the curvature may have a kink)."""
        out = [0.0]
        for g in self.segments:
            out.append(out[-1] + float(g.length))
        return tuple(out)

    def _pose(self, t: _Tables, s: Real) -> PathPose:
        """Pose at ``s`` (:func:`pose_flat`: of a float, or of each entry of an array, :func:`pose_columns_of`)."""
        if not isinstance(s, np.ndarray):
            return PathPose(*_pose_float(self._flat_list, s if type(s) is float else float(s)))
        a = np.ascontiguousarray(s, dtype=np.float64).reshape(-1)
        p = pose_columns_of(t.flat, np.zeros(a.size, dtype=np.int64), a)
        return PathPose(*(np.reshape(v, np.shape(s)) for v in p))

    def pose_columns(self, s: Real) -> PathPose:
        """Point, tangent angle, curvature and curvature rate at arc lengths ``s`` [m] (columns, any shape)."""
        return self._pose(self._t, s)

    def pose_floats(self, ss: list[float]) -> list[PathPose]:
        """:meth:`pose_columns` of each float in ``ss`` (the same bits), computed together (one robot's preview)."""
        return [PathPose(*q) for q in _poses_flat(self._flat_list, ss)]

    def _array_pose(self, s: ArrayLike) -> PathPose:
        a = np.asarray(s, dtype=np.float64)
        p = self._pose(self._t, a.reshape(-1))
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
        return self._pose(self._t, s).curvature

    # --- projection -------------------------------------------------------------------------------------

    def project(self, p: ArrayLike) -> Projection:
        """Closest point to ``p`` ``(..., 2)`` [m] (global search; :meth:`locate` for the column form with a hint)."""
        q = np.asarray(p, dtype=np.float64)
        return self.project_xy(q[..., 0], q[..., 1]).projection()

    def project_xy(self, x: Real, y: Real, minimal: bool = False) -> ClosestPoint:
        """Column form of :meth:`project` (global search), the :class:`~amigo_gym.paths.classic.Path` protocol.

        ``minimal`` is accepted for the protocol; every field is computed.
        """
        return self.locate(x, y).closest_point()

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        r"""Closest path point to the points ``(x, y)`` [m], keeping progress along the path.

        1. Coarse search over the precomputed samples ``s_j = j h`` (``h`` = the sample spacing): without a
           hint over the whole path (one lap), with a hint ``s_prev`` [m] (unwrapped progress) over the
           samples in the window ``[s_prev - max_retreat, s_prev + max_advance]`` only (unwrapped too). The
           window keeps the projection on its branch where the path passes near itself (a figure-8's
           crossing): choose it smaller than half the arc length between such branches and larger than the
           distance the point can advance between calls.
        2. Newton's method on ``g(s) = (p - c(s)) . t(s)`` (zero at a foot point), with
           ``g'(s) = -(1 - kappa e)``, ``e = (p - c) . n``: ``s <- s + g / max(1 - kappa e, 0.05)``, the step
           limited to ``h`` and ``s`` kept in the window and, on an open path, in ``[0, L]``;
           :data:`NEWTON_ITERATIONS` iterations, to machine precision from a start within ``h / 2``.
        3. The status says whether ``s`` was clamped at an end of an open path or at a window edge.

        Args:
            x, y: query points, columns [m].
            s_prev: the previous progress [m] (column broadcasting with ``x``), or None for a global search.
            max_advance, max_retreat: the window ahead of and behind ``s_prev`` [m], > 0 (``max_retreat``
                defaults to ``max_advance``).

        Returns:
            :class:`PathPoint` columns of the broadcast shape of ``x``, ``y`` (and ``s_prev``).
        """
        if not (isinstance(x, np.ndarray) or isinstance(y, np.ndarray) or isinstance(s_prev, np.ndarray)):
            sp = None if s_prev is None else float(s_prev)
            return _locate_float(self._flat_list, float(x), float(y), sp, max_advance, max_retreat)
        return locate_points(self._t.flat, x, y, s_prev, max_advance, max_retreat)


# --------------------------------------------------------------------------- the float path of one point
#
# The pose and the projection on Python floats (one robot's step evaluates about 15 poses), and on arrays entry by
# entry (locate_rows, pose_rows).
#
# The functions below from py_min to pose_rows are in numba's
# subset (floats, ints, comparisons, math.floor/copysign/sqrt, np.floor of a float, indexing of the flat path vector,
# no object, no exception): the compiled step of AmigoBot-v1 compiles these very functions
# (amigo_gym.sim._kernels_v1; docs/architecture.md, "One robot, one step"), so the projection is written once: the
# piece search, wrap and placement of a pose, the coarse search, the Newton loop, the foot terms, the status and the
# pose (pose_flat, whose quadrature is fresnel's node functions: numpy's cosines and sines of the nodes here, the C
# library's in compiled code, fresnel.cos_sin_nodes' overload, checked equal per process).


def py_min(a: float, b: float) -> float:
    """Python's ``min(a, b)`` of two floats: ``a`` unless ``b < a`` (the first on ties and NaN), for compiled code."""
    return b if b < a else a


def py_max(a: float, b: float) -> float:
    """Python's ``max(a, b)`` of two floats: ``a`` unless ``b > a`` (the first on ties and NaN), for compiled code."""
    return b if b > a else a


def wrap_arc(s: float, length: float, closed: bool) -> tuple[float, float, float]:
    """Arc length ``s`` [m] on a path of lap ``length`` [m] as ``(u, lap, extra)``: ``u`` in ``[0, length]``, the
    lap number (closed: ``u = s - lap length``) and the length past an open path's ends (``s = u + extra``)."""
    if closed:
        lap = _floor_float(s / length)
        return s - lap * length, lap, 0.0
    u = py_min(py_max(s, 0.0), length)
    return u, 0.0, s - u


def placed_pose(
    x: float,
    y: float,
    th: float,
    cos_t: float,
    sin_t: float,
    kappa: float,
    c: float,
    closed: bool,
    lap: float,
    turn: float,
    extra: float,
) -> tuple[float, float, float, float, float, float, float]:
    """The pose ``(x, y, theta, kappa, dkappa/ds, cos theta, sin theta)`` on the whole path from the pose at ``u``
    in its piece (:func:`wrap_arc`): laps of a closed path add whole turns ``turn`` [rad] to the heading, an open
    path goes straight on past its ends (curvature 0 there)."""
    if closed:
        return x, y, th + lap * turn, kappa, c, cos_t, sin_t
    if extra != 0.0:
        return x + extra * cos_t, y + extra * sin_t, th, 0.0, 0.0, cos_t, sin_t
    return x + extra * cos_t, y + extra * sin_t, th, kappa, c, cos_t, sin_t


def locate_window(sp: float, ahead: float, behind: float, length: float, closed: bool) -> tuple[float, float]:
    """The search window ``[lo, hi]`` [m] around the hint ``sp``, kept in
    ``[0, length]`` on an open path."""
    lo = sp - behind
    hi = sp + ahead
    if not closed:
        lo = min(max(lo, 0.0), length)
        hi = min(max(hi, 0.0), length)
    return lo, hi


def foot_terms(x: float, y: float, px: float, py: float, ct: float, st: float) -> tuple[float, float, float, float]:
    """``(dx, dy, g, e)`` of the point ``(x, y)`` against the path point ``(px, py)`` of tangent ``(ct, st)``:
    ``d = p - c``, ``g = d . t`` (zero at a foot point), ``e = d . n`` (the cross-track error)."""
    dx = x - px
    dy = y - py
    return dx, dy, dx * ct + dy * st, dy * ct - dx * st


def newton_step(
    x: float,
    y: float,
    px: float,
    py: float,
    kappa: float,
    ct: float,
    st: float,
    s: float,
    h: float,
    lo: float,
    hi: float,
) -> tuple[float, bool]:
    """One iteration of the projection's Newton method (:func:`_newton`) from ``s`` [m] with the pose there:
    ``s' = clip(s + clip(g / max(1 - kappa e, MIN_NEWTON_DENOMINATOR), -h, h), lo, hi)``, and whether ``s'`` is
    ``s`` bit for bit (a fixed point: the remaining iterations would repeat it)."""
    _dx, _dy, g, e = foot_terms(x, y, px, py, ct, st)
    den = 1.0 - kappa * e
    if den < MIN_NEWTON_DENOMINATOR:
        den = MIN_NEWTON_DENOMINATOR
    s_new = py_min(py_max(s + py_min(py_max(g / den, -h), h), lo), hi)
    return s_new, s_new == s and math.copysign(1.0, s_new) == math.copysign(1.0, s)


def locate_status_float(s: float, g: float, lo: float, hi: float, length: float, closed: bool) -> int:
    """The status (:data:`STATUS_INTERIOR`, ...) of one projection ``s`` [m] with residual ``g = (p - c) . t`` in the
    range ``[lo, hi]``: clamped at a window edge, or at an end of an open path."""
    status = STATUS_INTERIOR
    if (s <= lo and g < 0.0) or (s >= hi and g > 0.0):
        status = STATUS_WINDOW
    if not closed:
        if s <= 0.0 and g < 0.0:
            status = STATUS_START
        if s >= length and g > 0.0:
            status = STATUS_END
    return status


FloatPose = tuple[float, float, float, float, float, float, float]
#: a path's pose on floats, ``(buf, nodes, nb, pv, s) -> FloatPose`` (:func:`pose_flat`'s arguments)
PoseOf = Callable[[Buffer, Buffer, int, Any, float], FloatPose]
#: the fields of :func:`locate_flat`'s result: ``(progress, x, y, theta, kappa, dkappa/ds, e, cos theta, sin theta,
#: distance, status)``
FlatPoint = tuple[float, float, float, float, float, float, float, float, float, float, int]

# --------------------------------------------------------------------------- the flat path vector
#
# One path as one vector of floats: the header below, then the n pieces' s0, x0, y0, th0, k0, c (n each), then the
# m coarse samples' x, y (m each). The compiled step reads it as a float64 array (amigo_gym.sim.fast_v1.flat_path),
# the float path as a list of the same Python floats (ClothoidPath._flat_list); the functions below read either.

#: the head of a flat path vector (then the arrays)
PATH_HEADER: tuple[str, ...] = ("n_pieces", "n_samples", "length", "turn", "spacing", "closed")
P_N, P_M, P_LENGTH, P_TURN, P_SPACING, P_CLOSED = range(len(PATH_HEADER))
#: where the pieces' arrays start
P_TAIL = len(PATH_HEADER)
#: a flat path vector: a float64 array (compiled code) or a list of Python floats (the float path)
FlatPath = list[float] | NDArray[np.float64]


def piece_index(pv: FlatPath, u: float) -> int:
    """The piece of the flat path ``pv`` holding ``u`` [m]: ``bisect.bisect_right(s0, u) - 1`` clamped to
    ``[0, n - 1]`` (the last piece whose start ``s0`` is ``<= u``; NaN gives the last piece, as bisect)."""
    n = int(pv[P_N])
    lo = 0
    hi = n
    while lo < hi:
        mid = (lo + hi) // 2
        if u < pv[P_TAIL + mid]:
            hi = mid
        else:
            lo = mid + 1
    j = lo - 1
    if j < 0:
        j = 0
    if j > n - 1:
        j = n - 1
    return j


def piece_at(pv: FlatPath, s: float) -> tuple[int, float, float, float]:
    """The piece ``j`` holding the arc length ``s`` [m] on the flat path ``pv``, the distance ``du`` [m] into it, the
    lap number and the length ``extra`` [m] past an open path's ends (the wrap, clamp and
    search: :func:`wrap_arc`, :func:`piece_index`)."""
    u, lap, extra = wrap_arc(s, pv[P_LENGTH], pv[P_CLOSED] != 0.0)
    j = piece_index(pv, u)
    return j, u - pv[P_TAIL + j], lap, extra


def place(
    pv: FlatPath, j: int, du: float, lap: float, extra: float, x: float, y: float, th: float, ct: float, st: float
) -> FloatPose:
    """The pose at ``du`` [m] into piece ``j`` of the flat path ``pv`` (``x, y, th, ct, st``: its unit-speed pose from
    the piece's start, :func:`amigo_gym.model.fresnel.unit_speed_pose`) on the whole path (:func:`placed_pose`):
    curvature ``k0 + c du``, laps of a closed path add whole turns, an open path goes straight on past its ends."""
    n = int(pv[P_N])
    c = pv[P_TAIL + 5 * n + j]
    kappa = pv[P_TAIL + 4 * n + j] + c * du
    return placed_pose(x, y, th, ct, st, kappa, c, pv[P_CLOSED] != 0.0, lap, pv[P_TURN], extra)


def coarse_start(pv: FlatPath, x: float, y: float, sp: float, ahead: float, behind: float) -> float:
    """Step 1 of :meth:`ClothoidPath.locate` with a hint: ``s`` [m] of the sample
    nearest to ``(x, y)`` among the samples ``s_j = j h``, ``j = floor((sp - behind) / h) + k``, ``k < ceil((ahead +
    behind) / h) + 2`` (unwrapped: a closed path reads sample ``j mod m``, an open one sample ``clip(j, 0, m - 1)``).

    The rules of the column code: the squared distance ``dx^2 + dy^2``, the first minimum (``np.argmin``; the first
    NaN if any), ``np.mod`` (the float modulo of a whole number, exact) and ``np.clip`` of the sample numbers.
    """
    h = pv[P_SPACING]
    n = int(pv[P_N])
    m = int(pv[P_M])
    sx = P_TAIL + 6 * n
    sy = sx + m
    closed = pv[P_CLOSED] != 0.0
    count = math.ceil((ahead + behind) / h) + 2
    j0 = float(np.floor((sp - behind) / h))
    m_f = float(m)
    top = m_f - 1.0
    # the sample numbers j0 + k are whole numbers computed exactly below 2^53: then j mod m steps by one (a float
    # modulo per sample otherwise)
    stepping = abs(j0) + float(count) < 9007199254740992.0
    idx = int(j0 % m_f) if closed else 0
    best = 0.0
    best_j = 0.0
    for k in range(count):
        jj = j0 + float(k)
        if closed:
            if k > 0:
                if stepping:
                    idx += 1
                    if idx == m:
                        idx = 0
                else:
                    idx = int(jj % m_f)
        else:
            jj = min(max(jj, 0.0), top)
            idx = int(jj)
        ddx = pv[sx + idx] - x
        ddy = pv[sy + idx] - y
        d2 = ddx * ddx + ddy * ddy
        if k == 0 or d2 < best or (d2 != d2 and best == best):  # np.argmin: the first minimum (or NaN)
            best = d2
            best_j = jj
    return best_j * h


def locate_flat(
    pose: PoseOf, buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, x: float, y: float, sp: float, ahead: float,
    behind: float,
) -> FlatPoint:  # fmt: skip
    """:meth:`ClothoidPath.locate` of one point ``(x, y)`` [m] with the hint ``sp`` [m] and the window ``ahead``,
    ``behind`` [m] (> 0, finite) on the flat path ``pv``: the window (:func:`locate_window`), the coarse search
    (:func:`coarse_start`) clipped to it, then :func:`project_flat` (``pose``, ``buf``, ``nodes``, ``nb``: the pose
    function and what it is passed, :func:`pose_flat`'s). Returns :data:`FlatPoint` (the fields of
    :class:`PathPoint` but the lap's ``s``).
    """
    lo, hi = locate_window(sp, ahead, behind, pv[P_LENGTH], pv[P_CLOSED] != 0.0)
    s = min(max(coarse_start(pv, x, y, sp, ahead, behind), lo), hi)
    return project_flat(pose, buf, nodes, nb, pv, x, y, s, lo, hi)


def locate_global(pose: PoseOf, buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, x: float, y: float) -> FlatPoint:
    """:meth:`ClothoidPath.locate` of one point ``(x, y)`` [m] without a hint: from the nearest of all samples
    (:func:`coarse_global`), :func:`project_flat` in ``[0, length]`` (open) or unbounded (closed)."""
    if pv[P_CLOSED] != 0.0:
        lo, hi = -math.inf, math.inf
    else:
        lo, hi = 0.0, pv[P_LENGTH]
    return project_flat(pose, buf, nodes, nb, pv, x, y, coarse_global(pv, x, y), lo, hi)


def coarse_global(pv: FlatPath, x: float, y: float) -> float:
    """Step 1 of :meth:`ClothoidPath.locate` without a hint: ``s = j h`` [m] of the sample ``j`` nearest to ``(x, y)``
    among all of the flat path ``pv`` (squared distances, the first minimum or the first NaN, as ``np.argmin``)."""
    n = int(pv[P_N])
    m = int(pv[P_M])
    sx = P_TAIL + 6 * n
    best = 0.0
    best_j = 0
    for j in range(m):
        ddx = pv[sx + j] - x
        ddy = pv[sx + m + j] - y
        d2 = ddx * ddx + ddy * ddy
        if j == 0 or d2 < best or (d2 != d2 and best == best):
            best = d2
            best_j = j
    return float(best_j) * pv[P_SPACING]


def project_flat(
    pose: PoseOf, buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, x: float, y: float, s: float, lo: float, hi: float
) -> FlatPoint:
    """Steps 2 and 3 of :meth:`ClothoidPath.locate` from the coarse estimate ``s`` [m] in the range ``[lo, hi]``:
    Newton's method (:func:`newton_step`, :data:`NEWTON_ITERATIONS` iterations, stopped at a fixed point: the
    remaining ones would repeat it), the foot terms and the status; the poses by ``pose(buf, nodes, nb, pv, s)``
    (:func:`pose_flat`; a :class:`~amigo_gym.paths.user.UserPath`'s on floats)."""
    h = pv[P_SPACING]
    px, py, th, kappa, c, ct, st = pose(buf, nodes, nb, pv, s)
    for _ in range(NEWTON_ITERATIONS):
        s_new, settled = newton_step(x, y, px, py, kappa, ct, st, s, h, lo, hi)
        if settled:
            break
        s = s_new
        px, py, th, kappa, c, ct, st = pose(buf, nodes, nb, pv, s)
    dx, dy, g, e = foot_terms(x, y, px, py, ct, st)
    dist = math.sqrt(dx * dx + dy * dy)
    status = locate_status_float(s, g, lo, hi, pv[P_LENGTH], pv[P_CLOSED] != 0.0)
    return s, px, py, th, kappa, c, e, ct, st, dist, status


def lap_arc(s: float, length: float, closed: bool) -> float:
    """The arc length ``s`` [m] within one lap, in ``[0, length)``, on a closed path (``s`` itself on an open one):
    :attr:`PathPoint.s` of the progress ``s``."""
    if not closed:
        return s
    s_lap = s - _floor_float(s / length) * length
    if s_lap >= length:
        s_lap = s_lap - length
    return s_lap


def _floor_float(q: float) -> float:
    """``np.floor`` of a float: ``math.floor`` where finite, NaN and infinities as they are."""
    return float(math.floor(q)) if q - q == 0.0 else q


def locate_rows(
    pose: PoseOf,
    out: Array,
    buf: Buffer,
    nodes: Buffer,
    flat: FlatPath,
    start: list[int] | IntArray,
    x: FlatPath,
    y: FlatPath,
    sp: FlatPath,
    ahead: float,
    behind: float,
    hinted: bool,
) -> None:
    """:meth:`ClothoidPath.locate` of the points ``(x[i], y[i])`` [m] on the flat paths starting at ``flat[start[i]]``,
    row by row: :func:`locate_flat` with the hints ``sp[i]`` (``hinted``) else :func:`locate_global` (``pose``: as
    theirs); row ``i`` of
    ``out`` ``(12, N)``: the fields of :class:`PathPoint` (the status as a float). The column form of the projection:
    Python runs it on lists (a memoryview for ``flat``), compiled code on arrays (:class:`PathLoops`)."""
    for i in range(len(x)):
        pv = flat[start[i] :]
        if hinted:
            r = locate_flat(pose, buf, nodes, 0, pv, x[i], y[i], sp[i], ahead, behind)
        else:
            r = locate_global(pose, buf, nodes, 0, pv, x[i], y[i])
        out[0, i] = lap_arc(r[0], pv[P_LENGTH], pv[P_CLOSED] != 0.0)
        out[1, i] = r[0]
        out[2, i] = r[1]
        out[3, i] = r[2]
        out[4, i] = r[3]
        out[5, i] = r[4]
        out[6, i] = r[5]
        out[7, i] = r[6]
        out[8, i] = r[7]
        out[9, i] = r[8]
        out[10, i] = r[9]
        out[11, i] = r[10]


def pose_rows(out: Array, buf: Buffer, nodes: Buffer, flat: FlatPath, start: list[int] | IntArray, s: FlatPath) -> None:
    """:func:`pose_flat` at the arc lengths ``s[i]`` [m] on the flat paths starting at ``flat[start[i]]``, row by row,
    into the rows of ``out`` ``(7, N)`` (the fields of :class:`PathPose`), as :func:`locate_rows`."""
    for i in range(len(s)):
        x, y, th, kappa, c, ct, st = pose_flat(buf, nodes, 0, flat[start[i] :], s[i])
        out[0, i] = x
        out[1, i] = y
        out[2, i] = th
        out[3, i] = kappa
        out[4, i] = c
        out[5, i] = ct
        out[6, i] = st


def pose_flat(buf: Buffer, nodes: Buffer, nb: int, pv: FlatPath, s: float) -> FloatPose:
    """The pose at the arc length ``s`` [m] on the flat path ``pv``:
    ``(x, y, theta, kappa, dkappa/ds, cos theta, sin theta)`` [m, m, rad, 1/m, 1/m^2, -, -] by :func:`piece_at`, the
    quadrature from the piece's start (:func:`amigo_gym.model.fresnel.unit_speed_nodes`) and :func:`place`.

    ``buf``: a node buffer of ``3 (NODES + 1)`` floats (scratch); ``nodes[nb:]``: the path quadrature's ``NODES``
    nodes then weights on [0, 1] (:func:`amigo_gym.model.fresnel.node_table` of 1). The float path passes lists
    (:func:`_pose_float`), the compiled step a buffer on its stack and its constants (:mod:`amigo_gym.sim._kernels_v1`).
    """
    j, du, lap, extra = piece_at(pv, s)
    n = int(pv[P_N])
    b = P_TAIL + n + j
    x, y, th, ct, st = unit_speed_nodes(
        buf, pv[b], pv[b + n], pv[b + 2 * n], pv[b + 3 * n], pv[b + 4 * n], du, nodes, nb, NODES
    )
    return place(pv, j, du, lap, extra, x, y, th, ct, st)


#: the path quadrature's nodes and weights (:func:`pose_flat`'s ``nodes`` on the float path)
_PATH_TABLE: list[float] = node_table(1)


# --------------------------------------------------------------------------- building a path
#
# The loops of ClothoidPath._build, in numba's subset as the projection above: the float route runs them as Python on
# lists, a compiled route (PathLoops, amigo_gym.sim.fast_v1.path_loops) compiles these very functions (SHARED of
# amigo_gym.sim.layout_v1) with the C library's cosines and sines of the nodes (fresnel.cos_sin_nodes' overload).


def chain_pieces(
    out: Buffer,
    n: int,
    segs: Buffer,
    n_segs: int,
    x: float,
    y: float,
    th: float,
    buf: Buffer,
    nodes: Buffer,
) -> tuple[float, float, float, float]:
    """The pieces of a path and their start poses, chained (:meth:`ClothoidPath._build`).

    Segment ``g`` (``segs[4 g : 4 g + 4]``: length [m], curvature [1/m], curvature rate [1/m^2] and its number of
    pieces, as a float) is split into equal pieces; piece ``q``'s ``s0, x0, y0, th0, k0, c`` are written at ``out[q],
    out[n + q], ..., out[5 n + q]`` (``n`` pieces in all), its start pose the previous piece's end, one quadrature
    from ``(x, y, th)`` (:func:`amigo_gym.model.fresnel.unit_speed_nodes`: :func:`amigo_gym.model.fresnel.advance`'s
    bits; ``buf``: ``3 (NODES + 1)`` scratch, ``nodes``: :func:`amigo_gym.model.fresnel.node_table` of 1).

    Returns:
        the end pose and the length, ``(x, y, theta, length)``.
    """
    q = 0
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
            out[q] = s_seg + j * h
            out[n + q] = x
            out[2 * n + q] = y
            out[3 * n + q] = th
            out[4 * n + q] = kj
            out[5 * n + q] = rate
            x, y, th, _ct, _st = unit_speed_nodes(buf, x, y, th, kj, rate, hj, nodes, 0, NODES)
            q += 1
        s_seg += length
    return x, y, th, s_seg


def sample_points(buf: Buffer, nodes: Buffer, pv: FlatPath, o: int, count: int, spacing: float) -> None:
    """The coarse samples of the flat path ``pv`` written into it: the points at ``s_j = j spacing`` [m],
    ``j < count``, by :func:`pose_flat` (the float path's pose), their
    ``x`` at ``pv[o + j]``, ``y`` at ``pv[o + count + j]`` (``pv``'s header and pieces written before).

    The compiled route's samples (:class:`PathLoops`); the float route takes them from the column pose of all at
    once (:meth:`ClothoidPath._build`), faster in numpy than this loop in Python.
    """
    for j in range(count):
        x, y, _th, _k, _c, _ct, _st = pose_flat(buf, nodes, 0, pv, j * spacing)
        pv[o + j] = x
        pv[o + count + j] = y


def _pose_float(pv: FlatPath, s: float) -> FloatPose:
    """:func:`pose_flat` on the float path: a new scratch list, the path quadrature's nodes."""
    return pose_flat([0.0] * (3 * NODES + 3), _PATH_TABLE, 0, pv, s)


def _poses_flat(pv: FlatPath, ss: list[float]) -> list[FloatPose]:
    """:func:`_pose_float` of several floats, the cosines and sines of all in one numpy call each
    (:func:`amigo_gym.model.fresnel.unit_speed_poses`)."""
    n = int(pv[P_N])
    where = [piece_at(pv, s) for s in ss]
    starts = []
    for j, du, _, _ in where:
        b = P_TAIL + n + j
        starts.append((pv[b], pv[b + n], pv[b + 2 * n], pv[b + 3 * n], pv[b + 4 * n], du))
    return [
        place(pv, j, du, lap, extra, *pose)
        for pose, (j, du, lap, extra) in zip(unit_speed_poses(starts), where, strict=True)
    ]


def _window(max_advance: float, max_retreat: float | None) -> tuple[float, float]:
    """The search window ``ahead``, ``behind`` [m] of :meth:`ClothoidPath.locate`, checked (> 0, finite)."""
    if type(max_advance) is float and max_advance > 0.0 and max_advance < math.inf:
        ahead = max_advance  # what check_real returns for a finite positive float
    else:
        ahead = check_real("locate", "max_advance", max_advance, 0.0, low_open=True)
    if max_retreat is None:
        return ahead, ahead
    if type(max_retreat) is float and max_retreat > 0.0 and max_retreat < math.inf:
        return ahead, max_retreat
    return ahead, check_real("locate", "max_retreat", max_retreat, 0.0, low_open=True)


def _locate_float(
    pv: FlatPath, x: float, y: float, sp: float | None, max_advance: float, max_retreat: float | None
) -> PathPoint:
    """:meth:`ClothoidPath.locate` for float ``x``, ``y``, ``s_prev`` (or None) on the flat path ``pv``: the window
    checked, :func:`locate_flat` (:func:`locate_global` without a hint), the lap's ``s`` added."""
    buf = [0.0] * (3 * NODES + 3)
    if sp is None:
        r = locate_global(pose_flat, buf, _PATH_TABLE, 0, pv, x, y)
    else:
        ahead, behind = _window(max_advance, max_retreat)
        if sp - sp != 0.0:
            check_hint(sp)
        r = locate_flat(pose_flat, buf, _PATH_TABLE, 0, pv, x, y, sp, ahead, behind)
    return PathPoint(lap_arc(r[0], pv[P_LENGTH], pv[P_CLOSED] != 0.0), *r)


#: the compiled :func:`locate_rows` and :func:`pose_rows` (:class:`PathLoops`) once a compiled route registered them
#: (:func:`use_compiled_rows`); else Python runs them
_COMPILED: list[PathLoops] = []


def use_compiled_rows(loops: PathLoops) -> None:
    """From now on, run the column projection and pose (:func:`locate_columns`, :func:`pose_columns_of`) by the
    compiled :func:`locate_rows` and :func:`pose_rows` of ``loops`` (the same bits:
    :func:`amigo_gym.sim.fast_v1.path_loops` offers them only where the C library's ``cos``/``sin`` are numpy's)."""
    if not _COMPILED:
        _COMPILED.append(loops)


def locate_columns(
    flat: Array,
    start: IntArray,
    x: Array,
    y: Array,
    sp: Array | None,
    ahead: float,
    behind: float,
    pose: PoseOf | None = None,
) -> PathPoint:
    """:func:`locate_rows` on ``(N,)`` float64 columns, the flat path of row ``i`` at ``flat[start[i]:]``: compiled
    where registered (:func:`use_compiled_rows`), else in Python (always for a ``pose`` other than
    :func:`pose_flat`); a :class:`PathPoint` of ``(N,)`` columns."""
    out = np.empty((12, x.shape[0]))
    hints = x if sp is None else sp
    if _COMPILED and pose is None:
        _COMPILED[0].locate(out, flat, start, x, y, hints, ahead, behind, sp is not None)
    else:
        rows = (start.tolist(), x.tolist(), y.tolist(), hints.tolist())
        pv = cast(FlatPath, flat.data)  # a memoryview: its slices are views, its entries Python floats
        of = pose_flat if pose is None else pose
        locate_rows(of, out, [0.0] * (3 * NODES + 3), _PATH_TABLE, pv, *rows, ahead, behind, sp is not None)
    return PathPoint._make([*out[:11], out[11].astype(np.int64)])


def locate_points(
    flat: Array, x: Real, y: Real, s_prev: Real | None, max_advance: float, max_retreat: float | None,
    pose: PoseOf | None = None,
) -> PathPoint:  # fmt: skip
    """:meth:`ClothoidPath.locate` of points of any shape on the flat path ``flat`` (the window and the hints checked,
    the arguments broadcast): :func:`locate_columns`; ``pose``: as there. Arrays of the broadcast shape."""
    ahead, behind = (0.0, 0.0) if s_prev is None else _window(max_advance, max_retreat)
    if s_prev is not None:
        check_hint(s_prev)
    cols = np.broadcast_arrays(*(np.asarray(v, dtype=np.float64) for v in (x, y, 0.0 if s_prev is None else s_prev)))
    xf, yf, sf = (np.ascontiguousarray(v).reshape(-1) for v in cols)
    start = np.zeros(xf.size, dtype=np.int64)
    got = locate_columns(flat, start, xf, yf, None if s_prev is None else sf, ahead, behind, pose)
    return PathPoint._make([np.reshape(v, cols[0].shape) for v in got])


def pose_columns_of(flat: Array, start: IntArray, s: Array) -> PathPose:
    """:func:`pose_rows` on a ``(N,)`` float64 column, as :func:`locate_columns`; a :class:`PathPose` of columns."""
    out = np.empty((7, s.shape[0]))
    if _COMPILED:
        _COMPILED[0].pose(out, flat, start, s)
    else:
        pose_rows(out, [0.0] * (3 * NODES + 3), _PATH_TABLE, cast(FlatPath, flat.data), start.tolist(), s.tolist())
    return PathPose(*out)
