"""``amigo-gym inverse`` by subprocess: CSV columns and values, one-line errors."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
REQUIRED = ["t", "x_A", "y_A", "beta", "alpha1", "alpha2", "alpha3", "alpha1_dot", "alpha2_dot", "alpha3_dot"]


def _run(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "inverse", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )


def _read(path: Path) -> dict[str, np.ndarray]:
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, i] for i, name in enumerate(header)}


def test_circle_csv_reaches_model_md_steady_state(tmp_path: Path) -> None:
    out = tmp_path / "circle.csv"
    r = _run(
        "--path", "circle", "--radius", "1", "--speed", "0.2", "--duration", "100", "--dt", "0.5", "--csv", str(out)
    )
    assert r.returncode == 0, r.stderr
    cols = _read(out)
    for name in REQUIRED:
        assert name in cols, name
    np.testing.assert_allclose(cols["t"], 0.5 * np.arange(201), atol=1e-12)
    # the paper's start: H at the origin, beta = 0, A l3 = 0.08 m behind
    assert (cols["beta"][0], cols["x_A"][0], cols["y_A"][0]) == (0.0, -0.08, 0.0)
    # docs/model.md's steady state at the end of a long run
    assert round(cols["alpha1_dot"][-1], 6) == 4.481543
    assert round(cols["alpha2_dot"][-1], 6) == 3.518457
    assert round(cols["alpha3_dot"][-1], 6) == 6.714802
    # H = A + l3 (cos b, sin b) on eq. (6)'s circle: centre (0, 1), radius 1
    hx = cols["x_A"] + 0.08 * np.cos(cols["beta"])
    hy = cols["y_A"] + 0.08 * np.sin(cols["beta"])
    np.testing.assert_allclose(np.hypot(hx, hy - 1.0), 1.0, atol=1e-9)
    # wheel angles integrate the rates: trapezoid rule on the smooth steady part
    a1 = cols["alpha1"]
    np.testing.assert_allclose(np.diff(a1)[-20:], 0.5 * 4.481543 * np.ones(20), atol=1e-5)


def test_manoeuvre_csv(tmp_path: Path) -> None:
    out = tmp_path / "m.csv"
    r = _run(
        "--path", "manoeuvre", "--straight-length", "0.5", "--radius", "0.6", "--direction", "-1", "--csv", str(out)
    )
    assert r.returncode == 0, r.stderr
    cols = _read(out)
    assert np.all(cols["v_A"] <= 0.2 + 1e-15)
    assert np.all(cols["v_A"] >= 0.0)
    assert cols["v_A"][0] == 0.0 and cols["v_A"][-1] == 0.0  # standstill, then at rest after braking
    assert cols["beta"][-1] < -2 * math.pi * 0.9  # a right turn of about one lap
    assert np.all(np.abs(cols["alpha1_dot"]) <= 15.0)


def test_summary_without_csv() -> None:
    r = _run("--duration", "60", "--dt", "1")
    assert r.returncode == 0, r.stderr
    assert "steady state on the circle" in r.stdout
    assert "alpha1_dot = 4.481543" in r.stdout


@pytest.mark.parametrize(
    "args",
    [
        ["--radius", "-1"],
        ["--radius", "0.08"],  # must exceed l3
        ["--speed", "nan"],
        ["--speed", "2"],
        ["--dt", "0"],
        ["--duration", "-5"],
        ["--dt", "5", "--duration", "1"],
        ["--path", "square"],
        ["--direction", "2"],
        ["--radius", "abc"],
        ["--csv", "/nonexistent-dir/x.csv"],
        ["--path", "manoeuvre", "--accel", "0"],
        ["--path", "manoeuvre", "--straight-length", "-1"],
    ],
)
def test_bad_options_one_line_error(args: list[str], tmp_path: Path) -> None:
    r = _run(*args, cwd=tmp_path)
    assert r.returncode != 0
    err = r.stderr.strip()
    assert err.count("\n") == 0, err
    assert err.startswith("amigo-gym inverse: error:"), err
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_unwritable_csv(tmp_path: Path) -> None:
    for target in (str(tmp_path), "/proc/amigo.csv"):  # a directory; a folder nobody can create files in
        r = _run("--duration", "1", "--csv", target)
        assert r.returncode != 0, target
        err = r.stderr.strip()
        assert err.count("\n") == 0, err
        assert err.startswith("amigo-gym inverse: error: --csv"), err
    assert list(tmp_path.iterdir()) == []
