r"""The analytic inverse solution: wheel angles and rates that make H follow a path exactly.

For a path of H with tangent angle ``theta(s)`` at arc length ``s`` and a speed profile ``v_A(t)`` of A, the paper's
eqs (7)-(10) reduce to (``docs/model.md``)

.. math::
    \dot s = \frac{v_A}{\cos(\theta(s) - \beta)}, \qquad
    \dot\beta = \frac{v_A \tan(\theta(s) - \beta)}{l_3},

singular at ``|theta - beta| = pi/2``; the wheel rates follow from the rolling constraints (system 29). Units: m,
rad, s; arrays of an :class:`InverseSolution` have shape ``(T,)``."""

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
from amigo_gym.model.params import RobotParams, check_real
from amigo_gym.paths import CirclePath, ManoeuvrePath, wrap_angle

Array = NDArray[np.float64]
AnyPath = CirclePath | ManoeuvrePath

#: largest number of time-grid points accepted (about 120 MB of output columns)
MAX_GRID_POINTS = 1_000_000

#: the paper's manoeuvre's timing (the paper gives none): acceleration and deceleration [m/s^2], start [s], laps
MANOEUVRE_ACCEL = 0.1
MANOEUVRE_DECEL = 0.2
MANOEUVRE_T_START = 1.0
MANOEUVRE_LAPS = 1.0


class SpeedProfile(Protocol):
    """A prescribed speed of A, ``v_A(t) >= 0`` [m/s] (right-continuous), piecewise smooth in time ``t`` [s]:
    ``peak_speed`` its largest value, ``breakpoints()`` the increasing times where it or its derivative jumps."""

    @property
    def peak_speed(self) -> float: ...

    def __call__(self, t: ArrayLike) -> Array: ...

    def breakpoints(self) -> tuple[float, ...]: ...


@dataclass(frozen=True)
class ConstantSpeed:
    """``v_A(t) = speed`` [m/s], > 0 (the paper's case)."""

    speed: float = 0.2

    def __post_init__(self) -> None:
        check_real("ConstantSpeed", "speed", self.speed, 0.0, low_open=True)

    @property
    def peak_speed(self) -> float:
        return float(self.speed)

    def __call__(self, t: ArrayLike) -> Array:
        return np.full(np.shape(t), float(self.speed))

    def breakpoints(self) -> tuple[float, ...]:
        return ()


@dataclass(frozen=True)
class TrapezoidProfile:
    r"""Start, cruise, brake: a trapezoidal speed profile of A,

    .. math::
        v_A(t) = \begin{cases}
            0 & t < t_s \\
            \min(a (t - t_s), v) & t_s \le t < t_b \\
            \max(v - d (t - t_b), 0) & t \ge t_b
        \end{cases}

    with ``v = speed`` [m/s] > 0, ``a = accel`` [m/s^2] > 0 (``None``: a step at ``t_start``), ``d = decel``
    [m/s^2] > 0, ``t_s = t_start`` [s] >= 0 and ``t_b = t_brake`` [s] >= :attr:`t_cruise` (``None``: no braking)."""

    speed: float = 0.2
    accel: float | None = 0.3
    decel: float = 0.75
    t_start: float = 0.0
    t_brake: float | None = None

    def __post_init__(self) -> None:
        o = "TrapezoidProfile"
        check_real(o, "speed", self.speed, 0.0, low_open=True)
        if self.accel is not None:
            check_real(o, "accel", self.accel, 0.0, low_open=True)
        check_real(o, "decel", self.decel, 0.0, low_open=True)
        check_real(o, "t_start", self.t_start, 0.0)
        if self.t_brake is not None:
            check_real(o, "t_brake", self.t_brake, self.t_cruise)

    @classmethod
    def from_distance(
        cls, speed: float, distance: float, accel: float | None = 0.3, decel: float = 0.75, t_start: float = 0.0
    ) -> TrapezoidProfile:
        """The profile whose A travels ``distance = v^2/(2a) + v (t_b - t_s - v/a) + v^2/(2d)`` [m] in all (solved for
        ``t_b``; at least ``v^2/(2a) + v^2/(2d)``)."""
        o = "TrapezoidProfile"
        v = check_real(o, "speed", speed, 0.0, low_open=True)
        d_acc = 0.0 if accel is None else v * v / (2.0 * check_real(o, "accel", accel, 0.0, low_open=True))
        d_dec = v * v / (2.0 * check_real(o, "decel", decel, 0.0, low_open=True))
        dist = check_real(o, "distance", distance, d_acc + d_dec)
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
        v, ts = float(self.speed), self.t_start
        up = np.where(t >= ts, v, 0.0) if self.accel is None else np.clip(self.accel * (t - ts), 0.0, v)
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
        """Distance travelled by A from ``t0`` to ``t`` [m] (closed form)."""
        return self._cumulative(np.asarray(t, dtype=np.float64)) - self._cumulative(np.asarray(t0, dtype=np.float64))

    def _cumulative(self, t: Array) -> Array:
        v = float(self.speed)
        ts, tc = self.t_start, self.t_cruise
        tt = np.minimum(t, self.t_brake) if self.t_brake is not None else t
        ramp = np.clip(tt - ts, 0.0, tc - ts)  # 0 for a step (tc = ts)
        dist = 0.5 * (self.accel or 0.0) * ramp**2 + v * np.maximum(tt - tc, 0.0)
        if self.t_brake is not None:
            tb = np.clip(t - self.t_brake, 0.0, v / self.decel)
            dist = dist + v * tb - 0.5 * self.decel * tb**2
        return np.asarray(dist, dtype=np.float64)


