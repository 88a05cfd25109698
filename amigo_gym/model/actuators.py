r"""The real robot's actuators for ``AmigoBot-v1``: firmware speed ramps, actuation delay, slip, true geometry.

Pure, batched functions (no state, no environment code). Every function takes *columns* (floats, or
float64 arrays that broadcast together, e.g. ``(N,)`` for ``N`` robots) and returns the same kind,
as in :mod:`amigo_gym.model.kinematics`; one robot and a batch run the same code.
This module may import only numpy, :mod:`amigo_gym.model.params`, :mod:`amigo_gym.model.numeric`,
:mod:`amigo_gym.model.kinematics`, :mod:`amigo_gym.model.fresnel` and the standard library (``tests/test_actuators.py``
checks it).

The model (one control step of length ``dt``, step time ``0 <= t <= dt``)
-------------------------------------------------------------------------
1. **Setpoints.** The action is a wheel-rate setpoint pair ``(w1c, w2c)`` [rad/s] (wheel 1 right,
   wheel 2 left), clipped to ``[-w_max, w_max]`` with ``w_max = RobotParams.max_wheel_rate``
   (``max_speed / r = 0.75 / 0.05 = 15`` rad/s). The firmware (ARCOS) turns it into commanded speeds
   with the **nominal** robot (:func:`amigo_gym.model.kinematics.body_velocity_columns`)::

       v_c = (r1 w1c + r2 w2c) / 2,        w_c = (r1 w1c - r2 w2c) / (2 l1).

2. **Ramps** (:func:`ramp`). The firmware's translational speed ``v`` [m/s] and rotational speed
   ``w`` [rad/s] each move towards their command at a constant rate: ``A`` while ``|u|`` grows
   (speeding up), ``D`` while ``|u|`` shrinks (slowing down); a command of the other sign is reached
   by slowing down to 0 at ``D`` and then speeding up at ``A``. Rates (:class:`ActuatorParams`):
   ``A_v = 0.3 m/s^2``, ``D_v = 0.75 m/s^2``, ``A_w = 0.87 rad/s^2``, ``D_w = 2.5 rad/s^2``.
   Within a step each of ``v(t)``, ``w(t)`` is continuous and piecewise linear.

3. **Actuator state.** The actual wheel rates are the nominal inverse of the ramped speeds::

       w1 = (v + l1 w) / r1,        w2 = (v - l1 w) / r2,

   and they are the state carried from step to step (:func:`wheel_rates_columns`).

4. **Delay** (:func:`delay_split`, :func:`ring_read`). A command issued at step ``k`` (time ``k dt``)
   takes effect at ``k dt + delay``. With ``delay = m dt + f`` (``m`` whole steps, ``0 <= f < dt``),
   during step ``k`` the setpoint in effect is the command of step ``k - m - 1`` for ``t < f`` and the
   command of step ``k - m`` for ``t >= f``: :func:`actuator_step` takes both and the switch time
   ``f``. The environment keeps the commands of the last :func:`ring_length` steps in a ring of state
   columns; ``0 <= delay <= MAX_DELAY = 0.5`` s.

5. **Slip and the true robot.** The ground moves the body with the **true** wheel radii ``r1t``,
   ``r2t`` and half track ``l1t`` (columns: they may differ per robot), and each wheel loses a
   fraction ``s_i`` in ``[0, 1)`` of its ground speed in the step (drawn by the caller)::

       v_true = ((1 - s1) r1t w1 + (1 - s2) r2t w2) / 2,
       w_true = ((1 - s1) r1t w1 - (1 - s2) r2t w2) / (2 l1t).

   These are linear in ``(w1, w2)``, hence in ``(v, w)``: piecewise linear in time with the union
   of the breakpoints of ``v`` and ``w``.

6. **Exact step** (:func:`actuator_step`). On each linear piece the pose of A advances by
   :func:`amigo_gym.model.fresnel.advance` (exact: speed and turn rate linear in time); the wheel angles
   advance by the exact integral of the (piecewise linear) wheel rates.

Sources
-------
The limits (speed, accelerations, decelerations) are those of the manufacturer's (Adept MobileRobots, formerly
ActivMedia) AmigoBot parameter file and MobileSim model of the AmigoBot-SH (``docs/model.md``). The ramp rule is
the project's model of the ARCOS firmware's velocity profile, not checked against an ARCOS manual or the robot.
``MAX_DELAY`` is the project's choice; the delay is in seconds, applied exactly (``docs/amigobot_v1.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model import fresnel
from amigo_gym.model.kinematics import Real, body_velocity_of, wheel_rates_of
from amigo_gym.model.numeric import any_array, where
from amigo_gym.model.params import RobotParams, check_range

#: largest actuation delay supported [s] (the project's choice: a few 0.1 s control cycles)
MAX_DELAY = 0.5
#: relative deviation of the true wheel radii and half track from nominal assumed by :func:`turn_rate_bound`
MAX_TRUE_DEVIATION = 0.25
#: number of linear pieces per step in :func:`actuator_step` (some of zero length): 9 inner breakpoints
PIECES = 10


@dataclass(frozen=True)
class ActuatorParams:
    """Speed ramps of the robot's firmware and the actuation delay.

    Attributes:
        acceleration: rate at which the translational speed ``|v|`` grows [m/s^2], in (0, 10].
            Manufacturer's parameter file / MobileSim model: 0.3 (= ``RobotParams.max_acceleration``).
        deceleration: rate at which ``|v|`` shrinks [m/s^2], in (0, 10]. Manufacturer: 0.75
            (= ``RobotParams.max_deceleration``).
        rot_acceleration: rate at which the rotational speed ``|w|`` grows [rad/s^2], in (0, 100].
            Manufacturer: 0.87.
        rot_deceleration: rate at which ``|w|`` shrinks [rad/s^2], in (0, 100]. Manufacturer: 2.5.
        delay: actuation delay [s], in [0, MAX_DELAY]: a command issued at time ``t_k`` takes effect
            at ``t_k + delay``. Default 0 (no public measurement; the environment chooses).

    Sources: the module docstring (``docs/model.md``, public data on the real robot).
    """

    acceleration: float = 0.3
    deceleration: float = 0.75
    rot_acceleration: float = 0.87
    rot_deceleration: float = 2.5
    delay: float = 0.0

    def __post_init__(self) -> None:
        o = "ActuatorParams"
        highs = {"acceleration": 10.0, "deceleration": 10.0, "rot_acceleration": 100.0, "rot_deceleration": 100.0}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "delay":
                v = check_range(o, f.name, value, 0.0, MAX_DELAY)
            else:
                v = check_range(o, f.name, value, 0.0, highs[f.name], low_open=True)
            object.__setattr__(self, f.name, v)


def clip_setpoints(w1c: Real, w2c: Real, nominal: RobotParams) -> tuple[Real, Real]:
    """Setpoints of wheel 1 (right) and 2 (left) [rad/s], columns, clipped to ``[-w_max, w_max]`` with ``w_max =
    nominal.max_wheel_rate`` (the robot the firmware believes in: 15 rad/s by default)."""
    return clip_setpoint(w1c, nominal.max_wheel_rate), clip_setpoint(w2c, nominal.max_wheel_rate)


def clip_setpoint(w: Real, w_max: float) -> Real:
    """One setpoint (float or column) clipped: ``min(max(w, -w_max), w_max)`` [rad/s] (a NaN float gives ``-w_max``,
    a NaN element NaN)."""
    return np.minimum(np.maximum(w, -w_max), w_max)


def wheel_rates_columns(v: Real, w: Real, robot: RobotParams) -> tuple[Real, Real]:
    """Wheel rates ``(alpha1dot, alpha2dot)`` [rad/s] rolling without slip for the speeds ``v`` [m/s], ``w`` [rad/s]
    (columns): ``((v + l1 w) / r1, (v - l1 w) / r2)`` of ``robot``, the inverse of ``body_velocity_columns``."""
    return wheel_rates_of(v, w, robot.l1, robot.r1, robot.r2)


class Ramp(NamedTuple):
    """One speed channel ramped over ``[0, T]`` (:func:`ramp`): three linear pieces, some of zero length.

    Pieces ``[0, t_a]`` (from ``u0`` with slope ``s_a``), ``[t_a, t_b]`` (from ``u_a`` with slope ``s_b``)
    and ``[t_b, T]`` (constant ``u_b``). ``0 <= t_a <= t_b <= T``; ``u_b`` is the value at ``T``.
    Times in [s]; values in the channel's unit ([m/s] or [rad/s]), slopes in that unit per second.
    """

    t_a: Real
    t_b: Real
    u_a: Real
    u_b: Real
    s_a: Real
    s_b: Real


def ramp(u0: Real, target: Real, accel: float, decel: float, duration: Real) -> Ramp:
    r"""The firmware's ramp of one speed ``u`` from ``u0`` towards ``target`` over ``[0, T]``, in closed form.

    ``|u|`` grows at ``accel`` and shrinks at ``decel``; a target of the other sign is reached by
    slowing to 0 first. With ``c`` the target:

    * ``u0 c < 0`` (reversing): ``u`` falls to 0 at rate ``D`` until ``t_z = |u0| / D``, then grows
      towards ``c`` at rate ``A``: it reaches ``c`` at ``t_r = t_z + |c| / A``;
    * otherwise ``t_z = 0`` and ``c`` is reached at ``t_r = |c - u0| / A`` when ``|c| > |u0|``,
      at ``t_r = |c - u0| / D`` when ``|c| <= |u0|``;
    * after ``t_r``, ``u = c``.

    So ``u(t) = u0 - sign(u0) D t`` on ``[0, t_z]``, ``u(t) = u_z + sign(c - u_z) R (t - t_z)`` on
    ``[t_z, t_r]`` (``u_z`` = 0 when reversing, else ``u0``; ``R`` = A or D as above), ``u(t) = c`` after;
    the breakpoints are clipped to ``T``.

    Args:
        u0: speed at ``t = 0`` (column). target: the command ``c`` (column).
        accel, decel: the rates ``A``, ``D`` > 0 [unit/s].
        duration: ``T >= 0`` [s] (column).

    Returns:
        :class:`Ramp` with ``t_a = min(t_z, T)``, ``t_b = min(t_r, T)``, the values at these times and the slopes.
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
    r"""A bound of the true turn rate ``|w_true|`` [rad/s] in :func:`actuator_step`.

    The ramps keep ``v`` and ``w`` between their start values and their (clipped) commands, so from
    any state reached from within the limits ``|v| <= V = (r1 + r2) w_max / 2`` and ``|w| <= V / l1``;
    then ``|w_i| <= 2 V / r_i`` and, with true radii at most ``(1 + deviation)`` times nominal and a
    true half track at least ``l1 / (1 + deviation)``,

    .. math:: |w_{true}| \le (1 + \delta)^2 \, 2 V / l_1

    (19.5 rad/s for the default robot and ``deviation = 0.25``). Slip only lowers it.
    """
    check_range("turn_rate_bound", "deviation", deviation, 0.0, 1.0)
    v_max = 0.5 * (nominal.r1 + nominal.r2) * nominal.max_wheel_rate
    return (1.0 + deviation) ** 2 * 2.0 * v_max / nominal.l1


