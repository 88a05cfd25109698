"""Path families of AmigoBot-v1: constructors of :class:`~amigo_gym.paths.clothoid.ClothoidPath` and their registry
:data:`FAMILIES` (parameter ranges; :func:`make_family_path` builds one by name, a one-line ``ValueError`` naming a
bad field, value and range). ``loops``: :class:`~amigo_gym.paths.clothoid.PathLoops` or None (Python), the same
path either way; :func:`family_segments` (the figure-8's and lane change's segments) and the functions it calls are in
numba's subset.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from amigo_gym.model.fresnel import NODES, Buffer, node_table, subinterval_count, unit_speed_nodes
from amigo_gym.model.params import check_real
from amigo_gym.paths.clothoid import ClothoidPath, ClothoidSegment, PathLoops, py_max


@dataclass(frozen=True)
class ParamRange:
    """Allowed range ``[low, high]`` of one family parameter (open ends by ``low_open``, ``high_open``), its
    ``default``, ``unit`` (e.g. ``"m"``) and a one-line ``doc``."""

    low: float
    high: float
    default: float
    unit: str
    doc: str
    low_open: bool = False
    high_open: bool = False

    def check(self, owner: str, name: str, value: object) -> float:
        """``value`` as a float if it is a real number in range, else a one-line ``ValueError``."""
        return check_real(owner, name, value, self.low, self.high, low_open=self.low_open, high_open=self.high_open)


def _checked(owner: str, ranges: dict[str, ParamRange], values: tuple[object, ...]) -> list[float]:
    return [rng.check(owner, name, v) for (name, rng), v in zip(ranges.items(), values, strict=True)]


def _direction(owner: str, value: object) -> int:
    if isinstance(value, bool | np.bool_) or value not in (1, -1):
        raise ValueError(f"{owner}.direction must be +1 (left) or -1 (right), got {value!r}")
    return 1 if value == 1 else -1


CIRCLE_RANGES = {"radius": ParamRange(0.0, 1e3, 1.0, "m", "circle radius R", low_open=True)}
MANOEUVRE_RANGES = {
    "radius": ParamRange(0.0, 1e3, 1.0, "m", "radius R of the circular part", low_open=True),
    "straight_length": ParamRange(0.0, 1e3, 1.0, "m", "length of the straight part along x0"),
    "laps": ParamRange(0.0, 100.0, 1.0, "-", "number of laps of the circular part", low_open=True),
}
FIGURE8_RANGES = {
    "size": ParamRange(0.0, 1e3, 4.0, "m", "overall width of the figure-8 along x0", low_open=True),
    "crossing_angle": ParamRange(0.3, 2.0, math.pi / 2, "rad", "angle between the lines crossing at the origin"),
    "transition": ParamRange(0.0, 1.5, 0.5, "-", "length of each clothoid transition over the lobe radius"),
}
LANE_CHANGE_RANGES = {
    "offset": ParamRange(-1e2, 1e2, 0.5, "m", "sideways shift, positive to the left; |offset| <= 0.68 length"),
    "length": ParamRange(0.0, 1e3, 3.0, "m", "distance along x0 over which the shift happens", low_open=True),
    "lead": ParamRange(0.0, 1e3, 1.0, "m", "straight run before and after the shift"),
}
RANDOM_RANGES = {
    "length": ParamRange(0.0, 1e4, 20.0, "m", "arc length of the path", low_open=True),
    "max_curvature": ParamRange(0.0, 1e2, 1.0, "1/m", "bound of |curvature|", low_open=True),
    "max_curvature_rate": ParamRange(0.0, 1e3, 1.0, "1/m^2", "bound of |dcurvature/ds|", low_open=True),
    "min_piece": ParamRange(0.01, 1e2, 0.5, "m", "shortest random piece (before the rate bound stretches it)"),
    "max_piece": ParamRange(0.01, 1e2, 3.0, "m", "longest random piece"),
}


def circle(
    radius: float = 1.0, direction: int = 1, start: tuple[float, float] = (0.0, 0.0), start_angle: float = 0.0, *,
    loops: PathLoops | None = None,
) -> ClothoidPath:  # fmt: skip
    """A closed circle of ``radius`` [m] in (0, 1000] entered at ``start`` [m] with heading ``start_angle`` [rad],
    turning left (``direction = +1``) or right (-1): one arc of length ``2 pi R``, curvature ``d / R``; the defaults
    give the paper's eq. (6)."""
    r = CIRCLE_RANGES["radius"].check("circle", "radius", radius)
    d = _direction("circle", direction)
    return ClothoidPath((ClothoidSegment.arc(2.0 * math.pi * r, d / r),), start, start_angle, closed=True, loops=loops)


