"""Logs of a real robot: read them, replay them through the model, fit the model's parameters to them.

Logs are CSV files (:data:`CSV_COLUMNS`: ``t``, ``cmd_w1``, ``cmd_w2`` required, with ``x, y, theta`` of A
and/or ``w1, w2``) or ROS 2 bags (:func:`read_bag`), refused in one line (:class:`LogError`) by :func:`check_log`.
:func:`replay` drives :func:`amigo_gym.model.actuators.actuator_step` with the commands; :func:`identify` fits the
true radii, half track, delay and ramps by bounded least squares. Format, topics, messages: ``docs/logs.md``."""

from __future__ import annotations

import csv
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.io import finite_float
from amigo_gym.model.actuators import (
    MAX_DELAY,
    MAX_TRUE_DEVIATION,
    ActuatorParams,
    actuator_step,
    step_subintervals,
    wheel_rates_columns,
)
from amigo_gym.model.kinematics import body_velocity
from amigo_gym.model.params import RobotParams, show_value
from amigo_gym.paths.classic import wrap_angle

Array = NDArray[np.float64]

#: the columns of the CSV log format, with their units (docs/logs.md)
CSV_COLUMNS: dict[str, str] = {"t": "s", "cmd_w1": "rad/s", "cmd_w2": "rad/s", "x": "m", "y": "m", "theta": "rad",
                                "w1": "rad/s", "w2": "rad/s"}  # fmt: skip

#: search boxes of :func:`identify`: r1, r2, l1 within nominal * (1 +- FIT_BOUNDS), ramps within nominal * RAMP_FACTORS
FIT_BOUNDS = MAX_TRUE_DEVIATION
RAMP_FACTORS = (0.1, 10.0)
RAMP_NAMES = ("acceleration", "rot_acceleration")
XTOL = 1e-10
_ROBOT_FIELDS = frozenset(f.name for f in fields(RobotParams))
_ACTUATOR_FIELDS = frozenset(f.name for f in fields(ActuatorParams))
_META_FIELDS = frozenset(
    ("format", "uncertainty", "fitted", "fixed", "start_pose", "replay_before", "replay_after", "log", "nominal", "fit")
)
ROBOT_FORMAT = "amigo_gym robot 1"


class LogError(ValueError):
    """A log that cannot be used: the message is one line naming the problem (the CLI's exit status 2)."""


@dataclass(frozen=True)
class Log:
    """A recorded run: setpoints ``cmd`` ``(w1c, w2c)`` [rad/s], ``(n, 2)``, each held from its time ``t_cmd`` [s]
    until the next; at the times ``t_meas`` [s], ``(m >= 3,)``, the measured pose of A ``(x, y, theta)`` [m, m, rad],
    ``(m, 3)``, theta unwrapped, and wheel rates ``(w1, w2)`` [rad/s], ``(m, 2)``, each ``None`` if not measured.
    Times strictly increasing; ``source``: file name and topics."""

    t_cmd: Array
    cmd: Array
    t_meas: Array
    pose: Array | None
    rates: Array | None
    source: str = ""


@dataclass(frozen=True)
class Replay:
    """The model driven by a log's commands (:func:`simulate`) at the measurement times ``t`` [s], ``(m,)``: pose of
    A ``(x, y, theta)`` [m, m, rad], ``(m, 3)``, theta continuous, and wheel rates ``(w1, w2)`` [rad/s], ``(m, 2)``."""

    t: Array
    pose: Array
    rates: Array


def _cell_problem(where: str, column: str, cell: str, line: int, not_finite: bool) -> str:
    if not_finite:
        return f"{where}: column {column!r}: {cell} at line {line}; every value must be finite"
    return f"{where}: column {column!r}: {cell!r} at line {line} is not a number"