def step_subintervals(dt: float, nominal: RobotParams, deviation: float = MAX_TRUE_DEVIATION) -> int:
    """``n_sub`` for :func:`amigo_gym.model.fresnel.advance` on the pieces of a step of ``dt`` [s].

    From the bound ``turn_rate_bound(nominal, deviation) * dt`` of the phase change on a piece (1 for
    ``dt = 0.1`` with the default robot). It depends on parameters only, never on the state, so that
    one robot and a batch use the same quadrature.
    """
    return fresnel.subintervals(turn_rate_bound(nominal, deviation) * dt)


# -- delay ---------------------------------------------------------------------------------------------


def delay_split(delay: Real, dt: float) -> tuple[int | NDArray[np.int64], Real]:
    """``(m, f)`` with ``delay = m dt + f``, ``0 <= f < dt`` (``f = fmod(delay, dt)``, exact; module docstring, item 4)
    for a delay [s] in ``[0, MAX_DELAY]`` (a column) and the step ``dt > 0`` [s]: ``m`` an int (int64 array for an
    array ``delay``), the switch time ``f`` [s] a column."""
    if isinstance(delay, np.ndarray):
        f_arr = np.fmod(delay, dt)
        return np.rint((delay - f_arr) / dt).astype(np.int64), f_arr
    f = math.fmod(delay, dt)
    return round((delay - f) / dt), f