def manoeuvre(
    radius: float = 1.0, straight_length: float = 1.0, direction: int = 1, laps: float = 1.0, *,
    loops: PathLoops | None = None,
) -> ClothoidPath:  # fmt: skip
    """The paper's manoeuvre path: ``straight_length`` [m] in [0, 1000] along x0 from the origin, then ``laps``
    in (0, 100] laps of the circle of ``radius`` [m] in (0, 1000], turning by ``direction`` (+1 left, -1 right);
    open: it ends after the laps."""
    r, sl, n = _checked("manoeuvre", MANOEUVRE_RANGES, (radius, straight_length, laps))
    d = _direction("manoeuvre", direction)
    arc = ClothoidSegment.arc(2.0 * math.pi * r * n, d / r)
    segs = (ClothoidSegment.line(sl), arc) if sl > 0.0 else (arc,)
    return ClothoidPath(segs, loops=loops)


#: largest heading reached in a lane change [rad]
LANE_CHANGE_MAX_HEADING = 1.2
#: most sub-intervals of one segment of :func:`run_segments` (a turn of up to 8 rad; the families' take 1 or 2)
RUN_MAX_SUB = 4
#: the node tables of 1 to :data:`RUN_MAX_SUB` sub-intervals in turn (that of ``n`` from ``NODES n (n - 1)``)
RUN_NODES: list[float] = [v for n in range(1, RUN_MAX_SUB + 1) for v in node_table(n)]
#: entries of :func:`run_segments`' scratch ``buf`` (a node buffer of the most sub-intervals) and of its segments
RUN_SCRATCH = 3 * (NODES * RUN_MAX_SUB + 1)


def run_segments(
    buf: Buffer, nodes: Buffer, segs: Buffer, n_segs: int, x: float, y: float, th: float
) -> tuple[float, float, float]:
    """End pose after the segments ``segs[3 g : 3 g + 3] = (length, curvature, rate)`` from ``(x, y, th)``, each
    one quadrature of as many sub-intervals as it needs (``buf``: :data:`RUN_SCRATCH` floats; ``nodes``:
    :data:`RUN_NODES`); ``ValueError`` if a segment turns by more than ``2 RUN_MAX_SUB`` rad (or by NaN)."""
    for g in range(n_segs):
        length = segs[3 * g]
        k = segs[3 * g + 1]
        c = segs[3 * g + 2]
        kabs = py_max(abs(k), abs(k + c * length))
        phase = kabs * length + 0.5 * abs(c) * length * length
        if not phase <= 2.0 * RUN_MAX_SUB:
            raise ValueError("run_segments: a segment turns by more than 2 RUN_MAX_SUB rad")
        n = subinterval_count(phase)
        x, y, th, _ct, _st = unit_speed_nodes(buf, x, y, th, k, c, length, nodes, NODES * n * (n - 1), NODES * n)
    return x, y, th


def s_curve_half(buf: Buffer, nodes: Buffer, segs: Buffer, theta_max: float) -> tuple[float, float]:
    """End point of the first half of the unit S-curve from the origin along x0: clothoids of curvature
    ``0 -> theta_max -> 0`` over length 1 each (``segs``: 6 floats of scratch)."""
    _put(segs, _put(segs, 0, 1.0, 0.0, theta_max), 1.0, theta_max, -theta_max)
    x, y, _th = run_segments(buf, nodes, segs, 2, 0.0, 0.0, 0.0)
    return x, y


def lane_change_shape(buf: Buffer, nodes: Buffer, segs: Buffer, ratio: float) -> tuple[float, float, float, float]:
    """``(x1, y1, theta_m, xm)`` of a lane change of ``|offset| / length = ratio``: ``(x1, y1)`` the end of the
    half S-curve at :data:`LANE_CHANGE_MAX_HEADING` (the steepest); if ``ratio <= y1 / x1`` (else NaN) the heading
    ``theta_m`` whose half S-curve has ``y / x = ratio`` (bisection) and its ``x``, ``xm``."""
    x1, y1 = s_curve_half(buf, nodes, segs, LANE_CHANGE_MAX_HEADING)
    if ratio > y1 / x1:
        return x1, y1, math.nan, math.nan
    lo = 0.0
    hi = LANE_CHANGE_MAX_HEADING
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid == lo or mid == hi:  # noqa: SIM109  (numba's subset: no tuple built)
            break
        xm, ym = s_curve_half(buf, nodes, segs, mid)
        if ym / xm < ratio:
            lo = mid
        else:
            hi = mid
    theta_m = 0.5 * (lo + hi)
    xm, _ym = s_curve_half(buf, nodes, segs, theta_m)
    return x1, y1, theta_m, xm