def read_csv(path: str | os.PathLike[str], nominal: RobotParams | None = None) -> Log:
    """A CSV log (docs/logs.md), checked (:func:`check_log`). Raises ``FileNotFoundError`` or a one-line
    :class:`LogError` (missing column, text, NaN, time not increasing, units)."""
    nominal = RobotParams() if nominal is None else nominal
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"log {str(p)!r} does not exist or is not a file")
    with open(p, newline="", encoding="utf-8-sig") as fh:
        rows = [(i + 1, r) for i, r in enumerate(csv.reader(fh)) if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise LogError(f"{p.name}: empty log (no header row)")
    header_line, header = rows[0]
    names = [h.strip() for h in header]
    if dup := sorted({n for n in names if names.count(n) > 1}):
        raise LogError(f"{p.name}: column(s) {dup} appear more than once in the header (line {header_line})")
    has_pose, has_rates = ([c in names for c in g] for g in (("x", "y", "theta"), ("w1", "w2")))
    missing = [c for c in ("t", "cmd_w1", "cmd_w2") if c not in names]
    for group, has in ((("x", "y", "theta"), has_pose), (("w1", "w2"), has_rates)):
        missing += [c for c, h in zip(group, has, strict=True) if any(has) and not h]
    if missing:
        raise LogError(f"{p.name}: missing column(s) {missing}; the header has {names} (a log needs t, cmd_w1, "
                       "cmd_w2 and x, y, theta and/or w1, w2)")  # fmt: skip
    if not any(has_pose) and not any(has_rates):
        raise LogError(
            f"{p.name}: no measurement columns: a log needs x, y, theta and/or w1, w2; the header has {names}"
        )
    used = [c for c in CSV_COLUMNS if c in names]
    index = {c: names.index(c) for c in used}
    data = np.empty((len(rows) - 1, len(used)))
    for k, (line, row) in enumerate(rows[1:]):
        for j, c in enumerate(used):
            i = index[c]
            if i >= len(row) or not row[i].strip():
                raise LogError(f"{p.name}: column {c!r} is empty at line {line}")
            data[k, j] = finite_float(row[i], partial(_cell_problem, p.name, c, row[i].strip(), line), LogError)
    if data.shape[0] < 3:
        raise LogError(f"{p.name}: {data.shape[0]} data row(s); a log needs at least 3")
    col = {c: data[:, j] for j, c in enumerate(used)}
    t = col["t"]
    if (bad := np.flatnonzero(np.diff(t) <= 0.0)).size:
        k = int(bad[0]) + 1
        raise LogError(
            f"{p.name}: time t is not strictly increasing at line {rows[k + 1][0]} "
            f"(t = {float(t[k])!r} after {float(t[k - 1])!r})"
        )
    pose = np.stack([col["x"], col["y"], np.unwrap(col["theta"])], axis=1) if all(has_pose) else None
    rates = np.stack([col["w1"], col["w2"]], axis=1) if all(has_rates) else None
    cmd = np.stack([col["cmd_w1"], col["cmd_w2"]], axis=1)
    log = Log(t.copy(), cmd, t.copy(), pose, rates, source=p.name)
    check_log(log, nominal, names={"t": "t", "cmd": "cmd_w1, cmd_w2", "pose": "x, y", "theta": "theta",
                                   "rates": "w1, w2"}, where=p.name)  # fmt: skip
    return log


_TWIST_TYPES = ("geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped")
_POSE_TYPES = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/PoseWithCovarianceStamped")


def read_bag(
    path: str | os.PathLike[str], nominal: RobotParams | None = None, cmd_topic: str = "/cmd_vel",
    pose_topic: str = "/odom",
) -> Log:  # fmt: skip
    r"""A ROS 2 bag (a rosbag2 folder, or its ``.db3``/``.mcap`` file) as a :class:`Log`, checked.

    A Twist ``(v, w)`` [m/s, rad/s] gives the nominal setpoints ``((v + l1 w) / r1, (v - l1 w) / r2)``; a pose message
    A's ``x``, ``y`` and heading ``atan2(2(qw qz + qx qy), 1 - 2(qy^2 + qz^2))``. Times: record times [s] from the
    first message of either topic; of messages at one time on one topic, the last counts. Raises
    ``FileNotFoundError`` or :class:`LogError` (not a bag, empty, a topic missing or of another type, NaN, units)."""
    nominal = RobotParams() if nominal is None else nominal
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"log {str(p)!r} does not exist")
    from rosbags.highlevel import AnyReader  # the 'logs' extra

    folder = p if p.is_dir() else p.parent
    try:
        reader = AnyReader([folder])
        reader.open()
    except Exception as exc:  # rosbags raises its own errors for a folder that is not a bag
        raise LogError(f"{p.name}: not a readable ROS 2 bag ({' '.join(str(exc).split())})") from None
    try:
        topics = {c.topic: c.msgtype for c in reader.connections}
        if not topics or reader.message_count == 0:
            raise LogError(f"{p.name}: empty bag (no messages)")
        listing = ", ".join(f"{k} [{v}]" for k, v in sorted(topics.items()))
        for topic, kinds, what in ((cmd_topic, _TWIST_TYPES, "command"), (pose_topic, _POSE_TYPES, "pose")):
            if topic not in topics:
                raise LogError(f"{p.name}: {what} topic {topic!r} is not in the bag (topics: {listing})")
            if topics[topic] not in kinds:
                raise LogError(
                    f"{p.name}: {what} topic {topic!r} has type {topics[topic]}, expected one of {list(kinds)}"
                )
        t_c: list[int] = []
        cmd: list[tuple[float, float]] = []
        t_p: list[int] = []
        pose: list[tuple[float, float, float]] = []
        conns = [c for c in reader.connections if c.topic in (cmd_topic, pose_topic)]
        for conn, stamp, raw in reader.messages(connections=conns):
            msg: Any = reader.deserialize(raw, conn.msgtype)
            if conn.topic == cmd_topic:
                tw = msg.twist if conn.msgtype.endswith("Stamped") else msg
                t_c.append(stamp)
                cmd.append((float(tw.linear.x), float(tw.angular.z)))
            else:
                ps = msg.pose if conn.msgtype.endswith("PoseStamped") else msg.pose.pose
                q = ps.orientation
                t_p.append(stamp)
                yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
                pose.append((float(ps.position.x), float(ps.position.y), yaw))
    finally:
        reader.close()
    for topic, ts, vals in ((cmd_topic, t_c, cmd), (pose_topic, t_p, pose)):
        if not ts:
            raise LogError(f"{p.name}: topic {topic!r} has no messages")
        arr = np.asarray(vals, dtype=np.float64)
        if (bad := np.flatnonzero(~np.isfinite(arr).all(axis=1))).size:
            raise LogError(f"{p.name}: topic {topic!r}: NaN or inf in message {int(bad[0])} (of {len(ts)})")
    t0 = min(t_c[0], t_p[0])
    t_cmd, vc = _last_of_equal(t_c, cmd, t0)
    t_meas, vp = _last_of_equal(t_p, pose, t0)
    if t_meas.size < 3:
        raise LogError(f"{p.name}: topic {pose_topic!r} has {t_meas.size} message(s); a log needs at least 3")
    wheel = np.stack(wheel_rates_columns(vc[:, 0], vc[:, 1], nominal), axis=1)
    vp[:, 2] = np.unwrap(vp[:, 2])
    log = Log(t_cmd, wheel, t_meas, vp, None, source=f"{p.name} ({cmd_topic}, {pose_topic})")
    check_log(log, nominal, names={"t": "bag time", "cmd": f"{cmd_topic} (as wheel rates)", "pose": pose_topic,
                                   "theta": f"{pose_topic} heading", "rates": ""}, where=p.name)  # fmt: skip
    return log


