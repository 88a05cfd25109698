"""``amigo-gym inverse`` and ``amigo-gym paper``: the analytic inverse solution of H on a path (docs/core.md).

``inverse``, ``--path circle``: H starts at the origin on eq. (6)'s circle with ``beta = 0``, ``v_A`` constant from
t = 0 unless ``--accel``, ``--t-start`` or ``--brake-at`` ask for a ramp; ``--path manoeuvre``: the straight, then the
circle, with a trapezoidal speed profile that stops A after the straight plus ``--laps`` laps of its steady circle.
It prints a summary, or writes the solution as CSV (SI units, radians): ``t, s, x_A, y_A, beta, v_A, betadot,
alpha1, alpha2, alpha3, alpha1_dot, alpha2_dot, alpha3_dot, x_H, y_H``.

``paper --out DIR``: the paper's manoeuvre, "starting, driving straight, driving on circular curve, braking",
as ``DIR/paper_fig2_angles.png`` (wheel angles, as its Fig. 2), ``DIR/paper_fig3_rates.png`` (their rates, as Fig. 3,
the closed-form steady state dotted) and ``DIR/paper_manoeuvre.csv`` (the same columns), the phases shaded.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np

from amigo_gym.model.params import RobotParams, check_real
from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.task import inverse as inv
from amigo_gym.tools.options import check_fields, cli, run_command
from amigo_gym.tools.plots import pyplot, save_figure

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
        accel: acceleration [m/s^2], > 0 (default: circle: step to v_A at t=0; manoeuvre: {inv.MANOEUVRE_ACCEL}).
        decel: braking deceleration [m/s^2], > 0 (default {inv.MANOEUVRE_DECEL}).
        t_start: start of motion [s], >= 0 (default: circle 0, else {inv.MANOEUVRE_T_START}).
        brake_at: time at which braking starts [s], once cruising (default: none).
        laps: manoeuvre: stop after the straight plus this many laps of A's circle [laps], in [0, 1000] (default
            {inv.MANOEUVRE_LAPS}).
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
        robot, inf = RobotParams(), math.inf
        limits: dict[str, tuple[float, ...]] = {"radius": (robot.l3, 1e3, True), "dt": (0.0, 10.0, True)}
        limits |= {"speed": (0.0, robot.max_speed, True), "duration": (0.0, 1e5, True), "accel": (0.0, inf, True)}
        limits |= {"decel": (0.0, inf, True), "t_start": (0.0, inf), "laps": (0.0, 1e3)}
        if self.path == "manoeuvre":
            limits["straight_length"] = (0.0, 1e3)
        _as_options(check_fields, "_", self, **limits)
        if self.csv is not None:
            folder = os.path.dirname(os.path.abspath(self.csv))
            if os.path.isdir(self.csv):
                raise ValueError(f"--csv {self.csv!r} is a directory")
            if not os.path.isdir(folder):
                raise ValueError(f"--csv: folder {folder!r} does not exist")
            if not os.access(folder, os.W_OK):
                raise ValueError(f"--csv: folder {folder!r} is not writable")


def _as_options(check: Any, *args: Any, **kw: Any) -> None:
    """``check(*args, **kw)`` with its message's ``_.field_name`` as the option ``--field-name``."""
    try:
        check(*args, **kw)
    except ValueError as exc:
        raise ValueError(re.sub(r"^_\.(\w+)", lambda m: "--" + m[1].replace("_", "-"), str(exc))) from None


