"""PurePursuitPolicy's textbook options: look-ahead from A or from H, turn-rate limit, speed-scaled look-ahead."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the environments)
from amigo_gym.policies import PurePursuitPolicy
from amigo_gym.task.v1 import TrackingParams, obs_fields


def _obs(p: TrackingParams, v_ref: float, goals: dict[float, tuple[float, float]]) -> np.ndarray:
    """An observation with the given reference speed [m/s] and preview points (A's frame) [m]."""
    names = obs_fields(p)
    o = np.zeros(len(names), dtype=np.float32)
    o[names.index("reference_speed")] = v_ref / p.robot.max_speed
    for d, (x, y) in goals.items():
        o[names.index(f"preview_x_{d:g}m")] = x / p.preview_scale
        o[names.index(f"preview_y_{d:g}m")] = y / p.preview_scale
    return o


def test_the_forms_on_a_synthetic_goal() -> None:
    p = TrackingParams(speed=0.2)
    l3 = p.robot.l3
    o = _obs(p, 0.2, {0.5: (l3 + 1.0, 1.0)})[None, :]
    v_ref = float(np.float32(0.2 / p.robot.max_speed)) * p.robot.max_speed
    _, om = PurePursuitPolicy(p).command(o)  # from A: kappa = 2 y / (x^2 + y^2)
    assert om[0] == pytest.approx(v_ref * 2.0 / ((l3 + 1.0) ** 2 + 1.0), rel=1e-6)
    _, om = PurePursuitPolicy(p, origin="H").command(o)  # from H: the goal at (1, 1), kappa = 1
    assert om[0] == pytest.approx(v_ref, rel=1e-6)
    _, om = PurePursuitPolicy(p, origin="H", max_turn_rate=0.05).command(o)
    assert om[0] == pytest.approx(0.05)
    with pytest.raises(ValueError, match="origin must be 'axle' or 'H'"):
        PurePursuitPolicy(p, origin="A")
    with pytest.raises(ValueError, match="max_turn_rate"):
        PurePursuitPolicy(p, max_turn_rate=-1.0)


def test_speed_scaled_lookahead_picks_the_nearest_preview_point() -> None:
    p = TrackingParams(speed=(0.1, 0.4))
    goals = {0.2: (0.3, 0.1), 0.5: (0.6, 0.2), 1.0: (1.1, 0.3)}
    pol = PurePursuitPolicy(p, lookahead_time=2.5)
    o = np.stack([_obs(p, v, goals) for v in (0.08, 0.2, 0.4)])  # wants 0.2, 0.5 and 1.0 m
    v, om = pol.command(o)
    for i, d in enumerate((0.2, 0.5, 1.0)):
        x, y = goals[d]
        assert om[i] == pytest.approx(v[i] * 2.0 * y / (x * x + y * y), rel=1e-5)


def _steady_error_from_h(radius: float, d: float, l3: float) -> float:
    """H's steady cross-track error on a left circle under pure pursuit from H (geometry, solved by bisection).

    Steady state: A on a concentric circle of radius R_A (centre (0, R_A) in A's frame), H at (l3, 0); the goal
    is the path point d (arc length) beyond H's closest point; the law's 1/R_A = 2 y' / (x'^2 + y'^2) with the
    goal in H's frame (x', y') = (x_G - l3, y_G). The error is R - sqrt(R_A^2 + l3^2) (H inside: left, > 0).
    """

    def residual(r_a: float) -> float:
        phi = math.atan2(-r_a, l3) + d / radius
        gx, gy = radius * math.cos(phi), r_a + radius * math.sin(phi)
        xp, yp = gx - l3, gy
        return 1.0 / r_a - 2.0 * yp / (xp * xp + yp * yp)

    lo, hi = 0.5 * radius, 1.5 * radius
    assert residual(lo) * residual(hi) < 0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if residual(lo) * residual(mid) > 0 else (lo, mid)
    r_a = 0.5 * (lo + hi)
    return radius - math.sqrt(r_a * r_a + l3 * l3)


@pytest.mark.parametrize(("kw", "which"), [({}, "axle"), ({"origin": "H"}, "H")])
def test_steady_error_on_a_circle_matches_the_geometry(kw: dict[str, Any], which: str) -> None:
    env = gym.make("AmigoBot-v1", path="circle", radius=1.0, speed=0.2, max_episode_steps=400, randomize="none")
    p = env.unwrapped.params  # type: ignore[attr-defined]
    pol = PurePursuitPolicy(p, **kw)
    obs, _ = env.reset(seed=0)
    errs = []
    for _ in range(400):
        a, _ = pol.predict(obs)
        obs, _, term, _, info = env.step(a)
        errs.append(info["cross_track_error"])
        assert not term
    l3 = p.robot.l3
    want = -(math.sqrt(1.0 + l3 * l3) - 1.0) if which == "axle" else _steady_error_from_h(1.0, 0.5, l3)
    assert np.mean(errs[-50:]) == pytest.approx(want, abs=2e-4)