#: names of the columns of an :class:`InverseSolution`, in CSV order
COLUMNS: tuple[str, ...] = ("t", "s", "x_A", "y_A", "beta", "v_A", "betadot", "alpha1", "alpha2", "alpha3",
                            "alpha1_dot", "alpha2_dot", "alpha3_dot", "x_H", "y_H")  # fmt: skip


@dataclass(frozen=True)
class InverseSolution:
    """The inverse solution on a time grid, read-only ``(T,)`` arrays: time ``t`` [s], H's arc length ``s`` [m], A's
    position [m], the unwrapped heading ``beta`` [rad], ``v_A`` [m/s], ``betadot`` [rad/s], the wheel angles (right,
    left, castor) [rad] and rates [rad/s], and H from the integrated pose of A (paper eq. 4) [m]."""

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
        """Write the chosen columns as CSV with a header line, atomically. Raises ``ValueError`` on an unknown column,
        ``OSError`` when the folder does not exist or is not writable."""
        if unknown := [c for c in columns if c not in COLUMNS]:
            raise ValueError(f"unknown column(s) {unknown}; choose from {', '.join(COLUMNS)}")
        data = np.stack([getattr(self, c) for c in columns], axis=-1)
        header = ",".join(columns)
        atomic_save(lambda tmp: np.savetxt(tmp, data, delimiter=",", fmt="%.15g", header=header, comments=""), path)


