"""Logs of a robot (:mod:`amigo_gym.logs`, ``amigo-gym replay`` / ``identify``) on data the package did not make.

The logs come from :mod:`tests.logsim`, an independent fine-step integrator (exact unicycle arcs of 1 ms, the ramps
written again, known radii, half track and delay), with pose noise; written as CSV and as a ROS 2 bag.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the environments)
from amigo_gym import logs
from amigo_gym.model.actuators import ActuatorParams
from amigo_gym.model.params import RobotParams
from amigo_gym.tools.cli import main

sys.path.insert(0, str(Path(__file__).parent))
import logsim

DT = 0.1
SECONDS = 12.0  # of driving, then 1 s at rest: 131 samples
ROWS = 131
TRUE, SIGMA_XY, SIGMA_TH = logsim.TRUE, logsim.SIGMA_XY, logsim.SIGMA_TH


@pytest.fixture(scope="module")
def run() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(t, cmd, pose, rates)`` of 12 s of driving and 1 s at rest by the independent simulator, no noise."""
    cmd = logsim.commands(SECONDS, DT)
    t, pose, rates = logsim.run(cmd, DT, TRUE["r1"], TRUE["r2"], TRUE["l1"], TRUE["delay"])
    return t, cmd, pose, rates


@pytest.fixture(scope="module")
def noisy(run: tuple[np.ndarray, ...]) -> np.ndarray:
    _t, _cmd, pose, _rates = run
    rng = np.random.default_rng(7)
    return pose + rng.normal(size=pose.shape) * np.array([SIGMA_XY, SIGMA_XY, SIGMA_TH])


@pytest.fixture(scope="module")
def csv_log(run: tuple[np.ndarray, ...], noisy: np.ndarray, tmp_path_factory: pytest.TempPathFactory) -> Path:
    t, cmd, _pose, _rates = run
    path = tmp_path_factory.mktemp("csv") / "run.csv"
    logsim.write_csv(path, t, cmd, noisy, None)
    return path


@pytest.fixture(scope="module")
def bag_log(run: tuple[np.ndarray, ...], noisy: np.ndarray, tmp_path_factory: pytest.TempPathFactory) -> Path:
    t, cmd, _pose, _rates = run
    path = tmp_path_factory.mktemp("bag") / "run_bag"
    logsim.write_bag(path, t, cmd, noisy)
    return path


TRUE_ROBOT = RobotParams(r1=TRUE["r1"], r2=TRUE["r2"], l1=TRUE["l1"])
TRUE_ACT = ActuatorParams(delay=TRUE["delay"])


def test_replay_agrees_with_the_independent_integrator(run: tuple[np.ndarray, ...], tmp_path: Path) -> None:
    """Noise-free log, true parameters: the package's exact step and the 1 ms integrator agree to micrometres
    (the integrator's own error); the nominal robot is decimetres off."""
    t, cmd, pose, rates = run
    path = tmp_path / "clean.csv"
    logsim.write_csv(path, t, cmd, pose, rates)
    log = logs.read_log(path)
    rep = logs.simulate(log, TRUE_ROBOT, TRUE_ACT)
    s = logs.summarize(log, rep)
    assert s["max_position_error_m"] < 1e-5
    assert s["max_heading_error_rad"] < 1e-5
    assert s["max_wheel_rate_error_rad_s"] < 1e-3
    nominal = logs.summarize(log, logs.simulate(log))
    assert nominal["max_position_error_m"] > 0.1