def figure8(
    size: float = 4.0, crossing_angle: float = math.pi / 2, transition: float = 0.5, *, loops: PathLoops | None = None
) -> ClothoidPath:
    """A closed figure-8 of width ``size`` [m] in (0, 1000] crossing itself at the origin at ``crossing_angle``
    [rad] in [0.3, 2.0], curvature continuous (its segments: :func:`figure8_segments`); starts at the right lobe's
    rightmost point heading ``-pi/2``; crosses the origin at ``s = L/4`` and ``3L/4``.
    """
    size, phi, b = _checked("figure8", FIGURE8_RANGES, (size, crossing_angle, transition))
    path, _, n = _path_of(loops, 1, size, phi, b)
    if n == -1:
        raise ValueError(f"figure8.transition {transition!r} is too long for crossing_angle {crossing_angle!r}")
    if path is None:
        raise ValueError(
            f"figure8: crossing_angle {crossing_angle!r} with transition {transition!r} leaves no room for the "
            "crossing lines; use a smaller angle or transition"
        )
    return path


def figure8_segments(buf: Buffer, nodes: Buffer, out: Buffer, size: float, crossing_angle: float, b: float) -> int:
    """The segments ``out[3 g : 3 g + 3] = (length, curvature, rate)`` of :func:`figure8` (9, or 5 without
    transitions); their number, or -1 (``b`` too long), -2 (no room for the lines). With lobe radius 1, the right
    lobe leaves the origin at heading ``phi = crossing_angle / 2`` along a line of length ``a = -y_m / sin(phi)``
    (the lobe's middle on the x axis), turns right through a clothoid (curvature 0 to -1 over ``b``), an arc and the
    mirror clothoid, and returns; the left lobe mirrors it, the whole scaled to ``size``. ``buf``, ``nodes``: as
    :func:`run_segments`."""
    phi = 0.5 * crossing_angle
    # the right half-lobe from the line's end to the middle (heading phi -> -pi/2); the clothoid turns b/2
    arc_half = math.pi / 2 + phi - 0.5 * b
    if arc_half <= 0.0:
        return -1
    g = _transition(out, 0, b, 0.0, -1.0)
    g = _put(out, g, arc_half, -1.0, 0.0)
    xm, ym, _ = run_segments(buf, nodes, out, g, 0.0, 0.0, phi)
    a = -ym / math.sin(phi)
    if a < 0.0:
        return -2
    scale = size / (2.0 * (a * math.cos(phi) + xm))
    la, lb, lc = a * scale, b * scale, arc_half * scale
    k = 1.0 / scale
    g = _transition(out, _put(out, 0, lc, -k, 0.0), lb, -k, 0.0)
    g = _transition(out, _put(out, g, 2.0 * la, 0.0, 0.0), lb, 0.0, k)
    g = _transition(out, _put(out, g, 2.0 * lc, k, 0.0), lb, k, 0.0)
    g = _transition(out, _put(out, g, 2.0 * la, 0.0, 0.0), lb, 0.0, -k)
    return _put(out, g, lc, -k, 0.0)


def lane_change(
    offset: float = 0.5, length: float = 3.0, lead: float = 1.0, *, loops: PathLoops | None = None
) -> ClothoidPath:
    """A lane change: ``lead`` [m] in [0, 1000] along x0, a sideways shift by ``offset`` [m] in [-100, 100]
    (positive left) over ``length`` [m] in (0, 1000], ``lead`` again (its segments: :func:`lane_change_segments`;
    ``|offset| <~ 0.68 length``)."""
    off, ln, lead = _checked("lane_change", LANE_CHANGE_RANGES, (offset, length, lead))
    path, out, _ = _path_of(loops, 2, off, ln, lead)
    if path is None:
        bound = out[1]
        raise ValueError(
            f"lane_change.offset must satisfy |offset| <= {bound:.4f} length = {bound * ln:.4g} m, got {offset!r}"
        )
    return path