def ring_length(dt: float, max_delay: float = MAX_DELAY) -> int:
    """Number of past commands to keep for delays up to ``max_delay`` [s] with step ``dt`` [s].

    ``m + 2`` with ``m`` the whole steps of ``max_delay`` (:func:`delay_split`, the floor of the exact
    quotient of the binary numbers: 4 for 0.5 / 0.1): the commands of steps ``k - m - 1`` and ``k - m``
    for every delay up to ``max_delay`` (``m`` grows with the delay).
    """
    check_range("ring_length", "dt", dt, 0.0, low_open=True)
    check_range("ring_length", "max_delay", max_delay, 0.0, MAX_DELAY)
    m, _ = delay_split(max_delay, dt)
    return int(m) + 2


def make_ring(length: int, w1c: Real, w2c: Real) -> NDArray[np.float64]:
    """A ring of ``length`` (:func:`ring_length`) commands, each ``(w1c, w2c)`` [rad/s] (what the robot did before the
    first step; columns ``()`` or ``(N,)``): float64 ``(length, 2)`` or ``(N, length, 2)``; slot ``j % length`` holds
    the command of step ``j``."""
    shape = np.broadcast_shapes(np.shape(w1c), np.shape(w2c))
    ring = np.empty((*shape, length, 2))
    ring[..., 0] = np.asarray(w1c)[..., None]
    ring[..., 1] = np.asarray(w2c)[..., None]
    return ring


