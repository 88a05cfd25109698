r"""Paths from data: a :class:`~amigo_gym.paths.ClothoidPath` fitted to points, from arrays, CSV or JSON.

:func:`from_points` turns an ``(n, 2)`` array of points ``(x, y)`` [m], ordered along the path (optionally
closed), into a :class:`~amigo_gym.paths.ClothoidPath` with continuous curvature. Being a ``ClothoidPath`` it
runs everywhere a built-in family runs: the compiled step of the single and the vector ``AmigoBot-v1``, the
feasibility analysis, rendering, :class:`~amigo_gym.paths.PathBatch`.

Method (:func:`fit_points`):

1. **Interpolating cubic spline** ``(x(t), y(t))`` in the chord-length parameter ``t`` (``t_0 = 0``,
   ``t_{i+1} = t_i + |p_{i+1} - p_i|``): not-a-knot end conditions for an open path (a cubic through the
   points is reproduced exactly; three points give a parabola, two a line), periodic for a closed one. It is
   twice continuously differentiable, so its curvature
   ``kappa = (x' y'' - y' x'') / (x'^2 + y'^2)^{3/2}`` is continuous.
2. **Clothoid spline.** Every spline interval is cut into equal parameter steps of chord at most ``step``
   [m] (and a turn of at most 0.05 rad); each step becomes a :class:`~amigo_gym.paths.ClothoidSegment`
   whose length is the spline's arc length over the step (Gauss–Legendre, 8 nodes) and whose curvature runs
   linearly between the spline's curvatures at the step's ends. The path starts at ``p_0`` with the spline's
   tangent there. Curvature is continuous along the path (and across the joint of a closed path).
3. **Closure** (closed paths): the curvature is corrected by
   ``c_0 + c_1 cos(w s) + c_2 sin(w s) + c_3 cos(2 w s) + c_4 sin(2 w s)``, ``w = 2 pi / L``, with the
   smallest ``c`` (least squares) from Gauss–Newton on the end pose, so that the path ends at its start pose
   to rounding (:class:`~amigo_gym.paths.ClothoidPath` requires 1e-9). The correction is of the order of the
   discretisation error of step 2 (about 1e-5 relative to the curvature at the default ``step``); it keeps
   the curvature continuous across the joint.
4. **Error bound.** The distance of every input point ``p_i`` from the fitted path *at its own arc length*
   ``s_i`` (the path's arc length at the spline's knot ``t_i``), ``|c(s_i) - p_i|``, is computed; if its
   maximum exceeds ``tolerance`` (default 1 mm), ``step`` is halved and the fit repeated (at most
   :data:`MAX_REFINEMENTS` times), then a ``ValueError`` names the error reached. So a returned path passes
   within ``tolerance`` of every point (the closest-point distance is smaller still), and
   :attr:`PointsFit.max_error` is the measured bound.

Curvature between the points is the spline's: points sampled from a smooth curve give its curvature to the
spline's accuracy (``O(h^2)`` for a sample spacing ``h``); noisy points give a noisy curvature (smooth them
first). Points closer than 1e-9 m to their predecessor are refused, as are NaN, infinities, non-numbers and
wrong shapes, with one line naming the point.

Files (:func:`load_points`, :func:`from_file`): CSV with a header naming the columns ``x`` and ``y`` (metres;
other columns ignored); JSON as ``{"x": [...], "y": [...]}`` (optionally ``"closed": true``) or a list of
``{"x": ..., "y": ...}`` objects.

This module may import numpy, :mod:`amigo_gym.model.params`, :mod:`amigo_gym.model.fresnel`, :mod:`amigo_gym.io`,
the sibling path modules and the standard library's ``csv``, ``json`` and ``pathlib``.
"""

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
from amigo_gym.model.params import show_value
from amigo_gym.paths.clothoid import MAX_CURVATURE, TWO_PI, ClothoidPath, ClothoidSegment, check_real

__all__ = [
    "PointsFit",
    "fit_points",
    "from_points",
    "load_points",
    "from_file",
    "cached_file_path",
    "is_points_file",
    "MAX_REFINEMENTS",
]

Array = NDArray[np.float64]

