"""Motion with speed and turn rate linear in time: the integral behind every curve of AmigoBot-v1.

Speed ``v0 + a t`` and turn rate ``w0 + alpha t`` give the heading ``theta(t) = theta0 + w0 t + alpha t^2 / 2`` and
the position ``p(T) = p0 + int_0^T (v0 + a t) (cos, sin)(theta(t)) dt``, a generalised Fresnel integral: point A over
a linear piece of the firmware's ramps, and a clothoid path piece (arc length as time, ``v = 1``, ``a = 0``).

Gauss–Legendre quadrature, :data:`NODES` nodes on each of ``n_sub`` equal sub-intervals (:func:`subintervals`) of
phase change ``Phi = |w0| h + |alpha| h^2 / 2`` at most :data:`MAX_PHASE_PER_SUB` rad; with one sub-interval a piece of
``Phi <= TIER_PHASE[i]`` takes the rule of ``TIER_NODES[i]`` nodes (:func:`tier`). Error relative to ``int |v| dt``
(against mpmath, ``tests/test_fresnel.py``): 4e-16 where ``Phi <= 1``, 5e-14 where ``Phi <= 2``.
The node functions (numba's subset) use a buffer ``buf`` of stride ``m`` from ``buf[b]``: phases, cosines at
``+ m``, sines at ``+ 2m``.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, cast

import numpy as np

from amigo_gym.model.kinematics import Real

#: Gauss–Legendre nodes per sub-interval
NODES = 10
#: largest phase change [rad] on one sub-interval (the error there: module docstring)
MAX_PHASE_PER_SUB = 2.0
#: the smaller rules of one sub-interval: node counts, the largest ``Phi`` [rad] of each (:func:`tier`), where their
#: nodes then weights on [0, 1] stand after the ``2 NODES`` entries of the 10-node rule (:func:`step_table`)
TIER_NODES, TIER_PHASE = (6, 8), (0.0625, 0.25)
TIER_AT = tuple(2 * sum(TIER_NODES[:i]) for i in range(len(TIER_NODES)))


def _leg(n: int) -> list[float]:
    """The ``n`` Gauss–Legendre nodes on [0, 1], then their weights (summing to 1)."""
    x, w = np.polynomial.legendre.leggauss(n)
    return [*(0.5 * (x + 1.0)).tolist(), *(0.5 * w).tolist()]


#: :func:`node_table` for one sub-interval (a path piece's quadrature), and the cache of the others
_TABLE_1: list[float] = _leg(NODES)
_TIERS: list[float] = [v for n in TIER_NODES for v in _leg(n)]
_TABLE_CACHE: dict[int, list[float]] = {1: _TABLE_1}


def subintervals(max_phase_change: float) -> int:
    """Sub-intervals so that the phase varies by at most :data:`MAX_PHASE_PER_SUB` on each, given a bound
    ``max_phase_change`` [rad] of ``|w0| T + |alpha| T^2 / 2``."""
    if not math.isfinite(max_phase_change) or max_phase_change < 0:
        raise ValueError(f"max_phase_change must be a finite number >= 0, got {max_phase_change!r}")
    return subinterval_count(max_phase_change)


def subinterval_count(max_phase_change: float) -> int:
    """:func:`subintervals` of a finite ``max_phase_change >= 0`` [rad], unchecked (numba's subset)."""
    return max(1, math.ceil(max_phase_change / MAX_PHASE_PER_SUB))


def advance(
    x: Real, y: Real, theta: Real, v0: Real, a: Real, w0: Real, alpha: Real, t: Real, n_sub: int = 1
) -> tuple[Real, Real, Real]:
    """Pose ``(x', y', theta')`` [m, m, rad] after ``t >= 0`` [s] from ``(x, y, theta)`` with speed ``v0 + a tau``
    [m/s] and turn rate ``w0 + alpha tau`` [rad/s] (module docstring); floats or broadcasting arrays, ``n_sub`` of
    :func:`subintervals`."""
    m = NODES * n_sub
    pieces: list[Any] = [v0, a, w0, alpha, t]
    return advance_nodes([0.0] * (3 * m), 0, m, x, y, theta, pieces, 0, 1, step_table(n_sub), 0, m)  # type: ignore


def step_table(n_sub: int) -> list[float]:
    """:func:`node_table` of ``n_sub``, then the smaller rules that :func:`advance_nodes` takes (``TIER_AT``)."""
    return node_table(n_sub) + _TIERS


def tier(phase: Real) -> int:
    """The first ``i`` with every entry of ``phase <= TIER_PHASE[i]`` [rad], else ``len(TIER_PHASE)`` (the 10-node
    rule; NaN too)."""
    return tier_float(float(np.max(phase)))


def tier_float(phase: float) -> int:
    """:func:`tier` of a float."""
    i = 0
    while i < len(TIER_PHASE) and not phase <= TIER_PHASE[i]:
        i += 1
    return i


def piece_rule(w0: Any, alpha: Any, t: Any, j: int, nn: int) -> tuple[int, int]:
    """Where the nodes of a piece's rule start and how many: ``(j, nn)``, or with ``nn == NODES`` (one sub-interval
    of :func:`step_table` at ``j``) the smaller rule of :func:`tier` where it takes one."""
    i = tier(abs(w0) * t + 0.5 * abs(alpha) * t * t) if nn == NODES else len(TIER_NODES)
    return (j + 2 * NODES + TIER_AT[i], TIER_NODES[i]) if i < len(TIER_NODES) else (j, nn)


class Buffer(Protocol):
    """What the node functions index: a ``list`` of floats or a float64 array."""

    def __getitem__(self, i: int, /) -> float: ...
    def __setitem__(self, i: int, v: float, /) -> None: ...
    def __len__(self) -> int: ...


def cos_sin_nodes(buf: Buffer, b: int, n: int, m: int) -> None:
    """``buf[b + m + i] = cos(buf[b + i])``, ``buf[b + 2 m + i] = sin(buf[b + i])`` for ``i < n``; floats or columns."""
    lst = cast("list[Any]", buf)
    arr = np.array(lst[b : b + n])
    rows = list if arr.ndim > 1 else np.ndarray.tolist  # columns (fresnel.advance of columns): the rows; else floats
    lst[b + m : b + m + n] = rows(np.cos(arr))
    lst[b + 2 * m : b + 2 * m + n] = rows(np.sin(arr))


def node_phases(
    buf: Buffer, k: int, theta: float, w0: float, alpha: float, t: float, nodes: Buffer, j: int, nn: int
) -> float:
    """The phases ``theta + tau_i (w0 + alpha tau_i / 2)``, ``tau_i = u_i t``, into ``buf[k : k + nn]``; returns the
    heading at ``t`` [rad]. ``nodes[j + i]``: the ``nn`` nodes ``u_i`` on [0, 1], then their weights."""
    half_alpha = 0.5 * alpha
    for i in range(nn):
        tau = nodes[j + i] * t
        buf[k + i] = theta + tau * (w0 + half_alpha * tau)
    return theta + t * (w0 + half_alpha * t)


def node_sums(
    buf: Buffer, k: int, m: int, v0: float, a: float, t: float, nodes: Buffer, j: int, nn: int
) -> tuple[float, float]:
    """``(dx, dy) = sum_i (v0 + a tau_i) w_i (cos, sin)(phi_i)``: the position advances by ``(dx t, dy t)``."""
    dx = 0.0
    dy = 0.0
    for i in range(nn):
        weight = (v0 + a * (nodes[j + i] * t)) * nodes[j + nn + i]
        dx = dx + weight * buf[m + k + i]
        dy = dy + weight * buf[2 * m + k + i]
    return dx, dy


def advance_nodes(
    buf: Buffer, b: int, m: int, x: float, y: float, theta: float, pieces: Buffer, p: int, n_pieces: int,
    nodes: Buffer, j: int, nn: int,
) -> tuple[float, float, float]:  # fmt: skip
    """:func:`advance` of ``n_pieces`` pieces ``(v0, a, w0, alpha, t)`` at ``pieces[p + 5 q]`` in turn, each by
    :func:`piece_rule` of the rule of ``nn`` nodes at ``nodes[j]`` (:func:`step_table`), on a node buffer of stride ``m
    >= n_pieces * nn``; the pose after the last."""
    th = theta
    k = b
    for q in range(n_pieces):
        o = p + 5 * q
        jq, nq = piece_rule(pieces[o + 2], pieces[o + 3], pieces[o + 4], j, nn)
        th = node_phases(buf, k, th, pieces[o + 2], pieces[o + 3], pieces[o + 4], nodes, jq, nq)
        k += nq
    cos_sin_nodes(buf, b, k - b, m)
    k = b
    for q in range(n_pieces):
        o = p + 5 * q
        t = pieces[o + 4]
        jq, nq = piece_rule(pieces[o + 2], pieces[o + 3], t, j, nn)
        dx, dy = node_sums(buf, k, m, pieces[o], pieces[o + 1], t, nodes, jq, nq)
        k += nq
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
    """``(x', y', theta', cos theta', sin theta')`` of ``advance(x, y, theta, 1, 0, w0, alpha, t)`` on a node buffer of
    ``3 (nn + 1)``; for ``alpha == 0`` in closed form: the chord ``t sin(h)/h`` along ``theta + h``, ``h = w0 t/2``."""
    if alpha == 0.0:  # the end's cosine and sine by the angle sum mid + h: two sincos
        h = 0.5 * w0 * t
        ch, sh, cm, sm = math.cos(h), math.sin(h), math.cos(theta + h), math.sin(theta + h)
        chord = t if h == 0.0 else t * (sh / h)
        return x + chord * cm, y + chord * sm, theta + w0 * t, cm * ch - sm * sh, sm * ch + cm * sh
    m = nn + 1
    unit_speed_phases(buf, 0, theta, w0, alpha, t, nodes, j, nn)
    cos_sin_nodes(buf, 0, m, m)
    return unit_speed_sums(buf, m, 0, x, y, t, nodes, j, nn)


def node_table(n_sub: int) -> list[float]:
    """The ``NODES n_sub`` nodes on [0, 1] of ``n_sub`` equal sub-intervals, then their weights (cached)."""
    got = _TABLE_CACHE.get(n_sub)
    if got is None:
        got = [(k + ui) / n_sub for k in range(n_sub) for ui in _TABLE_1[:NODES]]
        got += [wi / n_sub for _ in range(n_sub) for wi in _TABLE_1[NODES:]]
        if len(_TABLE_CACHE) < 64:
            _TABLE_CACHE[n_sub] = got
    return got


def unit_speed_poses(
    starts: list[tuple[float, float, float, float, float, float]],
) -> list[tuple[float, float, float, float, float]]:
    """:func:`unit_speed_nodes` of several ``(x, y, theta, w0, alpha, t)``, one ``np.cos`` and ``np.sin`` for all."""
    nn = NODES + 1
    m = len(starts) * nn
    buf = [0.0] * (3 * m)
    for i, (_x, _y, theta, w0, alpha, t) in enumerate(starts):
        unit_speed_phases(buf, i * nn, theta, w0, alpha, t, _TABLE_1, 0, NODES)
    cos_sin_nodes(buf, 0, m, m)
    return [
        unit_speed_sums(buf, m, i * nn, x, y, t, _TABLE_1, 0, NODES) for i, (x, y, _th, _w, _al, t) in enumerate(starts)
    ]