def ring_write(ring: NDArray[np.float64], step: int, w1c: Real, w2c: Real) -> None:
    """Store the command ``(w1c, w2c)`` [rad/s] (columns matching the ring's leading shape) issued at ``step >= 0`` in
    its slot of ``ring`` (:func:`make_ring`), in place."""
    slot = ring_slot(step, ring.shape[-2])
    ring[..., slot, 0] = w1c
    ring[..., slot, 1] = w2c


def ring_slot(step: Any, length: int) -> Any:
    """The slot of the command issued at ``step`` in a ring of ``length`` commands: ``step % length`` (never < 0)."""
    return step % length


def ring_read_slots(step: Any, lag: Any, length: int) -> tuple[Any, Any]:
    """The slots ``(old, new)`` of the setpoints in effect during step ``step`` with a lag of ``lag`` whole steps: those
    of steps ``step - lag - 1`` and ``step - lag`` (ints or int columns)."""
    return ring_slot(step - lag - 1, length), ring_slot(step - lag, length)


def ring_read(ring: NDArray[np.float64], step: int, lag: int | NDArray[np.int64]) -> tuple[Real, Real, Real, Real]:
    """The setpoints in effect during step ``step``: those of steps ``step - lag - 1`` and ``step - lag``.

    Write the command of ``step`` (:func:`ring_write`) before reading.

    Args:
        ring: ``(length, 2)`` or ``(N, length, 2)`` with ``length >= lag + 2``.
        step: the step counter ``k``.
        lag: ``m`` from :func:`delay_split` (an int, or ``(N,)`` ints for a batch).

    Returns:
        ``(w1_old, w2_old, w1_new, w2_new)`` [rad/s]: floats for a ``(length, 2)`` ring, else ``(N,)`` arrays.

    Raises:
        ValueError: if the ring is too short for ``lag``.
    """
    length = ring.shape[-2]
    lags = lag if type(lag) is int else np.asarray(lag)  # one robot: no array arithmetic
    if np.any(lags + 2 > length) or np.any(lags < 0):
        raise ValueError(f"ring of {length} commands cannot serve a lag of {lag!r} steps (needs lag + 2)")
    i_old, i_new = ring_read_slots(step, lags, length)
    if ring.ndim == 2:
        (w1_old, w2_old), (w1_new, w2_new) = ring[int(i_old)].tolist(), ring[int(i_new)].tolist()
        return w1_old, w2_old, w1_new, w2_new
    rows = np.arange(ring.shape[0])
    old, new = ring[rows, i_old], ring[rows, i_new]
    return old[:, 0].copy(), old[:, 1].copy(), new[:, 0].copy(), new[:, 1].copy()


