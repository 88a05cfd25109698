"""Direct kinematics of the AmigoBot: closed-form, batched functions.

Conventions (``docs/model.md``): ground frame 0 with z up; ``pose = (x_A, y_A, beta)``, the axle midpoint A
[m] and the heading beta [rad]. Wheel 1 is the right wheel (contact K = A + l1 (sin b, -cos b)), wheel 2 the
left; wheel angles ``alpha1..3`` [rad] grow moving forward; wheel rates ``w = (alpha1dot, alpha2dot)`` [rad/s].

Array functions take one item or a batch with leading axes (pose ``(..., 3)``, rates ``(..., 2)``, speeds
``(...)``) and return the same leading axes. Column functions (``*_columns``, ``*_of``, :func:`arc_step`) take
each coordinate as a float or an array of any shape; the pure-arithmetic ones are also compiled by
:mod:`amigo_gym.sim` with numba. Nothing integrates numerically: :func:`step_pose` is exact for rates held
over a step of any ``dt``.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Protocol, TypeAlias, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


class Geometry(Protocol):
    """The robot's geometry [m] as read here (:class:`amigo_gym.model.params.RobotParams` provides it)."""

    @property
    def l1(self) -> float: ...
    @property
    def l3(self) -> float: ...
    @property
    def l5(self) -> float: ...
    @property
    def r1(self) -> float: ...
    @property
    def r2(self) -> float: ...
    @property
    def r3(self) -> float: ...


#: one column of a batch: a float (``np.float64`` included) or a float64 array of any shape
Real: TypeAlias = float | NDArray[np.float64]


# Column math: numpy's functions, a Python float for a scalar argument.


def col_sin(x: Real) -> Real:
    """``np.sin(x)``; a Python float for a scalar ``x``."""
    return np.sin(x) if isinstance(x, np.ndarray) else float(np.sin(x))


def col_cos(x: Real) -> Real:
    """``np.cos(x)``; a Python float for a scalar ``x``."""
    return np.cos(x) if isinstance(x, np.ndarray) else float(np.cos(x))


def col_tan(x: Real) -> Real:
    """``np.tan(x)``; a Python float for a scalar ``x``."""
    return np.tan(x) if isinstance(x, np.ndarray) else float(np.tan(x))


def cos_sin(x: Real) -> tuple[Real, Real]:
    r"""``(cos x, sin x)`` from one tangent of the half angle:

    .. math:: t = \tan\frac{x}{2}, \qquad \cos x = \frac{1 - t^2}{1 + t^2}, \qquad \sin x = \frac{2t}{1 + t^2}

    Within about 2e-16 of ``np.cos``, ``np.sin`` for any finite ``x``.
    """
    return half_tan_cos_sin(col_tan(0.5 * x))


# Pure arithmetic on floats or arrays alike, in numba's subset (compiled by amigo_gym.sim).


def half_tan_cos_sin(t: Real) -> tuple[Real, Real]:
    r"""``(cos x, sin x)`` from ``t = tan(x / 2)``: ``((1 - t^2) / (1 + t^2), 2 t / (1 + t^2))`` (:func:`cos_sin`)."""
    t2 = t * t
    r = 1.0 / (1.0 + t2)
    return (1.0 - t2) * r, (t + t) * r


@overload
def arc_from_tangents(
    x: float, y: float, v_a: float, dt: float, h: float, t_h: float, t_m: float
) -> tuple[float, float, float, float]: ...
@overload
def arc_from_tangents(
    x: Real, y: Real, v_a: Real, dt: Real, h: Real, t_h: Real, t_m: Real
) -> tuple[Real, Real, Real, Real]: ...
def arc_from_tangents(
    x: Real, y: Real, v_a: Real, dt: Real, h: Real, t_h: Real, t_m: Real
) -> tuple[Real, Real, Real, Real]:
    r"""The arc step of :func:`arc_step` from ``t_h = tan(h / 2)`` (``h = betadot dt / 2``) and
    ``t_m = tan(m / 2)`` (``m = beta + h``).

    .. math:: x' = x + c \cos m,\quad y' = y + c \sin m,\quad c = v_A\,dt\,\frac{\sin h}{h},\quad
        \cos\beta' = \cos m\cos h - \sin m\sin h,\quad \sin\beta' = \sin m\cos h + \cos m\sin h

    Returns:
        ``(x', y', cos beta', sin beta')`` [m, m, -, -].
    """
    cos_h, sin_h = half_tan_cos_sin(t_h)
    cos_mid, sin_mid = half_tan_cos_sin(t_m)
    zero = h == 0.0  # sin(h) / h, 1 at h = 0 (adds 1 to both sides there; exact elsewhere)
    chord = v_a * dt * ((sin_h + zero) / (h + zero))
    return (
        x + chord * cos_mid,
        y + chord * sin_mid,
        cos_mid * cos_h - sin_mid * sin_h,
        sin_mid * cos_h + cos_mid * sin_h,
    )


