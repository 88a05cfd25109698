"""Direct kinematics of the AmigoBot: closed-form, batched functions (``docs/model.md``).

``pose = (x_A, y_A, beta)``: the axle midpoint A [m] and the heading [rad], ground frame z up. Wheel 1 is the
right wheel, 2 the left; wheel rates ``w = (alpha1dot, alpha2dot)`` [rad/s], positive forward. Array functions take
leading batch axes (pose ``(..., 3)``, rates ``(..., 2)``); column functions (``*_columns``, ``*_of``,
:func:`arc_step`) take floats or arrays of any shape (floats in, floats out), and the pure-arithmetic ones are also
compiled (numba).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.params import RobotParams

Array = NDArray[np.float64]


#: one column of a batch: a float (``np.float64`` included) or a float64 array of any shape
Real: TypeAlias = float | NDArray[np.float64]


def col_sin(x: Real) -> Real:
    """``np.sin(x)``; a Python float for a scalar ``x``."""
    return np.sin(x) if isinstance(x, np.ndarray) else float(np.sin(x))


def col_cos(x: Real) -> Real:
    """``np.cos(x)``; a Python float for a scalar ``x``."""
    return np.cos(x) if isinstance(x, np.ndarray) else float(np.cos(x))


def col_tan(x: Real) -> Real:
    """``np.tan(x)``; a Python float for a scalar ``x``."""
    return np.tan(x) if isinstance(x, np.ndarray) else float(np.tan(x))


def half_tan_cos_sin(t: Real) -> tuple[Real, Real]:
    """``(cos x, sin x)`` from ``t = tan(x / 2)``: ``((1 - t^2) / (1 + t^2), 2 t / (1 + t^2))``."""
    t2 = t * t
    r = 1.0 / (1.0 + t2)
    return (1.0 - t2) * r, (t + t) * r


def arc_from_tangents(
    x: Real, y: Real, v_a: Real, dt: Real, h: Real, t_h: Real, t_m: Real
) -> tuple[Any, Any, Any, Any]:
    """:func:`arc_step`'s ``(x', y', cos beta', sin beta')`` from ``t_h = tan(h / 2)`` and ``t_m = tan(m / 2)``."""
    cos_h, sin_h = half_tan_cos_sin(t_h)
    cos_mid, sin_mid = half_tan_cos_sin(t_m)
    zero = h == 0.0  # sin(h) / h, 1 at h = 0
    chord = v_a * dt * ((sin_h + zero) / (h + zero))
    return (
        x + chord * cos_mid,
        y + chord * sin_mid,
        cos_mid * cos_h - sin_mid * sin_h,
        sin_mid * cos_h + cos_mid * sin_h,
    )


def body_velocity_of(w1: Real, w2: Real, r1: Real, r2: Real, two_l1: Real) -> tuple[Any, Any]:
    """``(v_A, betadot)`` [m/s, rad/s] of wheel rates [rad/s]: ``((r1 w1 + r2 w2) / 2, (r1 w1 - r2 w2) / two_l1)``."""
    u1 = r1 * w1
    u2 = r2 * w2
    return 0.5 * (u1 + u2), (u1 - u2) / two_l1


def wheel_rates_of(v_a: Real, betadot: Real, l1: Real, r1: Real, r2: Real) -> tuple[Any, Any]:
    """The wheel rates [rad/s] ``((v_A + l1 betadot) / r1, (v_A - l1 betadot) / r2)``."""
    lw = l1 * betadot
    return (v_a + lw) / r1, (v_a - lw) / r2


def castor_rate_float(v_a: float, betadot: float, l5: float, r3: float) -> float:
    """The castor's rate [rad/s] for floats: ``sign(v_A) sqrt(l5^2 betadot^2 + v_A^2) / r3``."""
    lb = l5 * betadot
    return math.copysign(math.sqrt(lb * lb + v_a * v_a), v_a) / r3


def advance_angle(alpha: Real, rate: Real, dt: float) -> Any:
    """A wheel's angle [rad] after ``dt`` [s] at ``rate`` [rad/s]: ``alpha + rate dt``."""
    return alpha + rate * dt


#: ``np.sqrt(x)``; ``math.sqrt(x)`` for a scalar ``x`` (the same value: IEEE 754 rounds sqrt exactly)
col_sqrt = np.sqrt