def _profile(args: InverseSettings, path: CirclePath | ManoeuvrePath, robot: RobotParams) -> inv.SpeedProfile:
    manoeuvre = isinstance(path, ManoeuvrePath)
    accel = args.accel if args.accel is not None or not manoeuvre else inv.MANOEUVRE_ACCEL
    decel = inv.MANOEUVRE_DECEL if args.decel is None else args.decel
    t_start = args.t_start if args.t_start is not None else (inv.MANOEUVRE_T_START if manoeuvre else 0.0)
    if args.brake_at is not None:
        t_cruise = t_start + (0.0 if accel is None else args.speed / accel)
        _as_options(check_real, "_", "brake_at", args.brake_at, t_cruise)
        return inv.TrapezoidProfile(args.speed, accel, decel, t_start, args.brake_at)
    if isinstance(path, ManoeuvrePath) and not args.no_brake:
        laps = inv.MANOEUVRE_LAPS if args.laps is None else args.laps
        return inv.manoeuvre_profile(path, args.speed, robot, accel=accel, decel=decel, t_start=t_start, laps=laps)
    if args.laps is not None:
        raise ValueError("--laps applies to --path manoeuvre only (use --brake-at for the circle)")
    if accel is None and t_start == 0.0:
        return inv.ConstantSpeed(args.speed)
    return inv.TrapezoidProfile(args.speed, accel, decel, t_start, None)


def _end(sol: inv.InverseSolution, names: str) -> str:
    return ", ".join(f"{k} = {getattr(sol, k)[-1]:.6f}" for k in names.split())


def _summary(sol: inv.InverseSolution, path: CirclePath | ManoeuvrePath, robot: RobotParams, speed: float) -> str:
    e = path.project(np.stack((sol.x_H, sol.y_H), axis=-1)).cross_track_error
    ss = inv.circle_steady_state(path.radius, speed, robot, path.direction)
    steady = {"betadot": ss.betadot, "alpha1_dot": ss.wheel_rates[0], "alpha2_dot": ss.wheel_rates[1]}
    steady["alpha3_dot"] = ss.castor_rate
    lines = [
        f"path: {type(path).__name__}, R = {path.radius:g} m, direction {path.direction:+d}; "
        f"{sol.t.size} samples, t = {sol.t[0]:g}..{sol.t[-1]:g} s",
        f"end: s = {sol.s[-1]:.6f} m, H = ({sol.x_H[-1]:.6f}, {sol.y_H[-1]:.6f}) m, beta = {sol.beta[-1]:.6f} rad",
        f"end rates [rad/s]: {_end(sol, 'betadot alpha1_dot alpha2_dot alpha3_dot')}",
        f"end angles [rad]: {_end(sol, 'alpha1 alpha2 alpha3')}",
        f"peak |drive wheel rate| = {float(np.max(np.abs(sol.wheel_rates))):.4f} rad/s (limit "
        f"{robot.max_wheel_rate:g}); max |cross-track error of H| = {float(np.max(np.abs(e))):.2e} m",
        "steady state on the circle (closed form): " + ", ".join(f"{k} = {float(v):.6f}" for k, v in steady.items()),
    ]
    return "\n".join(lines)


def _inverse(args: InverseSettings) -> None:
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
    sol = inv.solve_inverse(path, profile, inv.time_grid(duration, args.dt), robot)
    if args.csv is None:
        print(_summary(sol, path, robot, args.speed))
        return
    try:
        sol.to_csv(args.csv)
    except OSError as exc:
        raise ValueError(f"--csv: cannot write {args.csv!r}: {exc.strerror or exc}") from None
    print(f"wrote {sol.t.size} rows x {len(sol.columns())} columns to {args.csv}")