# -- the step ------------------------------------------------------------------------------------------


class ActuatorStep(NamedTuple):
    """Result of :func:`actuator_step` (columns).

    Attributes:
        x, y, beta: the new pose of A [m, m, rad] (heading not wrapped).
        w1, w2: the actual wheel rates at the end of the step [rad/s] (the new actuator state).
        dalpha1, dalpha2: wheel-angle increments over the step, ``int w_i dt`` [rad].
        distance: signed distance travelled by A over the step, ``int v_true dt`` [m]
            (its mean speed is ``distance / dt``).
        v_true, w_true: true speed of A [m/s] and turn rate [rad/s] at the end of the step.
    """

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
    x: Real,
    y: Real,
    beta: Real,
    w1: Real,
    w2: Real,
    w1c_old: Real,
    w2c_old: Real,
    w1c_new: Real,
    w2c_new: Real,
    t_switch: Real,
    dt: float,
    nominal: RobotParams,
    limits: ActuatorParams,
    r1_true: Real,
    r2_true: Real,
    l1_true: Real,
    slip1: Real = 0.0,
    slip2: Real = 0.0,
    n_sub: int | None = None,
) -> ActuatorStep:
    r"""One control step of the robot with its actuators, exact (the model: module docstring).

    Each speed channel is ramped twice (:func:`ramp`: towards the old, then the new command); the union of their
    breakpoints and ``t_s`` (9 times, sorted per robot) splits the step into :data:`PIECES` pieces (some of zero
    length, which change nothing) on which ``v`` and ``w`` are linear. On a piece of length ``L`` the pose advances by
    :func:`amigo_gym.model.fresnel.advance_nodes` of the true speeds (module docstring, item 5), the wheel angles by
    ``L (w_i + \dot w_i L / 2)`` and the distance by ``L (v_true + \dot v_true L / 2)``.

    Args:
        x, y, beta: pose of A at the start [m, m, rad].
        w1, w2: actual wheel rates at the start [rad/s] (the actuator state).
        w1c_old, w2c_old: setpoints in effect before the switch [rad/s] (unclipped is fine).
        w1c_new, w2c_new: setpoints in effect from the switch on [rad/s].
        t_switch: the switch time ``t_s`` in ``[0, dt]`` [s] (``f`` of :func:`delay_split`; 0 without delay).
        dt: the step [s], > 0.
        nominal: the robot the firmware believes in (radii, half track, ``max_wheel_rate``).
        limits: the ramp rates (its ``delay`` is not used here: pass ``t_switch`` and the right setpoints).
        r1_true, r2_true, l1_true: the true wheel radii and half track [m] (columns).
        slip1, slip2: slip fractions ``s_i`` in ``[0, 1)`` for this step [-] (columns).
        n_sub: quadrature sub-intervals per piece; default :func:`step_subintervals` ``(dt, nominal)``.

    Returns:
        :class:`ActuatorStep`. All inputs are columns (floats, or arrays that broadcast together);
        floats in, floats out; with any array input every output is an array of the broadcast shape.
        Not checked (for speed): ranges of ``t_switch``, slips and the true geometry.
    """
    if n_sub is None:
        n_sub = step_subintervals(dt, nominal)
    cols: tuple[Real, ...] = (
        x, y, beta, w1, w2, w1c_old, w2c_old, w1c_new, w2c_new, t_switch, r1_true, r2_true, l1_true, slip1, slip2
    )  # fmt: skip
    if any_array(*cols):  # columns: every input and output an array of the broadcast shape
        arrays = np.broadcast_arrays(*(np.asarray(c, dtype=np.float64) for c in cols))
        cols = tuple(np.array(a, dtype=np.float64) for a in arrays)
    else:
        cols = tuple(float(c) for c in cols)
    x, y, beta, w1, w2, w1c_old, w2c_old, w1c_new, w2c_new, t_s, r1t, r2t, l1t, s1, s2 = cols
    nn = fresnel.NODES * n_sub
    out = actuator_step_ws(
        [0.0] * SCRATCH, 0, [0.0] * (3 * PIECES * nn), 0, fresnel.node_table(n_sub), 0, nn,
        x, y, beta, w1, w2, w1c_old, w2c_old, w1c_new, w2c_new, t_s, dt,
        nominal.max_wheel_rate, nominal.l1, nominal.r1, nominal.r2, 2.0 * nominal.l1,
        limits.acceleration, limits.deceleration, limits.rot_acceleration, limits.rot_deceleration,
        r1t, r2t, l1t, s1, s2,
    )  # fmt: skip
    return ActuatorStep(*out)