#: how often ``step`` is halved before a fit that misses ``tolerance`` is refused
MAX_REFINEMENTS = 4
#: largest turn of one clothoid step [rad]
MAX_STEP_TURN = 0.05
#: smallest distance between consecutive points [m]
MIN_CHORD = 1e-9
#: most points accepted (the fit's cost is linear in them)
MAX_POINTS = 1_000_000
#: Gauss–Legendre nodes of the spline's arc length
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


@dataclass(frozen=True)
class PointsFit:
    """The result of :func:`fit_points`.

    Attributes:
        path: the fitted :class:`~amigo_gym.paths.ClothoidPath`.
        max_error: ``max_i |c(s_i) - p_i|`` [m]: the largest distance of an input point from the path at its
            own arc length (the bound the fit guarantees, ``<= tolerance``).
        point_s: ``(n,)`` arc length ``s_i`` of each input point along the path [m].
        step: the largest chord of a clothoid step used [m].
        closure_correction: ``(c_0, ..., c_4)`` [1/m] of the closed path's curvature correction (module
            docstring; empty if open).
    """

    path: ClothoidPath
    max_error: float
    point_s: Array
    step: float
    closure_correction: tuple[float, ...]


# --------------------------------------------------------------------------- input checks


def _check_points(points: Any, closed: bool, owner: str) -> Array:
    """``points`` as a float64 ``(n, 2)`` array of distinct consecutive finite points (one-line errors)."""
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
    bad = np.flatnonzero(~np.isfinite(p).all(axis=1))
    if bad.size:
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
    dup = np.flatnonzero(chord < MIN_CHORD)
    if dup.size:
        i = int(dup[0]) + 1
        raise ValueError(f"{owner}.points[{i}] repeats points[{i - 1}] ({p[i].tolist()}): points must be distinct")
    return p


# --------------------------------------------------------------------------- cubic splines


def _tridiagonal(a: Array, b: Array, c: Array, r: Array) -> Array:
    """Solve ``a_i z_{i-1} + b_i z_i + c_i z_{i+1} = r_i`` (Thomas' algorithm; ``a_0``, ``c_{-1}`` unused).

    ``r`` may have a trailing axis of right-hand sides. The systems here are diagonally dominant (spline
    moments), so no pivoting is needed.
    """
    n = len(b)
    cp = np.empty(n)
    rp = np.empty_like(r)
    cp[0] = c[0] / b[0]
    rp[0] = r[0] / b[0]
    for i in range(1, n):
        den = b[i] - a[i] * cp[i - 1]
        cp[i] = c[i] / den
        rp[i] = (r[i] - a[i] * rp[i - 1]) / den
    z = np.empty_like(r)
    z[-1] = rp[-1]
    for i in range(n - 2, -1, -1):
        z[i] = rp[i] - cp[i] * z[i + 1]
    return z


def _cyclic_tridiagonal(a: Array, b: Array, c: Array, r: Array) -> Array:
    """:func:`_tridiagonal` with the corner entries ``a_0`` (row 0, column n-1) and ``c_{n-1}`` (row n-1,
    column 0): the Sherman–Morrison formula on two tridiagonal solves."""
    n = len(b)
    gamma = -b[0]
    bb = b.copy()
    bb[0] = b[0] - gamma
    bb[-1] = b[-1] - a[0] * c[-1] / gamma
    u = np.zeros(n)
    u[0] = gamma
    u[-1] = c[-1]
    y = _tridiagonal(a, bb, c, r)
    q = _tridiagonal(a, bb, c, u)
    v0, v1 = 1.0, a[0] / gamma
    fac = (v0 * y[0] + v1 * y[-1]) / (1.0 + v0 * q[0] + v1 * q[-1])
    out: Array = y - np.multiply.outer(q, fac) if y.ndim > 1 else y - fac * q
    return out