def _last_of_equal(stamps: Sequence[int], values: Sequence[Any], t0: int) -> tuple[Array, Array]:
    """Samples in time order, times [s] since t0 [ns]; of equal times the last (a stable sort keeps the bag's order)."""
    t = np.asarray(stamps, dtype=np.int64)
    order = np.argsort(t, kind="stable")
    t, v = t[order], np.asarray(values)[order]
    keep = np.append(t[1:] != t[:-1], True)
    return np.asarray((t[keep] - t0) * 1e-9, dtype=np.float64), v[keep]


def read_log(
    path: str | os.PathLike[str], nominal: RobotParams | None = None, cmd_topic: str = "/cmd_vel",
    pose_topic: str = "/odom",
) -> Log:  # fmt: skip
    """A log from a CSV file (``.csv``) or a ROS 2 bag (a folder, ``.db3`` or ``.mcap``), checked. Raises
    ``FileNotFoundError`` or a one-line :class:`LogError` (docs/logs.md; also for an unknown kind of file)."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"log {str(p)!r} does not exist")
    if p.is_dir() or p.suffix.lower() in (".db3", ".mcap"):
        return read_bag(p, nominal, cmd_topic, pose_topic)
    if p.suffix.lower() in (".csv", ".txt"):
        return read_csv(p, nominal)
    raise LogError(f"{p.name}: unknown kind of log (a .csv file or a ROS 2 bag folder / .db3 / .mcap file)")


def check_log(log: Log, nominal: RobotParams, names: Mapping[str, str], where: str) -> None:
    """Refuse (:class:`LogError`: one line naming the quantity, what was found and the likely unit mistake) a log
    whose units look wrong: median sample interval outside [1e-4, 5] s, wheel rates over 3 times the limit, A over 3
    times its top speed, measured travel, turn or wheel rates off by more than 10 times from what the commands give.
    ``names`` maps ``t``, ``cmd``, ``pose``, ``theta``, ``rates`` to the user's column or topic names."""
    t = log.t_meas
    step = float(np.median(np.diff(t)))
    if not 1e-4 <= step <= 5.0:
        guess = "milliseconds or nanoseconds" if step > 5.0 else "a unit smaller than seconds"
        raise LogError(
            f"{where}: {names['t']}: the median sample interval is {step:.4g}, outside [1e-4, 5] s; "
            f"time must be in seconds (is it in {guess}?)"
        )
    w_max = nominal.max_wheel_rate
    for key, arr in (("cmd", log.cmd), ("rates", log.rates)):
        if arr is not None and (top := float(np.max(np.abs(arr)))) > 3.0 * w_max:
            raise LogError(
                f"{where}: {names[key]}: |wheel rate| up to {top:.4g} rad/s, over 3 times the robot's limit "
                f"{w_max:g} rad/s; wheel rates must be in rad/s (deg/s or rpm?)"
            )
    # windows of about 1 s, and the integrals of the commanded speed and turn rate (nominal robot) at their ends
    win = np.unique(np.clip(np.searchsorted(t, np.arange(t[0], t[-1] + 1.0, 1.0)), 0, t.size - 1))
    win = win if win.size >= 2 else np.array([0, t.size - 1])
    vw = np.stack(body_velocity(log.cmd, nominal))  # (2, n): speed and turn rate
    grid = np.union1d(log.t_cmd, t[win])
    j = np.searchsorted(log.t_cmd, grid[:-1], side="right") - 1
    held = np.where(j >= 0, vw[:, np.maximum(j, 0)], 0.0)
    s = np.concatenate([np.zeros((2, 1)), np.cumsum(held * np.diff(grid), axis=1)], axis=1)
    cmd_travel, cmd_turn = np.sum(np.abs(np.diff(s[:, np.searchsorted(grid, t[win])], axis=1)), axis=1).tolist()
    if log.pose is not None:
        xy = log.pose[win, :2]
        hops = np.hypot(*np.diff(xy, axis=0).T)
        speed = float(np.max(hops / np.diff(t[win])))
        if speed > 3.0 * nominal.max_speed:
            raise LogError(
                f"{where}: {names['pose']}: the measured point A moves at up to {speed:.4g} m/s, over 3 times the "
                f"robot's top speed {nominal.max_speed:g} m/s; positions must be in metres (millimetres?)"
            )
        _ratio(where, names["pose"], float(np.sum(hops)), cmd_travel, 0.1, "travel [m]", "millimetres or centimetres")
        turn = float(np.sum(np.abs(np.diff(log.pose[win, 2]))))
        _ratio(where, names["theta"], turn, cmd_turn, 0.5, "turn [rad]", "degrees")
    if log.rates is not None:
        meas = float(np.mean(np.abs(log.rates)))
        j = np.searchsorted(log.t_cmd, t, side="right") - 1
        cmd = float(np.mean(np.abs(log.cmd[np.maximum(j, 0)][j >= 0]))) if np.any(j >= 0) else 0.0
        _ratio(where, names["rates"], meas, cmd, 0.2, "mean |wheel rate| [rad/s]", "deg/s, rpm or m/s")


