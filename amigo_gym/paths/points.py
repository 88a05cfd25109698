"""Paths from data: a :class:`~amigo_gym.paths.ClothoidPath` of continuous curvature fitted to points ``(n, 2)``
[m] in path order (:func:`fit_points`; docs/amigobot_v1.md, "Paths of your own"):

1. a cubic spline through them in the chord-length parameter (not-a-knot ends if open, periodic if closed);
2. steps of at most ``step`` [m] of chord and :data:`MAX_STEP_TURN` of turn, each a clothoid of the spline's arc
   length, its curvature linear between the spline's ``kappa = (x' y'' - y' x'') / (x'^2 + y'^2)^{3/2}`` at its ends;
3. a closed path's curvature corrected by the smallest ``c_0 + sum_q (c cos + c sin)(q w s)``, ``q = 1, 2``,
   ``w = 2 pi / L``, closing it to rounding (Gauss–Newton);
4. ``max_i |c(s_i) - p_i|`` [m] at each point's arc length within ``tolerance`` (``step`` halved up to
   :data:`MAX_REFINEMENTS` times), else ``ValueError``.

With ``smoothing=sigma`` [m] (the points' noise) points are averaged in groups of ``g`` (a power of 2: points ``g``
apart a median ``3 sigma`` apart), then moved to the discrete cubic smoothing spline (Whittaker–Reinsch, least
``|z - b|^2 + lambda |z''|^2``) at an RMS distance ``sigma sqrt(2 / g)`` from the means (an open path's end
curvature 0)."""

from __future__ import annotations

import csv
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.io import finite_float
from amigo_gym.model.fresnel import advance
from amigo_gym.model.params import check_real, show_value
from amigo_gym.paths.clothoid import MAX_CURVATURE, TWO_PI, ClothoidPath, ClothoidSegment

Array = NDArray[np.float64]

#: how often ``step`` is halved before a fit that misses ``tolerance`` is refused
MAX_REFINEMENTS = 4
#: largest turn of one clothoid step [rad]
MAX_STEP_TURN = 0.05
#: smallest distance between consecutive points [m]
MIN_CHORD = 1e-9
#: most points accepted
MAX_POINTS = 1_000_000
#: shortest path through the points [m] (the robot's body length)
MIN_LENGTH = 0.33
#: longest path through the points [m]
MAX_LENGTH = 1000.0
#: points are out of order when consecutive ones are this many times farther apart than nearest neighbours
UNORDERED_RATIO = 10.0
#: Gauss–Legendre nodes of the spline's arc length
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


@dataclass(frozen=True)
class PointsFit:
    """The result of :func:`fit_points`: the ``path``, ``max_error = max_i |c(s_i) - p_i|`` [m] (``<= tolerance``)
    at the points' arc lengths ``point_s`` ``(n,)`` [m], the largest chord ``step`` [m] used, a closed path's
    ``closure_correction`` ``(c_0, ..., c_4)`` [1/m] (empty if open), and ``smoothed``: the RMS distance [m] the
    smoothing moved the grouped points (0 without; with it, the errors and ``point_s`` are of the smoothed points)."""

    path: ClothoidPath
    max_error: float
    point_s: Array
    step: float
    closure_correction: tuple[float, ...]
    smoothed: float = 0.0