def _moments(t: Array, v: Array, closed: bool) -> Array:
    r"""Second derivatives ``M_i`` of the interpolating cubic spline of ``v`` ``(m, 2)`` at knots ``t`` ``(m,)``.

    Interior rows: ``h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = 6 (d_i - d_{i-1})`` with
    ``h_i = t_{i+1} - t_i`` and ``d_i = (v_{i+1} - v_i) / h_i``. Closed: the same on every knot, cyclically
    (``t``, ``v`` then include the first point again at the end). Open: not-a-knot (the third derivative is
    continuous at ``t_1`` and ``t_{m-2}``), eliminated into the first and last interior rows.
    """
    h = np.diff(t)
    d = np.diff(v, axis=0) / h[:, None]
    if closed:
        hm = np.roll(h, 1)  # h_{i-1}
        rhs = 6.0 * (d - np.roll(d, 1, axis=0))
        mom = _cyclic_tridiagonal(hm.copy(), 2.0 * (hm + h), h.copy(), rhs)
        return np.vstack((mom, mom[:1]))
    m = len(t)
    if m == 2:
        return np.zeros_like(v)
    if m == 3:  # a parabola: one constant second derivative
        mm = 6.0 * (d[1] - d[0]) / (3.0 * (h[0] + h[1]))
        return np.tile(mm, (3, 1))
    hm, hi = h[:-1], h[1:]
    a = hm.copy()
    b = 2.0 * (hm + hi)
    c = hi.copy()
    rhs = 6.0 * (d[1:] - d[:-1])
    h0, h1 = h[0], h[1]
    b[0] += h0 * (h0 + h1) / h1
    c[0] -= h0 * h0 / h1
    g0, g1 = h[-1], h[-2]  # last and second-to-last intervals
    b[-1] += g0 * (g0 + g1) / g1
    a[-1] -= g0 * g0 / g1
    inner = _tridiagonal(a, b, c, rhs)
    first = ((h0 + h1) * inner[0] - h0 * inner[1]) / h1
    last = ((g0 + g1) * inner[-1] - g0 * inner[-2]) / g1
    return np.vstack((first, inner, last))


def _spline_derivatives(t: Array, v: Array, mom: Array, i: NDArray[np.integer[Any]], tau: Array) -> tuple[Array, Array]:
    """First and second derivatives ``(k, 2)`` of the spline at ``t_i + tau`` (``0 <= tau <= h_i``)."""
    h = (t[i + 1] - t[i])[:, None]
    m0, m1 = mom[i], mom[i + 1]
    tt = tau[:, None]
    d1 = (v[i + 1] - v[i]) / h - h * (2.0 * m0 + m1) / 6.0 + m0 * tt + (m1 - m0) * tt * tt / (2.0 * h)
    d2 = m0 + (m1 - m0) * tt / h
    return d1, d2


# --------------------------------------------------------------------------- the fit


def _end_pose(start: tuple[float, float, float], length: Array, k0: Array, rate: Array) -> tuple[float, float, float]:
    """End pose of the chain of clothoid steps (vectorised: each step's displacement at heading 0, rotated)."""
    x0, y0, th0 = start
    turn = length * (k0 + 0.5 * rate * length)
    head = th0 + np.concatenate(([0.0], np.cumsum(turn)[:-1]))
    dx, dy, _ = advance(np.zeros_like(length), np.zeros_like(length), np.zeros_like(length), 1.0, 0.0, k0, rate, length)
    ch, sh = np.cos(head), np.sin(head)
    x = x0 + float(np.sum(ch * dx - sh * dy))
    y = y0 + float(np.sum(sh * dx + ch * dy))
    return x, y, th0 + float(np.sum(turn))


def _segments(length: Array, kappa: Array) -> tuple[ClothoidSegment, ...]:
    rate = np.diff(kappa) / length
    return tuple(
        ClothoidSegment(ln, k, r) for ln, k, r in zip(length.tolist(), kappa[:-1].tolist(), rate.tolist(), strict=True)
    )


