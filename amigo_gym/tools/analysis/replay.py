"""``amigo-gym replay`` and ``amigo-gym identify``: a robot's log against the model (:mod:`amigo_gym.logs`).

``replay LOG --out DIR`` writes ``trajectory.csv``, ``replay.png``, ``summary.json``; ``identify LOG --out DIR`` fits
the true robot and writes ``robot.json`` (for ``gym.make("AmigoBot-v1", true_robot=...)``), ``trajectory.csv``,
``identify.png``, ``summary.json`` (docs/logs.md). ``DIR`` is written whole or not at all (:func:`write_folder`).
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from amigo_gym.io import file_mode, fsync_dir, json_safe
from amigo_gym.logs import Log, Replay, errors, identify, noise_level, read_log, replay, robot_from_file
from amigo_gym.model.actuators import ActuatorParams
from amigo_gym.model.params import RobotParams
from amigo_gym.tools.options import cli, run_command
from amigo_gym.tools.plots import pyplot, save_figure


def trajectory_csv(log: Log, rep: Replay) -> str:
    """The side-by-side table of ``trajectory.csv`` (module docstring) as CSV text."""
    e = errors(log, rep)
    xyt = ("x", "y", "theta")
    cols: dict[str, Any] = {"t": rep.t}
    if log.pose is not None:
        cols |= {f"{n}_meas": log.pose[:, i] for i, n in enumerate(xyt)}
    cols |= {f"{n}_sim": rep.pose[:, i] for i, n in enumerate(xyt)}
    if log.pose is not None:
        cols |= {"position_error": e["position"], "heading_error": e["heading"]}
    if log.rates is not None:
        cols["w1_meas"], cols["w2_meas"] = log.rates[:, 0], log.rates[:, 1]
    cols["w1_sim"], cols["w2_sim"] = rep.rates[:, 0], rep.rates[:, 1]
    rows = (",".join(repr(float(v)) for v in row) for row in zip(*cols.values(), strict=True))
    return "\n".join([",".join(cols), *rows]) + "\n"


def plot(path: str, log: Log, reps: Sequence[tuple[str, Replay]], title: str) -> None:
    """The comparison figure: A's path in the plane, wheel rates and errors over time, of the ``(label, replay)``
    pairs ``reps`` (the last one in full colour, the others thin)."""
    fig = pyplot().figure(figsize=(10.0, 7.0), layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=(1.0, 1.4))
    ax_xy = fig.add_subplot(grid[:, 0])
    ax_w = fig.add_subplot(grid[0, 1])
    ax_e = fig.add_subplot(grid[1, 1], sharex=ax_w)
    styles = [{"lw": 0.9, "ls": "--", "alpha": 0.8}] * (len(reps) - 1) + [{"lw": 1.4, "ls": "-", "alpha": 1.0}]
    if log.pose is not None:
        ax_xy.plot(log.pose[:, 0], log.pose[:, 1], ".", color="k", ms=2.5, label="measured")
    for (label, rep), st in zip(reps, styles, strict=True):
        ax_xy.plot(rep.pose[:, 0], rep.pose[:, 1], color="tab:green" if st["ls"] == "-" else "tab:orange",
                   label=f"simulated, {label}", lw=st["lw"], ls=st["ls"])  # fmt: skip
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.set(xlabel="x of A [m]", ylabel="y of A [m]")
    ax_xy.legend(fontsize=8, loc="best")
    ax_xy.set_title("path of A", fontsize=9)

    label, rep = reps[-1]
    t = rep.t - rep.t[0]
    for i, c in enumerate(("tab:blue", "tab:red")):
        ax_w.plot(t, rep.rates[:, i], color=c, lw=1.2, label=f"α̇{i + 1} simulated ({label})")
        if log.rates is not None:
            ax_w.plot(t, log.rates[:, i], ".", color=c, ms=2.5, label=f"α̇{i + 1} measured")
        ax_w.step(
            log.t_cmd - rep.t[0], log.cmd[:, i], where="post", color=c, lw=0.6, alpha=0.5, label=f"α̇{i + 1} command"
        )
    ax_w.set(ylabel="wheel rate [rad/s]", xlim=(t[0], t[-1]))
    ax_w.legend(fontsize=7, ncol=2, loc="best")
    ax_w.set_title("wheel rates (cf. the paper's Figs 3 and 5)", fontsize=9)

    for (label, rep), st in zip(reps, styles, strict=True):
        e = errors(log, rep)
        if "position" in e:
            ax_e.plot(t, 1e3 * e["position"], color="k", label=f"position [mm], {label}", **st)
            ax_e.plot(t, 1e3 * np.abs(e["heading"]), color="tab:purple", label=f"heading [mrad], {label}", **st)
        else:
            for i, c in enumerate(("tab:blue", "tab:red")):
                ax_e.plot(t, np.abs(e[f"rate{i + 1}"]), color=c, label=f"α̇{i + 1} [rad/s], {label}", **st)
    if (noise := noise_level(log)) is not None:
        label = f"position noise, {1e3 * noise:.2g} mm (estimated)"
        ax_e.axhline(1e3 * noise, color="0.4", lw=0.8, ls=":", label=label)
    ax_e.set(yscale="log", xlabel="t [s]", ylabel="|simulated − measured|")
    ax_e.legend(fontsize=7, loc="best")
    ax_e.set_title("error over time", fontsize=9)
    fig.suptitle(title, fontsize=9)
    save_figure(fig, path, dpi=120)


def check_out(out: Path, force: bool) -> None:
    """``FileExistsError`` if ``--out`` is a file, or a folder that is not empty without ``force``."""
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"--out {str(out)!r} is a file, not a folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise FileExistsError(f"--out folder {str(out)!r} exists and is not empty; choose another or pass --force")


def write_folder(out: Path, files: dict[str, Callable[[str], object]], force: bool) -> None:
    """Write every file by its writer ``files[name](path)`` into a temporary folder beside ``out``, then move it to
    ``out`` (replacing an existing ``out`` only when ``force``); a killed run's temporary folder is removed by the
    next run for ``out``."""
    check_out(out, force)
    parent = out.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    for left in [*parent.glob(f".{out.name}.*.tmp"), *parent.glob(f".{out.name}.*.old")]:
        pid = left.name[len(out.name) + 2 :].partition("-")[0]
        if not (pid.isdigit() and _alive(int(pid))):  # a killed run's; a running one's stays
            shutil.rmtree(left, ignore_errors=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.{os.getpid()}-", suffix=".tmp", dir=parent))
    old: Path | None = None
    try:
        for name, writer in files.items():
            target = str(tmp / name)
            writer(target)
            with open(target, "rb+") as fh:
                os.fsync(fh.fileno())
        os.chmod(tmp, file_mode(folder=True))
        fsync_dir(tmp)
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.{os.getpid()}-", suffix=".old", dir=parent))
            os.replace(out, old / "x")
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and (old / "x").exists() and not out.exists():
            os.replace(old / "x", out)
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    fsync_dir(parent)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's
        pass
    return True


def _text(data: str) -> Callable[[str], object]:
    return lambda p: Path(p).write_text(data, encoding="utf-8")


def _json(obj: Any) -> Callable[[str], object]:
    return _text(json.dumps(json_safe(obj), indent=2, allow_nan=False) + "\n")


@dataclass(frozen=True)
class LogSettings:
    """Options of ``amigo-gym replay`` and ``amigo-gym identify``, each the option of the same name.

    Attributes:
        log: the log: a CSV file or a ROS 2 bag (folder, .db3 or .mcap) [file] (required).
        out: output folder, written whole or not at all [dir] (required).
        force: replace a non-empty --out folder once the new one is complete.
        cmd_topic: bag topic of the velocity commands (Twist) [topic].
        nominal: the nominal robot and firmware ramps, a JSON of RobotParams and ActuatorParams fields [file]
            (default: the AmigoBot's).
        pose_topic: bag topic of the measured pose of A (Odometry, PoseStamped) [topic].
    """

    log: str = field(metadata=cli(positional=True))
    out: str
    force: bool = False
    cmd_topic: str = "/cmd_vel"
    nominal: str | None = None
    pose_topic: str = "/odom"


@dataclass(frozen=True)
class ReplaySettings(LogSettings):
    """Options of ``amigo-gym replay``.

    Attributes:
        robot: robot file (robot.json of identify) [file] (default: the nominal robot).
    """

    robot: str | None = None


@dataclass(frozen=True)
class IdentifySettings(LogSettings):
    """Options of ``amigo-gym identify``.

    Attributes:
        ramps: fit the ramp rates: where the log excites them, always, never.
        heading_weight: weight of heading errors in the fit [m/rad], in (0, 1000) (default: the nominal half track).
    """

    ramps: Literal["auto", "fit", "fixed"] = "auto"
    heading_weight: float | None = None

    def validate(self) -> None:
        """Raise ``ValueError`` naming the option, its allowed range and the value."""
        if self.heading_weight is not None and not 0.0 < self.heading_weight < 1e3:
            raise ValueError(f"--heading-weight must be in (0, 1000) m/rad, got {self.heading_weight!r}")


def _read(args: LogSettings) -> tuple[Path, RobotParams, ActuatorParams, Log]:
    """``--out`` checked, the nominal robot and ramps (``--nominal``, its delay ignored) and the log."""
    check_out(Path(args.out), args.force)
    nominal, act = RobotParams(), ActuatorParams()
    if args.nominal is not None:
        nominal, act = robot_from_file(args.nominal)
        act = replace(act, delay=0.0)
    return Path(args.out), nominal, act, read_log(args.log, nominal, args.cmd_topic, args.pose_topic)


def _replay(args: ReplaySettings) -> None:
    out, nominal, nominal_act, log = _read(args)
    robot, act, label = nominal, nominal_act, "nominal robot"
    if args.robot is not None:
        (robot, act), label = robot_from_file(args.robot, nominal, nominal_act), Path(args.robot).name
    rep, summary = replay(log, robot, act, nominal)
    used = {"r1": robot.r1, "r2": robot.r2, "l1": robot.l1, "delay": act.delay, "acceleration": act.acceleration,
            "rot_acceleration": act.rot_acceleration}  # fmt: skip
    summary = {**summary, "robot": used, "robot_file": args.robot, "log": log.source}
    files: dict[str, Callable[[str], object]] = {
        "trajectory.csv": _text(trajectory_csv(log, rep)),
        "replay.png": lambda path: plot(path, log, [(label, rep)], f"replay of {log.source}: {label}"),
        "summary.json": _json(summary),
    }
    write_folder(out, files, args.force)
    rms = summary["rms_position_error_m"]
    shown = f"rms position error {rms:.4g} m" if rms is not None else (
        f"rms wheel-rate error {summary['rms_wheel_rate_error_rad_s']:.4g} rad/s")  # fmt: skip
    print(f"replay: {log.t_meas.size} samples, {shown}; wrote {out}/trajectory.csv, replay.png, summary.json")


def main_replay(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym replay`` (module docstring)."""
    doc = "Replay a robot's log through the model; compare."
    return run_command(ReplaySettings, _replay, argv, "amigo-gym replay", doc)


def _identify(args: IdentifySettings) -> None:
    out, nominal, nominal_act, log = _read(args)
    fit = identify(log, nominal, args.ramps, args.heading_weight, nominal_act)
    before = replay(log, nominal, nominal_act, nominal)[0]
    after = replay(log, fit.robot, fit.actuators, nominal)[0]
    summary = {"values": fit.values, "uncertainty": fit.uncertainty, "fitted": list(fit.fitted), "fixed": fit.fixed,
               "replay_before": fit.before, "replay_after": fit.after, "cost": fit.cost, "n_residuals": fit.n_residuals,
               "model_evaluations": fit.nfev, "ramping_s": fit.excited, "log": log.source}  # fmt: skip
    files: dict[str, Callable[[str], object]] = {
        "robot.json": _json(fit.robot_json(log, nominal)),
        "trajectory.csv": _text(trajectory_csv(log, after)),
        "identify.png": lambda path: plot(
            path, log, [("nominal", before), ("identified", after)], f"identification from {log.source}"
        ),
        "summary.json": _json(summary),
    }
    write_folder(out, files, args.force)
    parts = [f"{k} = {fit.values[k]:.5g} ± {u:.2g}" if (u := fit.uncertainty.get(k)) is not None
             else f"{k} = {fit.values[k]:.5g}" for k in fit.fitted]  # fmt: skip
    b, a = fit.before["rms_position_error_m"], fit.after["rms_position_error_m"]
    err = f"; rms position error {b:.4g} m -> {a:.4g} m" if a is not None else ""
    print(f"identify: {', '.join(parts)}{err}; wrote {out}/robot.json, trajectory.csv, identify.png, summary.json")


def main_identify(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym identify`` (module docstring)."""
    doc = "Fit the robot's radii, track, delay to a log."
    return run_command(IdentifySettings, _identify, argv, "amigo-gym identify", doc)