def _ratio(where: str, name: str, measured: float, commanded: float, floor: float, what: str, guess: str) -> None:
    """Refuse ``measured`` more than 10 times or less than a tenth of ``commanded`` (both at least ``floor``)."""
    if max(measured, commanded) < floor:
        return
    if measured > 10.0 * max(commanded, floor) or commanded > 10.0 * max(measured, floor):
        raise LogError(
            f"{where}: {name}: the measured {what} is {measured:.4g} where the commands give {commanded:.4g}; "
            f"off by more than 10 times: check the units ({guess}?)"
        )


def simulate(
    log: Log, true_robot: RobotParams | None = None, actuators: ActuatorParams | None = None,
    nominal: RobotParams | None = None, start: Sequence[float] | None = None,
) -> Replay:  # fmt: skip
    """A :class:`Replay` at ``log.t_meas`` of ``true_robot`` (default ``nominal``, default :class:`RobotParams`) with
    ``actuators`` (default :class:`ActuatorParams`) driven by the log's commands, that of ``t_cmd[j]`` from
    ``t_cmd[j] + delay`` (before: the start rates held), by :func:`amigo_gym.model.actuators.actuator_step` (no slip)
    split at every switch; from ``start`` [m, m, rad] at ``t_meas[0]`` (default the first measured pose, else the
    origin) and the first measured wheel rates (else 0)."""
    nominal = RobotParams() if nominal is None else nominal
    robot = nominal if true_robot is None else true_robot
    act = ActuatorParams() if actuators is None else actuators
    if start is None:
        start = (0.0, 0.0, 0.0) if log.pose is None else tuple(log.pose[0].tolist())
    x, y, beta = (float(v) for v in start)
    w1, w2 = (0.0, 0.0) if log.rates is None else (float(log.rates[0, 0]), float(log.rates[0, 1]))
    c0 = (w1, w2)
    t = log.t_meas
    switch = log.t_cmd + act.delay
    cmds = log.cmd.tolist()
    dev = max(abs(robot.r1 / nominal.r1 - 1), abs(robot.r2 / nominal.r2 - 1), abs(nominal.l1 / robot.l1 - 1))
    n_sub = step_subintervals(float(np.max(np.diff(t))), nominal, min(max(dev, MAX_TRUE_DEVIATION), 1.0))
    r1t, r2t, l1t = robot.r1, robot.r2, robot.l1
    out = np.empty((t.size, 5))
    out[0] = (x, y, beta, w1, w2)
    ts = t.tolist()
    lo_all = np.searchsorted(switch, t, side="left").tolist()  # first switch at or after each t
    for k in range(t.size - 1):
        ta, tb = ts[k], ts[k + 1]
        lo, hi = lo_all[k], lo_all[k + 1]
        cur = c0 if lo == 0 else cmds[lo - 1]
        # calls (held, new, switch time, length): the first switch inside the first call, one call per further switch
        edges = [*switch[lo + 1 : hi].tolist(), tb]
        calls = [(cur, cur, 0.0, tb - ta)] if hi == lo else [(cur, cmds[lo], float(switch[lo]) - ta, edges[0] - ta)]
        calls += [(cmds[lo + i], cmds[lo + i], 0.0, edges[i] - edges[i - 1]) for i in range(1, len(edges))]
        for i, (a, b, t_switch, length) in enumerate(calls):
            if i == 0 or length > 0.0:
                s = actuator_step(x, y, beta, w1, w2, a[0], a[1], b[0], b[1], t_switch, length, nominal, act,
                                  r1t, r2t, l1t, n_sub=n_sub)  # fmt: skip
                x, y, beta, w1, w2 = float(s.x), float(s.y), float(s.beta), float(s.w1), float(s.w2)
        out[k + 1] = (x, y, beta, w1, w2)
    return Replay(t.copy(), out[:, :3].copy(), out[:, 3:].copy())