def fit_points(
    points: Any,
    closed: bool = False,
    *,
    tolerance: float = 1e-3,
    step: float = 0.02,
    sample_spacing: float = 0.02,
) -> PointsFit:
    """Fit a continuous-curvature :class:`~amigo_gym.paths.ClothoidPath` to points (method: module docstring).

    Args:
        points: ``(n, 2)`` x, y [m] in path order; a closed path may repeat its first point at the end.
        closed: the path is a loop from the last point back to the first (traversed in laps).
        tolerance: largest distance of an input point from the path at its own arc length [m], in [1e-9, 1].
        step: largest chord of a clothoid step [m] to start with, in [1e-4, 10] (halved while the error
            exceeds ``tolerance``).
        sample_spacing: the path's coarse projection samples [m] (:class:`~amigo_gym.paths.ClothoidPath`).

    Raises:
        ValueError: bad points or arguments (one line naming them), a curvature above 1e4 1/m (a cusp in
            the data), or ``tolerance`` not reached after :data:`MAX_REFINEMENTS` halvings of ``step``.
    """
    owner = "from_points"
    if not isinstance(closed, bool | np.bool_):
        raise ValueError(f"{owner}.closed must be True or False, got {show_value(closed)}")
    closed = bool(closed)
    tol = check_real(owner, "tolerance", tolerance, 1e-9, 1.0)
    h_max = check_real(owner, "step", step, 1e-4, 10.0)
    p = _check_points(points, closed, owner)
    knots = np.vstack((p, p[:1])) if closed else p
    chord = np.hypot(np.diff(knots[:, 0]), np.diff(knots[:, 1]))
    t = np.concatenate(([0.0], np.cumsum(chord)))
    mom = _moments(t, knots, closed)
    # the spline's turn per interval bounds the number of steps too (a step turns by at most MAX_STEP_TURN)
    d1k, d2k = _spline_derivatives(t, knots, mom, np.arange(len(chord)), np.zeros(len(chord)))
    speed_k = np.hypot(d1k[:, 0], d1k[:, 1])
    kappa_k = np.abs(d1k[:, 0] * d2k[:, 1] - d1k[:, 1] * d2k[:, 0]) / speed_k**3
    last_error = math.inf
    for _ in range(MAX_REFINEMENTS + 1):
        want = np.ceil(np.maximum(chord / h_max, kappa_k * chord * 1.5 / MAX_STEP_TURN))
        n_sub = np.minimum(np.maximum(2, want), 10_000).astype(np.int64)
        # step k: interval idx[k], parameter offsets [tau0, tau1]
        idx = np.repeat(np.arange(len(chord)), n_sub)
        first = np.concatenate(([0], np.cumsum(n_sub)[:-1]))
        j = np.arange(len(idx)) - np.repeat(first, n_sub)
        hs = (chord / n_sub)[idx]
        tau0 = j * hs
        tau1 = np.where(j == n_sub[idx] - 1, chord[idx], (j + 1) * hs)
        # arc length of each step: Gauss-Legendre of the spline's speed
        w = 0.5 * (tau1 - tau0)
        mid = 0.5 * (tau1 + tau0)
        seg_len = np.zeros(len(idx))
        for xg, wg in zip(_GL_X.tolist(), _GL_W.tolist(), strict=True):
            d1, _ = _spline_derivatives(t, knots, mom, idx, mid + w * xg)
            seg_len += wg * w * np.hypot(d1[:, 0], d1[:, 1])
        # curvature at the step ends (the last end: the end of the last interval)
        ends_i = np.concatenate((idx, idx[-1:]))
        ends_tau = np.concatenate((tau0, tau1[-1:]))
        d1, d2 = _spline_derivatives(t, knots, mom, ends_i, ends_tau)
        sp = np.hypot(d1[:, 0], d1[:, 1])
        if not (sp > 0.0).all():
            raise ValueError(f"{owner}: the spline through the points stops (a cusp); smooth or thin the points")
        kappa = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / sp**3
        if closed:
            kappa[-1] = kappa[0]  # periodic spline: equal to rounding; exactly equal for the joint
        kmax = float(np.max(np.abs(kappa)))
        if not kmax <= MAX_CURVATURE:
            raise ValueError(
                f"{owner}: the spline through the points has curvature {kmax:.3g} 1/m, above {MAX_CURVATURE:g} "
                "(a cusp or a kink in the data); smooth or thin the points"
            )
        theta0 = math.atan2(float(d1[0, 1]), float(d1[0, 0]))
        start = (float(p[0, 0]), float(p[0, 1]), theta0)
        s_knots = np.concatenate(([0.0], np.cumsum(seg_len)))
        corr: tuple[float, ...] = ()
        if closed:
            kappa, corr = _close(start, seg_len, kappa, s_knots)
        path = ClothoidPath(
            _segments(seg_len, kappa),
            start=(start[0], start[1]),
            start_angle=theta0,
            closed=closed,
            sample_spacing=sample_spacing,
        )
        point_s = s_knots[np.concatenate(([0], np.cumsum(n_sub)))][: len(p)]
        pose = path.pose_columns(point_s)
        err = float(np.max(np.hypot(np.asarray(pose.x) - p[:, 0], np.asarray(pose.y) - p[:, 1])))
        if err <= tol:
            return PointsFit(path, err, point_s, h_max, corr)
        last_error = err
        h_max = 0.5 * h_max
    raise ValueError(
        f"{owner}: the fitted path passes {last_error:.3g} m from a point, above tolerance={tol:g} m after "
        f"{MAX_REFINEMENTS} refinements; raise the tolerance or give denser points"
    )