# -- the step written once: floats, columns and the compiled step ----------------------------------------
# The step written once on a scratch buffer ``ws``: a list of floats (one robot) or of columns (a batch: the vector
# env's numpy route), or the workspace array of AmigoBot-v1's compiled step, which compiles these functions as they
# are (amigo_gym.sim._kernels_v1). Offsets from the scratch's start ``k``: per channel (v, then w) 7 knots,
# 6 values and 6 slopes, the 11 piece boundaries, then ``(vt, at, wt, alt, length)`` of each live piece (on columns:
# of each piece live in some row). Two steps differ between floats and columns, each a helper with a float form
# that the kernel compiles in its place (``amigo_gym.sim._kernels_v1``): the sort of the piece boundaries
# (:func:`sort_knots`) and the pose over the pieces (:func:`advance_pieces`).

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
    """Sort the floats ``ws[i0 : i0 + n]`` in place, ascending (an insertion sort: stable, as ``sorted()``): the float
    form of :func:`sort_knots`."""
    for i in range(i0 + 1, i0 + n):
        key = ws[i]
        j = i - 1
        while j >= i0 and key < ws[j]:
            ws[j + 1] = ws[j]
            j -= 1
        ws[j + 1] = key


def sort_knots(ws: Any, i0: int, n: int) -> None:
    """Sort ``ws[i0 : i0 + n]`` in place, ascending: row by row for a list of columns (``np.sort``; the same values as
    :func:`sort_knots_float`, which sorts floats and which the compiled step runs in its place)."""
    if not any_array(*ws[i0 : i0 + n]):
        sort_knots_float(ws, i0, n)
        return
    ws[i0 : i0 + n] = list(np.sort(np.stack(np.broadcast_arrays(*ws[i0 : i0 + n])), axis=0))


def advance_pieces(
    buf: Any,
    b: int,
    m: int,
    x: Any,
    y: Any,
    theta: Any,
    pieces: Any,
    p: int,
    n_pieces: int,
    nodes: Any,
    j: int,
    nn: int,
) -> tuple[Any, Any, Any]:
    """:func:`amigo_gym.model.fresnel.advance_nodes` of the pieces ``(v0, a, w0, alpha, t)`` at ``pieces[p + 5 q]``,
    a piece of length ``t <= 0`` (or NaN) leaving a row unchanged: on floats (every piece is live: its float form,
    which the compiled step runs) all pieces at once; on columns piece by piece, each advancing the rows where it is
    live (on those rows alone when they are fewer than half), the same bits per row."""
    if not any_array(x):  # floats (actuator_step makes every input a column when one is)
        return fresnel.advance_nodes(buf, b, m, x, y, theta, pieces, p, n_pieces, nodes, j, nn)
    for q in range(n_pieces):
        piece = pieces[p + 5 * q : p + 5 * q + 5]
        live = np.asarray(piece[4] > 0.0)
        if 2 * int(np.count_nonzero(live)) < live.size:  # few rows: the quadrature of the live rows alone
            x, y, theta = np.array(x), np.array(y), np.array(theta)
            rows = [np.asarray(c)[live] for c in (x, y, theta, *piece)]
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
    """One speed channel over the step, targets ``c_old`` on ``[0, t_s)``, ``c_new`` on ``[t_s, dt]`` (:func:`ramp`
    twice), into ``ws``: the 7 knots ``0 <= ... <= dt`` (0, 4 ramp breakpoints, ``t_s``, ``dt`` in order) at
    ``ws[k : k + 7]``, the value and slope at the start of each of the 6 pieces at ``ws[k + 7 : k + 13]`` and
    ``ws[k + 13 : k + 19]``; returns the value at ``dt``."""
    ta1, tb1, ua1, ub1, sa1, sb1 = ramp(u0, c_old, accel, decel, t_s)
    ta2, tb2, ua2, ub2, sa2, sb2 = ramp(ub1, c_new, accel, decel, dt - t_s)
    for i, knot in enumerate((0.0, ta1, tb1, t_s, np.minimum(t_s + ta2, dt), np.minimum(t_s + tb2, dt), dt)):
        ws[k + i] = knot
    for i, value in enumerate((u0, ua1, ub1, ub1, ua2, ub2)):
        ws[k + 7 + i] = value
    for i, slope in enumerate((sa1, sb1, 0.0, sa2, sb2, 0.0)):
        ws[k + 13 + i] = slope
    return ub2


