"""An independent simulator of a robot's log for the tests of :mod:`amigo_gym.logs` (no code of the package).

Fine time steps of ``h`` with exact unicycle arcs at the step's mean speed and turn rate; the firmware's speed
ramps written again from their description (``|u|`` grows at A, shrinks at D, a command of the other sign is
reached through 0), the delay applied as a whole number of fine steps, the true wheel radii and half track
moving the body. Its error against the exact motion is of order ``h`` times the ramp rates' effect (about
1e-6 m over the tests' runs at ``h = 1 ms``), far below the tests' tolerances.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

R_NOM = 0.05  # nominal wheel radius [m]
L1_NOM = 0.12  # nominal half track [m]


def _ramp(u: float, c: float, acc: float, dec: float, h: float) -> float:
    """``u`` after ``h`` seconds of the ramp towards ``c`` (exact for the piecewise-linear ramp)."""
    rem = h
    if u * c < 0.0:  # reverse: slow to 0 first
        t0 = abs(u) / dec
        if t0 >= rem:
            return u - math.copysign(dec * rem, u)
        u, rem = 0.0, rem - t0
    rate = acc if abs(c) > abs(u) else dec
    step = rate * rem
    return c if abs(c - u) <= step else u + math.copysign(step, c - u)


def run(
    commands: np.ndarray,
    dt: float,
    r1: float,
    r2: float,
    l1: float,
    delay: float,
    acc: tuple[float, float, float, float] = (0.3, 0.75, 0.87, 2.5),
    h: float = 1e-3,
    r_nom: float = R_NOM,
    l1_nom: float = L1_NOM,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True trajectory of A for wheel-rate commands ``(n, 2)`` [rad/s] issued at ``k dt``, starting at rest at 0.

    ``acc``: the ramps' rates (v up, v down [m/s^2], w up, w down [rad/s^2]); ``r_nom``, ``l1_nom``: the nominal
    wheel radius and half track the firmware converts with [m].

    Returns ``(t, pose, rates)``: times ``k dt`` (n + 1), pose ``(x, y, theta)`` and wheel rates at those times.
    """
    per = round(dt / h)
    lag = round(delay / h)
    n = commands.shape[0]
    x = y = th = 0.0
    v = w = 0.0
    poses = [(0.0, 0.0, 0.0)]
    rates = [(0.0, 0.0)]
    for i in range(n * per):
        j = (i - lag) // per
        c1, c2 = (0.0, 0.0) if j < 0 else (float(commands[j, 0]), float(commands[j, 1]))
        vc = r_nom * (c1 + c2) / 2
        wc = r_nom * (c1 - c2) / (2 * l1_nom)
        v_new = _ramp(v, vc, acc[0], acc[1], h)
        w_new = _ramp(w, wc, acc[2], acc[3], h)
        vm, wm = (v + v_new) / 2, (w + w_new) / 2
        # true body motion from the wheel rates (nominal inverse of the firmware's speeds)
        a1 = (vm + l1_nom * wm) / r_nom
        a2 = (vm - l1_nom * wm) / r_nom
        vt = (r1 * a1 + r2 * a2) / 2
        wt = (r1 * a1 - r2 * a2) / (2 * l1)
        dth = wt * h
        half = dth / 2
        sinc = 1.0 - half * half / 6 if abs(half) < 1e-4 else math.sin(half) / half
        x += vt * h * sinc * math.cos(th + half)
        y += vt * h * sinc * math.sin(th + half)
        th += dth
        v, w = v_new, w_new
        if (i + 1) % per == 0:
            poses.append((x, y, th))
            rates.append(((v + l1_nom * w) / r_nom, (v - l1_nom * w) / r_nom))
    return np.arange(n + 1) * dt, np.array(poses), np.array(rates)


def commands(seconds: float, dt: float, seed: int = 1, r_nom: float = R_NOM, l1_nom: float = L1_NOM) -> np.ndarray:
    """Wheel-rate commands [rad/s] rich enough to identify radii and track: segments of 1.5–3 s of random speed
    in [0, 0.3] m/s and turn rate in [-0.8, 0.8] rad/s, a spin in place and a stop; then rest for 1 s."""
    rng = np.random.default_rng(seed)
    out: list[tuple[float, float]] = []
    n = round(seconds / dt)
    segment = 0
    while len(out) < n:
        length = round(rng.uniform(1.5, 3.0) / dt)
        if segment == 2:
            v, w = 0.0, 0.7
        elif segment == 5:
            v, w = 0.0, 0.0
        else:
            v, w = rng.uniform(0.05, 0.3), rng.uniform(-0.8, 0.8)
        out += [((v + l1_nom * w) / r_nom, (v - l1_nom * w) / r_nom)] * length
        segment += 1
    out = out[:n] + [(0.0, 0.0)] * round(1.0 / dt)
    return np.array(out)