@overload
def body_velocity_of(w1: float, w2: float, r1: float, r2: float, two_l1: float) -> tuple[float, float]: ...
@overload
def body_velocity_of(w1: Real, w2: Real, r1: Real, r2: Real, two_l1: Real) -> tuple[Real, Real]: ...
def body_velocity_of(w1: Real, w2: Real, r1: Real, r2: Real, two_l1: Real) -> tuple[Real, Real]:
    r"""``(v_A, betadot)`` [m/s, rad/s] from the wheel rates [rad/s]: ``v_A = (r_1 w_1 + r_2 w_2) / 2``,
    ``betadot = (r_1 w_1 - r_2 w_2) / (2 l_1)`` (``two_l1`` is ``2 l_1`` [m])."""
    u1 = r1 * w1
    u2 = r2 * w2
    return 0.5 * (u1 + u2), (u1 - u2) / two_l1


@overload
def wheel_rates_of(v_a: float, betadot: float, l1: float, r1: float, r2: float) -> tuple[float, float]: ...
@overload
def wheel_rates_of(v_a: Real, betadot: Real, l1: Real, r1: Real, r2: Real) -> tuple[Real, Real]: ...
def wheel_rates_of(v_a: Real, betadot: Real, l1: Real, r1: Real, r2: Real) -> tuple[Real, Real]:
    r"""The wheel rates [rad/s] of a body velocity: ``w_1 = (v_A + l_1 betadot) / r_1``,
    ``w_2 = (v_A - l_1 betadot) / r_2`` (the inverse of :func:`body_velocity_of`)."""
    lw = l1 * betadot
    return (v_a + lw) / r1, (v_a - lw) / r2


def castor_rate_float(v_a: float, betadot: float, l5: float, r3: float) -> float:
    r"""The castor wheel's rate [rad/s] for floats: ``sign(v_A) sqrt(l_5^2 betadot^2 + v_A^2) / r_3``
    (:func:`castor_rate_columns`)."""
    lb = l5 * betadot
    return math.copysign(math.sqrt(lb * lb + v_a * v_a), v_a) / r3


@overload
def advance_angle(alpha: float, rate: float, dt: float) -> float: ...
@overload
def advance_angle(alpha: NDArray[np.float64], rate: Real, dt: float) -> NDArray[np.float64]: ...
@overload
def advance_angle(alpha: Real, rate: Real, dt: float) -> Real: ...
def advance_angle(alpha: Real, rate: Real, dt: float) -> Real:
    r"""A wheel's angle [rad] after ``dt`` [s] at ``rate`` [rad/s]: :math:`\alpha + \dot\alpha\, dt`."""
    return alpha + rate * dt


#: ``np.sqrt(x)``; ``math.sqrt(x)`` for a scalar ``x`` (the same value: IEEE 754 rounds sqrt exactly)
col_sqrt = np.sqrt


def sinc(x: ArrayLike) -> Array:
    """Unnormalised sinc, ``sin(x) / x`` with value 1 at 0, elementwise [-] (``x == 0`` adds 1 to both sides)."""
    x = np.asarray(x, dtype=np.float64)
    zero = x == 0.0
    return np.asarray((np.sin(x) + zero) / (x + zero))


def body_velocity_columns(w1: Real, w2: Real, robot: Geometry) -> tuple[Real, Real]:
    """Column form of :func:`body_velocity`: ``(v_A, betadot)`` from the wheel rates ``w1``, ``w2`` [rad/s]."""
    return body_velocity_of(w1, w2, robot.r1, robot.r2, 2.0 * robot.l1)


def castor_rate_columns(v_a: Real, betadot: Real, robot: Geometry) -> Real:
    """Column form of :func:`castor_rate`: ``sign(v_A) sqrt(l5^2 betadot^2 + v_A^2) / r3`` [rad/s]
    (the sign of ``-0.0`` is negative)."""
    if not (isinstance(v_a, np.ndarray) or isinstance(betadot, np.ndarray)):
        return castor_rate_float(v_a, betadot, robot.l5, robot.r3)
    lb = robot.l5 * betadot
    out: Real = np.copysign(col_sqrt(lb * lb + v_a * v_a), v_a) / robot.r3
    return out