def _evaluate_ws(ws: Any, k: int, t: Real, mid: Real) -> tuple[Real, Real]:
    """Value at ``t`` and slope of the piece of the channel at ``ws[k:]`` (:func:`_channel_ws`) that contains ``mid``
    (``t <= mid``, the same piece)."""
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
    ws: Any,
    k: int,
    buf: Any,
    b: int,
    nodes: fresnel.Buffer,
    node_at: int,
    nn: int,
    x: Real,
    y: Real,
    beta: Real,
    w1: Real,
    w2: Real,
    w1c_old: Real,
    w2c_old: Real,
    w1c_new: Real,
    w2c_new: Real,
    t_s: Real,
    dt: float,
    w_max: float,
    l1n: float,
    r1n: float,
    r2n: float,
    two_l1: float,
    accel: float,
    decel: float,
    rot_accel: float,
    rot_decel: float,
    r1t: Real,
    r2t: Real,
    l1t: Real,
    s1: Real,
    s2: Real,
) -> tuple[Real, Real, Real, Real, Real, Real, Real, Real, Real, Real]:
    """:func:`actuator_step` on floats (one robot) or columns of one shape (a batch; ``ws`` and ``buf`` lists): the
    float path, the column route and the compiled step of ``AmigoBot-v1`` run this one source.

    Args:
        ws: scratch of :data:`SCRATCH` entries from ``ws[k]`` (offsets :data:`SCRATCH_V` ...).
        buf, b: node buffer of ``3 PIECES nn`` entries from ``buf[b]`` (:func:`amigo_gym.model.fresnel.advance_nodes`;
            the compiled step's is on its stack).
        nodes, node_at, nn: the quadrature's ``nn = NODES n_sub`` nodes on [0, 1] from ``nodes[node_at]``, then
            their weights (:func:`amigo_gym.model.fresnel.node_table`).
        x ... t_s: as :func:`actuator_step` [m, m, rad, rad/s, ..., s]; dt: the step [s].
        w_max, l1n, r1n, r2n, two_l1: the nominal robot's wheel-rate limit [rad/s], half track, radii, ``2 l1`` [m].
        accel, decel, rot_accel, rot_decel: the ramps (:class:`ActuatorParams`).
        r1t, r2t, l1t, s1, s2: the true geometry [m] and the slips [-].

    Returns:
        the fields of :class:`ActuatorStep` as a tuple of floats.
    """
    # 1. commands (clip_setpoints, body_velocity_columns)
    vc_old, wc_old = body_velocity_of(clip_setpoint(w1c_old, w_max), clip_setpoint(w2c_old, w_max), r1n, r2n, two_l1)
    vc_new, wc_new = body_velocity_of(clip_setpoint(w1c_new, w_max), clip_setpoint(w2c_new, w_max), r1n, r2n, two_l1)
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
        # the nominal wheel rates p_i + q_i tau (wheel_rates_of) and the true body's vt + at tau, wt + alt tau:
        # vt = (g1 p1 + g2 p2) / 2, wt = (g1 p1 - g2 p2) / (2 l1t)
        p1 = (v + l1n * om) / r1n
        q1 = (a + l1n * al) / r1n
        p2 = (v - l1n * om) / r2n
        q2 = (a - l1n * al) / r2n
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