def lane_change_segments(buf: Buffer, nodes: Buffer, out: Buffer, offset: float, length: float, lead: float) -> int:
    """The segments ``out[3 g : 3 g + 3]`` of :func:`lane_change` (6, or 4 without leads) and their number; -1 (and
    the largest ``|offset| / length`` in ``out[1]``) if the offset is too large. The shift: four clothoids of length
    ``q``, curvature ``0 -> k -> 0 -> -k -> 0``, heading up to ``theta_m = k q <= 1.2 rad`` solving ``Y1/X1 =
    |offset| / length`` for the unit half S-curve (:func:`lane_change_shape`), ``q = L / (2 X1)``."""
    ratio = abs(offset) / length
    x1, y1, theta_m, xm = lane_change_shape(buf, nodes, out, ratio)
    if ratio > y1 / x1:
        out[1] = y1 / x1
        return -1
    q = length / (2.0 * xm)
    k = math.copysign(theta_m / q, offset) if offset != 0.0 else 0.0
    g = _put(out, 0, lead, 0.0, 0.0) if lead > 0.0 else 0
    g = _transition(out, _transition(out, g, q, 0.0, k), q, k, 0.0)
    g = _transition(out, _transition(out, g, q, 0.0, -k), q, -k, 0.0)
    return _put(out, g, lead, 0.0, 0.0) if lead > 0.0 else g


#: the families :func:`family_segments` builds, by number
SEGMENT_FAMILIES: tuple[str, ...] = ("circle", "figure8", "lane_change")
#: most segments :func:`family_segments` writes (a figure-8's)
FAMILY_SEGMENTS = 9


def family_segments(buf: Buffer, nodes: Buffer, out: Buffer, kind: int, a: float, b: float, c: float) -> int:
    """The segments of family ``SEGMENT_FAMILIES[kind]`` with its parameters in order (checked), into ``out`` (at
    least ``3 FAMILY_SEGMENTS`` floats): :func:`figure8_segments`, :func:`lane_change_segments`, or a circle of
    radius ``a`` turning by ``b`` (+-1): one arc ``(2 pi a, b / a, 0)``."""
    if kind == 1:
        return figure8_segments(buf, nodes, out, a, b, c)
    if kind == 2:
        return lane_change_segments(buf, nodes, out, a, b, c)
    return _put(out, 0, 2.0 * math.pi * a, b / a, 0.0)


def segment_params(name: str, values: dict[str, Any]) -> tuple[int, float, float, float]:
    """``(kind, a, b, c)`` of :func:`family_segments` for the family ``name`` (of :data:`SEGMENT_FAMILIES`) with the
    parameters ``values`` (unchecked; the rest at their defaults)."""
    kind = SEGMENT_FAMILIES.index(name)
    if kind == 0:
        return 0, float(values.get("radius", 1.0)), float(values.get("direction", 1)), 0.0
    a, b, c = (float(values.get(k, r.default)) for k, r in FAMILIES[name].params.items())
    return kind, a, b, c


def family_start(kind: int, a: float) -> tuple[float, float, float, bool]:
    """Start ``(x, y, theta)`` [m, m, rad] and closedness of the path of :func:`family_segments` (``a``: the figure-8's
    size; a circle from the origin along x0)."""
    if kind == 1:
        return 0.5 * a, 0.0, -math.pi / 2, True
    return 0.0, 0.0, 0.0, kind == 0


def _put(out: Buffer, g: int, length: float, k: float, rate: float) -> int:
    out[3 * g] = length
    out[3 * g + 1] = k
    out[3 * g + 2] = rate
    return g + 1


def _transition(out: Buffer, g: int, length: float, k0: float, k1: float) -> int:
    # a clothoid from k0 to k1 (ClothoidSegment.transition), none if length is 0
    return _put(out, g, length, k0, (k1 - k0) / length) if length > 0.0 else g


def _path_of(loops: PathLoops | None, k: int, a: float, b: float, c: float) -> tuple[ClothoidPath | None, Any, int]:
    # family_segments' path (compiled with loops) from family_start, its output and count (< 0: an error, no path)
    if loops is not None:
        out = loops.family(k, a, b, c).tolist()
        n = int(out.pop())
    else:
        out = [0.0] * (3 * FAMILY_SEGMENTS)
        n = family_segments([0.0] * RUN_SCRATCH, RUN_NODES, out, k, a, b, c)
    if n < 0:
        return None, out, n
    x, y, th, closed = family_start(k, a)
    segs = tuple(ClothoidSegment(out[3 * g], out[3 * g + 1], out[3 * g + 2]) for g in range(n))
    return ClothoidPath(segs, (x, y), th, closed=closed, loops=loops), out, n