def sinc(x: ArrayLike) -> Array:
    """Unnormalised sinc, ``sin(x) / x`` with value 1 at 0, elementwise."""
    x = np.asarray(x, dtype=np.float64)
    zero = x == 0.0
    return np.asarray((np.sin(x) + zero) / (x + zero))


def body_velocity_columns(w1: Real, w2: Real, robot: RobotParams) -> tuple[Real, Real]:
    """Column form of :func:`body_velocity`: ``(v_A, betadot)`` from the wheel rates ``w1``, ``w2`` [rad/s]."""
    return body_velocity_of(w1, w2, robot.r1, robot.r2, 2.0 * robot.l1)


def castor_rate_columns(v_a: Real, betadot: Real, robot: RobotParams) -> Real:
    """Column form of :func:`castor_rate` (the sign of ``-0.0`` is negative)."""
    if not (isinstance(v_a, np.ndarray) or isinstance(betadot, np.ndarray)):
        return castor_rate_float(v_a, betadot, robot.l5, robot.r3)
    lb = robot.l5 * betadot
    out: Real = np.copysign(col_sqrt(lb * lb + v_a * v_a), v_a) / robot.r3
    return out


class ArcStep(NamedTuple):
    """Result of :func:`arc_step`: the new pose, with the cosine and sine of its heading."""

    x: Real
    y: Real
    beta: Real
    cos_beta: Real
    sin_beta: Real


def arc_step(x: Real, y: Real, beta: Real, v_a: Real, betadot: Real, dt: Real, with_heading: bool = True) -> ArcStep:
    """Column form of :func:`step_pose` from ``v_a`` [m/s], ``betadot`` [rad/s] held over ``dt`` [s]: an
    :class:`ArcStep`, ``cos beta'``, ``sin beta'`` NaN unless ``with_heading``. With ``h = betadot dt / 2``,
    ``m = beta + h``: ``(x', y') = (x, y) + v_A dt (sin h / h) (cos m, sin m)``, ``beta' = beta + 2h``."""
    db = betadot * dt
    h = 0.5 * db
    x1, y1, cos_b, sin_b = arc_from_tangents(x, y, v_a, dt, h, col_tan(0.5 * h), col_tan(0.5 * (beta + h)))
    if not with_heading:
        cos_b = sin_b = math.nan
    return ArcStep(x1, y1, beta + db, cos_b, sin_b)


def pack(*columns: Real) -> Array:
    """Stack columns along a new last axis (broadcast against each other): ``(..., len(columns))``."""
    out = np.empty((*np.broadcast_shapes(*(np.shape(c) for c in columns)), len(columns)))
    for i, c in enumerate(columns):
        out[..., i] = c
    return out


def body_velocity(w: ArrayLike, robot: RobotParams) -> tuple[Array, Array]:
    """Speed of A and turn rate ``(v_A [m/s], betadot [rad/s])``, each ``(...)``, of wheel rates ``w`` ``(..., 2)``
    [rad/s]: ``v_A = (r1 w1 + r2 w2) / 2``, ``betadot = (r1 w1 - r2 w2) / (2 l1)``."""
    w = np.asarray(w, dtype=np.float64)
    v, b = body_velocity_columns(w[..., 0], w[..., 1], robot)
    return np.asarray(v), np.asarray(b)


def wheel_rates(v_a: ArrayLike, betadot: ArrayLike, robot: RobotParams) -> Array:
    """Wheel rates ``(..., 2)`` [rad/s] rolling without slip at ``v_A`` [m/s] and ``betadot`` [rad/s], ``(...)``:
    ``r1 w1 = v_A + l1 betadot``, ``r2 w2 = v_A - l1 betadot``."""
    v = np.asarray(v_a, dtype=np.float64)
    b = np.asarray(betadot, dtype=np.float64)
    return pack(*wheel_rates_of(v, b, robot.l1, robot.r1, robot.r2))


def castor_rate(v_a: ArrayLike, betadot: ArrayLike, robot: RobotParams) -> Array:
    """Rolling rate ``(...)`` [rad/s] of the self-aligned castor: ``sign(v_A) sqrt(l5^2 betadot^2 + v_A^2) / r3``."""
    v = np.asarray(v_a, dtype=np.float64)
    b = np.asarray(betadot, dtype=np.float64)
    return np.asarray(castor_rate_columns(v + 0.0, b, robot))  # + 0.0: positive for v_A = -0.0 too