def errors(log: Log, rep: Replay) -> dict[str, Array]:
    """Simulated minus measured per sample, of what the log measures: ``position`` (distance of A [m]), ``heading``
    (wrapped [rad]), ``rate1``, ``rate2`` [rad/s]."""
    out: dict[str, Array] = {}
    if log.pose is not None:
        d = rep.pose - log.pose
        out["position"] = np.hypot(d[:, 0], d[:, 1])
        out["heading"] = wrap_angle(d[:, 2])
    if log.rates is not None:
        out["rate1"] = rep.rates[:, 0] - log.rates[:, 0]
        out["rate2"] = rep.rates[:, 1] - log.rates[:, 1]
    return out


def summarize(log: Log, rep: Replay) -> dict[str, Any]:
    """RMS and maximum errors of a replay (``None`` for what the log does not measure), keyed as returned."""
    e = errors(log, rep)
    p, h = e.get("position"), e.get("heading")
    r = np.concatenate([e["rate1"], e["rate2"]]) if "rate1" in e else None

    def stat(f: Any, a: Array | None) -> float | None:
        return None if a is None else float(f(a))

    return {
        "n_samples": int(log.t_meas.size),
        "duration_s": float(log.t_meas[-1] - log.t_meas[0]),
        "rms_position_error_m": stat(_rms, p),
        "max_position_error_m": stat(np.max, p),
        "final_position_error_m": stat(lambda a: a[-1], p),
        "rms_heading_error_rad": stat(_rms, h),
        "max_heading_error_rad": stat(lambda a: np.max(np.abs(a)), h),
        "rms_wheel_rate_error_rad_s": stat(_rms, r),
        "max_wheel_rate_error_rad_s": stat(lambda a: np.max(np.abs(a)), r),
    }


def _rms(a: Array) -> float:
    return float(np.sqrt(np.mean(a**2)))


def placed(pose: Array, start: Sequence[float] | Array) -> Array:
    """Poses ``(m, 3)`` of a motion from the origin moved rigidly to start at ``start`` ``(x, y, theta)``."""
    c, s = math.cos(start[2]), math.sin(start[2])
    px, py = pose[:, 0], pose[:, 1]
    return np.stack([start[0] + c * px - s * py, start[1] + s * px + c * py, start[2] + pose[:, 2]], axis=1)


