"""``amigo-gym paper`` smoke test by subprocess: files exist, the CSV is sane, rates within the robot's limits."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np

from amigo_gym.model.params import RobotParams

ROOT = Path(__file__).resolve().parents[1]
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "paper", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_paper_figures(tmp_path: Path) -> None:
    out = tmp_path / "figs"
    r = _run("--out", str(out), "--dt", "0.02", "--dpi", "40")
    assert r.returncode == 0, r.stderr
    for name in ("paper_fig2_angles.png", "paper_fig3_rates.png"):
        data = (out / name).read_bytes()
        assert data[:8] == PNG_MAGIC, name
        assert len(data) > 2000, name
    csv = out / "paper_manoeuvre.csv"
    with open(csv) as fh:
        header = fh.readline().strip().split(",")
    d = dict(zip(header, np.loadtxt(csv, delimiter=",", skiprows=1).T, strict=True))
    robot = RobotParams()
    t, v = d["t"], d["v_A"]
    assert np.all(np.diff(t) > 0)
    np.testing.assert_allclose(np.diff(t), 0.02, atol=1e-9)
    # v_A = 0.2 m/s cruise, standstill at both ends, acceleration and braking within the robot's limits
    assert v.max() == 0.2
    assert v[0] == 0.0 and v[-1] == 0.0
    acc = np.diff(v) / np.diff(t)
    assert acc.max() <= robot.max_acceleration + 1e-9
    assert -acc.min() <= robot.max_deceleration + 1e-9
    # wheel rates and turn rate within the robot's limits
    for k in ("alpha1_dot", "alpha2_dot"):
        assert np.max(np.abs(d[k])) <= robot.max_wheel_rate
    assert np.max(np.abs(d["betadot"])) <= robot.max_rotation_rate
    # the manoeuvre: starts straight along x0 at the origin, ends after about one left lap
    assert (d["x_H"][0], d["y_H"][0], d["beta"][0]) == (0.0, 0.0, 0.0)
    assert 0.9 * 2 * math.pi < d["beta"][-1] < 1.1 * 2 * math.pi
    on_straight = d["s"] < 1.0
    np.testing.assert_allclose(d["y_H"][on_straight], 0.0, atol=1e-12)
    assert "phases: standstill" in r.stdout and "braking" in r.stdout


def test_paper_bad_option(tmp_path: Path) -> None:
    r = _run("--out", str(tmp_path), "--accel", "0.5")  # above the robot's 0.3 m/s^2
    assert r.returncode != 0
    err = r.stderr.strip()
    assert err.count("\n") == 0 and "Settings.accel" in err, err
    assert list(tmp_path.iterdir()) == []