def h_from_a(x_a: Real, y_a: Real, cos_beta: Real, sin_beta: Real, l3: Real) -> tuple[Any, Any]:
    """Point H, ``l3`` [m] ahead of A (paper eq. 4): ``(x_A + l3 cos beta, y_A + l3 sin beta)``; columns."""
    return x_a + l3 * cos_beta, y_a + l3 * sin_beta


def a_from_h(x_h: Real, y_h: Real, cos_beta: Real, sin_beta: Real, l3: Real) -> tuple[Real, Real]:
    """Point A, ``l3`` behind H: ``(x_H - l3 cos beta, y_H - l3 sin beta)``; columns."""
    return x_h - l3 * cos_beta, y_h - l3 * sin_beta


def h_position(pose: ArrayLike, robot: RobotParams) -> Array:
    """Ground point H ``(..., 2)`` [m] of poses ``(..., 3)``, ``l3`` ahead of A (paper eq. 4)."""
    p = np.asarray(pose, dtype=np.float64)
    b = p[..., 2]
    return pack(*h_from_a(p[..., 0], p[..., 1], np.cos(b), np.sin(b), robot.l3))


def contact_points(pose: ArrayLike, robot: RobotParams) -> tuple[Array, Array]:
    """Contact points ``(K, L)``, each ``(..., 2)`` [m], of wheel 1 (right) and 2 (left) (paper eqs 14, 22):
    ``K = A + l1 (sin b, -cos b)``, ``L = A - l1 (sin b, -cos b)``."""
    p = np.asarray(pose, dtype=np.float64)
    side = pack(np.sin(p[..., 2]), -np.cos(p[..., 2])) * robot.l1
    return p[..., :2] + side, p[..., :2] - side


def castor_position(pose: ArrayLike, robot: RobotParams) -> Array:
    """Ground position of the castor swivel, ``l5`` behind A on the body axis: ``(..., 2)`` [m]."""
    p = np.asarray(pose, dtype=np.float64)
    b = p[..., 2]
    return pack(p[..., 0] - robot.l5 * np.cos(b), p[..., 1] - robot.l5 * np.sin(b))


def step_pose(pose: ArrayLike, w: ArrayLike, dt: ArrayLike, robot: RobotParams) -> Array:
    """Exact pose ``(..., 3)`` after ``dt`` [s] of ``pose`` ``(..., 3)`` with wheel rates ``w`` ``(..., 2)`` [rad/s]
    held (heading not wrapped): ``d beta = betadot dt``, ``d A = v_A dt sinc(d beta / 2) (cos, sin)(beta + d beta / 2)``
    (:func:`arc_step`)."""
    p = np.asarray(pose, dtype=np.float64)
    v, bdot = body_velocity(w, robot)
    new = arc_step(p[..., 0], p[..., 1], p[..., 2], v, bdot, np.asarray(dt, dtype=np.float64), with_heading=False)
    return pack(new.x, new.y, new.beta)


class SteadyCircle(NamedTuple):
    """Steady state of H on a circle (:func:`circle_steady_state`): ``radius_a`` [m], ``betadot`` [rad/s],
    ``heading_lag`` [rad], ``wheel_rates`` ``(..., 2)`` and ``castor_rate`` [rad/s], ``speed_h = v_A R / R_A`` [m/s]."""

    radius_a: Array
    betadot: Array
    heading_lag: Array
    wheel_rates: Array
    castor_rate: Array
    speed_h: Array


def circle_steady_state(radius: ArrayLike, v_a: ArrayLike, robot: RobotParams, direction: int = 1) -> SteadyCircle:
    """Steady state of H on a circle of radius ``R`` [m] with A at constant speed ``v_A`` [m/s], ``direction`` ``d``
    +1 (left turn) or -1: ``R_A = sqrt(R^2 - l3^2)``, ``betadot = d v_A / R_A``, ``theta - beta = d atan(l3 / R_A)``;
    ``ValueError`` unless ``R > l3``."""
    r = np.asarray(radius, dtype=np.float64)
    if np.any(~(r > robot.l3)):
        raise ValueError(f"radius must exceed l3 = {robot.l3} m for a steady state, got {radius!r}")
    v = np.asarray(v_a, dtype=np.float64)
    ra = np.sqrt(r * r - robot.l3**2)
    bd = direction * v / ra
    return SteadyCircle(
        radius_a=ra,
        betadot=bd,
        heading_lag=direction * np.arctan2(robot.l3, ra),
        wheel_rates=wheel_rates(v, bd, robot),
        castor_rate=castor_rate(v, bd, robot),
        speed_h=v * r / ra,
    )
