r"""Motion with speed and turn rate linear in time: the integral behind every curve of AmigoBot-v1.

A body with speed ``v(t) = v0 + a t`` along its heading and turn rate ``w(t) = w0 + alpha t`` has the heading
``theta(t) = theta0 + w0 t + alpha t^2 / 2`` and the position

.. math::
    \mathbf{p}(T) = \mathbf{p}_0 + \int_0^T (v_0 + a t)
        \begin{pmatrix}\cos\theta(t)\\ \sin\theta(t)\end{pmatrix} dt,

a generalised Fresnel integral. It gives point A within a control step while the firmware ramps its speeds
(:mod:`amigo_gym.model.actuators`, one call per linear piece) and a clothoid path piece (:mod:`amigo_gym.paths`:
arc length as time, ``v = 1``, ``a = 0``, curvature as turn rate).

Evaluation: Gauss–Legendre quadrature with :data:`NODES` nodes on each of ``n_sub`` equal sub-intervals. Where
the phase varies by at most :data:`MAX_PHASE_PER_SUB` rad on a sub-interval the error bound
``|E| <= h^{2n+1} (n!)^4 / ((2n+1) ((2n)!)^3) max|f^{(2n)}|`` is below 1e-20 relative to ``|v| h``: exact to
rounding (checked against mpmath in ``tests/test_fresnel.py``), lines, arcs and clothoids alike. Callers
choose ``n_sub`` with :func:`subintervals`.

:func:`advance` takes floats or broadcasting float64 arrays. The node functions (:func:`advance_nodes`,
:func:`unit_speed_nodes` and their parts) work on a buffer ``buf`` of stride ``m`` from ``buf[b]``: phases in
``buf[b : b + m]``, cosines in ``buf[b + m : b + 2m]``, sines in ``buf[b + 2m : b + 3m]``; they are in numba's
subset and compiled by :mod:`amigo_gym.sim._kernels_v1`.
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
    """:func:`subintervals` of a finite ``max_phase_change >= 0`` [rad], unchecked (numba's subset)."""
    return max(1, math.ceil(max_phase_change / MAX_PHASE_PER_SUB))


def advance(
    x: Real, y: Real, theta: Real, v0: Real, a: Real, w0: Real, alpha: Real, t: Real, n_sub: int = 1
) -> tuple[Real, Real, Real]:
    r"""Pose after time ``t`` with speed ``v0 + a tau`` and turn rate ``w0 + alpha tau`` (``0 <= tau <= t``).

    .. math::
        \theta' = \theta + w_0 t + \tfrac12 \alpha t^2, \qquad
        (x', y') = (x, y) + \int_0^t (v_0 + a\tau)\,(\cos, \sin)(\theta + w_0\tau + \tfrac12\alpha\tau^2)\,d\tau

    Args:
        x, y, theta: start pose [m, m, rad].
        v0, a: speed at the start [m/s] and its rate of change [m/s^2].
        w0, alpha: turn rate at the start [rad/s] and its rate of change [rad/s^2].
        t: duration [s], >= 0 (unchecked).
        n_sub: number of equal sub-intervals (:func:`subintervals`).

    Returns:
        ``(x', y', theta')`` of the broadcast shape.
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


class Buffer(Protocol):
    """What the node functions index: a ``list`` of floats or a float64 array."""

    def __getitem__(self, i: int, /) -> float: ...
    def __setitem__(self, i: int, v: float, /) -> None: ...
    def __len__(self) -> int: ...


def cos_sin_nodes(buf: Buffer, b: int, n: int, m: int) -> None:
    """``buf[b + m + i] = cos(buf[b + i])``, ``buf[b + 2 m + i] = sin(buf[b + i])`` for ``i < n``, by numpy
    (``buf`` a list of floats or of equal-shape columns). Compiled code overloads it with ``math.cos``/``math.sin``."""
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
    r"""Weighted sums of one piece's node cosines and sines:

    .. math:: (d_x, d_y) = \sum_i (v_0 + a \tau_i) w_i (\cos, \sin)\phi_i, \quad \tau_i = u_i t

    so that the position advances by ``(dx t, dy t)``; ``nodes, j, nn`` as :func:`node_phases`.
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
    """:func:`advance` of several pieces in turn: all phases, one :func:`cos_sin_nodes`, then the sums.

    Args:
        buf, b, m: node buffer of stride ``m >= n_pieces * nn`` from ``buf[b]``.
        x, y, theta: start pose [m, m, rad].
        pieces: ``(v0, a, w0, alpha, t)`` of piece ``q`` at ``pieces[p + 5 q]``.
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
    """:func:`node_phases` of a path piece into ``buf[k : k + nn]``, its end heading at ``buf[k + nn]``."""
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
    """``advance(x, y, theta, 1, 0, w0, alpha, t)`` with the cosine and sine of the new heading,
    ``(x', y', theta', cos theta', sin theta')``, on a node buffer of length ``3 (nn + 1)``. A piece of constant
    curvature (``alpha == 0``: a line or an arc) in closed form: the chord ``t sin(h)/h`` along ``theta + h``,
    ``h = w0 t / 2``."""
    if alpha == 0.0:
        h = 0.5 * w0 * t
        chord = t if h == 0.0 else t * (math.sin(h) / h)
        mid = theta + h
        end = theta + w0 * t
        return x + chord * math.cos(mid), y + chord * math.sin(mid), end, math.cos(end), math.sin(end)
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


def unit_speed_poses(
    starts: list[tuple[float, float, float, float, float, float]],
) -> list[tuple[float, float, float, float, float]]:
    """:func:`unit_speed_nodes` of several ``(x, y, theta, w0, alpha, t)`` (floats), one ``np.cos`` and
    ``np.sin`` call for all."""
    nn = NODES + 1
    m = len(starts) * nn
    buf = [0.0] * (3 * m)
    for i, (_x, _y, theta, w0, alpha, t) in enumerate(starts):
        unit_speed_phases(buf, i * nn, theta, w0, alpha, t, _TABLE_1, 0, NODES)
    cos_sin_nodes(buf, 0, m, m)
    return [
        unit_speed_sums(buf, m, i * nn, x, y, t, _TABLE_1, 0, NODES) for i, (x, y, _th, _w, _al, t) in enumerate(starts)
    ]
