"""Settled task metrics (t >= settle time) against closed forms (amigo_gym.tools.training.task_metrics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amigo_gym.tools.training.task_metrics import METRIC_NAMES, episode_metrics


def test_settled_metrics_of_a_ramp_then_a_square_wave() -> None:
    """dt = 0.1 s, 100 steps (t = 0.1 ... 10 s), settle time 5 s: steps k >= 49 are settled (51 samples).

    Speed error: -0.2 m/s during the ramp (k < 49), then +-0.01 m/s alternating: settled RMS exactly 0.01.
    Command: constant during the ramp, then a square wave of +-A on wheel 1 (wheel 2 constant): each settled
    change is 2 A on wheel 1 and 0 on wheel 2, so the settled chatter is sqrt((2A)^2 / 2) = sqrt(2) A.
    Cross-track error: 0.05 m before, 0.002 m after: settled RMS 0.002 m.
    """
    n, dt, amp = 100, 0.1, 0.75
    k = np.arange(n)
    settled = (k + 1) * dt >= 5.0 - 1e-9
    assert settled.sum() == 51
    ve = np.where(settled, 0.01 * (-1.0) ** k, -0.2)
    cmd = np.zeros((n, 2))
    cmd[:, 1] = 3.0
    cmd[settled, 0] = amp * (-1.0) ** k[settled]
    cmd[~settled, 0] = amp * (-1.0) ** 48  # continuous into the first settled step: that change is 0 or 2A
    e = np.where(settled, 0.002, 0.05)
    m = episode_metrics(e, ve, cmd, cmd, np.zeros(n), dt=dt, terminated=False)
    assert m["speed_err_settled_rms"] == pytest.approx(0.01, rel=1e-12)
    assert m["speed_err_rms"] == pytest.approx(math.sqrt((49 * 0.04 + 51 * 1e-4) / 100), rel=1e-12)
    assert m["h_rms_settled_m"] == pytest.approx(0.002, rel=1e-12)
    # changes ending at settled steps k = 49..99: k = 49 changes from cmd[48] = +A to cmd[49] = -A (2A), all others 2A
    assert m["chatter_settled_rms"] == pytest.approx(math.sqrt(2.0) * amp, rel=1e-12)
    assert "speed_err_settled_rms" in METRIC_NAMES


def test_settled_metrics_are_nan_when_the_episode_ends_before_settling() -> None:
    m = episode_metrics(np.ones(10), np.ones(10), np.zeros((10, 2)), np.zeros((10, 2)), np.zeros(10), dt=0.1,
                        terminated=True)  # fmt: skip
    assert math.isnan(m["speed_err_settled_rms"]) and math.isnan(m["h_rms_settled_m"])
    assert m["speed_err_rms"] == 1.0