def write_csv(path: Path, t: np.ndarray, cmd: np.ndarray, pose: np.ndarray | None, rates: np.ndarray | None) -> None:
    """A CSV log: the command of row k is the one issued at ``t[k]`` (the last row repeats the last command)."""
    head = ["t", "cmd_w1", "cmd_w2"]
    cols = [t, np.append(cmd[:, 0], cmd[-1, 0]), np.append(cmd[:, 1], cmd[-1, 1])]
    if pose is not None:
        head += ["x", "y", "theta"]
        cols += [pose[:, 0], pose[:, 1], np.angle(np.exp(1j * pose[:, 2]))]
    if rates is not None:
        head += ["w1", "w2"]
        cols += [rates[:, 0], rates[:, 1]]
    with open(path, "w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(head)
        for row in zip(*cols, strict=True):
            wr.writerow([repr(float(v)) for v in row])


def write_bag(
    path: Path,
    t: np.ndarray,
    cmd: np.ndarray,
    pose: np.ndarray,
    cmd_topic: str = "/cmd_vel",
    pose_topic: str = "/odom",
    t0_ns: int = 1_700_000_000_000_000_000,
    stamped: bool = False,
    keep: np.ndarray | None = None,
) -> None:
    """A ROS 2 bag (sqlite3) with the commands as Twist on ``cmd_topic`` and the pose as Odometry on ``pose_topic``
    (``stamped``: TwistStamped and PoseStamped; ``keep``: a mask of the poses to record, default all).

    Twists from the wheel rates with the nominal robot; the command of step k is recorded 1 ms after the pose of
    step k (a controller answering the measurement), both at bag times ``t0_ns + t``.
    """
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    Twist = ts.types["geometry_msgs/msg/Twist"]
    Vector3 = ts.types["geometry_msgs/msg/Vector3"]
    Odometry = ts.types["nav_msgs/msg/Odometry"]
    Header = ts.types["std_msgs/msg/Header"]
    Time = ts.types["builtin_interfaces/msg/Time"]
    Pose = ts.types["geometry_msgs/msg/Pose"]
    PoseCov = ts.types["geometry_msgs/msg/PoseWithCovariance"]
    TwistCov = ts.types["geometry_msgs/msg/TwistWithCovariance"]
    Point = ts.types["geometry_msgs/msg/Point"]
    Quat = ts.types["geometry_msgs/msg/Quaternion"]
    with Writer(path, version=8) as wr:
        cmd_type = "geometry_msgs/msg/TwistStamped" if stamped else "geometry_msgs/msg/Twist"
        pose_type = "geometry_msgs/msg/PoseStamped" if stamped else "nav_msgs/msg/Odometry"
        c_cmd = wr.add_connection(cmd_topic, cmd_type, typestore=ts)
        c_pose = wr.add_connection(pose_topic, pose_type, typestore=ts)
        zero = Vector3(x=0.0, y=0.0, z=0.0)
        for k in range(t.size):
            stamp = t0_ns + round(t[k] * 1e9)
            x, y, th = (float(v) for v in pose[k])
            hdr = Header(stamp=Time(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id="odom")
            q = Quat(x=0.0, y=0.0, z=math.sin(th / 2), w=math.cos(th / 2))
            pose_msg = Pose(position=Point(x=x, y=y, z=0.0), orientation=q)
            if stamped:
                msg = ts.types["geometry_msgs/msg/PoseStamped"](header=hdr, pose=pose_msg)
            else:
                msg = Odometry(
                    header=hdr,
                    child_frame_id="base_link",
                    pose=PoseCov(pose=pose_msg, covariance=np.zeros(36)),
                    twist=TwistCov(twist=Twist(linear=zero, angular=zero), covariance=np.zeros(36)),
                )
            if keep is None or keep[k]:
                wr.write(c_pose, stamp, ts.serialize_cdr(msg, pose_type))
            if k < cmd.shape[0]:
                c1, c2 = (float(v) for v in cmd[k])
                v = R_NOM * (c1 + c2) / 2
                w = R_NOM * (c1 - c2) / (2 * L1_NOM)
                tw = Twist(linear=Vector3(x=v, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=w))
                if stamped:
                    tw = ts.types["geometry_msgs/msg/TwistStamped"](header=hdr, twist=tw)
                wr.write(c_cmd, stamp + 1_000_000, ts.serialize_cdr(tw, cmd_type))


#: the robot of the tests and of the example in docs/logs.md: radii, half track [m], delay [s]
TRUE = {"r1": 0.0515, "r2": 0.0490, "l1": 0.1296, "delay": 0.13}
#: pose noise of the tests and the example: position per axis [m], heading [rad]
SIGMA_XY = 0.002
SIGMA_TH = 0.002


def example(out: Path, seconds: float = 20.0, dt: float = 0.1, seed: int = 7) -> None:
    """Write ``run.csv`` (pose with noise), ``run_bag/`` (the same as a ROS 2 bag) and ``truth.json`` into ``out``."""
    cmd = commands(seconds, dt)
    t, pose, _ = run(cmd, dt, TRUE["r1"], TRUE["r2"], TRUE["l1"], TRUE["delay"])
    rng = np.random.default_rng(seed)
    noisy = pose + rng.normal(size=pose.shape) * np.array([SIGMA_XY, SIGMA_XY, SIGMA_TH])
    out.mkdir(parents=True, exist_ok=True)
    write_csv(out / "run.csv", t, cmd, noisy, None)
    write_bag(out / "run_bag", t, cmd, noisy)
    (out / "truth.json").write_text(json.dumps({**TRUE, "sigma_xy": SIGMA_XY, "sigma_theta": SIGMA_TH}, indent=2))


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description="Write an example robot log made by the independent simulator.")
    parser.add_argument(
        "--out", required=True, help="folder for run.csv, run_bag/ and truth.json (must not hold a bag)"
    )
    example(Path(parser.parse_args().out))