def time_grid(duration: float, dt: float, t0: float = 0.0) -> Array:
    """Uniform grid ``t0, t0 + dt, ..., t0 + n dt`` [s], ``n = floor(duration/dt)``; ``ValueError`` unless
    ``0 < dt <= duration`` are finite and the grid has at most :data:`MAX_GRID_POINTS` points."""
    check_real("time_grid", "duration", duration, 0.0, low_open=True)
    check_real("time_grid", "dt", dt, 0.0, duration, low_open=True)
    check_real("time_grid", "t0", t0)
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
    r"""Integrate the inverse kinematics of H on ``path`` with speed ``profile`` (DOP853) and sample it at ``t``.

    State ``(s, psi, x_A, y_A, alpha1, alpha2, alpha3)`` with ``psi = theta(s) - beta``, split at the profile's
    breakpoints and the path's curvature jumps:

    .. math::
        \dot s = \frac{v_A}{\cos\psi},\quad
        \dot\beta = \frac{v_A \tan\psi}{l_3},\quad
        \dot\psi = \kappa(s)\,\dot s - \dot\beta,\quad
        \dot x_A = v_A\cos\beta,\quad \dot y_A = v_A\sin\beta,\quad
        \dot\alpha_{1,2} = \frac{v_A \pm l_1\dot\beta}{r_{1,2}},\quad
        \dot\alpha_3 = \frac{\sqrt{l_5^2\dot\beta^2 + v_A^2}}{r_3}

    At ``t[0]`` (of the increasing grid) H is at ``path.point(s0)`` [m] (a ``CirclePath`` or ``ManoeuvrePath`` of
    radius above ``l3``), heading ``beta0`` [rad] (default ``theta(s0)``; ``|theta(s0) - beta0| < pi/2``), the wheel
    angles ``alpha0`` [rad]; the ``profile``'s peak at most ``robot.max_speed``. ``ValueError`` names a bad field."""
    from scipy.integrate import solve_ivp

    robot = RobotParams() if robot is None else robot
    o = "solve_inverse"
    if not isinstance(path, (CirclePath, ManoeuvrePath)):
        raise ValueError(f"{o}.path must be a CirclePath or ManoeuvrePath, got {type(path).__name__}")
    check_real(o, "path.radius", float(path.radius), robot.l3, low_open=True)
    check_real(o, "profile.peak_speed", profile.peak_speed, 0.0, robot.max_speed, low_open=True)
    tg = np.asarray(t, dtype=np.float64)
    if tg.ndim != 1 or tg.size < 1:
        raise ValueError(f"{o}.t must be a 1-D time grid with at least one point, got shape {tg.shape}")
    if not np.all(np.isfinite(tg)):
        raise ValueError(f"{o}.t must be finite")
    if tg.size > 1 and not np.all(np.diff(tg) > 0.0):
        raise ValueError(f"{o}.t must be strictly increasing")
    check_real(o, "s0", s0, 0.0)
    theta0 = float(path.tangent_angle(s0))
    b0 = theta0 if beta0 is None else check_real(o, "beta0", beta0)
    if not abs(float(wrap_angle(theta0 - b0))) < 0.5 * math.pi:
        raise ValueError(
            f"{o}.beta0 must satisfy |theta(s0) - beta0| in [0, pi/2) (the inverse ODE is singular at pi/2); "
            f"theta(s0) = {theta0!r}, got beta0 = {b0!r}"
        )
    for i, a in enumerate(alpha0):
        check_real(o, f"alpha0[{i}]", a)
    check_real(o, "rtol", rtol, 0.0, 1.0, low_open=True)
    check_real(o, "atol", atol, 0.0, 1.0, low_open=True)

    l3 = robot.l3
    h0 = path.point(s0)
    y = np.array([s0, theta0 - b0, *a_from_h(h0[0], h0[1], math.cos(b0), math.sin(b0), l3), *alpha0], dtype=np.float64)

    def make_rhs(ta: float, tb: float) -> Callable[[float, Array], Array]:
        lo, hi = np.nextafter(ta, math.inf), np.nextafter(tb, -math.inf)

        def rhs(tt: float, yy: Array) -> Array:
            v = float(profile(min(max(tt, lo), hi)))
            psi = yy[1]
            sdot = v / math.cos(psi)
            bdot = v * math.tan(psi) / l3
            beta = float(path.tangent_angle(yy[0])) - psi
            w1, w2 = wheel_rates(v, bdot, robot)
            dpsi = float(path.curvature(yy[0])) * sdot - bdot
            return np.array((sdot, dpsi, v * math.cos(beta), v * math.sin(beta), w1, w2, castor_rate(v, bdot, robot)))

        return rhs

    # psi relaxes at the rate v_A / l3: longer steps than 2 l3 / v_A leave DOP853's stability region
    max_step = 2.0 * l3 / profile.peak_speed
    t_first, t_last = float(tg[0]), float(tg[-1])
    edges = [t_first, *(b for b in profile.breakpoints() if t_first < b < t_last), t_last]
    s_breaks = [float(path.straight_length)] if isinstance(path, ManoeuvrePath) and path.straight_length > s0 else []
    out = np.empty((y.size, tg.size))
    out[:, 0] = y

    def reach(_t: float, yy: Array) -> float:  # the event of the next curvature jump
        return float(yy[0] - s_breaks[0])

    reach.terminal = True  # type: ignore[attr-defined]
    reach.direction = 1.0  # type: ignore[attr-defined]
    for ta, tb in itertools.pairwise(edges):
        tc = ta
        while tc < tb:
            sol = solve_ivp(make_rhs(ta, tb), (tc, tb), y, "DOP853", dense_output=True,
                            events=[reach] if s_breaks else None, max_step=max_step, rtol=rtol, atol=atol)  # fmt: skip
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
    """Speed profile of the manoeuvre "starting, driving straight, circular curve, braking": A rests until
    ``t_start`` [s] and comes to rest after ``straight_length + laps 2 pi R_A`` [m], ``R_A = sqrt(R^2 - l3^2)``."""
    robot = RobotParams() if robot is None else robot
    check_real("manoeuvre_profile", "laps", laps, 0.0, 1e3)
    ra = math.sqrt(check_real("manoeuvre_profile", "radius", path.radius, robot.l3, low_open=True) ** 2 - robot.l3**2)
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
    """The paper's case: H from the origin on eq. (6)'s circle of radius [m] > l3 (``direction`` +1 left, -1 right),
    ``beta0 = 0``, constant ``speed`` [m/s], sampled every ``dt`` [s] over ``duration`` [s]."""
    path = CirclePath(radius=radius, direction=direction)
    return solve_inverse(path, ConstantSpeed(speed), time_grid(duration, dt), robot)