def random_path(
    rng: np.random.Generator, length: float = 20.0, max_curvature: float = 1.0, max_curvature_rate: float = 1.0,
    min_piece: float = 0.5, max_piece: float = 3.0, *, loops: PathLoops | None = None,
) -> ClothoidPath:  # fmt: skip
    """A random smooth open path of ``length`` [m] in (0, 10000] from the origin along x0, ``|kappa| <=
    max_curvature`` [1/m] in (0, 100], ``|dkappa/ds| <= max_curvature_rate`` [1/m^2] in (0, 1000]: from 0 the
    curvature alternates ramps (linear to ``U(-max_curvature, max_curvature)`` over ``U(min_piece, max_piece)`` [m]
    in [0.01, 100], stretched to ``|delta kappa| / max_curvature_rate`` if needed) and holds (arcs of
    ``U(0, max_piece)``), cut at ``length``; ``rng`` is consumed.
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"random_path.rng must be a numpy.random.Generator, got {rng!r}")
    given = (length, max_curvature, max_curvature_rate, min_piece, max_piece)
    total, kmax, cmax, pmin, pmax = _checked("random_path", RANDOM_RANGES, given)
    if pmin > pmax:
        raise ValueError(f"random_path.min_piece must be <= max_piece = {pmax:g} m, got {min_piece!r}")
    segs: list[ClothoidSegment] = []
    s = 0.0
    k = 0.0
    while s < total:
        target = float(rng.uniform(-kmax, kmax))
        ramp = max(float(rng.uniform(pmin, pmax)), abs(target - k) / cmax)
        hold = float(rng.uniform(0.0, pmax))
        rate = (target - k) / ramp
        ramp = min(ramp, total - s)
        segs.append(ClothoidSegment(ramp, k, rate))
        s += ramp
        k = min(max(k + rate * ramp, -kmax), kmax)
        if s < total and hold > 0.0:
            hold = min(hold, total - s)
            segs.append(ClothoidSegment.arc(hold, k))
            s += hold
    return ClothoidPath(tuple(segs), loops=loops)


@dataclass(frozen=True)
class Family:
    """A family of the registry: ``name``, the constructor ``build`` (its first argument the generator if
    ``random``), its numeric ``params`` and a one-line ``doc``."""

    name: str
    build: Callable[..., ClothoidPath]
    params: dict[str, ParamRange]
    random: bool
    doc: str


FAMILIES: dict[str, Family] = {
    "circle": Family("circle", circle, CIRCLE_RANGES, False, "closed circle (paper eq. 6); also direction=+-1"),
    "manoeuvre": Family(
        "manoeuvre", manoeuvre, MANOEUVRE_RANGES, False, "straight along x0, then the circle; also direction=+-1"
    ),
    "figure8": Family("figure8", figure8, FIGURE8_RANGES, False, "closed figure-8 crossing itself at the origin"),
    "lane_change": Family("lane_change", lane_change, LANE_CHANGE_RANGES, False, "sideways shift by clothoids"),
    "random": Family("random", random_path, RANDOM_RANGES, True, "seeded random path, bounded curvature and rate"),
}


def make_family_path(
    name: str, rng: np.random.Generator | None = None, *, loops: PathLoops | None = None, **params: Any
) -> ClothoidPath:
    """The path of family ``name`` (a key of :data:`FAMILIES`) with ``params`` (the rest at defaults); ``ValueError``
    for an unknown family or parameter, a parameter out of range, or no ``rng`` for ``"random"``."""
    fam = FAMILIES.get(name) if isinstance(name, str) else None
    if fam is None:
        raise ValueError(f"path family must be one of {sorted(FAMILIES)}, got {name!r}")
    allowed = set(fam.params) | ({"direction"} if name in ("circle", "manoeuvre") else set())
    if unknown := sorted(set(params) - allowed):
        raise ValueError(f"path family {name!r} has no parameter {unknown[0]!r}; it takes {sorted(allowed)}")
    if fam.random:
        if rng is None:
            raise ValueError(f"path family {name!r} needs a numpy.random.Generator rng")
        return fam.build(rng, loops=loops, **params)
    return fam.build(loops=loops, **params)