class ArcStep(NamedTuple):
    """Result of :func:`arc_step`: the new pose as columns, with the cosine and sine of its heading."""

    x: Real
    y: Real
    beta: Real
    cos_beta: Real
    sin_beta: Real


def arc_step(x: Real, y: Real, beta: Real, v_a: Real, betadot: Real, dt: Real, with_heading: bool = True) -> ArcStep:
    r"""Column form of :func:`step_pose`, with the cosine and sine of the new heading.

    With ``h = betadot dt / 2`` and the mid-step heading ``m = beta + h``:

    .. math::
        x' = x + c \cos m, \quad y' = y + c \sin m, \quad \beta' = \beta + 2h,
        \qquad c = v_A\,dt\,\frac{\sin h}{h}

    ``cos``/``sin`` of ``m`` and ``h`` each come from one half-angle tangent (:func:`cos_sin`); ``sin(h)/h`` is 1
    at ``h = 0``.

    Args:
        x, y, beta: the pose [m, m, rad].
        v_a, betadot: speed of A [m/s] and turn rate [rad/s], held over the step.
        dt: step [s].
        with_heading: compute ``cos(beta')``, ``sin(beta')`` (else NaN).

    Returns:
        :class:`ArcStep` ``(x', y', beta', cos beta', sin beta')``; ``beta'`` is not wrapped.
    """
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


def body_velocity(w: ArrayLike, robot: Geometry) -> tuple[Array, Array]:
    r"""Speed of A and turn rate ``(v_A [m/s], betadot [rad/s])``, each ``(...)``, from wheel rates ``w``
    ``(..., 2)`` [rad/s] (right, left); the inverse of :func:`wheel_rates`:

    .. math::
        v_A = \frac{r_1 \dot\alpha_1 + r_2 \dot\alpha_2}{2}, \qquad
        \dot\beta = \frac{r_1 \dot\alpha_1 - r_2 \dot\alpha_2}{2 l_1}
    """
    w = np.asarray(w, dtype=np.float64)
    v, b = body_velocity_columns(w[..., 0], w[..., 1], robot)
    return np.asarray(v), np.asarray(b)


def wheel_rates(v_a: ArrayLike, betadot: ArrayLike, robot: Geometry) -> Array:
    r"""Wheel rates ``(..., 2)`` [rad/s] rolling without slip for ``v_A`` [m/s] and ``betadot`` [rad/s] of shape
    ``(...)`` (docs/model.md, system 29):

    .. math::
        r_1 \dot\alpha_1 = v_A + l_1 \dot\beta, \qquad r_2 \dot\alpha_2 = v_A - l_1 \dot\beta
    """
    v = np.asarray(v_a, dtype=np.float64)
    b = np.asarray(betadot, dtype=np.float64)
    return pack(*wheel_rates_of(v, b, robot.l1, robot.r1, robot.r2))


def castor_rate(v_a: ArrayLike, betadot: ArrayLike, robot: Geometry) -> Array:
    r"""Rolling rate ``alpha3dot`` ``(...)`` [rad/s] of the self-aligned castor (system 29), signed like ``v_A``:

    .. math:: r_3 \dot\alpha_3 = \sqrt{l_5^2 \dot\beta^2 + v_A^2}
    """
    v = np.asarray(v_a, dtype=np.float64)
    b = np.asarray(betadot, dtype=np.float64)
    return np.asarray(castor_rate_columns(v + 0.0, b, robot))  # + 0.0: positive for v_A = -0.0 too


@overload
def h_from_a(x_a: float, y_a: float, cos_beta: float, sin_beta: float, l3: float) -> tuple[float, float]: ...
@overload
def h_from_a(x_a: Real, y_a: Real, cos_beta: Real, sin_beta: Real, l3: Real) -> tuple[Real, Real]: ...
def h_from_a(x_a: Real, y_a: Real, cos_beta: Real, sin_beta: Real, l3: Real) -> tuple[Real, Real]:
    """Point H, ``l3`` [m] ahead of A along the heading (paper eq. 4):
    ``(x_A + l3 cos beta, y_A + l3 sin beta)``; columns. Inverse of :func:`a_from_h`."""
    return x_a + l3 * cos_beta, y_a + l3 * sin_beta


def a_from_h(x_h: Real, y_h: Real, cos_beta: Real, sin_beta: Real, l3: float) -> tuple[Real, Real]:
    """Point A from point H in column form: A lies ``l3`` behind H, ``(x_H - l3 cos beta, y_H - l3 sin beta)``."""
    return x_h - l3 * cos_beta, y_h - l3 * sin_beta


