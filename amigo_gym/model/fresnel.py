r"""The one integral behind every curve of AmigoBot-v1: motion with speed and turn rate linear in time.

A body moving with speed ``v(t) = v0 + a t`` along its heading and turn rate ``w(t) = w0 + alpha t``
has the heading ``theta(t) = theta0 + w0 t + alpha t^2 / 2`` (exact, a quadratic) and the position

.. math::
    \mathbf{p}(T) = \mathbf{p}_0 + \int_0^T (v_0 + a t)
        \begin{pmatrix}\cos\theta(t)\\ \sin\theta(t)\end{pmatrix} dt,

a generalised Fresnel integral. Two things in this package are such motions:

* the robot's point A within a control step when the firmware ramps its speeds (:mod:`amigo_gym.model.actuators`):
  ``v``, ``w`` are piecewise linear in time, and each linear piece is one call;
* a clothoid path segment (:mod:`amigo_gym.paths`): arc length plays the time, ``v = 1``, ``a = 0``,
  and the curvature ``kappa0 + c s`` the turn rate.

Evaluation: Gauss–Legendre quadrature with :data:`NODES` nodes on each of ``n_sub`` equal
sub-intervals. The integrand is entire; on a sub-interval over which the phase ``theta`` varies by
at most :data:`MAX_PHASE_PER_SUB` radians the quadrature error bound,
``|E| <= h^{2n+1} (n!)^4 / ((2n+1) ((2n)!)^3) max|f^{(2n)}|``, is below 1e-20 relative to ``|v| h``,
so the result is exact to rounding (about 1e-16 relative; measured against mpmath at 50 digits in
``tests/test_fresnel.py``). The closed forms via Fresnel integrals lose digits when the curvature
rate is small (the difference of two nearly equal Fresnel values); the quadrature has no such
branch: lines (``w0 = alpha = 0``), arcs (``alpha = 0``) and clothoids are the same code.
Callers choose ``n_sub`` with :func:`subintervals` from a bound of the phase change they can meet.

Every function takes columns (floats, or float64 arrays that broadcast together) and returns the
same kind, so one robot and a batch run the same code.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.kinematics import Real

__all__ = [
    "NODES",
    "MAX_PHASE_PER_SUB",
    "subintervals",
    "advance",
    "advance_float",
    "advance_chain_float",
    "unit_speed_pose",
]

#: Gauss–Legendre nodes per sub-interval
NODES = 10
#: largest phase change [rad] on one sub-interval for which the quadrature is exact to rounding
MAX_PHASE_PER_SUB = 2.0

_X, _W = np.polynomial.legendre.leggauss(NODES)
#: nodes on [0, 1] and their weights (summing to 1)
_U: NDArray[np.float64] = 0.5 * (_X + 1.0)
_UW: NDArray[np.float64] = 0.5 * _W
_U_LIST: list[float] = _U.tolist()
_UW_LIST: list[float] = _UW.tolist()
#: nodes and weights on [0, 1] for ``n_sub`` sub-intervals (lists, built once per ``n_sub``)
_NODE_CACHE: dict[int, tuple[list[float], list[float]]] = {1: (_U_LIST, _UW_LIST)}

_np_array = np.array
_np_cos = np.cos
_np_sin = np.sin


def subintervals(max_phase_change: float) -> int:
    """Number of sub-intervals so that the phase varies by at most :data:`MAX_PHASE_PER_SUB` on each.

    Args:
        max_phase_change: a bound of ``|w0| T + |alpha| T^2 / 2`` over the calls to come [rad].
    """
    if not math.isfinite(max_phase_change) or max_phase_change < 0:
        raise ValueError(f"max_phase_change must be a finite number >= 0, got {max_phase_change!r}")
    return max(1, math.ceil(max_phase_change / MAX_PHASE_PER_SUB))


def advance(
    x: Real, y: Real, theta: Real, v0: Real, a: Real, w0: Real, alpha: Real, t: Real, n_sub: int = 1
) -> tuple[Real, Real, Real]:
    r"""Pose after time ``t`` with speed ``v0 + a tau`` and turn rate ``w0 + alpha tau`` (``0 <= tau <= t``).

    .. math::
        \theta' = \theta + w_0 t + \tfrac12 \alpha t^2, \qquad
        (x', y') = (x, y) + \int_0^t (v_0 + a\tau)\,(\cos, \sin)(\theta + w_0\tau + \tfrac12\alpha\tau^2)\,d\tau

    evaluated by Gauss–Legendre quadrature (module docstring); ``t = 0`` returns the pose unchanged.

    Args:
        x, y, theta: start pose [m, m, rad].
        v0, a: speed at the start [m/s] and its rate of change [m/s^2].
        w0, alpha: turn rate at the start [rad/s] and its rate of change [rad/s^2].
        t: duration [s], >= 0 (not checked: callers pass piece lengths they computed).
        n_sub: number of equal sub-intervals (:func:`subintervals`).

    Returns:
        ``(x', y', theta')``, columns of the broadcast shape of the inputs.
    """
    if not isinstance(t, np.ndarray) and not _any_array(x, y, theta, v0, a, w0, alpha):
        return advance_float(x, y, theta, v0, a, w0, alpha, t, n_sub)  # type: ignore[arg-type]
    u, uw = _nodes(n_sub)
    # all nodes at once: arrays of shape (nodes, *shape), the same expressions element by element; then the
    # sums node by node in a fixed order, so that a float and an array element get the same bits
    nd = max(np.ndim(c) for c in (x, y, theta, v0, a, w0, alpha, t))
    col = (len(u),) + (1,) * nd
    u_col = np.asarray(u).reshape(col)
    half_alpha = 0.5 * alpha
    tau = u_col * t
    phase = theta + tau * (w0 + half_alpha * tau)
    weight = (v0 + a * tau) * np.asarray(uw).reshape(col)
    px = weight * np.cos(phase)
    py = weight * np.sin(phase)
    dx = 0.0 + px[0]
    dy = 0.0 + py[0]
    for k in range(1, len(u)):
        dx = dx + px[k]
        dy = dy + py[k]
    return x + dx * t, y + dy * t, theta + t * (w0 + half_alpha * t)


def _any_array(*cols: object) -> bool:
    for c in cols:  # noqa: SIM110  (a loop: a third of the time of any() over a generator)
        if isinstance(c, np.ndarray):
            return True
    return False


def _nodes(n_sub: int) -> tuple[list[float], list[float]]:
    """Nodes and weights on [0, 1] for ``n_sub`` equal sub-intervals (cached lists)."""
    got = _NODE_CACHE.get(n_sub)
    if got is None:
        u = [(k + ui) / n_sub for k in range(n_sub) for ui in _U_LIST]
        uw = [wi / n_sub for _ in range(n_sub) for wi in _UW_LIST]
        got = (u, uw)
        if len(_NODE_CACHE) < 64:
            _NODE_CACHE[n_sub] = got
    return got


def advance_float(
    x: float, y: float, theta: float, v0: float, a: float, w0: float, alpha: float, t: float, n_sub: int = 1
) -> tuple[float, float, float]:
    """:func:`advance` for Python floats: the same bits, computed faster.

    The same expressions node by node (Python floats round each operation as numpy does), the node phases'
    cosines and sines from one ``np.cos`` and one ``np.sin`` call on an array (numpy gives each element the
    bits it gives a scalar), and the sums in the same order.
    """
    u, uw = _nodes(n_sub)
    half_alpha = 0.5 * alpha
    taus = [ui * t for ui in u]
    phases = _np_array([theta + tau * (w0 + half_alpha * tau) for tau in taus])
    cs = _np_cos(phases).tolist()
    sn = _np_sin(phases).tolist()
    dx = 0.0
    dy = 0.0
    for tau, wi, ci, si in zip(taus, uw, cs, sn, strict=True):
        weight = (v0 + a * tau) * wi
        dx = dx + weight * ci
        dy = dy + weight * si
    return x + dx * t, y + dy * t, theta + t * (w0 + half_alpha * t)


def unit_speed_pose(
    x: float, y: float, theta: float, w0: float, alpha: float, t: float
) -> tuple[float, float, float, float, float]:
    """``advance(x, y, theta, 1.0, 0.0, w0, alpha, t, 1)`` for Python floats (a path piece: arc length as time),
    with ``cos`` and ``sin`` of the new heading: ``(x', y', theta', cos theta', sin theta')``, the same bits as
    :func:`advance` and ``np.cos``/``np.sin`` of ``theta'`` (one ``np.cos`` and one ``np.sin`` call for all).

    With unit speed the weights ``(1 + 0 tau) w_i`` are exactly ``w_i``.
    """
    half_alpha = 0.5 * alpha
    taus = [ui * t for ui in _U_LIST]
    th = theta + t * (w0 + half_alpha * t)
    phases = [theta + tau * (w0 + half_alpha * tau) for tau in taus]
    phases.append(th)
    arr = _np_array(phases)
    cs = _np_cos(arr).tolist()
    sn = _np_sin(arr).tolist()
    dx = 0.0
    dy = 0.0
    for i in range(NODES):
        wi = _UW_LIST[i]
        dx = dx + wi * cs[i]
        dy = dy + wi * sn[i]
    return x + dx * t, y + dy * t, th, cs[NODES], sn[NODES]


def advance_chain_float(
    x: float, y: float, theta: float, pieces: list[tuple[float, float, float, float, float]], n_sub: int = 1
) -> tuple[float, float, float]:
    """:func:`advance` applied piece after piece, for Python floats: the same bits, one ``np.cos`` and one
    ``np.sin`` call for the nodes of all pieces.

    Args:
        x, y, theta: start pose [m, m, rad].
        pieces: ``(v0, a, w0, alpha, t)`` of each piece, in order (as :func:`advance`'s arguments).
        n_sub: sub-intervals per piece.

    Returns:
        the pose after the last piece (the start pose for no pieces).
    """
    if not pieces:
        return x, y, theta
    u, uw = _nodes(n_sub)
    # the heading at the start of each piece only needs the headings before (closed form), so all node
    # phases are known before any cosine
    phases: list[float] = []
    taus: list[list[float]] = []
    th = theta
    for _v0, _a, w0, alpha, t in pieces:
        half_alpha = 0.5 * alpha
        tj = [ui * t for ui in u]
        taus.append(tj)
        phases += [th + tau * (w0 + half_alpha * tau) for tau in tj]
        th = th + t * (w0 + half_alpha * t)
    arr = _np_array(phases)
    cs = _np_cos(arr).tolist()
    sn = _np_sin(arr).tolist()
    i = 0
    for (v0, a, _w0, _alpha, t), tj in zip(pieces, taus, strict=True):
        dx = 0.0
        dy = 0.0
        for tau, wi in zip(tj, uw, strict=True):
            weight = (v0 + a * tau) * wi
            dx = dx + weight * cs[i]
            dy = dy + weight * sn[i]
            i += 1
        x = x + dx * t
        y = y + dy * t
    return x, y, th


def unit_speed_poses(
    starts: list[tuple[float, float, float, float, float, float]],
) -> list[tuple[float, float, float, float, float]]:
    """:func:`unit_speed_pose` of several independent ``(x, y, theta, w0, alpha, t)``, with one ``np.cos`` and one
    ``np.sin`` call for all (the same bits as one call each)."""
    phases: list[float] = []
    ends: list[float] = []
    for _x, _y, theta, w0, alpha, t in starts:
        half_alpha = 0.5 * alpha
        phases += [theta + tau * (w0 + half_alpha * tau) for tau in [ui * t for ui in _U_LIST]]
        th = theta + t * (w0 + half_alpha * t)
        phases.append(th)
        ends.append(th)
    arr = _np_array(phases)
    cs = _np_cos(arr).tolist()
    sn = _np_sin(arr).tolist()
    out: list[tuple[float, float, float, float, float]] = []
    base = 0
    for (x, y, _theta, _w0, _alpha, t), th in zip(starts, ends, strict=True):
        dx = 0.0
        dy = 0.0
        for i in range(NODES):
            wi = _UW_LIST[i]
            dx = dx + wi * cs[base + i]
            dy = dy + wi * sn[base + i]
        out.append((x + dx * t, y + dy * t, th, cs[base + NODES], sn[base + NODES]))
        base += NODES + 1
    return out