def _close(
    start: tuple[float, float, float], seg_len: Array, kappa: Array, s_knots: Array
) -> tuple[Array, tuple[float, ...]]:
    """The curvature ``kappa + sum_q c_q mode_q(s)`` closing the path (module docstring: Gauss–Newton with the
    smallest step on the end pose's gap, finite-difference Jacobian), and ``c``."""
    length = float(s_knots[-1])
    om = TWO_PI * s_knots / length
    modes = np.stack((np.ones_like(om), np.cos(om), np.sin(om), np.cos(2.0 * om), np.sin(2.0 * om)))
    raw_turn = float(np.sum(seg_len * 0.5 * (kappa[:-1] + kappa[1:])))
    target = TWO_PI * round(raw_turn / TWO_PI)

    def gap(coef: Array) -> Array:
        k = kappa + coef @ modes
        x, y, th = _end_pose(start, seg_len, k[:-1], np.diff(k) / seg_len)
        return np.array((x - start[0], y - start[1], th - start[2] - target))

    nm = len(modes)
    coef = np.zeros(nm)
    scale = max(1.0, length)
    g = gap(coef)
    for _ in range(12):
        if abs(g[0]) + abs(g[1]) <= 1e-12 * scale and abs(g[2]) <= 1e-12:
            break
        jac = np.empty((3, nm))
        eps = 1e-6 / scale
        for q in range(nm):
            dc = np.zeros(nm)
            dc[q] = eps
            jac[:, q] = (gap(coef + dc) - gap(coef - dc)) / (2.0 * eps)
        coef = coef - np.linalg.pinv(jac) @ g  # the smallest correction (least squares over the modes)
        g = gap(coef)
    k = kappa + coef @ modes
    return k, tuple(coef.tolist())


def from_points(
    points: Any,
    closed: bool = False,
    *,
    tolerance: float = 1e-3,
    step: float = 0.02,
    sample_spacing: float = 0.02,
) -> ClothoidPath:
    """A path ``AmigoBot-v1`` accepts, fitted with continuous curvature to points ``(n, 2)`` [m] (:func:`fit_points`).

    ```python
    import numpy as np, gymnasium as gym, amigo_gym
    from amigo_gym.paths import from_points

    s = np.linspace(0.0, 2.0 * np.pi, 60, endpoint=False)
    path = from_points(np.c_[np.cos(s), np.sin(s)], closed=True)
    env = gym.make("AmigoBot-v1", path=path)
    ```
    """
    return fit_points(points, closed, tolerance=tolerance, step=step, sample_spacing=sample_spacing).path


# --------------------------------------------------------------------------- files


def _number(text: str, file: str, row: int, col: str) -> float:
    what = f"{file}: row {row}, column {col!r} must be"
    return finite_float(text, lambda inf: f"{what} {'finite' if inf else 'a number [m]'}, got {text!r}")