def _check_points(points: Any, closed: bool, owner: str) -> Array:
    # points as a float64 (n, 2) array of distinct consecutive finite points in path order, in metres
    if isinstance(points, str | bytes | os.PathLike):
        raise ValueError(f"{owner}.points must be an (n, 2) array of x, y in metres; for a file use from_file")
    try:
        arr = np.asarray(points)
    except (ValueError, TypeError):
        got = show_value(points)
        raise ValueError(f"{owner}.points must be an (n, 2) array of x, y in metres, got {got}") from None
    if arr.dtype.kind not in "fiu" or arr.dtype == np.bool_:
        raise ValueError(f"{owner}.points must be real numbers (x, y in metres), got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"{owner}.points must have shape (n, 2) (x, y in metres), got shape {arr.shape}")
    p = arr.astype(np.float64)
    if (bad := np.flatnonzero(~np.isfinite(p).all(axis=1))).size:
        i = int(bad[0])
        raise ValueError(f"{owner}.points[{i}] must be finite, got {p[i].tolist()}")
    if closed and len(p) > 1 and np.hypot(*(p[-1] - p[0])) < MIN_CHORD:
        p = p[:-1]  # the first point repeated at the end of a closed path
    need = 3 if closed else 2
    if len(p) < need:
        what = "closed" if closed else "open"
        raise ValueError(f"{owner}.points must hold at least {need} distinct points for an {what} path, got {len(p)}")
    if len(p) > MAX_POINTS:
        raise ValueError(f"{owner}.points must hold at most {MAX_POINTS} points, got {len(p)}")
    chord = np.hypot(np.diff(p[:, 0]), np.diff(p[:, 1]))
    if (dup := np.flatnonzero(chord < MIN_CHORD)).size:
        i = int(dup[0]) + 1
        raise ValueError(f"{owner}.points[{i}] repeats points[{i - 1}] ({p[i].tolist()}): points must be distinct")
    # shuffled: consecutive points far apart where each has a close neighbour
    step, extent = float(np.median(chord)), float(np.hypot(*np.ptp(p, axis=0)))
    if step > 0.1 * extent and len(p) > 4:
        from scipy.spatial import cKDTree

        near = float(np.median(cKDTree(p).query(p, k=2)[0][:, 1]))
        if step > UNORDERED_RATIO * near:
            raise ValueError(
                f"{owner}.points are not in path order: consecutive points are {step:.3g} m apart (median), "
                f"{step / near:.3g} times the {near:.3g} m to each one's nearest neighbour (allowed: at most "
                f"{UNORDERED_RATIO:g} times); sort them along the path"
            )
    if extent > MAX_LENGTH:  # before any work: a path that long is longer still
        _check_length(owner, extent, "spread over")
    return p


def _check_length(owner: str, length: float, what: str = "span a path of") -> None:
    if not MIN_LENGTH <= length <= MAX_LENGTH:
        guess = "millimetres?" if length > MAX_LENGTH else "kilometres? the robot is 0.33 m long"
        raise ValueError(
            f"{owner}.points {what} {length:.3g} m, outside [{MIN_LENGTH:g}, {MAX_LENGTH:g}] m; x, y must be in "
            f"metres ({guess})"
        )


def _smooth(p: Array, closed: bool, sigma: float, owner: str) -> tuple[Array, float]:
    # the smoothed points (module docstring) and their RMS distance from the group means [m]
    group = 1
    while np.median(np.hypot(*(p[group:] - p[:-group]).T)) < 3.0 * sigma:
        group *= 2
        if len(p) // group < 4:
            raise ValueError(
                f"{owner}.smoothing={sigma:g} m needs groups of {group} points to get 3 sigma apart, leaving "
                f"{len(p) // group} (at least 4); give the points' noise [m], a smaller value, or more points"
            )
    n = len(p) // group
    b = p[: n * group].reshape(n, group, 2).mean(axis=1)
    if len(p) > n * group:
        b = np.vstack((b, p[n * group :].mean(axis=0, keepdims=True)))
    target = sigma * math.sqrt(2.0 / group)  # RMS distance of the true path from the group means
    z = _whittaker(b, b, closed, target)
    z = _whittaker(b, z, closed, target)  # again in the chord parameter of the first result
    return z, float(np.sqrt(np.mean(np.sum((z - b) ** 2, axis=1))))


def _whittaker(b: Array, z: Array, closed: bool, target: float) -> Array:
    # the points minimising |z - b|^2 + lambda |D z|^2 (D: weighted second divided differences in the chord
    # parameter of z) at an RMS distance target [m] from b (or the largest lambda tried, if still closer)
    from scipy.optimize import brentq
    from scipy.sparse import csc_matrix, identity
    from scipy.sparse.linalg import splu

    n = len(b)
    h = np.hypot(*np.diff(np.vstack((z, z[:1])) if closed else z, axis=0).T)
    i = np.arange(n) if closed else np.arange(1, n - 1)
    hm, hp = h[i - 1], h[i % len(h)]
    w = np.sqrt(0.5 * (hm + hp)) * 2.0 / (hm + hp) * float(np.mean(h)) ** 1.5
    vals = w[:, None] * np.c_[1.0 / hm, -(1.0 / hm + 1.0 / hp), 1.0 / hp]
    cols = np.c_[(i - 1) % n, i, (i + 1) % n]
    d = csc_matrix((vals.ravel(), (np.repeat(np.arange(len(i)), 3), cols.ravel())), shape=(len(i), n))
    penalty, eye = (d.T @ d).tocsc(), identity(n, format="csc")

    def solve(log_lam: float) -> Array:
        return np.asarray(splu(eye + math.exp(log_lam) * penalty).solve(b), dtype=np.float64)

    def gap(log_lam: float) -> float:
        return float(np.sqrt(np.mean(np.sum((solve(log_lam) - b) ** 2, axis=1)))) - target

    return solve(30.0 if gap(30.0) <= 0.0 else float(brentq(gap, -20.0, 30.0, xtol=1e-2)))


def _chain(start: tuple[float, float, float], length: Array, k0: Array, rate: Array) -> tuple[Array, Array, Array]:
    # poses (m + 1,) at the ends of a chain of clothoid steps from start: each step at heading 0, rotated, summed
    x0, y0, th0 = start
    head = th0 + np.concatenate(([0.0], np.cumsum(length * (k0 + 0.5 * rate * length))))
    zero = np.zeros_like(length)
    dx, dy, _ = advance(zero, zero, zero, 1.0, 0.0, k0, rate, length)
    ch, sh = np.cos(head[:-1]), np.sin(head[:-1])
    x = x0 + np.concatenate(([0.0], np.cumsum(ch * dx - sh * dy)))
    y = y0 + np.concatenate(([0.0], np.cumsum(sh * dx + ch * dy)))
    return x, y, head


def _arc(spline: Any, a: Array, b: Array) -> Array:
    # arc length of the spline from parameter a to b (Gauss–Legendre, 8 nodes)
    w, mid = 0.5 * (b - a), 0.5 * (b + a)
    out = np.zeros_like(a)
    for xg, wg in zip(_GL_X.tolist(), _GL_W.tolist(), strict=True):
        d1 = spline(mid + w * xg, 1)
        out += wg * w * np.hypot(d1[:, 0], d1[:, 1])
    return out


def _curvature(spline: Any, u: Array) -> tuple[Array, Array, Array]:
    d1, d2 = spline(u, 1), spline(u, 2)
    sp = np.hypot(d1[:, 0], d1[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / sp**3
    return d1, sp, kappa


def fit_points(
    points: Any, closed: bool = False, *, smoothing: float | None = None, tolerance: float = 1e-3, step: float = 0.02,
    sample_spacing: float = 0.02,
) -> PointsFit:  # fmt: skip
    """Fit a continuous-curvature :class:`~amigo_gym.paths.ClothoidPath` to points (module docstring).

    ``points`` ``(n, 2)`` [m] in path order (a closed path may repeat its first point at the end); ``smoothing``
    None (through the points) or the points' noise ``sigma`` [m] in (0, 1]; ``tolerance`` [m] in [1e-9, 1]; the
    first ``step`` [m] in [1e-4, 10]; ``sample_spacing`` [m] of the path's coarse projection samples. ``ValueError``
    for bad points or arguments, a curvature above 1e4 1/m (a cusp), or ``tolerance`` not reached after
    :data:`MAX_REFINEMENTS` halvings of ``step``."""
    from scipy.interpolate import CubicSpline

    owner = "from_points"
    if not isinstance(closed, bool | np.bool_):
        raise ValueError(f"{owner}.closed must be True or False, got {show_value(closed)}")
    closed = bool(closed)
    tol = check_real(owner, "tolerance", tolerance, 1e-9, 1.0)
    h_max = check_real(owner, "step", step, 1e-4, 10.0)
    sigma = None if smoothing is None else check_real(owner, "smoothing", smoothing, 0.0, 1.0)
    if sigma == 0.0:
        raise ValueError(f"{owner}.smoothing must be in (0, 1] m or None, got 0")
    p = _check_points(points, closed, owner)
    p, smoothed = (p, 0.0) if sigma is None else _smooth(p, closed, sigma, owner)
    knots = np.vstack((p, p[:1])) if closed else p
    chord = np.hypot(np.diff(knots[:, 0]), np.diff(knots[:, 1]))
    t = np.concatenate(([0.0], np.cumsum(chord)))
    _check_length(owner, float(t[-1]))
    spline = CubicSpline(t, knots, bc_type="periodic" if closed else "not-a-knot")
    kk = np.abs(_curvature(spline, t)[2])
    turn_density = 1.5 * np.nan_to_num(np.maximum(kk[:-1], kk[1:]), nan=0.0) / MAX_STEP_TURN  # steps per metre
    for _ in range(MAX_REFINEMENTS + 1):
        # steps of at most h_max chord and MAX_STEP_TURN turn, laid along the parameter
        dens = np.concatenate(([0.0], np.cumsum(chord * np.maximum(1.0 / h_max, turn_density))))
        u = np.interp(np.linspace(0.0, dens[-1], max(1, math.ceil(dens[-1])) + 1), dens, t)
        u[0], u[-1] = t[0], t[-1]
        seg_len = _arc(spline, u[:-1], u[1:])
        d1, sp, kappa = _curvature(spline, u)
        if not (sp > 0.0).all():
            raise ValueError(f"{owner}: the spline through the points stops (a cusp); smooth or thin the points")
        if closed:
            kappa[-1] = kappa[0]  # periodic spline: equal to rounding; exactly equal for the joint
        kmax = float(np.max(np.abs(kappa)))
        if not kmax <= MAX_CURVATURE:
            raise ValueError(
                f"{owner}: the spline through the points has curvature {kmax:.3g} 1/m, above {MAX_CURVATURE:g} "
                "(a cusp or a kink in the data); smooth them (smoothing=) or thin them"
            )
        theta0 = math.atan2(float(d1[0, 1]), float(d1[0, 0]))
        start = (float(p[0, 0]), float(p[0, 1]), theta0)
        s_ends = np.concatenate(([0.0], np.cumsum(seg_len)))
        corr: tuple[float, ...] = ()
        if closed:
            kappa, corr = _close(start, seg_len, kappa, s_ends)
        rate = np.diff(kappa) / seg_len
        # each point at its own arc length on the chain of steps (numpy; the path's own pose agrees to rounding)
        j = np.clip(np.searchsorted(u, t[: len(p)], side="right") - 1, 0, len(seg_len) - 1)
        point_s = s_ends[j] + _arc(spline, u[j], t[: len(p)])
        cx, cy, ch = _chain(start, seg_len, kappa[:-1], rate)
        px, py, _ = advance(cx[j], cy[j], ch[j], 1.0, 0.0, kappa[j], rate[j], point_s - s_ends[j])
        err = float(np.max(np.hypot(px - p[:, 0], py - p[:, 1])))
        if err <= tol:
            segs = zip(seg_len.tolist(), kappa[:-1].tolist(), rate.tolist(), strict=True)
            path = ClothoidPath(tuple(ClothoidSegment(*g) for g in segs), start=(start[0], start[1]),
                                start_angle=theta0, closed=closed, sample_spacing=sample_spacing)  # fmt: skip
            return PointsFit(path, err, point_s, h_max, corr, smoothed)
        h_max = 0.5 * h_max
    raise ValueError(
        f"{owner}: the fitted path passes {err:.3g} m from a point, above tolerance={tol:g} m after "
        f"{MAX_REFINEMENTS} refinements; raise the tolerance or give denser points"
    )


def _close(
    start: tuple[float, float, float], seg_len: Array, kappa: Array, s_knots: Array
) -> tuple[Array, tuple[float, ...]]:
    # the curvature kappa + sum_q c_q mode_q(s) closing the path (Gauss–Newton, smallest step) and c
    length = float(s_knots[-1])
    om = TWO_PI * s_knots / length
    modes = np.stack((np.ones_like(om), np.cos(om), np.sin(om), np.cos(2.0 * om), np.sin(2.0 * om)))
    raw_turn = float(np.sum(seg_len * 0.5 * (kappa[:-1] + kappa[1:])))
    target = TWO_PI * round(raw_turn / TWO_PI)

    def gap(coef: Array) -> Array:
        k = kappa + coef @ modes
        x, y, th = _chain(start, seg_len, k[:-1], np.diff(k) / seg_len)
        return np.array((x[-1] - start[0], y[-1] - start[1], th[-1] - start[2] - target))

    nm = len(modes)
    coef: Array = np.zeros(nm)
    scale = max(1.0, length)
    g = gap(coef)
    for _ in range(12):
        if abs(g[0]) + abs(g[1]) <= 1e-12 * scale and abs(g[2]) <= 1e-12:
            break
        eps = 1e-6 / scale  # central differences along each mode
        jac = np.stack([(gap(coef + dc) - gap(coef - dc)) / (2.0 * eps) for dc in np.eye(nm) * eps], axis=1)
        coef = coef - np.linalg.pinv(jac) @ g  # the smallest correction (least squares over the modes)
        g = gap(coef)
    return kappa + coef @ modes, tuple(coef.tolist())


def from_points(
    points: Any, closed: bool = False, *, smoothing: float | None = None, tolerance: float = 1e-3, step: float = 0.02,
    sample_spacing: float = 0.02,
) -> ClothoidPath:  # fmt: skip
    """The path of :func:`fit_points` (examples: docs/amigobot_v1.md, "Paths of your own")."""
    fit = fit_points(points, closed, smoothing=smoothing, tolerance=tolerance, step=step, sample_spacing=sample_spacing)
    return fit.path


def _number(text: str, file: str, row: int, col: str) -> float:
    what = f"{file}: row {row}, column {col!r} must be"
    return finite_float(text, lambda inf: f"{what} {'finite' if inf else 'a number [m]'}, got {text!r}")


def load_points(file: str | os.PathLike[str]) -> tuple[Array, bool | None]:
    """The points ``(n, 2)`` [m] of a file, and the JSON's ``"closed"`` if given. JSON (``.json``):
    ``{"x": [...], "y": [...]}`` (optionally ``"closed": true``) or a list of ``{"x", "y"}`` objects; CSV (any
    other suffix): a header naming ``x`` and ``y`` (any case), one point per row, blank and ``#`` lines skipped.
    Raises ``FileNotFoundError`` (no such file) or ``ValueError`` (one line naming the file and the row or key)."""
    f = Path(file)
    name = str(f)
    if not f.is_file():
        raise FileNotFoundError(f"{name}: no such points file")
    if f.suffix.lower() == ".json":
        try:
            doc = json.loads(f.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"{name}: not valid JSON ({exc})") from None
        closed = doc.get("closed") if isinstance(doc, dict) else None
        if isinstance(doc, dict):
            if missing := [k for k in ("x", "y") if k not in doc]:
                raise ValueError(f"{name}: missing key(s) {missing}; expected {{'x': [...], 'y': [...]}}")
            xs, ys = doc["x"], doc["y"]
            if not isinstance(xs, list) or not isinstance(ys, list) or len(xs) != len(ys):
                raise ValueError(f"{name}: 'x' and 'y' must be lists of equal length")
            if "closed" in doc and not isinstance(closed, bool):
                raise ValueError(f"{name}: 'closed' must be true or false, got {closed!r}")
            rows = list(zip(xs, ys, strict=True))
        elif isinstance(doc, list):
            for i, item in enumerate(doc):
                if not isinstance(item, dict) or "x" not in item or "y" not in item:
                    raise ValueError(f"{name}: item {i} must be an object with 'x' and 'y', got {show_value(item)}")
            rows = [(item["x"], item["y"]) for item in doc]
        else:
            raise ValueError(f"{name}: expected {{'x': [...], 'y': [...]}} or a list of {{'x', 'y'}} objects")
        for i, (x, y) in enumerate(rows):
            for key, v in (("x", x), ("y", y)):
                if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
                    raise ValueError(f"{name}: point {i}, {key!r} must be a finite number [m], got {v!r}")
        return np.array(rows, dtype=np.float64).reshape(-1, 2), closed
    try:
        text = f.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{name}: not a text (UTF-8) CSV file") from None
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines()) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise ValueError(f"{name}: empty; expected a header with columns x, y and one point per row")
    table = list(csv.reader([ln for _, ln in lines]))
    header = [h.strip().lower() for h in table[0]]
    if missing := [k for k in ("x", "y") if k not in header]:
        raise ValueError(f"{name}: missing column(s) {missing} in the header {table[0]}; expected columns x, y [m]")
    ix, iy = header.index("x"), header.index("y")
    pts: list[tuple[float, float]] = []
    for (row_no, _), cells in zip(lines[1:], table[1:], strict=True):
        if len(cells) <= max(ix, iy):
            raise ValueError(f"{name}: row {row_no} has {len(cells)} cells, fewer than the header's columns")
        pts.append((_number(cells[ix], name, row_no, "x"), _number(cells[iy], name, row_no, "y")))
    return np.array(pts, dtype=np.float64).reshape(-1, 2), None


def from_file(
    file: str | os.PathLike[str], closed: bool | None = None, *, smoothing: float | None = None,
    tolerance: float = 1e-3, step: float = 0.02, sample_spacing: float = 0.02,
) -> ClothoidPath:  # fmt: skip
    """:func:`from_points` of the points of a CSV or JSON file (:func:`load_points`); ``closed`` None: the JSON's
    ``"closed"`` if given, else whether the last point repeats the first (to 1e-9 m). Raises ``ValueError`` (the
    file's or the fit's problem, one line naming the file)."""
    pts, use = load_points(file)
    if closed is not None:
        use = closed
    elif use is None:
        use = len(pts) > 2 and bool(np.hypot(*(pts[-1] - pts[0])) < MIN_CHORD)
    try:
        return from_points(pts, use, smoothing=smoothing, tolerance=tolerance, step=step, sample_spacing=sample_spacing)
    except ValueError as exc:
        raise ValueError(f"{file}: {exc}") from None


#: the suffixes of a points file (``path="points.csv"`` in ``gym.make``)
POINTS_SUFFIXES: tuple[str, ...] = (".csv", ".json")
#: most bytes the fitted paths of points files keep in memory (besides the newest)
CACHE_BYTES = 64 * 2**20
_FILE_CACHE: dict[tuple[str, int, int], tuple[ClothoidPath, int]] = {}


def is_points_file(name: str) -> bool:
    """Whether ``name`` (a ``path=`` string that is not a family) names a points file (:data:`POINTS_SUFFIXES`)."""
    return name.lower().endswith(POINTS_SUFFIXES)


def cached_file_path(file: str | os.PathLike[str]) -> ClothoidPath:
    """:func:`from_file` with default settings, built once per process per file version (resolved name,
    modification time, size); at most :data:`CACHE_BYTES` of paths kept (oldest dropped, the newest always)."""
    f = Path(file)
    try:
        st = f.resolve().stat()
    except OSError:
        raise FileNotFoundError(f"{file}: no such points file") from None
    key = (str(f.resolve()), st.st_mtime_ns, st.st_size)
    hit = _FILE_CACHE.pop(key, None)
    path = from_file(f) if hit is None else hit[0]
    size = 5 * path._t.flat.nbytes + 200 * len(path.segments)
    while _FILE_CACHE and size + sum(b for _, b in _FILE_CACHE.values()) > CACHE_BYTES:
        del _FILE_CACHE[next(iter(_FILE_CACHE))]
    _FILE_CACHE[key] = (path, size)
    return path
