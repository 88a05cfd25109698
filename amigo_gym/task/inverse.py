r"""The analytic inverse solution: wheel angles and rates that make H follow a path exactly.

Given a path of H with tangent angle ``theta(s)`` at arc length ``s`` (:mod:`amigo_gym.paths`) and a
prescribed speed profile ``v_A(t)`` of the axle midpoint A, the paper's eqs (7)–(10) reduce to a
two-state ODE (``docs/model.md``, "The path of H and the inverse problem"):

.. math::
    \dot s = \frac{v_A}{\cos(\theta(s) - \beta)}, \qquad
    \dot\beta = \frac{v_A \tan(\theta(s) - \beta)}{l_3}.

The wheel rates follow from the rolling constraints (system 29, :func:`~amigo_gym.model.kinematics.wheel_rates`
and :func:`~amigo_gym.model.kinematics.castor_rate`), the wheel angles by integration: :func:`solve_inverse`
integrates ``(s, psi = theta(s) - beta, x_A, y_A, alpha1, alpha2, alpha3)`` with SciPy's DOP853 (``r_H`` of the
integrated pose checks independently that H stays on the path), split at every kink of the speed profile and every
curvature jump of the path (an ODE event in ``s``) so that each piece has a smooth right-hand side.

The ODE is singular where ``|theta - beta| = pi/2``; for forward motion the heading error decays, so a
start with ``|theta(s0) - beta0| < pi/2`` is well defined (the paper's start is ``beta0 = theta(0)``).

The closed-form steady state on a circle is :func:`amigo_gym.model.kinematics.circle_steady_state`,
re-exported here.

Units: metres, radians, seconds throughout; arrays of an :class:`InverseSolution` have shape ``(T,)``.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.io import atomic_save
from amigo_gym.model.kinematics import a_from_h, castor_rate, h_position, wheel_rates
from amigo_gym.model.kinematics import circle_steady_state as circle_steady_state
from amigo_gym.model.params import RobotParams, check_range
from amigo_gym.paths import CirclePath, ManoeuvrePath, wrap_angle

Array = NDArray[np.float64]
AnyPath = CirclePath | ManoeuvrePath

#: largest number of time-grid points accepted (about 120 MB of output columns)
MAX_GRID_POINTS = 1_000_000

#: the project's choice for the paper's manoeuvre (the paper gives no timing): gentle start and stop,
#: well inside the real robot's limits (0.3 m/s^2 and 0.75 m/s^2), so that the phases are visible
MANOEUVRE_ACCEL = 0.1
MANOEUVRE_DECEL = 0.2
MANOEUVRE_T_START = 1.0
MANOEUVRE_LAPS = 1.0


class SpeedProfile(Protocol):
    """A prescribed speed of A, ``v_A(t) >= 0`` [m/s], piecewise smooth in time ``t`` [s]."""

    @property
    def peak_speed(self) -> float:
        """Largest value of ``v_A`` [m/s]."""
        ...

    def __call__(self, t: ArrayLike) -> Array:
        """``v_A(t)`` [m/s], same shape as ``t``; right-continuous at a jump."""
        ...

    def breakpoints(self) -> tuple[float, ...]:
        """Times [s] where ``v_A`` or its derivative is discontinuous, increasing."""
        ...


@dataclass(frozen=True)
class ConstantSpeed:
    """``v_A(t) = speed`` for all ``t`` (the paper's case: "constant velocity of the point A").

    Attributes:
        speed: v_A [m/s], > 0.
    """

    speed: float = 0.2

    def __post_init__(self) -> None:
        check_range("ConstantSpeed", "speed", self.speed, 0.0, low_open=True)

    @property
    def peak_speed(self) -> float:
        return float(self.speed)

    def __call__(self, t: ArrayLike) -> Array:
        return np.full(np.shape(t), float(self.speed))

    def breakpoints(self) -> tuple[float, ...]:
        return ()

    def distance(self, t: ArrayLike, t0: float = 0.0) -> Array:
        """Distance travelled by A from ``t0`` to ``t`` [m]: ``speed (t - t0)``."""
        return float(self.speed) * (np.asarray(t, dtype=np.float64) - t0)


@dataclass(frozen=True)
class TrapezoidProfile:
    r"""Start, cruise, brake: a trapezoidal speed profile of A.

    .. math::
        v_A(t) = \begin{cases}
            0 & t < t_s \\
            \min(a (t - t_s), v) & t_s \le t < t_b \\
            \max(v - d (t - t_b), 0) & t \ge t_b
        \end{cases}

    with ``a = accel``, ``d = decel``, ``v = speed``, ``t_s = t_start``, ``t_b = t_brake``. With
    ``accel=None`` the speed jumps to ``v`` at ``t_start``; with ``t_brake=None`` it never brakes.

    Attributes:
        speed: cruise speed v [m/s], > 0.
        accel: acceleration a [m/s^2], > 0, or ``None`` for a step. The real robot: 0.3.
        decel: deceleration d [m/s^2], > 0. The real robot: 0.75.
        t_start: start of the motion [s], >= 0.
        t_brake: start of braking [s], ``>= t_start + speed/accel`` (cruise speed reached), or ``None``.
    """

    speed: float = 0.2
    accel: float | None = 0.3
    decel: float = 0.75
    t_start: float = 0.0
    t_brake: float | None = None

    def __post_init__(self) -> None:
        o = "TrapezoidProfile"
        check_range(o, "speed", self.speed, 0.0, low_open=True)
        if self.accel is not None:
            check_range(o, "accel", self.accel, 0.0, low_open=True)
        check_range(o, "decel", self.decel, 0.0, low_open=True)
        check_range(o, "t_start", self.t_start, 0.0)
        if self.t_brake is not None:
            check_range(o, "t_brake", self.t_brake, self.t_cruise)

    @classmethod
    def from_distance(
        cls, speed: float, distance: float, accel: float | None = 0.3, decel: float = 0.75, t_start: float = 0.0
    ) -> TrapezoidProfile:
        """The profile whose A travels ``distance`` [m] in all, braking at the right time.

        ``distance = v^2/(2a) + v (t_b - t_s - v/a) + v^2/(2d)``, solved for ``t_b``; ``distance``
        must be at least the start and stop distances ``v^2/(2a) + v^2/(2d)``.
        """
        o = "TrapezoidProfile"
        v = check_range(o, "speed", speed, 0.0, low_open=True)
        d_acc = 0.0 if accel is None else v * v / (2.0 * check_range(o, "accel", accel, 0.0, low_open=True))
        d_dec = v * v / (2.0 * check_range(o, "decel", decel, 0.0, low_open=True))
        dist = check_range(o, "distance", distance, d_acc + d_dec)
        t_cruise = float(t_start) + (0.0 if accel is None else v / float(accel))
        return cls(v, accel, float(decel), float(t_start), t_cruise + (dist - d_acc - d_dec) / v)

    @property
    def t_cruise(self) -> float:
        """End of the acceleration [s]: ``t_start + speed/accel`` (``t_start`` for a step)."""
        return self.t_start + (0.0 if self.accel is None else self.speed / self.accel)

    @property
    def t_stop(self) -> float:
        """End of braking [s] (``inf`` without braking)."""
        return math.inf if self.t_brake is None else self.t_brake + self.speed / self.decel

    @property
    def peak_speed(self) -> float:
        return float(self.speed)

    def __call__(self, t: ArrayLike) -> Array:
        t = np.asarray(t, dtype=np.float64)
        v = float(self.speed)
        if self.accel is None:
            up = np.where(t >= self.t_start, v, 0.0)
        else:
            up = np.clip(self.accel * (t - self.t_start), 0.0, v)
        if self.t_brake is None:
            return up
        down = np.clip(v - self.decel * (t - self.t_brake), 0.0, v)
        return np.where(t < self.t_brake, up, down)

    def breakpoints(self) -> tuple[float, ...]:
        out = [self.t_start, self.t_cruise]
        if self.t_brake is not None:
            out += [self.t_brake, self.t_stop]
        return tuple(sorted(set(out)))

    def distance(self, t: ArrayLike, t0: float = 0.0) -> Array:
        """Distance travelled by A from ``t0`` to ``t`` [m], the integral of ``v_A`` (closed form)."""
        return self._cumulative(np.asarray(t, dtype=np.float64)) - self._cumulative(np.asarray(t0, dtype=np.float64))

    def _cumulative(self, t: Array) -> Array:
        v = float(self.speed)
        ts, tc = self.t_start, self.t_cruise
        tt = np.minimum(t, self.t_brake) if self.t_brake is not None else t
        if self.accel is None:
            dist = v * np.maximum(tt - ts, 0.0)
        else:
            ramp = np.clip(tt - ts, 0.0, tc - ts)
            dist = 0.5 * self.accel * ramp**2 + v * np.maximum(tt - tc, 0.0)
        if self.t_brake is not None:
            tb = np.clip(t - self.t_brake, 0.0, v / self.decel)
            dist = dist + v * tb - 0.5 * self.decel * tb**2
        return np.asarray(dist, dtype=np.float64)


#: names of the columns of an :class:`InverseSolution`, in CSV order
COLUMNS: tuple[str, ...] = ("t", "s", "x_A", "y_A", "beta", "v_A", "betadot", "alpha1", "alpha2", "alpha3",
                            "alpha1_dot", "alpha2_dot", "alpha3_dot", "x_H", "y_H")  # fmt: skip


@dataclass(frozen=True)
class InverseSolution:
    """The inverse solution sampled on a time grid; every array has shape ``(T,)`` (read-only).

    Attributes:
        t: time [s].
        s: arc length of H along the path [m].
        x_A, y_A: position of the axle midpoint A in frame 0 [m].
        beta: heading [rad], continuous (not wrapped).
        v_A: speed of A [m/s] (the prescribed profile).
        betadot: turn rate ``v_A tan(theta(s) - beta) / l3`` [rad/s].
        alpha1, alpha2, alpha3: wheel angles (right, left, castor) [rad], from 0 at ``t[0]`` by default.
        alpha1_dot, alpha2_dot, alpha3_dot: wheel rates [rad/s] (system 29).
        x_H, y_H: point H computed from the integrated pose of A (paper eq. 4) [m].
    """

    t: Array
    s: Array
    x_A: Array
    y_A: Array
    beta: Array
    v_A: Array
    betadot: Array
    alpha1: Array
    alpha2: Array
    alpha3: Array
    alpha1_dot: Array
    alpha2_dot: Array
    alpha3_dot: Array
    x_H: Array
    y_H: Array

    def __post_init__(self) -> None:
        n = None
        for f in fields(self):
            a = np.array(getattr(self, f.name), dtype=np.float64)
            if a.ndim != 1 or (n is not None and a.shape[0] != n):
                raise ValueError(f"InverseSolution.{f.name} must have shape ({n or 'T'},), got {a.shape}")
            n = a.shape[0]
            a.setflags(write=False)
            object.__setattr__(self, f.name, a)

    def columns(self) -> dict[str, Array]:
        """The columns as an ordered ``{name: array (T,)}`` (order of :data:`COLUMNS`)."""
        return {name: getattr(self, name) for name in COLUMNS}

    @property
    def pose(self) -> Array:
        """Poses ``(T, 3)`` as ``(x_A, y_A, beta)``."""
        return np.stack((self.x_A, self.y_A, self.beta), axis=-1)

    @property
    def wheel_rates(self) -> Array:
        """Drive-wheel rates ``(T, 2)`` as ``(alpha1_dot, alpha2_dot)`` [rad/s]."""
        return np.stack((self.alpha1_dot, self.alpha2_dot), axis=-1)

    @property
    def wheel_angles(self) -> Array:
        """Wheel angles ``(T, 3)`` as ``(alpha1, alpha2, alpha3)`` [rad]."""
        return np.stack((self.alpha1, self.alpha2, self.alpha3), axis=-1)

    def to_csv(self, path: str | os.PathLike[str], columns: Sequence[str] = COLUMNS) -> None:
        """Write the chosen columns as CSV with a header line (SI units, radians), atomically (never half-written).

        Raises:
            ValueError: on an unknown column name.
            OSError: when the folder does not exist or is not writable.
        """
        unknown = [c for c in columns if c not in COLUMNS]
        if unknown:
            raise ValueError(f"unknown column(s) {unknown}; choose from {', '.join(COLUMNS)}")
        data = np.stack([getattr(self, c) for c in columns], axis=-1)
        header = ",".join(columns)
        atomic_save(lambda tmp: np.savetxt(tmp, data, delimiter=",", fmt="%.15g", header=header, comments=""), path)


def time_grid(duration: float, dt: float, t0: float = 0.0) -> Array:
    """Uniform grid ``t0, t0 + dt, ..., t0 + n dt`` with ``n = floor(duration/dt)`` (plus rounding slack) [s].

    Raises:
        ValueError: unless ``0 < dt <= duration`` are finite and the grid has at most
            :data:`MAX_GRID_POINTS` points.
    """
    check_range("time_grid", "duration", duration, 0.0, low_open=True)
    check_range("time_grid", "dt", dt, 0.0, duration, low_open=True)
    check_range("time_grid", "t0", t0)
    n = math.floor(duration / dt + 1e-9)
    if n + 1 > MAX_GRID_POINTS:
        raise ValueError(f"time_grid: duration/dt = {duration / dt:.3g} gives more than {MAX_GRID_POINTS} points")
    return t0 + dt * np.arange(n + 1, dtype=np.float64)


def solve_inverse(
    path: AnyPath,
    profile: SpeedProfile,
    t: ArrayLike,
    robot: RobotParams | None = None,
    *,
    s0: float = 0.0,
    beta0: float | None = None,
    alpha0: tuple[float, float, float] = (0.0, 0.0, 0.0),
    rtol: float = 1e-12,
    atol: float = 1e-12,
) -> InverseSolution:
    r"""Integrate the inverse kinematics of H on ``path`` with speed ``profile`` and sample it at ``t``.

    The ODE of docs/model.md is integrated in the variables ``(s, psi)`` with the heading error
    ``psi = theta(s) - beta`` (so ``beta = theta(s) - psi``; ``psidot = kappa(s) sdot - betadot``), together
    with the pose of A and the wheel angles; state ``y = (s, psi, x_A, y_A, alpha1, alpha2, alpha3)``:

    .. math::
        \dot s = \frac{v_A}{\cos\psi},\quad
        \dot\beta = \frac{v_A \tan\psi}{l_3},\quad
        \dot\psi = \kappa(s)\,\dot s - \dot\beta,\quad
        \dot x_A = v_A\cos\beta,\quad \dot y_A = v_A\sin\beta,\quad
        \dot\alpha_{1,2} = \frac{v_A \pm l_1\dot\beta}{r_{1,2}},\quad
        \dot\alpha_3 = \frac{\sqrt{l_5^2\dot\beta^2 + v_A^2}}{r_3}

    ``psi`` tends to the constant lag ``atan(l3 / R_A)`` on a circle; integrating it rather than ``beta``
    (which grows without bound) puts the solver's error control on the quantity the rates depend on.

    At ``t[0]`` H is at ``path.point(s0)`` with heading ``beta0`` (default ``theta(s0)``, the paper's
    start) and A is ``l3`` behind H.

    Args:
        path: :class:`~amigo_gym.paths.CirclePath` or :class:`~amigo_gym.paths.ManoeuvrePath`; its radius
            must exceed ``robot.l3`` (the steady state needs ``R_A = sqrt(R^2 - l3^2)``).
        profile: speed of A, ``v_A(t) >= 0``, peak at most ``robot.max_speed``.
        t: increasing time grid ``(T,)`` [s], the integration starts at ``t[0]``.
        robot: geometry (default :class:`RobotParams()`).
        s0: start arc length of H [m], >= 0.
        beta0: start heading [rad]; ``|wrap(theta(s0) - beta0)| < pi/2`` (the ODE is singular there).
        alpha0: start wheel angles [rad].
        rtol, atol: tolerances of DOP853.

    Raises:
        ValueError: on a bad grid, radius, speed, start (naming the field and its range).
    """
    from scipy.integrate import solve_ivp

    robot = RobotParams() if robot is None else robot
    o = "solve_inverse"
    if not isinstance(path, (CirclePath, ManoeuvrePath)):
        raise ValueError(f"{o}.path must be a CirclePath or ManoeuvrePath, got {type(path).__name__}")
    check_range(o, "path.radius", float(path.radius), robot.l3, low_open=True)
    check_range(o, "profile.peak_speed", profile.peak_speed, 0.0, robot.max_speed, low_open=True)
    tg = np.asarray(t, dtype=np.float64)
    if tg.ndim != 1 or tg.size < 1:
        raise ValueError(f"{o}.t must be a 1-D time grid with at least one point, got shape {tg.shape}")
    if not np.all(np.isfinite(tg)):
        raise ValueError(f"{o}.t must be finite")
    if tg.size > 1 and not np.all(np.diff(tg) > 0.0):
        raise ValueError(f"{o}.t must be strictly increasing")
    check_range(o, "s0", s0, 0.0)
    theta0 = float(path.tangent_angle(s0))
    b0 = theta0 if beta0 is None else check_range(o, "beta0", beta0)
    if not abs(float(wrap_angle(theta0 - b0))) < 0.5 * math.pi:
        raise ValueError(
            f"{o}.beta0 must satisfy |theta(s0) - beta0| in [0, pi/2) (the inverse ODE is singular at pi/2); "
            f"theta(s0) = {theta0!r}, got beta0 = {b0!r}"
        )
    for i, a in enumerate(alpha0):
        check_range(o, f"alpha0[{i}]", a)
    check_range(o, "rtol", rtol, 0.0, 1.0, low_open=True)
    check_range(o, "atol", atol, 0.0, 1.0, low_open=True)

    l3 = robot.l3
    h0 = path.point(s0)
    # the heading error psi = theta(s) - beta is integrated instead of beta: it tends to a constant on a
    # circle, so that the error control acts on the small, well-scaled quantity the rates depend on
    y = np.array([s0, theta0 - b0, *a_from_h(h0[0], h0[1], math.cos(b0), math.sin(b0), l3), *alpha0], dtype=np.float64)

    def make_rhs(ta: float, tb: float) -> Callable[[float, Array], Array]:
        lo, hi = np.nextafter(ta, math.inf), np.nextafter(tb, -math.inf)

        def rhs(tt: float, yy: Array) -> Array:
            # the profile is smooth inside (ta, tb); evaluate it there (one-sided at the ends)
            v = float(profile(min(max(tt, lo), hi)))
            psi = yy[1]
            sdot = v / math.cos(psi)
            bdot = v * math.tan(psi) / l3
            beta = float(path.tangent_angle(yy[0])) - psi
            w1, w2 = wheel_rates(v, bdot, robot)
            dpsi = float(path.curvature(yy[0])) * sdot - bdot
            return np.array((sdot, dpsi, v * math.cos(beta), v * math.sin(beta), w1, w2, castor_rate(v, bdot, robot)))

        return rhs

    # The heading error relaxes at the rate v_A / l3 (exactly, on any circle, at the steady state): steps
    # longer than a few l3 / v_A put DOP853 at the edge of its stability region, where the error
    # estimate no longer bounds the dense output's error; 2 l3 / v_A keeps every sample near 1e-12.
    max_step = 2.0 * l3 / profile.peak_speed
    t_first, t_last = float(tg[0]), float(tg[-1])
    edges = [t_first, *(b for b in profile.breakpoints() if t_first < b < t_last), t_last]
    # the arc length where the path's curvature jumps: the manoeuvre's straight->circle junction
    s_breaks = [float(path.straight_length)] if isinstance(path, ManoeuvrePath) and path.straight_length > s0 else []
    out = np.empty((y.size, tg.size))
    out[:, 0] = y
    for ta, tb in itertools.pairwise(edges):
        tc = ta
        while tc < tb:
            events = []
            if s_breaks:
                target = s_breaks[0]

                def reach(_t: float, yy: Array, target: float = target) -> float:
                    return float(yy[0] - target)

                reach.terminal = True  # type: ignore[attr-defined]
                reach.direction = 1.0  # type: ignore[attr-defined]
                events.append(reach)
            sol = solve_ivp(make_rhs(ta, tb), (tc, tb), y, "DOP853", dense_output=True, events=events or None,
                            max_step=max_step, rtol=rtol, atol=atol)  # fmt: skip
            if not sol.success:
                raise RuntimeError(f"{o}: integration failed at t = {sol.t[-1]:.6g} s: {sol.message}")
            t_end = float(sol.t[-1])
            mask = (tg >= tc) & (tg <= t_end)
            if np.any(mask):
                out[:, mask] = sol.sol(tg[mask])
            y = np.array(sol.y[:, -1], dtype=np.float64)
            if sol.status == 1:  # reached a curvature jump of the path: restart there
                y[0] = s_breaks.pop(0)
            if t_end <= tc and sol.status != 1:
                break
            tc = t_end

    s, psi, xa, ya, a1, a2, a3 = out
    beta = path.tangent_angle(s) - psi
    v = profile(tg)
    bdot = v * np.tan(psi) / l3
    w = wheel_rates(v, bdot, robot)
    h = h_position(np.stack((xa, ya, beta), axis=-1), robot)
    a3dot = castor_rate(v, bdot, robot)
    return InverseSolution(tg, s, xa, ya, beta, v, bdot, a1, a2, a3, w[:, 0], w[:, 1], a3dot, h[:, 0], h[:, 1])


def manoeuvre_profile(
    path: ManoeuvrePath,
    speed: float = 0.2,
    robot: RobotParams | None = None,
    *,
    accel: float | None = MANOEUVRE_ACCEL,
    decel: float = MANOEUVRE_DECEL,
    t_start: float = MANOEUVRE_T_START,
    laps: float = MANOEUVRE_LAPS,
) -> TrapezoidProfile:
    """Speed profile of the manoeuvre "starting, driving straight, circular curve, braking".

    A stands still until ``t_start``, accelerates at ``accel`` to ``speed``, cruises and brakes at
    ``decel`` so that it comes to rest after travelling ``straight_length + laps * 2 pi R_A`` [m], the
    straight plus ``laps`` laps of its steady circle ``R_A = sqrt(R^2 - l3^2)`` (H stops close to,
    not exactly at, the end of the lap, because A's path differs from the steady circle during the
    transient at the start of the curve).
    """
    robot = RobotParams() if robot is None else robot
    check_range("manoeuvre_profile", "laps", laps, 0.0, 1e3)
    ra = math.sqrt(check_range("manoeuvre_profile", "radius", path.radius, robot.l3, low_open=True) ** 2 - robot.l3**2)
    return TrapezoidProfile.from_distance(
        speed, path.straight_length + laps * 2.0 * math.pi * ra, accel=accel, decel=decel, t_start=t_start
    )


def paper_circle(
    radius: float = 1.0,
    speed: float = 0.2,
    duration: float = 40.0,
    dt: float = 0.1,
    robot: RobotParams | None = None,
    direction: int = 1,
) -> InverseSolution:
    """The paper's case: H from the origin on eq. (6)'s circle, ``beta0 = 0``, ``v_A`` constant from t = 0.

    Args:
        radius: R [m], > l3.
        speed: v_A [m/s].
        duration: simulated time [s]; the grid is ``time_grid(duration, dt)``.
        dt: output step [s] (the integration itself is adaptive and accurate to ~1e-12).
        robot: geometry.
        direction: +1 left (eq. 6), -1 right.
    """
    path = CirclePath(radius=radius, direction=direction)
    return solve_inverse(path, ConstantSpeed(speed), time_grid(duration, dt), robot)
