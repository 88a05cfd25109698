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
same kind, so one robot and a batch run the same code; the node functions (:func:`advance_nodes`,
:func:`unit_speed_nodes` and their parts) are the float path's loops on buffers, which AmigoBot-v1's compiled
step compiles as they are.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.kinematics import Real

__all__ = [
    "NODES",
    "MAX_PHASE_PER_SUB",
    "subintervals",
    "subinterval_count",
    "advance",
    "advance_chain_float",
    "unit_speed_pose",
    "unit_speed_poses",
    "Buffer",
    "cos_sin_nodes",
    "node_phases",
    "node_sums",
    "advance_nodes",
    "unit_speed_phases",
    "unit_speed_sums",
    "unit_speed_nodes",
    "node_table",
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
#: :func:`node_table` for one sub-interval (a path piece's quadrature), and the cache of the others
_TABLE_1: list[float] = _U_LIST + _UW_LIST
_TABLE_CACHE: dict[int, list[float]] = {1: _TABLE_1}

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
    return subinterval_count(max_phase_change)


def subinterval_count(max_phase_change: float) -> int:
    """:func:`subintervals` of a finite ``max_phase_change >= 0`` [rad], unchecked (in numba's subset: the compiled
    path builders call it, :func:`amigo_gym.paths.families.run_segments`)."""
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

    One source for floats, columns and the compiled step: :func:`advance_nodes` of one piece on a node buffer (a list
    whose entries are floats, or columns of the broadcast shape).
    """
    table = node_table(n_sub)
    m = NODES * n_sub
    buf: list[Any] = [0.0] * (3 * m)
    pieces: list[Any] = [v0, a, w0, alpha, t]
    out: tuple[Real, Real, Real] = advance_nodes(buf, 0, m, x, y, theta, pieces, 0, 1, table, 0, m)  # type: ignore[arg-type]
    return out


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


# -- the node sums of the float path and the compiled step, written once ------------------------------------
#
# Plain Python on buffers (``list`` of floats in the float path, where indexing is cheapest; float64 arrays in the
# compiled step of AmigoBot-v1, which compiles these functions as they are: amigo_gym.sim._kernels_v1). Their
# expressions and order of operations are :func:`advance`'s. A node buffer ``buf`` of stride ``m`` from ``buf[b]``
# holds the phases in ``buf[b : b + m]``, their cosines in ``buf[b + m : b + 2m]`` and sines in
# ``buf[b + 2m : b + 3m]``.


class Buffer(Protocol):
    """What the node functions index: a ``list`` of floats (float path) or a float64 array (compiled step)."""

    def __getitem__(self, i: int, /) -> float: ...
    def __setitem__(self, i: int, v: float, /) -> None: ...
    def __len__(self) -> int: ...


def cos_sin_nodes(buf: Buffer, b: int, n: int, m: int) -> None:
    """``buf[b + m + i] = cos(buf[b + i])``, ``buf[b + 2 m + i] = sin(buf[b + i])`` for ``i < n``: numpy's
    ``np.cos``/``np.sin`` of the phases as one array (a ``list`` buffer of floats, or of columns of one shape: then
    one 2-D array; numpy gives each element the bits it gives a scalar).

    The compiled step does not compile this body: it overloads this function with the loop of ``math.cos`` and
    ``math.sin`` (:mod:`amigo_gym.sim._kernels_v1`).
    """
    lst = cast("list[Any]", buf)
    arr = _np_array(lst[b : b + n])
    cos = _np_cos(arr)
    sin = _np_sin(arr)
    if arr.ndim > 1:  # a list of columns (fresnel.advance of columns): the rows
        lst[b + m : b + m + n] = list(cos)
        lst[b + 2 * m : b + 2 * m + n] = list(sin)
        return
    lst[b + m : b + m + n] = cos.tolist()
    lst[b + 2 * m : b + 2 * m + n] = sin.tolist()


def node_phases(
    buf: Buffer, k: int, theta: float, w0: float, alpha: float, t: float, nodes: Buffer, j: int, nn: int
) -> float:
    r"""The phases at the nodes of one piece into ``buf[k : k + nn]``; returns the heading at its end.

    .. math:: \phi_i = \theta + \tau_i (w_0 + \tfrac12\alpha\tau_i),\quad \tau_i = u_i t, \qquad
        \theta' = \theta + t (w_0 + \tfrac12\alpha t)

    Args:
        buf: node buffer; k: where this piece's phases start.
        theta, w0, alpha, t: start heading [rad], turn rate [rad/s] and its rate [rad/s^2], duration [s].
        nodes, j, nn: the ``nn`` nodes ``u_i`` on [0, 1] at ``nodes[j + i]``, their weights at ``nodes[j + nn + i]``
            (:func:`node_table`).
    """
    half_alpha = 0.5 * alpha
    for i in range(nn):
        tau = nodes[j + i] * t
        buf[k + i] = theta + tau * (w0 + half_alpha * tau)
    return theta + t * (w0 + half_alpha * t)


def node_sums(
    buf: Buffer, k: int, m: int, v0: float, a: float, t: float, nodes: Buffer, j: int, nn: int
) -> tuple[float, float]:
    r"""The weighted sums of one piece's node cosines and sines (``buf[m + k + i]``, ``buf[2 m + k + i]``), in order.

    .. math:: (d_x, d_y) = \sum_i (v_0 + a \tau_i) w_i (\cos, \sin)\phi_i, \quad \tau_i = u_i t

    so that the position advances by ``(dx t, dy t)``. ``v0 = 1``, ``a = 0`` (a path piece) weights by ``w_i``
    exactly. ``nodes, j, nn`` as :func:`node_phases`.
    """
    dx = 0.0
    dy = 0.0
    for i in range(nn):
        weight = (v0 + a * (nodes[j + i] * t)) * nodes[j + nn + i]
        dx = dx + weight * buf[m + k + i]
        dy = dy + weight * buf[2 * m + k + i]
    return dx, dy


def advance_nodes(
    buf: Buffer,
    b: int,
    m: int,
    x: float,
    y: float,
    theta: float,
    pieces: Buffer,
    p: int,
    n_pieces: int,
    nodes: Buffer,
    j: int,
    nn: int,
) -> tuple[float, float, float]:
    """:func:`advance` applied piece after piece: the phases of all pieces' nodes first (the heading at each piece's
    start is closed form), one :func:`cos_sin_nodes`, then the sums in order.

    Args:
        buf, b, m: node buffer of stride ``m >= n_pieces * nn`` from ``buf[b]`` (``3 m`` entries).
        x, y, theta: start pose [m, m, rad].
        pieces: ``(v0, a, w0, alpha, t)`` of each piece (as :func:`advance`'s arguments) at ``pieces[p + 5 q]``.
        n_pieces: number of pieces (0: the start pose).
        nodes, j, nn: the nodes and weights (:func:`node_phases`).

    Returns:
        the pose after the last piece.
    """
    th = theta
    for q in range(n_pieces):
        o = p + 5 * q
        th = node_phases(buf, b + q * nn, th, pieces[o + 2], pieces[o + 3], pieces[o + 4], nodes, j, nn)
    cos_sin_nodes(buf, b, n_pieces * nn, m)
    for q in range(n_pieces):
        o = p + 5 * q
        t = pieces[o + 4]
        dx, dy = node_sums(buf, b + q * nn, m, pieces[o], pieces[o + 1], t, nodes, j, nn)
        x = x + dx * t
        y = y + dy * t
    return x, y, th


def unit_speed_phases(
    buf: Buffer, k: int, theta: float, w0: float, alpha: float, t: float, nodes: Buffer, j: int, nn: int
) -> None:
    """:func:`node_phases` of a path piece (arc length as time) into ``buf[k : k + nn]``, its end heading at
    ``buf[k + nn]`` (so that one :func:`cos_sin_nodes` gives its cosine and sine too)."""
    buf[k + nn] = node_phases(buf, k, theta, w0, alpha, t, nodes, j, nn)


def unit_speed_sums(
    buf: Buffer, m: int, k: int, x: float, y: float, t: float, nodes: Buffer, j: int, nn: int
) -> tuple[float, float, float, float, float]:
    """The pose ``(x', y', theta', cos theta', sin theta')`` after :func:`unit_speed_phases` at ``k`` and
    :func:`cos_sin_nodes` (the position's sums by :func:`node_sums` with unit speed)."""
    dx, dy = node_sums(buf, k, m, 1.0, 0.0, t, nodes, j, nn)
    return x + dx * t, y + dy * t, buf[k + nn], buf[m + k + nn], buf[2 * m + k + nn]


def unit_speed_nodes(
    buf: Buffer, x: float, y: float, theta: float, w0: float, alpha: float, t: float, nodes: Buffer, j: int, nn: int
) -> tuple[float, float, float, float, float]:
    """:func:`unit_speed_pose` on a node buffer of stride ``nn + 1`` (length ``3 (nn + 1)``)."""
    m = nn + 1
    unit_speed_phases(buf, 0, theta, w0, alpha, t, nodes, j, nn)
    cos_sin_nodes(buf, 0, m, m)
    return unit_speed_sums(buf, m, 0, x, y, t, nodes, j, nn)


def node_table(n_sub: int) -> list[float]:
    """The nodes on [0, 1] for ``n_sub`` equal sub-intervals, then their weights (``2 NODES n_sub`` floats, cached):
    the ``nodes`` of :func:`node_phases` with ``j = 0``, ``nn = NODES n_sub``."""
    got = _TABLE_CACHE.get(n_sub)
    if got is None:
        u, uw = _nodes(n_sub)
        got = u + uw
        if len(_TABLE_CACHE) < 64:
            _TABLE_CACHE[n_sub] = got
    return got


# -- the float path's entry points: thin wrappers on lists --------------------------------------------------


def unit_speed_pose(
    x: float, y: float, theta: float, w0: float, alpha: float, t: float
) -> tuple[float, float, float, float, float]:
    """``advance(x, y, theta, 1.0, 0.0, w0, alpha, t, 1)`` for Python floats (a path piece: arc length as time),
    with ``cos`` and ``sin`` of the new heading: ``(x', y', theta', cos theta', sin theta')``, the same bits as
    :func:`advance` and ``np.cos``/``np.sin`` of ``theta'`` (:func:`unit_speed_nodes`).

    With unit speed the weights ``(1 + 0 tau) w_i`` are exactly ``w_i``.
    """
    return unit_speed_nodes([0.0] * (3 * NODES + 3), x, y, theta, w0, alpha, t, _TABLE_1, 0, NODES)


def advance_chain_float(
    x: float, y: float, theta: float, pieces: list[tuple[float, float, float, float, float]], n_sub: int = 1
) -> tuple[float, float, float]:
    """:func:`advance` applied piece after piece, for Python floats: the same bits (:func:`advance_nodes`).

    Args:
        x, y, theta: start pose [m, m, rad].
        pieces: ``(v0, a, w0, alpha, t)`` of each piece, in order (as :func:`advance`'s arguments).
        n_sub: sub-intervals per piece.

    Returns:
        the pose after the last piece (the start pose for no pieces).
    """
    nn = NODES * n_sub
    m = len(pieces) * nn
    flat = [v for piece in pieces for v in piece]
    return advance_nodes([0.0] * (3 * m), 0, m, x, y, theta, flat, 0, len(pieces), node_table(n_sub), 0, nn)


def unit_speed_poses(
    starts: list[tuple[float, float, float, float, float, float]],
) -> list[tuple[float, float, float, float, float]]:
    """:func:`unit_speed_pose` of several independent ``(x, y, theta, w0, alpha, t)``, with one ``np.cos`` and one
    ``np.sin`` call for all (the same bits as one call each)."""
    nn = NODES + 1
    m = len(starts) * nn
    buf = [0.0] * (3 * m)
    for i, (_x, _y, theta, w0, alpha, t) in enumerate(starts):
        unit_speed_phases(buf, i * nn, theta, w0, alpha, t, _TABLE_1, 0, NODES)
    cos_sin_nodes(buf, 0, m, m)
    return [
        unit_speed_sums(buf, m, i * nn, x, y, t, _TABLE_1, 0, NODES) for i, (x, y, _th, _w, _al, t) in enumerate(starts)
    ]
