"""Smoke test of `amigo-gym convergence` by subprocess, and its fit against the k = 1 closed loop."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

from amigo_gym.tools.analysis.convergence import Settings, halving_times


def test_convergence_command_writes_table_and_plot(tmp_path: Path) -> None:
    png = tmp_path / "conv.png"
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "amigo_gym.tools.cli",
            "convergence",
            "--gains",
            "2,3",
            "--seeds",
            "2",
            "--plot",
            str(png),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0, r.stderr
    assert "error halves every" in r.stdout
    assert png.stat().st_size > 10_000


def test_small_gain_halving_time_near_continuous_law() -> None:
    # for k dt << 1 the sampled loop is close to e(t) = e0 exp(-k t): halving ln2/k (0.69 s at k = 1)
    row = halving_times(Settings(gains="1", seeds=3, steps=50))[0]
    assert abs(row.halving_s - math.log(2.0)) / math.log(2.0) < 0.1


def test_bad_gain_is_one_line_error() -> None:
    r = subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "convergence", "--gains", "-1"], capture_output=True, text=True
    )
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "gains" in r.stderr
