"""``amigo-gym inverse``: the analytic inverse solution of H on a path, as CSV or a short summary.

Examples::

    amigo-gym inverse --path circle --radius 1 --speed 0.2 --duration 40 --dt 0.1 --csv circle.csv
    amigo-gym inverse --path manoeuvre --straight-length 1 --radius 1 --accel 0.1 --decel 0.2 --csv m.csv

``--path circle`` is the paper's case: H starts at the origin on eq. (6)'s circle with ``beta = 0`` and
``v_A`` constant from t = 0 (unless ``--accel`` or braking is asked for). ``--path manoeuvre`` drives the
straight segment, then the circle, with a trapezoidal speed profile: standstill until ``--t-start``,
acceleration ``--accel``, cruise, braking ``--decel`` so that A stops after the straight plus ``--laps``
laps of its steady circle (or from ``--brake-at`` seconds; ``--no-brake`` to keep going).

CSV columns (SI units, radians): ``t, s, x_A, y_A, beta, v_A, betadot, alpha1, alpha2, alpha3,
alpha1_dot, alpha2_dot, alpha3_dot, x_H, y_H``. Bad options give a one-line error and exit status 2.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence

import numpy as np

from amigo_gym.model.params import RobotParams, check_range
from amigo_gym.options import OneLineParser, run_guarded
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

__all__ = ["build_parser", "main"]

PROG = "amigo-gym inverse"

#: default duration of a circle run without braking [s]: more than one lap of the default circle (31.3 s)
DEFAULT_DURATION = 40.0


def build_parser() -> argparse.ArgumentParser:
    """The option parser (one-line errors)."""
    p = OneLineParser(prog=PROG, description="Analytic inverse solution of point H on a path (CSV or summary).")
    p.add_argument("--path", choices=("circle", "manoeuvre"), default="circle", help="path of H (default circle)")
    p.add_argument("--radius", type=float, default=1.0, help="circle radius R [m], > l3 (default 1)")
    p.add_argument("--speed", type=float, default=0.2, help="cruise speed of A, v_A [m/s] (default 0.2)")
    p.add_argument(
        "--direction", type=int, choices=(1, -1), default=1, help="+1 left turn (eq. 6), -1 right (default 1)"
    )
    p.add_argument("--straight-length", type=float, default=1.0, help="manoeuvre: straight part [m] (default 1)")
    p.add_argument(
        "--duration", type=float, default=None, help="simulated time [s] (default: 40, or until 1 s after stopping)"
    )
    p.add_argument("--dt", type=float, default=0.1, help="output time step [s] (default 0.1)")
    p.add_argument(
        "--accel",
        type=float,
        default=None,
        help=f"acceleration [m/s^2] (default: circle: step to v_A at t=0; manoeuvre: {MANOEUVRE_ACCEL})",
    )
    p.add_argument(
        "--decel", type=float, default=None, help=f"braking deceleration [m/s^2] (default {MANOEUVRE_DECEL})"
    )
    p.add_argument(
        "--t-start",
        type=float,
        default=None,
        help=f"start of motion [s] (default: circle 0, else {MANOEUVRE_T_START})",
    )
    brake = p.add_mutually_exclusive_group()
    brake.add_argument("--brake-at", type=float, default=None, help="time at which braking starts [s] (default: none)")
    brake.add_argument(
        "--laps",
        type=float,
        default=None,
        help=f"manoeuvre: stop after the straight plus this many laps of A's circle [laps] (default {MANOEUVRE_LAPS})",
    )
    brake.add_argument("--no-brake", action="store_true", help="manoeuvre: never brake")
    p.add_argument(
        "--csv",
        default=None,
        metavar="FILE",
        help="write the solution as CSV, atomically [file] (default: none, a summary)",
    )
    return p


def _check(flag: str, value: float, low: float, high: float = math.inf, **kw: bool) -> float:
    """``check_range`` with the option's name in the message."""
    try:
        return check_range("_", "_", value, low, high, **kw)
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


def _profile(args: argparse.Namespace, path: CirclePath | ManoeuvrePath, robot: RobotParams) -> SpeedProfile:
    manoeuvre = isinstance(path, ManoeuvrePath)
    if args.accel is not None:
        _check("--accel", args.accel, 0.0, low_open=True)
    if args.decel is not None:
        _check("--decel", args.decel, 0.0, low_open=True)
    if args.t_start is not None:
        _check("--t-start", args.t_start, 0.0)
    if args.laps is not None:
        _check("--laps", args.laps, 0.0, 1e3)
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
    w_max = robot.max_wheel_rate
    peak = float(np.max(np.abs(sol.wheel_rates)))
    lines = [
        f"path: {type(path).__name__}, R = {path.radius:g} m, direction {path.direction:+d}; "
        f"{sol.t.size} samples, t = {sol.t[0]:g}..{sol.t[-1]:g} s",
        f"end: s = {sol.s[-1]:.6f} m, H = ({sol.x_H[-1]:.6f}, {sol.y_H[-1]:.6f}) m, beta = {sol.beta[-1]:.6f} rad",
        f"end rates [rad/s]: betadot = {sol.betadot[-1]:.6f}, alpha1_dot = {sol.alpha1_dot[-1]:.6f}, "
        f"alpha2_dot = {sol.alpha2_dot[-1]:.6f}, alpha3_dot = {sol.alpha3_dot[-1]:.6f}",
        f"end angles [rad]: alpha1 = {sol.alpha1[-1]:.6f}, alpha2 = {sol.alpha2[-1]:.6f}, "
        f"alpha3 = {sol.alpha3[-1]:.6f}",
        f"peak |drive wheel rate| = {peak:.4f} rad/s (limit {w_max:g}); max |cross-track error of H| = "
        f"{float(np.max(np.abs(e))):.2e} m",
    ]
    ss = circle_steady_state(path.radius, speed, robot, path.direction)
    lines.append(
        f"steady state on the circle (closed form): betadot = {float(ss.betadot):.6f}, "
        f"alpha1_dot = {float(ss.wheel_rates[0]):.6f}, alpha2_dot = {float(ss.wheel_rates[1]):.6f}, "
        f"alpha3_dot = {float(ss.castor_rate):.6f}"
    )
    return "\n".join(lines)


def _run(args: argparse.Namespace) -> int:
    robot = RobotParams()
    _check("--radius", args.radius, robot.l3, 1e3, low_open=True)
    _check("--speed", args.speed, 0.0, robot.max_speed, low_open=True)
    _check("--dt", args.dt, 0.0, 10.0, low_open=True)
    if args.duration is not None:
        _check("--duration", args.duration, 0.0, 1e5, low_open=True)
    if args.csv is not None:
        _check_csv_target(args.csv)
    path: CirclePath | ManoeuvrePath
    if args.path == "circle":
        path = CirclePath(radius=args.radius, direction=args.direction)
    else:
        _check("--straight-length", args.straight_length, 0.0, 1e3)
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
        return 0
    try:
        sol.to_csv(args.csv)
    except OSError as exc:
        raise ValueError(f"--csv: cannot write {args.csv!r}: {exc.strerror or exc}") from None
    print(f"wrote {sol.t.size} rows x {len(sol.columns())} columns to {args.csv}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym inverse`` (returns the exit status)."""
    args = build_parser().parse_args(sys.argv[1:] if argv is None else list(argv))
    return run_guarded(lambda: _run(args), PROG)


if __name__ == "__main__":
    sys.exit(main())
