"""The paper's manoeuvre, "starting, driving straight, driving on circular curve, braking" (its Figs 2, 3).

``amigo-gym paper --out DIR`` solves the inverse problem exactly (:func:`amigo_gym.task.inverse.solve_inverse`) for H on
the manoeuvre path and writes ``DIR/paper_fig2_angles.png`` (wheel angles, as Fig. 2), ``DIR/paper_fig3_rates.png``
(their rates, as Fig. 3, the closed-form steady state dotted) and ``DIR/paper_manoeuvre.csv`` (every column, SI units,
radians), the phases shaded. The default path and speed profile and why: docs/core.md."""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from amigo_gym.model.params import RobotParams
from amigo_gym.paths import ManoeuvrePath
from amigo_gym.task.inverse import (
    MANOEUVRE_ACCEL,
    MANOEUVRE_DECEL,
    MANOEUVRE_LAPS,
    MANOEUVRE_T_START,
    InverseSolution,
    TrapezoidProfile,
    circle_steady_state,
    manoeuvre_profile,
    solve_inverse,
    time_grid,
)
from amigo_gym.tools.options import check_fields, run_command
from amigo_gym.tools.plots import pyplot, save_figure

PROG = "amigo-gym paper"
FIG2 = "paper_fig2_angles.png"
FIG3 = "paper_fig3_rates.png"
CSV = "paper_manoeuvre.csv"


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
    accel: float = MANOEUVRE_ACCEL
    decel: float = MANOEUVRE_DECEL
    t_start: float = MANOEUVRE_T_START
    laps: float = MANOEUVRE_LAPS
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


@dataclass(frozen=True)
class Phase:
    """A phase of the manoeuvre: ``name`` from ``t0`` to ``t1`` [s]."""

    name: str
    t0: float
    t1: float


def phases(sol: InverseSolution, profile: TrapezoidProfile, path: ManoeuvrePath) -> list[Phase]:
    """The phases standstill, starting (A accelerates), straight (until H's ``s = straight_length``), circle,
    braking, rest (empty ones dropped)."""
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
    out = [Phase(name, max(float(sol.t[0]), a), min(t_end, b)) for name, a, b in cuts]
    return [p for p in out if p.t1 > p.t0]


def _shade(ax: Any, ph: list[Phase]) -> None:
    colours = ("#f2f2f2", "#ffffff")
    for i, p in enumerate(ph):
        ax.axvspan(p.t0, p.t1, color=colours[i % 2], zorder=0)
        if i:
            ax.axvline(p.t0, color="0.6", lw=0.6, ls="--", zorder=1)
        kw = {"ha": "center", "va": "bottom", "fontsize": 7, "rotation": 0 if p.t1 - p.t0 > 4.0 else 60}
        ax.text(0.5 * (p.t0 + p.t1), 1.01, p.name, transform=ax.get_xaxis_transform(), **kw)


def run(settings: Settings) -> tuple[InverseSolution, list[Phase], dict[str, str]]:
    """Solve the manoeuvre, write the two figures and the CSV; return the solution, phases and paths."""
    robot = RobotParams()
    os.makedirs(settings.out, exist_ok=True)
    if not os.access(settings.out, os.W_OK):
        raise ValueError(f"--out folder {settings.out!r} is not writable")
    path = ManoeuvrePath(settings.radius, settings.straight_length, settings.direction)
    kw = {k: getattr(settings, k) for k in ("accel", "decel", "t_start", "laps")}
    profile = manoeuvre_profile(path, settings.speed, robot, **kw)
    sol = solve_inverse(path, profile, time_grid(profile.t_stop + settings.tail, settings.dt), robot)
    ph = phases(sol, profile, path)
    ss = circle_steady_state(settings.radius, settings.speed, robot, settings.direction)
    files = {k: os.path.join(settings.out, v) for k, v in (("fig2", FIG2), ("fig3", FIG3), ("csv", CSV))}
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
    return sol, ph, files


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym paper``."""
    return run_command(Settings, _report, argv, PROG, "The paper's manoeuvre: Fig. 2/3-style plots and a CSV.")


def _report(settings: Settings) -> int:
    """:func:`run`, then what it found on stdout."""
    sol, ph, files = run(settings)
    robot = RobotParams()
    print("settings: " + ", ".join(f"{k} {v}" for k, v in asdict(settings).items()))
    print("phases: " + ", ".join(f"{p.name} {p.t0:.2f}-{p.t1:.2f} s" for p in ph))
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