def main_inverse(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym inverse`` (module docstring); returns the exit status."""
    doc = "Analytic inverse solution of point H on a path (CSV or summary)."
    return run_command(InverseSettings, _inverse, argv, "amigo-gym inverse", doc)


@dataclass(frozen=True)
class Settings:
    """Settings of the paper's manoeuvre (each one is a command-line option of the same name).

    Attributes:
        out: output folder for the figures and the CSV [dir].
        speed: cruise speed of A, v_A [m/s] (paper: 0.2).
        radius: circle radius R [m].
        straight_length: straight part of the path [m].
        direction: +1 left turn, -1 right [-].
        accel: acceleration of A [m/s^2], at most the robot's 0.3.
        decel: deceleration of A [m/s^2], at most the robot's 0.75.
        t_start: standstill before the start [s].
        laps: laps of A's steady circle driven before A comes to rest [laps].
        tail: time at rest after stopping [s].
        dt: output time step [s].
        dpi: resolution of the PNG files [dots/inch].
    """

    out: str = "results/paper"
    speed: float = 0.2
    radius: float = 1.0
    straight_length: float = 1.0
    direction: int = 1
    accel: float = inv.MANOEUVRE_ACCEL
    decel: float = inv.MANOEUVRE_DECEL
    t_start: float = inv.MANOEUVRE_T_START
    laps: float = inv.MANOEUVRE_LAPS
    tail: float = 1.0
    dt: float = 0.01
    dpi: int = 120

    def __post_init__(self) -> None:
        robot = RobotParams()
        if self.direction not in (1, -1):
            raise ValueError(f"Settings.direction must be +1 or -1, got {self.direction!r}")
        limits = {"speed": (0, robot.max_speed, True), "radius": (robot.l3, 1e3, True), "straight_length": (0, 1e3)}
        limits |= {"accel": (0, robot.max_acceleration, True), "decel": (0, robot.max_deceleration, True)}
        limits |= {"t_start": (0, 1e3), "laps": (0, 100), "tail": (0, 1e3), "dt": (0, 1, True), "dpi": (20, 600)}
        check_fields("Settings", self, **limits)


def phases(
    sol: inv.InverseSolution, profile: inv.TrapezoidProfile, path: ManoeuvrePath
) -> list[tuple[str, float, float]]:
    """The phases ``(name, t0, t1 [s])`` standstill, starting (A accelerates), straight (until H's ``s =
    straight_length``), circle, braking, rest (empty ones dropped)."""
    t_end = float(sol.t[-1])
    moving = sol.s > sol.s[0]
    if path.straight_length > 0.0 and np.any(sol.s >= path.straight_length) and np.any(moving):
        i = int(np.argmax(sol.s >= path.straight_length))
        t_junction = float(np.interp(path.straight_length, sol.s[max(i - 1, 0) : i + 1], sol.t[max(i - 1, 0) : i + 1]))
    else:
        t_junction = profile.t_cruise if path.straight_length == 0.0 else t_end
    t_brake = t_end if profile.t_brake is None else profile.t_brake
    cuts = [
        ("standstill", 0.0, profile.t_start),
        ("starting", profile.t_start, profile.t_cruise),
        ("straight", profile.t_cruise, max(t_junction, profile.t_cruise)),
        ("circle", max(t_junction, profile.t_cruise), t_brake),
        ("braking", t_brake, profile.t_stop),
        ("rest", profile.t_stop, t_end),
    ]
    out = [(name, max(float(sol.t[0]), a), min(t_end, b)) for name, a, b in cuts]
    return [(name, a, b) for name, a, b in out if b > a]


def _shade(ax: Any, ph: list[tuple[str, float, float]]) -> None:
    for i, (name, t0, t1) in enumerate(ph):
        ax.axvspan(t0, t1, color=("#f2f2f2", "#ffffff")[i % 2], zorder=0)
        if i:
            ax.axvline(t0, color="0.6", lw=0.6, ls="--", zorder=1)
        kw = {"ha": "center", "va": "bottom", "fontsize": 7, "rotation": 0 if t1 - t0 > 4.0 else 60}
        ax.text(0.5 * (t0 + t1), 1.01, name, transform=ax.get_xaxis_transform(), **kw)


def _paper(settings: Settings) -> None:
    """Solve the manoeuvre, write the two figures and the CSV, print what it found."""
    robot = RobotParams()
    os.makedirs(settings.out, exist_ok=True)
    if not os.access(settings.out, os.W_OK):
        raise ValueError(f"--out folder {settings.out!r} is not writable")
    path = ManoeuvrePath(settings.radius, settings.straight_length, settings.direction)
    kw = {k: getattr(settings, k) for k in ("accel", "decel", "t_start", "laps")}
    profile = inv.manoeuvre_profile(path, settings.speed, robot, **kw)
    sol = inv.solve_inverse(path, profile, inv.time_grid(profile.t_stop + settings.tail, settings.dt), robot)
    ph = phases(sol, profile, path)
    ss = inv.circle_steady_state(settings.radius, settings.speed, robot, settings.direction)
    names = {"fig2": "paper_fig2_angles.png", "fig3": "paper_fig3_rates.png", "csv": "paper_manoeuvre.csv"}
    files = {k: os.path.join(settings.out, v) for k, v in names.items()}
    title = (
        f"v_A = {settings.speed:g} m/s, straight {settings.straight_length:g} m, R = {settings.radius:g} m, "
        f"a = {settings.accel:g} m/s², braking {settings.decel:g} m/s²"
    )

    for key, y1, y2, symbol, what, fig_no in (
        ("fig2", sol.alpha1, sol.alpha2, "α", "angle [rad]", 2),
        ("fig3", sol.alpha1_dot, sol.alpha2_dot, "α̇", "rate [rad/s]", 3),
    ):
        fig, ax = pyplot().subplots(figsize=(8.0, 4.2), layout="constrained")
        _shade(ax, ph)
        ax.plot(sol.t, y1, color="tab:blue", label=f"{symbol}1 (wheel 1, right)")
        ax.plot(sol.t, y2, color="tab:red", label=f"{symbol}2 (wheel 2, left)")
        if key == "fig3":
            for k, c in ((0, "tab:blue"), (1, "tab:red")):
                ax.axhline(float(ss.wheel_rates[k]), color=c, lw=0.8, ls=":")
            ax.plot([], [], color="0.3", lw=0.8, ls=":", label="steady state on the circle (closed form)")
            ax.set_ylim(-0.2, 1.25 * float(np.max(sol.wheel_rates)))
        ax.set(xlabel="t [s]", ylabel=f"wheel {what}", xlim=(sol.t[0], sol.t[-1]))
        ax.legend(loc="upper left" if key == "fig2" else "lower center", fontsize=None if key == "fig2" else 8)
        fig.suptitle(f"Wheel {what.split()[0]}s (cf. paper Fig. {fig_no}): " + title, fontsize=9)
        save_figure(fig, files[key], settings.dpi)

    sol.to_csv(files["csv"])
    print("settings: " + ", ".join(f"{k} {v}" for k, v in asdict(settings).items()))
    print("phases: " + ", ".join(f"{n} {a:.2f}-{b:.2f} s" for n, a, b in ph))
    print(
        f"peak wheel rates: alpha1_dot {float(np.max(np.abs(sol.alpha1_dot))):.4f}, "
        f"alpha2_dot {float(np.max(np.abs(sol.alpha2_dot))):.4f} rad/s (limit {robot.max_wheel_rate:g}); "
        f"peak |betadot| {float(np.max(np.abs(sol.betadot))):.4f} rad/s (limit {robot.max_rotation_rate:g})"
    )
    print(
        f"end: alpha1 = {sol.alpha1[-1]:.4f} rad, alpha2 = {sol.alpha2[-1]:.4f} rad, "
        f"s = {sol.s[-1]:.4f} m, beta = {sol.beta[-1]:.4f} rad ({math.degrees(sol.beta[-1]):.2f} deg)"
    )
    for v in files.values():
        print(f"wrote {v}")


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym paper`` (module docstring); returns the exit status."""
    doc = "The paper's manoeuvre: Fig. 2/3-style plots and a CSV."
    return run_command(Settings, _paper, argv, "amigo-gym paper", doc)