def load_points(file: str | os.PathLike[str]) -> tuple[Array, bool | None]:
    """The points ``(n, 2)`` [m] of a CSV or JSON file (module docstring), and the JSON's ``"closed"`` if given.

    CSV (any other suffix than ``.json``): a header row naming ``x`` and ``y`` (case-insensitive, other columns
    ignored), then one point per row; blank lines and lines starting with ``#`` are skipped.

    Raises:
        FileNotFoundError: no such file.
        ValueError: one line naming the file and the row or key that is wrong.
    """
    f = Path(file)
    name = str(f)
    if not f.is_file():
        raise FileNotFoundError(f"{name}: no such points file")
    if f.suffix.lower() == ".json":
        try:
            doc = json.loads(f.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise ValueError(f"{name}: not valid JSON ({exc})") from None
        closed: bool | None = None
        if isinstance(doc, dict):
            missing = [k for k in ("x", "y") if k not in doc]
            if missing:
                raise ValueError(f"{name}: missing key(s) {missing}; expected {{'x': [...], 'y': [...]}}")
            xs, ys = doc["x"], doc["y"]
            if not isinstance(xs, list) or not isinstance(ys, list) or len(xs) != len(ys):
                raise ValueError(f"{name}: 'x' and 'y' must be lists of equal length")
            if "closed" in doc:
                if not isinstance(doc["closed"], bool):
                    raise ValueError(f"{name}: 'closed' must be true or false, got {doc['closed']!r}")
                closed = doc["closed"]
            rows = list(zip(xs, ys, strict=True))
        elif isinstance(doc, list):
            rows = []
            for i, item in enumerate(doc):
                if not isinstance(item, dict) or "x" not in item or "y" not in item:
                    raise ValueError(f"{name}: item {i} must be an object with 'x' and 'y', got {show_value(item)}")
                rows.append((item["x"], item["y"]))
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
    reader = csv.reader([ln for _, ln in lines])
    table = list(reader)
    header = [h.strip().lower() for h in table[0]]
    missing = [k for k in ("x", "y") if k not in header]
    if missing:
        raise ValueError(f"{name}: missing column(s) {missing} in the header {table[0]}; expected columns x, y [m]")
    ix, iy = header.index("x"), header.index("y")
    pts: list[tuple[float, float]] = []
    for (row_no, _), cells in zip(lines[1:], table[1:], strict=True):
        if len(cells) <= max(ix, iy):
            raise ValueError(f"{name}: row {row_no} has {len(cells)} cells, fewer than the header's columns")
        pts.append((_number(cells[ix], name, row_no, "x"), _number(cells[iy], name, row_no, "y")))
    return np.array(pts, dtype=np.float64).reshape(-1, 2), None


def from_file(
    file: str | os.PathLike[str],
    closed: bool | None = None,
    *,
    tolerance: float = 1e-3,
    step: float = 0.02,
    sample_spacing: float = 0.02,
) -> ClothoidPath:
    """:func:`from_points` of the points of a CSV or JSON file (:func:`load_points`).

    Args:
        closed: None: the JSON's ``"closed"`` if it has one, else closed when the last point repeats the first
            (to 1e-9 m), else open.

    Raises:
        ValueError: the file's or the fit's problem, one line naming the file.
    """
    pts, file_closed = load_points(file)
    if closed is None:
        repeats = len(pts) > 2 and bool(np.hypot(*(pts[-1] - pts[0])) < MIN_CHORD)
        use = repeats if file_closed is None else file_closed
    else:
        use = closed
    try:
        return from_points(pts, use, tolerance=tolerance, step=step, sample_spacing=sample_spacing)
    except ValueError as exc:
        raise ValueError(f"{file}: {exc}") from None


#: the suffixes of a points file (``path="points.csv"`` in ``gym.make``)
POINTS_SUFFIXES: tuple[str, ...] = (".csv", ".json")
_FILE_CACHE: dict[tuple[str, int, int], ClothoidPath] = {}


def is_points_file(name: str) -> bool:
    """Whether ``name`` (a ``path=`` string that is not a family) names a points file (:data:`POINTS_SUFFIXES`)."""
    return name.lower().endswith(POINTS_SUFFIXES)


def cached_file_path(file: str | os.PathLike[str]) -> ClothoidPath:
    """:func:`from_file` with the default settings, built once per process for each file version (resolved
    name, modification time and size): ``gym.make("AmigoBot-v1", path="points.csv")`` and every vector env
    of a benchmark share one fitted path."""
    f = Path(file)
    try:
        st = f.resolve().stat()
    except OSError:
        raise FileNotFoundError(f"{file}: no such points file") from None
    key = (str(f.resolve()), st.st_mtime_ns, st.st_size)
    path = _FILE_CACHE.get(key)
    if path is None:
        path = from_file(f)
        if len(_FILE_CACHE) >= 64:
            _FILE_CACHE.clear()
        _FILE_CACHE[key] = path
    return path
