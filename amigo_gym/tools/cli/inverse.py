"""``amigo-gym inverse``: the analytic inverse solution of H on a path, as CSV or a short summary.

``--path circle``: H starts at the origin on eq. (6)'s circle with ``beta = 0``, ``v_A`` constant from t = 0 unless
``--accel``, ``--t-start`` or ``--brake-at`` ask for a ramp. ``--path manoeuvre``: the straight, then the circle,
with a trapezoidal speed profile that stops A after the straight plus ``--laps`` laps of its steady circle. CSV
columns (SI units, radians): ``t, s, x_A, y_A, beta, v_A, betadot, alpha1, alpha2, alpha3, alpha1_dot, alpha2_dot,
alpha3_dot, x_H, y_H``. Examples: docs/core.md.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from amigo_gym.model.params import RobotParams, check_range
from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.task.inverse import (
    MANOEUVRE_ACCEL,
    MANOEUVRE_DECEL,
    MANOEUVRE_LAPS,
    MANOEUVRE_T_START,
    ConstantSpeed,
    InverseSolution,
    SpeedProfile,
    TrapezoidProfile,
    circle_steady_state,
    manoeuvre_profile,
    solve_inverse,
    time_grid,
)
from amigo_gym.tools.options import cli, run_command

PROG = "amigo-gym inverse"

#: default duration of a circle run without braking [s]: more than one lap of the default circle (31.3 s)
DEFAULT_DURATION = 40.0


@dataclass(frozen=True)
class InverseSettings:
    __doc__ = f"""Options of ``amigo-gym inverse``, each the option of the same name (checked by :meth:`validate`).

    Attributes:
        path: path of H.
        radius: circle radius R [m], > l3, at most 1000.
        speed: cruise speed of A, v_A [m/s], in (0, the robot's max speed].
        direction: +1 left turn (eq. 6), -1 right.
        straight_length: manoeuvre: straight part [m], in [0, 1000].
        duration: simulated time [s], in (0, 1e5] (default: {DEFAULT_DURATION:g}, or until 1 s after stopping).
        dt: output time step [s], in (0, 10], at most the duration.
        accel: acceleration [m/s^2], > 0 (default: circle: step to v_A at t=0; manoeuvre: {MANOEUVRE_ACCEL}).
        decel: braking deceleration [m/s^2], > 0 (default {MANOEUVRE_DECEL}).
        t_start: start of motion [s], >= 0 (default: circle 0, else {MANOEUVRE_T_START}).
        brake_at: time at which braking starts [s], once cruising (default: none).
        laps: manoeuvre: stop after the straight plus this many laps of A's circle [laps], in [0, 1000] (default
            {MANOEUVRE_LAPS}).
        no_brake: manoeuvre: never brake.
        csv: write the solution as CSV, atomically [file] (default: none, a summary).
    """

    path: Literal["circle", "manoeuvre"] = "circle"
    radius: float = 1.0
    speed: float = 0.2
    direction: Literal[1, -1] = 1
    straight_length: float = 1.0
    duration: float | None = None
    dt: float = 0.1
    accel: float | None = None
    decel: float | None = None
    t_start: float | None = None
    brake_at: float | None = field(default=None, metadata=cli(group="brake"))
    laps: float | None = field(default=None, metadata=cli(group="brake"))
    no_brake: bool = field(default=False, metadata=cli(group="brake"))
    csv: str | None = field(default=None, metadata=cli(metavar="FILE"))

    def validate(self) -> None:
        """Raise ``ValueError`` naming the option, its allowed range and the value (the limits: the AmigoBot's)."""
        robot = RobotParams()
        _check("--radius", self.radius, robot.l3, 1e3, low_open=True)
        _check("--speed", self.speed, 0.0, robot.max_speed, low_open=True)
        _check("--dt", self.dt, 0.0, 10.0, low_open=True)
        _check("--duration", self.duration, 0.0, 1e5, low_open=True)
        if self.csv is not None:
            _check_csv_target(self.csv)
        if self.path == "manoeuvre":
            _check("--straight-length", self.straight_length, 0.0, 1e3)
        _check("--accel", self.accel, 0.0, low_open=True)
        _check("--decel", self.decel, 0.0, low_open=True)
        _check("--t-start", self.t_start, 0.0)
        _check("--laps", self.laps, 0.0, 1e3)


def _check(flag: str, value: float | None, low: float, high: float = math.inf, **kw: bool) -> None:
    """``check_range`` with the option's name in the message; ``None`` passes."""
    try:
        if value is not None:
            check_range("_", "_", value, low, high, **kw)
    except ValueError as exc:
        raise ValueError(str(exc).replace("_._", flag, 1)) from None


def _check_csv_target(path: str) -> None:
    if os.path.isdir(path):
        raise ValueError(f"--csv {path!r} is a directory")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"--csv: folder {folder!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise ValueError(f"--csv: folder {folder!r} is not writable")


def _profile(args: InverseSettings, path: CirclePath | ManoeuvrePath, robot: RobotParams) -> SpeedProfile:
    manoeuvre = isinstance(path, ManoeuvrePath)
    accel = args.accel if args.accel is not None or not manoeuvre else MANOEUVRE_ACCEL
    decel = MANOEUVRE_DECEL if args.decel is None else args.decel
    t_start = args.t_start if args.t_start is not None else (MANOEUVRE_T_START if manoeuvre else 0.0)
    if args.brake_at is not None:
        t_cruise = t_start + (0.0 if accel is None else args.speed / accel)
        _check("--brake-at", args.brake_at, t_cruise)
        return TrapezoidProfile(args.speed, accel, decel, t_start, args.brake_at)
    if manoeuvre and not args.no_brake:
        assert isinstance(path, ManoeuvrePath)
        laps = MANOEUVRE_LAPS if args.laps is None else args.laps
        return manoeuvre_profile(path, args.speed, robot, accel=accel, decel=decel, t_start=t_start, laps=laps)
    if args.laps is not None:
        raise ValueError("--laps applies to --path manoeuvre only (use --brake-at for the circle)")
    if accel is None and t_start == 0.0:
        return ConstantSpeed(args.speed)
    return TrapezoidProfile(args.speed, accel, decel, t_start, None)


def _summary(sol: InverseSolution, path: CirclePath | ManoeuvrePath, robot: RobotParams, speed: float) -> str:
    e = path.project(np.stack((sol.x_H, sol.y_H), axis=-1)).cross_track_error
    peak = float(np.max(np.abs(sol.wheel_rates)))
    ss = circle_steady_state(path.radius, speed, robot, path.direction)
    lines = [
        f"path: {type(path).__name__}, R = {path.radius:g} m, direction {path.direction:+d}; "
        f"{sol.t.size} samples, t = {sol.t[0]:g}..{sol.t[-1]:g} s",
        f"end: s = {sol.s[-1]:.6f} m, H = ({sol.x_H[-1]:.6f}, {sol.y_H[-1]:.6f}) m, beta = {sol.beta[-1]:.6f} rad",
        f"end rates [rad/s]: betadot = {sol.betadot[-1]:.6f}, alpha1_dot = {sol.alpha1_dot[-1]:.6f}, "
        f"alpha2_dot = {sol.alpha2_dot[-1]:.6f}, alpha3_dot = {sol.alpha3_dot[-1]:.6f}",
        f"end angles [rad]: alpha1 = {sol.alpha1[-1]:.6f}, alpha2 = {sol.alpha2[-1]:.6f}, "
        f"alpha3 = {sol.alpha3[-1]:.6f}",
        f"peak |drive wheel rate| = {peak:.4f} rad/s (limit {robot.max_wheel_rate:g}); max |cross-track error of H| = "
        f"{float(np.max(np.abs(e))):.2e} m",
        f"steady state on the circle (closed form): betadot = {float(ss.betadot):.6f}, "
        f"alpha1_dot = {float(ss.wheel_rates[0]):.6f}, alpha2_dot = {float(ss.wheel_rates[1]):.6f}, "
        f"alpha3_dot = {float(ss.castor_rate):.6f}",
    ]
    return "\n".join(lines)


def _run(args: InverseSettings) -> None:
    robot = RobotParams()
    path: CirclePath | ManoeuvrePath
    if args.path == "circle":
        path = CirclePath(radius=args.radius, direction=args.direction)
    else:
        path = ManoeuvrePath(radius=args.radius, straight_length=args.straight_length, direction=args.direction)
    profile = _profile(args, path, robot)
    duration = args.duration
    if duration is None:
        t_stop = getattr(profile, "t_stop", math.inf)
        duration = t_stop + 1.0 if math.isfinite(t_stop) else DEFAULT_DURATION
    if args.dt > duration:
        raise ValueError(f"--dt must not exceed --duration ({duration:g} s), got {args.dt!r}")
    sol = solve_inverse(path, profile, time_grid(duration, args.dt), robot)
    if args.csv is None:
        print(_summary(sol, path, robot, args.speed))
        return
    try:
        sol.to_csv(args.csv)
    except OSError as exc:
        raise ValueError(f"--csv: cannot write {args.csv!r}: {exc.strerror or exc}") from None
    print(f"wrote {sol.t.size} rows x {len(sol.columns())} columns to {args.csv}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym inverse`` (returns the exit status)."""
    return run_command(
        InverseSettings, _run, argv, PROG, "Analytic inverse solution of point H on a path (CSV or summary)."
    )


if __name__ == "__main__":
    sys.exit(main())