def test_replay_with_true_parameters_is_at_the_noise_level(csv_log: Path, tmp_path: Path) -> None:
    """With the true robot the replay error is the measurement noise: the RMS of a 2-D error of sigma per axis is
    sigma sqrt(2); the start pose fitted to the first 27 poses adds a little (the log's first pose
    alone, noise and all, gave 2-3 times the noise). Bound: 1.5 times the noise."""
    robot_file = tmp_path / "true.json"
    robot_file.write_text(json.dumps(TRUE))
    out = tmp_path / "out"
    assert main(["replay", str(csv_log), "--robot", str(robot_file), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    level = SIGMA_XY * math.sqrt(2)
    assert 0.7 * level < s["rms_position_error_m"] <= 1.5 * level, s
    assert s["rms_heading_error_rad"] < 2 * SIGMA_TH
    assert abs(s["position_noise_m"] / level - 1.0) < 0.3  # the level the figure marks, estimated from the log
    assert sorted(p.name for p in out.iterdir()) == ["replay.png", "summary.json", "trajectory.csv"]
    table = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    assert table.size == ROWS
    assert np.allclose(np.hypot(table["x_sim"] - table["x_meas"], table["y_sim"] - table["y_meas"]),
                       table["position_error"])  # fmt: skip
    # the nominal robot is far from the noise level
    log = logs.read_log(csv_log)
    assert logs.replay(log)[1]["rms_position_error_m"] > 20 * level


def test_the_fitted_start_is_what_brings_replay_to_the_noise(run: tuple[np.ndarray, ...], tmp_path: Path) -> None:
    """20 draws of the 2 mm noise: replayed from the fitted start every one is within 1.5 times the noise, and
    the noise level the figure marks is estimated within 30 %; from the log's first measured pose (the old start)
    at least 5 of them are over 1.5 times the noise (from its heading noise times the distance driven)."""
    t, cmd, pose, _rates = run
    level = SIGMA_XY * math.sqrt(2)
    fitted, first, noise = [], [], []
    for seed in range(20):
        noisy = pose + np.random.default_rng(seed).normal(size=pose.shape) * np.array([SIGMA_XY, SIGMA_XY, SIGMA_TH])
        logsim.write_csv(tmp_path / "n.csv", t, cmd, noisy, None)
        log = logs.read_log(tmp_path / "n.csv")
        _, s = logs.replay(log, TRUE_ROBOT, TRUE_ACT)
        fitted.append(s["rms_position_error_m"] / level)
        noise.append(s["position_noise_m"] / level)
        first.append(logs.summarize(log, logs.simulate(log, TRUE_ROBOT, TRUE_ACT))["rms_position_error_m"] / level)
    # docs/logs.md's figures: python -m pytest tests/test_logs.py -k fitted_start -s -q
    ranges = [f"{min(v):.2f}-{max(v):.2f}" for v in (fitted, first, noise)]
    print("\nRMS / noise: fitted start {}, first pose {}; estimated noise / true {}".format(*ranges))
    assert max(abs(n - 1.0) for n in noise) < 0.3, noise
    assert max(fitted) <= 1.5, fitted
    assert sum(f > 1.5 for f in first) >= 5, first


def _check_estimates(robot: dict[str, float], delay_tolerance: float = DT) -> None:
    assert abs(robot["r1"] / TRUE["r1"] - 1) < 0.01, robot
    assert abs(robot["r2"] / TRUE["r2"] - 1) < 0.01, robot
    assert abs(robot["l1"] / TRUE["l1"] - 1) < 0.02, robot
    assert abs(robot["delay"] - TRUE["delay"]) < delay_tolerance, robot


def test_identify_csv_recovers_the_robot(csv_log: Path, tmp_path: Path) -> None:
    """Radii within 1 %, half track within 2 %, delay within one sample; the replay error falls to the noise level;
    gym.make and replay --robot take the robot.json."""
    out = tmp_path / "fit"
    assert main(["identify", str(csv_log), "--out", str(out)]) == 0
    robot = json.loads((out / "robot.json").read_text())
    _check_estimates(robot)
    for k in ("r1", "r2", "l1", "delay"):
        assert 0 < robot["uncertainty"][k] < 0.05 * max(robot[k], DT), (k, robot["uncertainty"])
    assert robot["replay_after"]["rms_position_error_m"] < 2.5 * SIGMA_XY * math.sqrt(2)
    assert robot["replay_before"]["rms_position_error_m"] > 20 * robot["replay_after"]["rms_position_error_m"]
    assert sorted(p.name for p in out.iterdir()) == ["identify.png", "robot.json", "summary.json", "trajectory.csv"]
    envs = gym.make_vec("AmigoBot-v1", num_envs=2, true_robot=out / "robot.json")
    assert envs.reset(seed=0)[1]["delay"].tolist() == [robot["delay"]] * 2
    env = gym.make("AmigoBot-v1", true_robot=str(out / "robot.json"), kernel="numpy")
    _, info = env.reset(seed=0)
    assert info["true_robot"] == {k: robot[k] for k in ("r1", "r2", "l1")}
    assert info["delay"] == pytest.approx(robot["delay"], abs=1e-12)
    out2 = tmp_path / "again"
    assert main(["replay", str(csv_log), "--robot", str(out / "robot.json"), "--out", str(out2)]) == 0
    again = json.loads((out2 / "summary.json").read_text())
    assert again["rms_position_error_m"] == pytest.approx(robot["replay_after"]["rms_position_error_m"], rel=1e-9)


def test_identify_bag_recovers_the_robot(bag_log: Path, tmp_path: Path) -> None:
    """The same run as a ROS 2 bag (Twist on /cmd_vel recorded 1 ms after each Odometry on /odom)."""
    out = tmp_path / "fit"
    assert main(["identify", str(bag_log), "--out", str(out)]) == 0
    _check_estimates(json.loads((out / "robot.json").read_text()))


def test_bag_and_csv_read_alike(bag_log: Path, csv_log: Path) -> None:
    bag = logs.read_log(bag_log)
    csv = logs.read_log(csv_log)
    assert np.allclose(bag.t_meas, csv.t_meas, atol=1e-9)
    assert np.allclose(bag.t_cmd, csv.t_cmd[:-1] + 1e-3, atol=1e-9)
    assert np.allclose(bag.pose, csv.pose, atol=1e-12)
    assert np.allclose(bag.cmd, csv.cmd[:-1], atol=1e-12)


def test_bag_with_stamped_messages(run: tuple[np.ndarray, ...], csv_log: Path, tmp_path: Path) -> None:
    """TwistStamped commands and PoseStamped poses read as Twist and Odometry do (a pose noise-free here)."""
    t, cmd, pose, _ = run
    logsim.write_bag(tmp_path / "stamped", t, cmd, pose, pose_topic="/mocap", stamped=True)
    log = logs.read_log(tmp_path / "stamped", pose_topic="/mocap")
    assert log.pose is not None and np.allclose(log.pose, pose, atol=1e-12)
    assert np.allclose(log.cmd, logs.read_log(csv_log).cmd[:-1], atol=1e-12)


def test_replay_of_an_irregular_bag(run: tuple[np.ndarray, ...], tmp_path: Path) -> None:
    """Poses at irregular times (a random 40 % of them recorded, gaps up to a second), every command: intervals
    with several setpoint switches in them replay as exactly as the regular log."""
    t, cmd, pose, _ = run
    keep = np.random.default_rng(2).random(t.size) < 0.4
    keep[[0, 1, -1]] = True
    logsim.write_bag(tmp_path / "sparse", t, cmd, pose, keep=keep)
    log = logs.read_log(tmp_path / "sparse")
    assert log.t_meas.size == int(keep.sum()) and np.max(np.diff(log.t_meas)) > 0.35
    delay = ActuatorParams(delay=TRUE["delay"] - 1e-3)  # the bag's commands are recorded 1 ms late
    s = logs.summarize(log, logs.simulate(log, TRUE_ROBOT, delay))
    assert s["max_position_error_m"] < 1e-5 and s["max_heading_error_rad"] < 1e-5, s


def test_identify_from_wheel_rates_alone_fits_the_delay(run: tuple[np.ndarray, ...], tmp_path: Path) -> None:
    """Without a pose the radii and track cannot be seen (the wheels turn as the firmware says whatever they are):
    they stay nominal, and the delay is fitted from the measured wheel rates."""
    t, cmd, _pose, rates = run
    rng = np.random.default_rng(3)
    path = tmp_path / "rates.csv"
    logsim.write_csv(path, t, cmd, None, rates + rng.normal(scale=0.05, size=rates.shape))
    fit = logs.identify(logs.read_log(path), ramps="fixed")
    assert fit.fitted == ("delay",)
    assert abs(fit.actuators.delay - TRUE["delay"]) < DT
    assert fit.robot == RobotParams()
    assert fit.after["rms_wheel_rate_error_rad_s"] < fit.before["rms_wheel_rate_error_rad_s"] / 3


def test_replay_is_the_environment_step() -> None:
    """A log recorded from AmigoBot-v1 itself (no noise, a delay of 1.3 steps) replays to the same poses."""
    robot = {"r1": 0.052, "r2": 0.049, "l1": 0.125}
    env = gym.make(
        "AmigoBot-v1", true_robot=robot, actuators={"delay": 0.13}, kernel="numpy", termination_distance=10.0
    )
    _, info = env.reset(seed=1)
    rng = np.random.default_rng(0)
    poses, cmds = [info["pose"]], []
    for _ in range(60):
        a = np.clip(np.array([0.3, 0.3]) + rng.normal(scale=0.2, size=2), -1, 1)
        _, _, term, _trunc, info = env.step(a)
        cmds.append(info["command"])
        poses.append(info["pose"])
        assert not term
    t = np.arange(61) * 0.1
    cmd = np.array([*cmds, cmds[-1]])
    pose = np.array(poses)
    log = logs.Log(t, cmd, t, pose, None)
    rep = logs.simulate(log, RobotParams(**robot), ActuatorParams(delay=0.13))
    assert np.max(np.abs(rep.pose - pose)) < 1e-12


def test_another_nominal_robot(tmp_path: Path) -> None:
    """``--nominal``: a Pioneer-sized robot (r = 0.0975 m, l1 = 0.19 m, slower ramps) whose firmware converts
    with its own geometry; the replay with its true robot file agrees with the independent integrator."""
    nominal = {"r1": 0.0975, "r2": 0.0975, "l1": 0.19, "max_speed": 1.2, "acceleration": 0.5, "rot_acceleration": 1.5}
    true = {"r1": 0.099, "r2": 0.0965, "l1": 0.2, "delay": 0.1}
    cmd = logsim.commands(8.0, DT, r_nom=0.0975, l1_nom=0.19)
    t, pose, _ = logsim.run(cmd, DT, 0.099, 0.0965, 0.2, 0.1, acc=(0.5, 0.75, 1.5, 2.5), r_nom=0.0975, l1_nom=0.19)
    log, nom, tru = tmp_path / "p.csv", tmp_path / "nominal.json", tmp_path / "true.json"
    logsim.write_csv(log, t, cmd, pose, None)
    nom.write_text(json.dumps(nominal))
    tru.write_text(json.dumps(true))
    out = tmp_path / "out"
    assert main(["replay", str(log), "--nominal", str(nom), "--robot", str(tru), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["max_position_error_m"] < 1e-5 and s["max_heading_error_rad"] < 1e-5, s
    assert s["robot"]["acceleration"] == 0.5 and s["robot"]["delay"] == 0.1
    # the same log read as an AmigoBot's is far off
    amigo = logs.read_log(log)
    robot, act = logs.robot_from_file(tru)
    assert logs.summarize(amigo, logs.simulate(amigo, robot, act))["max_position_error_m"] > 0.05


# ------------------------------------------------------------------------------------------------ bad logs


def _csv(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _good_rows(run: tuple[np.ndarray, ...]) -> list[list[float]]:
    t, cmd, pose, _rates = run
    cmd = np.vstack([cmd, cmd[-1]])
    return [[t[k], cmd[k, 0], cmd[k, 1], pose[k, 0], pose[k, 1], pose[k, 2]] for k in range(t.size)]


def _write_rows(path: Path, head: str, rows: list[list[float]]) -> Path:
    return _csv(path, head + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in rows) + "\n")


HEAD = "t,cmd_w1,cmd_w2,x,y,theta"


def _bad_cases(run: tuple[np.ndarray, ...], tmp: Path) -> dict[str, tuple[Path, str]]:
    rows = _good_rows(run)
    cases: dict[str, tuple[Path, str]] = {}
    cases["missing column"] = (_write_rows(tmp / "a.csv", "t,cmd_w1,cmd_w2,x,y", [r[:5] for r in rows]), "theta")
    cases["no measurement"] = (_write_rows(tmp / "b.csv", "t,cmd_w1,cmd_w2", [r[:3] for r in rows]), "measurement")
    back = [list(r) for r in rows]
    back[40][0] = back[38][0]
    cases["time backwards"] = (_write_rows(tmp / "c.csv", HEAD, back), "not strictly increasing at line 42")
    nan = [list(r) for r in rows]
    nan[10][3] = float("nan")
    cases["NaN"] = (_write_rows(tmp / "d.csv", HEAD, nan), "d.csv: column 'x': nan at line 12")
    ms = [[r[0] * 1000, *r[1:]] for r in rows]
    cases["time in ms"] = (_write_rows(tmp / "e.csv", HEAD, ms), "seconds")
    mm = [[r[0], r[1], r[2], r[3] * 1000, r[4] * 1000, r[5]] for r in rows]
    cases["position in mm"] = (_write_rows(tmp / "f.csv", HEAD, mm), "metres")
    cm = [[r[0], r[1], r[2], r[3] * 100, r[4] * 100, r[5]] for r in rows]
    cases["position in cm"] = (_write_rows(tmp / "f2.csv", HEAD, cm), "metres")
    deg = [[*r[:5], math.degrees(math.atan2(math.sin(r[5]), math.cos(r[5])))] for r in rows]
    cases["heading in degrees"] = (_write_rows(tmp / "g.csv", HEAD, deg), "degrees")
    degs = [[r[0], math.degrees(r[1]), math.degrees(r[2]), *r[3:]] for r in rows]
    cases["commands in deg/s"] = (_write_rows(tmp / "h.csv", HEAD, degs), "deg/s")
    cases["empty file"] = (_csv(tmp / "i.csv", ""), "empty log")
    cases["header only"] = (_csv(tmp / "j.csv", HEAD + "\n"), "at least 3")
    text = [[repr(float(v)) for v in r] for r in rows]
    text[5][1] = "fast"
    cases["text"] = (_csv(tmp / "k.csv", HEAD + "\n" + "\n".join(",".join(r) for r in text)), "'fast' at line 7")
    cases["unknown kind"] = (_csv(tmp / "l.json", "{}"), "unknown kind of log")
    return cases


def _bags(run: tuple[np.ndarray, ...], tmp: Path) -> dict[str, tuple[Path, str]]:
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    t, cmd, pose, _rates = run
    ts = get_typestore(Stores.ROS2_HUMBLE)
    empty = tmp / "empty_bag"
    with Writer(empty, version=8) as wr:
        wr.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
    other = tmp / "other_topics"
    logsim.write_bag(other, t, cmd, pose, cmd_topic="/robot/cmd_vel")
    not_bag = tmp / "not_a_bag"
    not_bag.mkdir()
    return {
        "empty bag": (empty, "empty bag"),
        "missing topic": (other, "command topic '/cmd_vel' is not in the bag (topics: /odom [nav_msgs/msg/Odometry]"),
        "not a bag": (not_bag, "not a readable ROS 2 bag"),
    }


@pytest.fixture(scope="module")
def bad_logs(run: tuple[np.ndarray, ...], tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, str]]:
    tmp = tmp_path_factory.mktemp("bad")
    return {**_bad_cases(run, tmp), **_bags(run, tmp)}


BAD = [
    "missing column", "no measurement", "time backwards", "NaN", "time in ms", "position in mm", "position in cm",
    "heading in degrees", "commands in deg/s", "empty file", "header only", "text", "unknown kind", "empty bag",
    "missing topic", "not a bag",
]  # fmt: skip


@pytest.mark.parametrize("case", BAD)
def test_bad_log_is_one_line_exit_2_nothing_written(
    case: str, bad_logs: dict[str, tuple[Path, str]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, phrase = bad_logs[case]
    for command in ("replay", "identify"):
        out = tmp_path / command
        assert main([command, str(path), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"amigo-gym {command}: error: "), err
        assert phrase in err, err
        assert not out.exists()
        assert list(tmp_path.iterdir()) == []


def test_the_good_log_passes_the_same_checks(run: tuple[np.ndarray, ...], tmp_path: Path) -> None:
    """The bad-log cases are the good log with one thing broken: the good one is accepted."""
    log = logs.read_log(_write_rows(tmp_path / "good.csv", HEAD, _good_rows(run)))
    assert log.pose is not None and log.t_meas.size == ROWS
    wrapped = [[*r[:5], math.atan2(math.sin(r[5]), math.cos(r[5]))] for r in _good_rows(run)]
    log2 = logs.read_log(_write_rows(tmp_path / "wrapped.csv", HEAD, wrapped))
    assert log2.pose is not None and np.allclose(log2.pose[:, 2], log.pose[:, 2], atol=1e-12)


def test_bag_with_other_topic_names(bad_logs: dict[str, tuple[Path, str]]) -> None:
    path, _ = bad_logs["missing topic"]
    log = logs.read_log(path, cmd_topic="/robot/cmd_vel")
    assert log.t_meas.size == ROWS


# ------------------------------------------------------------------------------------------------ outputs


def test_out_folder_is_refused_when_not_empty_and_replaced_with_force(csv_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("keep")
    assert main(["replay", str(csv_log), "--out", str(out)]) == 2
    assert (out / "mine.txt").read_text() == "keep"
    assert main(["replay", str(csv_log), "--out", str(out), "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["replay.png", "summary.json", "trajectory.csv"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_a_failing_writer_leaves_nothing(tmp_path: Path) -> None:
    from amigo_gym.tools.analysis.replay import write_folder

    def fail(path: str) -> None:
        Path(path).write_text("half")
        raise KeyboardInterrupt

    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        write_folder(out, {"a.txt": lambda p: Path(p).write_text("a"), "b.txt": fail}, force=False)
    assert list(tmp_path.iterdir()) == []
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        write_folder(out, {"b.txt": fail}, force=True)
    assert [p.name for p in tmp_path.iterdir()] == ["out"] and (out / "old.txt").read_text() == "old"


def test_a_killed_runs_temporary_folder_goes_with_the_next_run(csv_log: Path, tmp_path: Path) -> None:
    """What a killed run leaves (``.out.<random>.tmp`` of the old naming, ``.out.<pid>-<random>.tmp`` of a process
    that is gone) is removed by the next run for ``out``; a running process's folder and other names stay."""
    import os
    import subprocess

    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    gone = int(done.stdout)  # a process that has ended
    stale = [tmp_path / ".out.k2j4x8.tmp", tmp_path / f".out.{gone}-ab12cd.tmp", tmp_path / f".out.{gone}-x.old"]
    keep = [tmp_path / f".out.{os.getpid()}-live.tmp", tmp_path / ".other.k2j4x8.tmp"]
    for d in stale + keep:
        d.mkdir()
        (d / "summary.json").write_text("half")
    assert main(["replay", str(csv_log), "--out", str(tmp_path / "out")]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["out", *(d.name for d in keep)])


# ------------------------------------------------------------------------------------------------ robot files


def test_robot_file_errors(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"r1": 0.05, "wheel_radius": 0.05}))
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['wheel_radius'\]"):
        gym.make("AmigoBot-v1", true_robot=str(bad))
    bad.write_text(json.dumps({"r1": "0.05"}))
    with pytest.raises(ValueError, match="r1 must be a number"):
        logs.load_robot_file(bad)
    bad.write_text(json.dumps({"delay": 2.0}))
    with pytest.raises(ValueError, match="delay"):
        gym.make("AmigoBot-v1", true_robot=str(bad))
    bad.write_text("{")
    with pytest.raises(ValueError, match="not a JSON file"):
        logs.load_robot_file(bad)
    with pytest.raises(FileNotFoundError):
        gym.make("AmigoBot-v1", true_robot=str(tmp_path / "none.json"))
    good = tmp_path / "good.json"
    good.write_text(json.dumps({"r1": 0.051, "delay": 0.2, "acceleration": 0.25}))
    env = gym.make("AmigoBot-v1", true_robot=good, actuators={"delay": 0.1})
    p = env.unwrapped.params  # type: ignore[attr-defined]
    assert p.true_robot.r1 == 0.051 and p.true_robot.r2 == 0.05
    assert p.actuators.delay == 0.1 and p.actuators.acceleration == 0.25  # the keyword's own field wins


def test_docs_page_names_the_columns() -> None:
    page = (Path(__file__).parents[1] / "docs" / "logs.md").read_text()
    for column, unit in logs.CSV_COLUMNS.items():
        assert f"`{column}`" in page and unit in page