def h_position(pose: ArrayLike, robot: Geometry) -> Array:
    """Ground point H ``(..., 2)`` [m] of poses ``(..., 3)``, ``l3`` ahead of A (paper eq. 4):
    ``(x_A + l3 cos b, y_A + l3 sin b)``; its height ``r1 - l4`` is constant."""
    p = np.asarray(pose, dtype=np.float64)
    b = p[..., 2]
    return pack(*h_from_a(p[..., 0], p[..., 1], np.cos(b), np.sin(b), robot.l3))


def contact_points(pose: ArrayLike, robot: Geometry) -> tuple[Array, Array]:
    """Contact points ``(K, L)``, each ``(..., 2)`` [m], of wheel 1 (right) and 2 (left) (paper eqs 14, 22):
    ``K = A + l1 (sin b, -cos b)``, ``L = A - l1 (sin b, -cos b)``."""
    p = np.asarray(pose, dtype=np.float64)
    side = pack(np.sin(p[..., 2]), -np.cos(p[..., 2])) * robot.l1
    return p[..., :2] + side, p[..., :2] - side


def castor_position(pose: ArrayLike, robot: Geometry) -> Array:
    """Ground position of the castor swivel, ``l5`` behind A on the body axis: ``(..., 2)`` [m]."""
    p = np.asarray(pose, dtype=np.float64)
    b = p[..., 2]
    return pack(p[..., 0] - robot.l5 * np.cos(b), p[..., 1] - robot.l5 * np.sin(b))


def step_pose(pose: ArrayLike, w: ArrayLike, dt: ArrayLike, robot: Geometry) -> Array:
    r"""Exact pose after ``dt`` with wheel rates ``w`` held (A moves on a circular arc or a line):

    .. math::
        \Delta\beta = \dot\beta\,dt, \qquad
        \Delta \mathbf{r}_A = v_A\,dt\,\operatorname{sinc}\!\left(\tfrac{\Delta\beta}{2}\right)
        \begin{pmatrix}\cos(\beta + \Delta\beta/2)\\ \sin(\beta + \Delta\beta/2)\end{pmatrix}

    with ``(v_A, betadot)`` from :func:`body_velocity`; evaluated by :func:`arc_step`. The heading is not wrapped.

    Args:
        pose: ``(..., 3)`` as ``(x_A, y_A, beta)`` [m, m, rad].
        w: wheel rates ``(..., 2)`` [rad/s] (broadcast against ``pose``).
        dt: step [s], scalar or ``(...)``.
        robot: geometry.

    Returns:
        new pose ``(..., 3)``.
    """
    p = np.asarray(pose, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)
    v, bdot = body_velocity_columns(w[..., 0], w[..., 1], robot)
    new = arc_step(p[..., 0], p[..., 1], p[..., 2], v, bdot, np.asarray(dt, dtype=np.float64), with_heading=False)
    return pack(new.x, new.y, new.beta)


class SteadyCircle(NamedTuple):
    """Steady state of H on a circle (:func:`circle_steady_state`; docs/model.md).

    Attributes:
        radius_a: radius of A's circle ``R_A = sqrt(R^2 - l3^2)`` [m].
        betadot: turn rate ``d v_A / R_A`` [rad/s].
        heading_lag: ``theta - beta = d atan(l3 / R_A)`` [rad].
        wheel_rates: ``(alpha1dot, alpha2dot)`` [rad/s], ``(..., 2)``; castor_rate: ``alpha3dot`` [rad/s].
        speed_h: speed of H, ``v_A R / R_A`` [m/s].
    """

    radius_a: Array
    betadot: Array
    heading_lag: Array
    wheel_rates: Array
    castor_rate: Array
    speed_h: Array


def circle_steady_state(radius: ArrayLike, v_a: ArrayLike, robot: Geometry, direction: int = 1) -> SteadyCircle:
    r"""Steady state of H on a circle of radius ``R`` [m] with A at constant speed ``v_A`` [m/s]:

    .. math::
        R_A = \sqrt{R^2 - l_3^2},\quad \dot\beta = d\,\frac{v_A}{R_A},\quad
        \theta - \beta = d \arctan\frac{l_3}{R_A}

    with the wheel rates of :func:`wheel_rates`; ``direction`` ``d`` is +1 (left turn) or -1 (right).

    Raises:
        ValueError: unless ``R > l3``.
    """
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