def fit_start(log: Log, origin: Replay, heading_weight: float) -> tuple[float, float, float]:
    """The start pose ``(x0, y0, theta0)`` [m, m, rad] placing ``origin`` (a replay from the origin) on the log's first
    poses (a fifth, at least 10): least squares of the position errors and ``heading_weight`` [m/rad] x heading."""
    from scipy.optimize import least_squares  # heavy: only here

    if log.pose is None:
        raise ValueError("fit_start: the log measures no pose")
    k = min(log.t_meas.size, max(10, math.ceil(log.t_meas.size / 5)))
    meas, sim = log.pose[:k], origin.pose[:k]

    def residuals(z: Array) -> Array:
        d = placed(sim, z) - meas
        return np.concatenate([d[:, 0], d[:, 1], heading_weight * wrap_angle(d[:, 2])])

    sol = least_squares(residuals, meas[0], x_scale=np.array([0.01, 0.01, 0.01]), xtol=1e-12, ftol=1e-12)
    return float(sol.x[0]), float(sol.x[1]), float(sol.x[2])


def noise_level(log: Log) -> float | None:
    """The measured position's noise [m]: ``sigma sqrt(2)``, ``sigma = 1.4826 MAD / sqrt(20)`` of the third differences
    of ``x`` and ``y``; ``None`` without a measured pose or with fewer than 8 samples."""
    if log.pose is None or log.t_meas.size < 8:
        return None
    d3 = np.diff(log.pose[:, :2], n=3, axis=0).ravel()
    sigma = 1.4826 * float(np.median(np.abs(d3 - np.median(d3)))) / math.sqrt(20.0)
    return sigma * math.sqrt(2.0)


def replay(
    log: Log, true_robot: RobotParams | None = None, actuators: ActuatorParams | None = None,
    nominal: RobotParams | None = None,
) -> tuple[Replay, dict[str, Any]]:  # fmt: skip
    """:func:`simulate` from the start pose of :func:`fit_start` (weight ``nominal.l1``; the origin without a measured
    pose), and :func:`summarize` of it with ``start_pose`` and ``position_noise_m`` (:func:`noise_level`)."""
    nominal = RobotParams() if nominal is None else nominal
    rep = simulate(log, true_robot, actuators, nominal, (0.0, 0.0, 0.0))
    start = (0.0, 0.0, 0.0)
    if log.pose is not None:
        start = fit_start(log, rep, nominal.l1)
        rep = Replay(rep.t, placed(rep.pose, start), rep.rates)
    return rep, {**summarize(log, rep), "start_pose": list(start), "position_noise_m": noise_level(log)}


def load_robot_file(path: str | os.PathLike[str]) -> tuple[dict[str, float], dict[str, float]]:
    """The :class:`RobotParams` and :class:`ActuatorParams` fields of a robot file (a JSON object, e.g. the
    ``robot.json`` of ``amigo-gym identify``, report keys ignored), unchecked. Raises ``FileNotFoundError`` or
    ``ValueError`` (not a JSON object, an unknown key, a value not a number)."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"robot file {str(p)!r} does not exist or is not a file")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{p.name}: not a JSON file ({exc})") from None
    if not isinstance(data, Mapping):
        raise ValueError(f"{p.name}: a robot file must hold a JSON object, got {show_value(data)}")
    if unknown := sorted(str(k) for k in data if k not in _ROBOT_FIELDS | _ACTUATOR_FIELDS | _META_FIELDS):
        raise ValueError(
            f"{p.name}: unknown key(s) {unknown}; allowed: RobotParams fields {sorted(_ROBOT_FIELDS)} and "
            f"ActuatorParams fields {sorted(_ACTUATOR_FIELDS)}"
        )
    robot: dict[str, float] = {}
    act: dict[str, float] = {}
    for k, v in data.items():
        if k in _META_FIELDS:
            continue
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise ValueError(f"{p.name}: {k} must be a number, got {show_value(v)}")
        (robot if k in _ROBOT_FIELDS else act)[str(k)] = float(v)
    return robot, act


def robot_from_file(
    path: str | os.PathLike[str], nominal: RobotParams | None = None, actuators: ActuatorParams | None = None
) -> tuple[RobotParams, ActuatorParams]:
    """The robot and actuators of a robot file: its values on top of ``nominal`` and ``actuators``. Raises as
    :func:`load_robot_file`, and ``ValueError`` for a value out of its range."""
    nominal = RobotParams() if nominal is None else nominal
    actuators = ActuatorParams() if actuators is None else actuators
    robot, act = load_robot_file(path)
    return replace(nominal, **robot), replace(actuators, **act)


@dataclass(frozen=True)
class Fit:
    """Result of :func:`identify`: the identified ``robot`` and ``actuators``; the fitted ``values`` [m, s, m/s^2,
    rad/s^2] (with the start pose ``x0``, ``y0``, ``theta0``) and their standard errors ``uncertainty`` (``None``: not
    determined); the names ``fitted`` and the ``fixed`` values; :func:`replay`'s summaries ``before`` and ``after``;
    ``cost = 0.5 sum(residual^2)`` [m^2], ``n_residuals``, ``nfev``; ``excited`` (:func:`ramp_excitation`) [s]."""

    robot: RobotParams
    actuators: ActuatorParams
    values: dict[str, float]
    uncertainty: dict[str, float | None]
    fitted: tuple[str, ...]
    fixed: dict[str, float]
    before: dict[str, Any]
    after: dict[str, Any]
    cost: float
    n_residuals: int
    nfev: int
    excited: dict[str, float]

    def robot_json(self, log: Log, nominal: RobotParams) -> dict[str, Any]:
        """The content of ``robot.json``: the robot as replayed under ``gym.make``'s names, then the report."""
        act, v, unc = self.actuators, self.values, self.uncertainty
        out: dict[str, Any] = {"format": ROBOT_FORMAT, "r1": self.robot.r1, "r2": self.robot.r2, "l1": self.robot.l1}
        out |= {k: getattr(act, k) for k in ("delay", "acceleration", "deceleration", "rot_acceleration",
                                              "rot_deceleration")}  # fmt: skip
        out["uncertainty"] = {k: unc[k] for k in (*self.fitted, "x0", "y0", "theta0") if k in unc}
        out |= {"fitted": list(self.fitted), "fixed": dict(self.fixed)}
        if "x0" in v:
            out["start_pose"] = [v["x0"], v["y0"], v["theta0"]]
        out |= {"replay_before": self.before, "replay_after": self.after}
        out["fit"] = {"cost": self.cost, "n_residuals": self.n_residuals, "model_evaluations": self.nfev,
                      "ramping_s": self.excited}  # fmt: skip
        return out | {"nominal": {"r1": nominal.r1, "r2": nominal.r2, "l1": nominal.l1}, "log": log.source}


