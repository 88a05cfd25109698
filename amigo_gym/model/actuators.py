"""The real robot's actuators for ``AmigoBot-v1``: firmware speed ramps, actuation delay, slip, true geometry.

Pure functions of *columns* (floats, or float64 arrays that broadcast together), returning the same kind. One
control step of length ``dt``:

1. **Setpoints** ``(w1c, w2c)`` [rad/s] (wheel 1 right), clipped to ``[-w_max, w_max]``, become commanded speeds
   with the **nominal** robot: ``v_c = (r1 w1c + r2 w2c) / 2``, ``w_c = (r1 w1c - r2 w2c) / (2 l1)``.
2. **Ramps** (:func:`ramp`): ``v`` [m/s] and ``w`` [rad/s] each move towards their command at ``A`` while ``|u|``
   grows and ``D`` while it shrinks (through 0 for a command of the other sign); :class:`ActuatorParams`.
3. **State**: the wheel rates ``w1 = (v + l1 w) / r1``, ``w2 = (v - l1 w) / r2`` (:func:`wheel_rates_columns`).
4. **Delay** (:func:`delay_split`, :func:`ring_read`): with ``delay = m dt + f`` (``0 <= f < dt``), during step ``k``
   the command of step ``k - m - 1`` holds for ``t < f``, that of step ``k - m`` after.
5. **Slip and true robot**: with the true ``r1t``, ``r2t``, ``l1t`` and slips ``s_i`` in ``[0, 1)``,
   ``v_true = ((1 - s1) r1t w1 + (1 - s2) r2t w2) / 2``, ``w_true = ((1 - s1) r1t w1 - (1 - s2) r2t w2) / (2 l1t)``.
6. **Exact step** (:func:`actuator_step`): on each piece where both are linear the pose advances by
   :func:`amigo_gym.model.fresnel.advance`, the wheel angles by the exact integral of the rates.

The limits are the manufacturer's (``docs/model.md``); the ramp rule (a model of the ARCOS firmware, not checked
against the robot) and ``MAX_DELAY`` are the project's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model import fresnel
from amigo_gym.model.kinematics import Real, body_velocity_of, wheel_rates_of
from amigo_gym.model.numeric import any_array, clip, where
from amigo_gym.model.params import RobotParams, check_real

#: largest actuation delay supported [s] (the project's choice: a few 0.1 s control cycles)
MAX_DELAY = 0.5
#: relative deviation of the true wheel radii and half track from nominal assumed by :func:`turn_rate_bound`
MAX_TRUE_DEVIATION = 0.25
#: linear pieces per step in :func:`actuator_step` (some of zero length)
PIECES = 10


@dataclass(frozen=True)
class ActuatorParams:
    """The firmware's ramp rates (defaults: the manufacturer's): ``acceleration``, ``deceleration`` at which ``|v|``
    grows and shrinks [m/s^2], in (0, 10]; ``rot_acceleration``, ``rot_deceleration`` for ``|w|`` [rad/s^2], in
    (0, 100]; and the ``delay`` [s] in [0, MAX_DELAY] after which a command takes effect."""

    acceleration: float = 0.3
    deceleration: float = 0.75
    rot_acceleration: float = 0.87
    rot_deceleration: float = 2.5
    delay: float = 0.0

    def __post_init__(self) -> None:
        highs = {"acceleration": 10.0, "deceleration": 10.0, "rot_acceleration": 100.0, "rot_deceleration": 100.0}
        for f in fields(self):
            high, low_open = highs.get(f.name, MAX_DELAY), f.name != "delay"
            v = check_real("ActuatorParams", f.name, getattr(self, f.name), 0.0, high, low_open=low_open)
            object.__setattr__(self, f.name, v)


def wheel_rates_columns(v: Real, w: Real, robot: RobotParams) -> tuple[Real, Real]:
    """Wheel rates [rad/s] rolling without slip at ``v`` [m/s], ``w`` [rad/s]: ``((v + l1 w)/r1, (v - l1 w)/r2)``."""
    return wheel_rates_of(v, w, robot.l1, robot.r1, robot.r2)


class Ramp(NamedTuple):
    """One speed channel ramped over ``[0, T]`` (:func:`ramp`): pieces ``[0, t_a]`` (from ``u0``, slope ``s_a``),
    ``[t_a, t_b]`` (from ``u_a``, slope ``s_b``), ``[t_b, T]`` (``u_b``); ``0 <= t_a <= t_b <= T`` [s]."""

    t_a: Real
    t_b: Real
    u_a: Real
    u_b: Real
    s_a: Real
    s_b: Real


def ramp(u0: Real, target: Real, accel: float, decel: float, duration: Real) -> Ramp:
    r"""The firmware's ramp of a speed from ``u0`` towards ``target`` ``c`` over ``[0, T]`` (``duration``), closed form.

    Reversing (``u0 c < 0``): ``u`` falls to 0 at ``D = decel`` until ``t_z = |u0| / D``, then reaches ``c`` at
    ``A = accel`` at ``t_r = t_z + |c| / A``. Otherwise ``t_z = 0``, ``t_r = |c - u0| / R`` with ``R = A`` if
    ``|c| > |u0|`` else ``D``. Then ``u = c``. Returns :class:`Ramp` with ``t_a = min(t_z, T)``, ``t_b = min(t_r, T)``.
    """
    reverse = u0 * target < 0.0
    u_z = where(reverse, 0.0, u0)
    t_z = where(reverse, np.abs(u0) / decel, 0.0)
    s_a = where(reverse, np.copysign(decel, -u0), 0.0)
    d = target - u_z
    rate = where(np.abs(target) > np.abs(u_z), accel, decel)
    t_r = t_z + np.abs(d) / rate
    s_b = np.copysign(rate, d)
    z_in = t_z <= duration
    r_in = t_r <= duration
    u_a = where(z_in, u_z, u0 + s_a * duration)
    u_b = where(r_in, target, where(z_in, u_z + s_b * (duration - t_z), u_a))
    return Ramp(np.minimum(t_z, duration), np.minimum(t_r, duration), u_a, u_b, s_a, s_b)


def turn_rate_bound(nominal: RobotParams, deviation: float = MAX_TRUE_DEVIATION) -> float:
    r"""A bound of the true turn rate [rad/s] in :func:`actuator_step`, true radii and half track within a relative
    ``deviation`` of nominal: :math:`(1 + \delta)^2 \, 2 V / l_1`, ``V = (r1 + r2) w_max / 2`` (19.5 by default)."""
    check_real("turn_rate_bound", "deviation", deviation, 0.0, 1.0)
    v_max = 0.5 * (nominal.r1 + nominal.r2) * nominal.max_wheel_rate
    return (1.0 + deviation) ** 2 * 2.0 * v_max / nominal.l1


def step_subintervals(dt: float, nominal: RobotParams, deviation: float = MAX_TRUE_DEVIATION) -> int:
    """``n_sub`` for :func:`amigo_gym.model.fresnel.advance` on a step of ``dt`` [s], from the phase bound
    ``turn_rate_bound(nominal, deviation) * dt`` (never from the state: one robot and a batch alike)."""
    return fresnel.subintervals(turn_rate_bound(nominal, deviation) * dt)


def delay_split(delay: Real, dt: float) -> tuple[int | NDArray[np.int64], Real]:
    """``(m, f)`` with ``delay = m dt + f`` [s], ``f = fmod(delay, dt)``: ``m`` an int (int64 for an array)."""
    if isinstance(delay, np.ndarray):
        f_arr = np.fmod(delay, dt)
        return np.rint((delay - f_arr) / dt).astype(np.int64), f_arr
    f = math.fmod(delay, dt)
    return round((delay - f) / dt), f


def ring_length(dt: float, max_delay: float = MAX_DELAY) -> int:
    """Past commands to keep for delays up to ``max_delay`` [s] with step ``dt`` [s]: ``m + 2``, ``m`` of
    :func:`delay_split` (6 for 0.5 / 0.1)."""
    check_real("ring_length", "dt", dt, 0.0, low_open=True)
    check_real("ring_length", "max_delay", max_delay, 0.0, MAX_DELAY)
    m, _ = delay_split(max_delay, dt)
    return int(m) + 2


def ring_write(ring: NDArray[np.float64], step: int, w1c: Real, w2c: Real) -> None:
    """Store the command ``(w1c, w2c)`` [rad/s] of ``step >= 0`` in its slot of ``ring``, in place."""
    slot = ring_slot(step, ring.shape[-2])
    ring[..., slot, 0] = w1c
    ring[..., slot, 1] = w2c


def ring_slot(step: Any, length: int) -> Any:
    """The slot of the command of ``step``: ``step % length``."""
    return step % length


def ring_read_slots(step: Any, lag: Any, length: int) -> tuple[Any, Any]:
    """The slots ``(old, new)`` of the commands of steps ``step - lag - 1`` and ``step - lag``."""
    return ring_slot(step - lag - 1, length), ring_slot(step - lag, length)


def ring_read(ring: NDArray[np.float64], step: int, lag: int | NDArray[np.int64]) -> tuple[Real, Real, Real, Real]:
    """The setpoints ``(w1_old, w2_old, w1_new, w2_new)`` [rad/s] of steps ``step - lag - 1`` and ``step - lag``
    (``lag``: ``m`` of :func:`delay_split`, an int or ``(N,)`` ints), floats for a ``(length, 2)`` ring, else ``(N,)``;
    ``ValueError`` if the ring is shorter than ``lag + 2``."""
    length = ring.shape[-2]
    lags = lag if type(lag) is int else np.asarray(lag)  # one robot: no array arithmetic
    if np.any(lags + 2 > length) or np.any(lags < 0):
        raise ValueError(f"ring of {length} commands cannot serve a lag of {lag!r} steps (needs lag + 2)")
    i_old, i_new = ring_read_slots(step, lags, length)
    if ring.ndim == 2:
        return (*ring[int(i_old)].tolist(), *ring[int(i_new)].tolist())
    rows = np.arange(ring.shape[0])
    old, new = ring[rows, i_old], ring[rows, i_new]
    return old[:, 0].copy(), old[:, 1].copy(), new[:, 0].copy(), new[:, 1].copy()


class ActuatorStep(NamedTuple):
    """Result of :func:`actuator_step` (columns): the new pose of A ``x, y, beta`` [m, m, rad] (not wrapped), the wheel
    rates ``w1, w2`` [rad/s] at the end, the wheel-angle increments ``dalpha1, dalpha2`` [rad], the signed distance of
    A ``int v_true dt`` [m], and the true speed [m/s] and turn rate [rad/s] at the end."""

    x: Real
    y: Real
    beta: Real
    w1: Real
    w2: Real
    dalpha1: Real
    dalpha2: Real
    distance: Real
    v_true: Real
    w_true: Real


def actuator_step(
    x: Real, y: Real, beta: Real, w1: Real, w2: Real, w1c_old: Real, w2c_old: Real, w1c_new: Real, w2c_new: Real,
    t_switch: Real, dt: float, nominal: RobotParams, limits: ActuatorParams, r1_true: Real, r2_true: Real,
    l1_true: Real, slip1: Real = 0.0, slip2: Real = 0.0, n_sub: int | None = None,
) -> ActuatorStep:  # fmt: skip
    r"""One control step of the robot with its actuators, exact (module docstring); an :class:`ActuatorStep`.

    From the pose of A ``x, y, beta`` [m, m, rad] and wheel rates ``w1, w2`` [rad/s], the setpoints ``*_old`` before
    ``t_switch`` in ``[0, dt]`` [s] and ``*_new`` after, the ramps of ``limits`` (delay unused), the true radii and
    half track [m], slips in ``[0, 1)`` (unchecked); ``n_sub`` default :func:`step_subintervals`. The ramps'
    breakpoints split the step into :data:`PIECES` pieces with ``v``, ``w`` linear: on one of length ``L`` the pose
    advances by :func:`amigo_gym.model.fresnel.advance_nodes`, the wheel angles by ``L (w_i + \dot w_i L / 2)``, the
    distance by ``L (v_true + \dot v_true L / 2)``. Floats in, floats out; any array in: broadcast arrays out.
    """
    if n_sub is None:
        n_sub = step_subintervals(dt, nominal)
    cols: tuple[Real, ...] = (
        x, y, beta, w1, w2, w1c_old, w2c_old, w1c_new, w2c_new, t_switch, r1_true, r2_true, l1_true, slip1, slip2
    )  # fmt: skip
    if any_array(*cols):  # columns: every input and output an array of the broadcast shape
        cols = tuple(np.array(a, dtype=np.float64) for a in np.broadcast_arrays(*cols))
    else:
        cols = tuple(float(c) for c in cols)
    x, y, beta, w1, w2, w1c_old, w2c_old, w1c_new, w2c_new, t_s, r1t, r2t, l1t, s1, s2 = cols
    nn = fresnel.NODES * n_sub
    out = actuator_step_ws(
        [0.0] * SCRATCH, 0, [0.0] * (3 * PIECES * nn), 0, fresnel.step_table(n_sub), 0, nn,
        x, y, beta, w1, w2, w1c_old, w2c_old, w1c_new, w2c_new, t_s, dt,
        nominal.max_wheel_rate, nominal.l1, nominal.r1, nominal.r2, 2.0 * nominal.l1,
        limits.acceleration, limits.deceleration, limits.rot_acceleration, limits.rot_deceleration,
        r1t, r2t, l1t, s1, s2,
    )  # fmt: skip
    return ActuatorStep(*out)


# The step on a scratch ``ws`` (a list of floats or of columns, or a stack buffer in the compiled step): per channel (v,
# then w) 7 knots, 6 values and 6 slopes; the 11 piece boundaries; ``(vt, at, wt, alt, length)`` of each live piece.

#: scratch entries of one speed channel: 7 knots, 6 values, 6 slopes
CHANNEL_SCRATCH = 19
#: offsets in the scratch of :func:`actuator_step_ws`: the v and w channels, the piece boundaries, the pieces
SCRATCH_V = 0
SCRATCH_W = SCRATCH_V + CHANNEL_SCRATCH
SCRATCH_TIMES = SCRATCH_W + CHANNEL_SCRATCH
SCRATCH_PIECES = SCRATCH_TIMES + PIECES + 1
#: length of the scratch of :func:`actuator_step_ws`
SCRATCH = SCRATCH_PIECES + 5 * PIECES


def sort_knots_float(ws: fresnel.Buffer, i0: int, n: int) -> None:
    """Sort the floats ``ws[i0 : i0 + n]`` in place, ascending (insertion sort): :func:`sort_knots` of floats."""
    for i in range(i0 + 1, i0 + n):
        key = ws[i]
        j = i - 1
        while j >= i0 and key < ws[j]:
            ws[j + 1] = ws[j]
            j -= 1
        ws[j + 1] = key


def sort_knots(ws: Any, i0: int, n: int) -> None:
    """Sort ``ws[i0 : i0 + n]`` in place, ascending: floats, or a list of columns row by row."""
    if not any_array(*ws[i0 : i0 + n]):
        sort_knots_float(ws, i0, n)
        return
    ws[i0 : i0 + n] = list(np.sort(np.stack(np.broadcast_arrays(*ws[i0 : i0 + n])), axis=0))


def advance_pieces(
    buf: Any, b: int, m: int, x: Any, y: Any, theta: Any, pieces: Any, p: int, n_pieces: int,
    nodes: Any, j: int, nn: int,
) -> tuple[Any, Any, Any]:  # fmt: skip
    """:func:`amigo_gym.model.fresnel.advance_nodes` of the pieces ``(v0, a, w0, alpha, t)`` at ``pieces[p + 5 q]``;
    on columns piece by piece, a piece of ``t <= 0`` (or NaN) leaving a row unchanged."""
    if not any_array(x):  # floats (actuator_step makes every input a column when one is)
        return fresnel.advance_nodes(buf, b, m, x, y, theta, pieces, p, n_pieces, nodes, j, nn)
    for q in range(n_pieces):
        piece = pieces[p + 5 * q : p + 5 * q + 5]
        live = np.asarray(piece[4] > 0.0)
        if 2 * int(np.count_nonzero(live)) < live.size:  # few rows: the quadrature of the live rows alone
            x, y, theta = np.array(x), np.array(y), np.array(theta)
            rows: list[Any] = [np.asarray(c)[live] for c in (x, y, theta, *piece)]
            x[live], y[live], theta[live] = fresnel.advance_nodes(
                [0.0] * (3 * nn), 0, nn, rows[0], rows[1], rows[2], rows[3:], 0, 1, nodes, j, nn
            )
            continue
        nx, ny, nb = fresnel.advance_nodes([0.0] * (3 * nn), 0, nn, x, y, theta, piece, 0, 1, nodes, j, nn)
        x, y, theta = np.where(live, nx, x), np.where(live, ny, y), np.where(live, nb, theta)
    return x, y, theta


def _channel_ws(
    ws: Any, k: int, u0: Real, c_old: Real, c_new: Real, accel: float, decel: float, t_s: Real, dt: float
) -> Real:
    """One channel ramped to ``c_old`` on ``[0, t_s)``, ``c_new`` after: its 7 knots, 6 start values and 6 slopes into
    ``ws[k : k + 19]``; returns the value at ``dt``."""
    ta1, tb1, ua1, ub1, sa1, sb1 = ramp(u0, c_old, accel, decel, t_s)
    ta2, tb2, ua2, ub2, sa2, sb2 = ramp(ub1, c_new, accel, decel, dt - t_s)
    knots = (0.0, ta1, tb1, t_s, np.minimum(t_s + ta2, dt), np.minimum(t_s + tb2, dt), dt)
    for i, entry in enumerate((*knots, u0, ua1, ub1, ub1, ua2, ub2, sa1, sb1, 0.0, sa2, sb2, 0.0)):
        ws[k + i] = entry
    return ub2


def _evaluate_ws(ws: Any, k: int, t: Real, mid: Real) -> tuple[Real, Real]:
    """Value at ``t`` and slope of the piece of the channel at ``ws[k:]`` containing ``mid`` (``t <= mid``)."""
    v = k + 7
    s = k + 13
    val = ws[v] + ws[s] * t
    slope = ws[s]
    for i in range(1, 6):
        inside = mid >= ws[k + i]
        val = where(inside, ws[v + i] + ws[s + i] * (t - ws[k + i]), val)
        slope = where(inside, ws[s + i], slope)
    return val, slope


def actuator_step_ws(
    ws: Any, k: int, buf: Any, b: int, nodes: fresnel.Buffer, node_at: int, nn: int,
    x: Real, y: Real, beta: Real, w1: Real, w2: Real, w1c_old: Real, w2c_old: Real, w1c_new: Real, w2c_new: Real,
    t_s: Real, dt: float, w_max: float, l1n: float, r1n: float, r2n: float, two_l1: float,
    accel: float, decel: float, rot_accel: float, rot_decel: float, r1t: Real, r2t: Real, l1t: Real, s1: Real, s2: Real,
) -> tuple[Real, Real, Real, Real, Real, Real, Real, Real, Real, Real]:  # fmt: skip
    """:func:`actuator_step` on floats or columns of one shape (``ws``, ``buf`` lists), also compiled as it is; the
    fields of :class:`ActuatorStep` as a tuple. Scratch of :data:`SCRATCH` from ``ws[k]``, a node buffer of
    ``3 PIECES nn`` from ``buf[b]``, ``nn = NODES n_sub`` nodes then weights from ``nodes[node_at]``
    (:func:`amigo_gym.model.fresnel.step_table`); the nominal ``w_max`` [rad/s], ``l1n``, ``r1n``, ``r2n``,
    ``two_l1 = 2 l1`` [m]; the ramps; the others as :func:`actuator_step`.
    """
    # 1. commands (clipped; body_velocity_columns)
    vc_old, wc_old = body_velocity_of(clip(w1c_old, -w_max, w_max), clip(w2c_old, -w_max, w_max), r1n, r2n, two_l1)
    vc_new, wc_new = body_velocity_of(clip(w1c_new, -w_max, w_max), clip(w2c_new, -w_max, w_max), r1n, r2n, two_l1)
    # 2. ramps
    v0, om0 = body_velocity_of(w1, w2, r1n, r2n, two_l1)
    kv = k + SCRATCH_V
    kw = k + SCRATCH_W
    v_end = _channel_ws(ws, kv, v0, vc_old, vc_new, accel, decel, t_s, dt)
    w_end = _channel_ws(ws, kw, om0, wc_old, wc_new, rot_accel, rot_decel, t_s, dt)
    # times = [0, *sorted(9 inner breakpoints), dt]
    tm = k + SCRATCH_TIMES
    ws[tm] = 0.0
    for i, src in enumerate((kv + 1, kv + 2, kv + 3, kv + 4, kv + 5, kw + 1, kw + 2, kw + 4, kw + 5)):
        ws[tm + 1 + i] = ws[src]
    ws[tm + 10] = dt
    sort_knots(ws, tm + 1, 9)
    # 3. pieces: their rates, the wheel angles and the distance; then the pose over all (fresnel.advance_nodes)
    g1 = (1.0 - s1) * r1t
    g2 = (1.0 - s2) * r2t
    inv_2l1t = 0.5 / l1t
    da1: Real = 0.0
    da2: Real = 0.0
    dist: Real = 0.0
    pcs = k + SCRATCH_PIECES
    n_pieces = 0
    for j in range(PIECES):
        t0 = ws[tm + j]
        t1 = ws[tm + j + 1]
        length = t1 - t0
        live = length > 0.0
        if not np.any(live):
            continue
        mid = 0.5 * (t0 + t1)
        v, a = _evaluate_ws(ws, kv, t0, mid)
        om, al = _evaluate_ws(ws, kw, t0, mid)
        # nominal wheel rates p_i + q_i tau; true speeds vt + at tau = (g1 w1 + g2 w2) / 2, wt + alt tau (/ 2 l1t)
        p1, p2 = wheel_rates_of(v, om, l1n, r1n, r2n)
        q1, q2 = wheel_rates_of(a, al, l1n, r1n, r2n)
        vt = 0.5 * (g1 * p1 + g2 * p2)
        at = 0.5 * (g1 * q1 + g2 * q2)
        wt = (g1 * p1 - g2 * p2) * inv_2l1t
        alt = (g1 * q1 - g2 * q2) * inv_2l1t
        for i, rate in enumerate((vt, at, wt, alt, length)):
            ws[pcs + 5 * n_pieces + i] = rate
        n_pieces += 1
        half = 0.5 * length
        da1 = where(live, da1 + length * (p1 + q1 * half), da1)
        da2 = where(live, da2 + length * (p2 + q2 * half), da2)
        dist = where(live, dist + length * (vt + at * half), dist)
    x, y, beta = advance_pieces(buf, b, PIECES * nn, x, y, beta, ws, pcs, n_pieces, nodes, node_at, nn)
    # 4. the new actuator state (wheel_rates_columns) and the true speeds at the end
    w1n, w2n = wheel_rates_of(v_end, w_end, l1n, r1n, r2n)
    v_true = 0.5 * (g1 * w1n + g2 * w2n)
    w_true = (g1 * w1n - g2 * w2n) * inv_2l1t
    return x, y, beta, w1n, w2n, da1, da2, dist, v_true, w_true