def ramp_excitation(log: Log, nominal: RobotParams, actuators: ActuatorParams | None = None) -> dict[str, float]:
    """Seconds the nominal ramps speed up over the log: ``sum max(|c_k| - |c_{k-1}|, 0) / A`` of the commanded speed
    (``acceleration``) and turn rate (``rot_acceleration``), ``A`` the nominal rate."""
    act = ActuatorParams() if actuators is None else actuators
    v, w = body_velocity(log.cmd, nominal)
    out = {}
    for name, c, rate in (("acceleration", v, act.acceleration), ("rot_acceleration", w, act.rot_acceleration)):
        up = np.maximum(np.diff(np.abs(np.concatenate([[0.0], c]))), 0.0)
        out[name] = float(np.sum(up) / rate)
    return out


def identify(
    log: Log, nominal: RobotParams | None = None, ramps: str = "auto", heading_weight: float | None = None,
    actuators: ActuatorParams | None = None,
) -> Fit:  # fmt: skip
    """Fit the true robot to a log: bounded least squares on the replayed trajectory.

    Parameters: ``r1``, ``r2``, ``l1`` [m] (pose measured), ``delay`` [s], the ramp rates ``acceleration`` [m/s^2]
    and ``rot_acceleration`` [rad/s^2] (``"auto"``: those ramping for 3 samples or more, :func:`ramp_excitation`;
    ``"fit"``: both; ``"fixed"``: neither), and the start pose. Residuals per sample ``k >= 1``, measured only:
    simulated minus measured ``x``, ``y``, ``lambda wrap(theta)``, ``r1 Delta t w1``, ``r2 Delta t w2``, with
    ``Delta t`` the median sample interval; by :func:`scipy.optimize.least_squares` (``trf``) within ``r, l1`` in
    nominal ``* (1 +- 0.25)``, ``delay`` in ``[0, 0.5]`` s, ramps in nominal ``* [0.1, 10]``, from the nominal robot
    (``nominal``, :class:`RobotParams` by default; ramps of ``actuators``) and the best delay of a grid of
    ``MAX_DELAY / 10``. ``lambda = heading_weight`` [m/rad], default ``nominal.l1``. Uncertainties:
    ``sqrt(diag(s^2 (J^T J)^{-1}))``, ``s^2 = 2 cost / (N - p)``. ``ValueError`` for a bad ``ramps``."""
    from scipy.optimize import least_squares  # heavy: only here

    nominal = RobotParams() if nominal is None else nominal
    if ramps not in ("auto", "fit", "fixed"):
        raise ValueError(f"identify: ramps must be 'auto', 'fit' or 'fixed', got {ramps!r}")
    lam = nominal.l1 if heading_weight is None else float(heading_weight)
    base_act = ActuatorParams() if actuators is None else actuators
    step = float(np.median(np.diff(log.t_meas)))
    excited = ramp_excitation(log, nominal, base_act)
    ramped = [k for k in RAMP_NAMES if ramps == "fit" or (ramps == "auto" and excited[k] >= 3.0 * step)]
    names = [*(["r1", "r2", "l1"] if log.pose is not None else []), "delay", *ramped]
    n_fit = len(names)
    names += ["x0", "y0", "theta0"] if log.pose is not None else []
    nom = {"r1": nominal.r1, "r2": nominal.r2, "l1": nominal.l1, "delay": base_act.delay,
           "acceleration": base_act.acceleration, "rot_acceleration": base_act.rot_acceleration}  # fmt: skip
    box = {"delay": (0.0, MAX_DELAY, 0.01)}  # (low, high, scale) of each parameter; the start pose: unbounded
    box |= {n: (nom[n] * (1 - FIT_BOUNDS), nom[n] * (1 + FIT_BOUNDS), nom[n] * 0.01) for n in ("r1", "r2", "l1")}
    box |= {n: (nom[n] * RAMP_FACTORS[0], nom[n] * RAMP_FACTORS[1], nom[n] * 0.1) for n in RAMP_NAMES}
    lo, hi, x_scale = zip(*(box.get(n, (-np.inf, np.inf, 0.01)) for n in names), strict=True)
    rate_w = np.array([nominal.r1, nominal.r2]) * step

    def unpack(z: Sequence[float]) -> tuple[RobotParams, ActuatorParams, tuple[float, float, float] | None]:
        v = dict(zip(names, (float(a) for a in z), strict=True))
        robot = replace(nominal, **{k: v[k] for k in ("r1", "r2", "l1") if k in v})
        act = replace(base_act, **{k: v[k] for k in ("delay", "acceleration", "rot_acceleration") if k in v})
        start = (v["x0"], v["y0"], v["theta0"]) if "x0" in v else None
        return robot, act, start

    cache: dict[tuple[float, ...], Replay] = {}

    def residuals(z: Sequence[float]) -> Array:
        robot, act, start = unpack(z)
        # one simulation per robot, from the origin, placed at each start pose
        key = tuple(float(a) for a in z[:n_fit])
        if (rep := cache.get(key)) is None:
            rep = cache[key] = simulate(log, robot, act, nominal, (0.0, 0.0, 0.0))
            if len(cache) > 64:
                cache.pop(next(iter(cache)))
        parts = []
        if log.pose is not None and start is not None:
            d = placed(rep.pose[1:], start) - log.pose[1:]
            parts += [d[:, 0], d[:, 1], lam * wrap_angle(d[:, 2])]
        if log.rates is not None:
            d = (rep.rates[1:] - log.rates[1:]) * rate_w
            parts += [d[:, 0], d[:, 1]]
        return np.concatenate(parts)

    z0 = [nom[n] for n in names[:n_fit]] + ([] if log.pose is None else log.pose[0].tolist())
    i = names.index("delay")  # start from the best delay of the grid
    grid = ([*z0[:i], d, *z0[i + 1 :]] for d in np.linspace(0.0, MAX_DELAY, 11).tolist())
    z_start = min(grid, key=lambda z: float(np.sum(residuals(z) ** 2)))
    sol = least_squares(
        residuals, np.asarray(z_start), bounds=(np.asarray(lo), np.asarray(hi)), x_scale=np.asarray(x_scale),
        method="trf", jac="2-point", xtol=XTOL, ftol=XTOL, gtol=XTOL, max_nfev=200,
    )  # fmt: skip
    jac = np.asarray(sol.jac, dtype=np.float64)
    n_res = int(sol.fun.size)
    s2 = 2.0 * float(sol.cost) / max(n_res - len(names), 1)
    unc: dict[str, float | None] = dict.fromkeys(names)
    try:
        diag = np.diag(np.linalg.inv(jac.T @ jac) * s2)
        unc = {n: (float(np.sqrt(v)) if v >= 0 and np.isfinite(v) else None) for n, v in zip(names, diag, strict=True)}
    except np.linalg.LinAlgError:
        pass
    values = {n: float(v) for n, v in zip(names, sol.x, strict=True)}
    robot, act, _ = unpack(sol.x)
    fitted = tuple(names[:n_fit])
    fixed = {k: float(v) for k, v in nom.items() if k not in fitted}
    _, before = replay(log, nominal, base_act, nominal)
    _, after = replay(log, robot, act, nominal)
    return Fit(robot, act, values, unc, fitted, fixed, before, after, float(sol.cost), n_res, int(sol.nfev), excited)
