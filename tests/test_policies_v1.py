"""AmigoBot-v1's classical baselines: the analytic tracking policy and pure pursuit (amigo_gym.policies.tracking).

Checked against independent facts: the path's geometry (H's true cross-track error from the env), the exact peak
turn-rate change of :func:`amigo_gym.paths.feasibility`, the closed-form pure-pursuit geometry on a circle, the
reference speed profile, and per-row predictions.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from amigo_gym.envs.amigobot_v1 import AmigoBotV1Env
from amigo_gym.paths import feasibility
from amigo_gym.policies import AnalyticTrackingPolicy, PurePursuitPolicy
from amigo_gym.policies.tracking import DEFAULT_TRACKING_GAIN, limit_wheel_rates
from amigo_gym.task import v1 as tracking

QUIET = {"init_position_noise": 0.0, "init_heading_noise": 0.0}
TRUE_PLUS_5 = {"r1": 0.05 * 1.05, "r2": 0.05 * 1.05, "l1": 0.12 * 1.05}


def closed_loop_impulse_response(gain: float, integral_gain: float, dt: float, steps: int = 20000) -> np.ndarray:
    """Response ``h_n`` ``(steps,)`` [m per m] of ``z_k = z_{k-1} + dt e_k``, ``e_{k+1} = e_k + dt (-k e_k - k_i z_k)
    + delta_k`` to ``delta_0 = 1`` m."""
    h = np.zeros(steps)
    e, z = 0.0, 0.0
    for n in range(1, steps):
        z += dt * e
        c = -gain * e - integral_gain * z
        e = e + dt * c + (1.0 if n == 1 else 0.0)
        h[n] = e
    return h


def zoh_error_bound(
    params: tracking.TrackingParams,
    speed: float,
    max_curvature: float,
    max_curvature_rate: float,
    gain: float = DEFAULT_TRACKING_GAIN,
    integral_gain: float | None = None,
) -> float:
    """Bound [m] on H's settled cross-track error on a path with ``|kappa| <= max_curvature`` [1/m] and
    ``|dkappa/ds| <= max_curvature_rate`` [1/m^2] at the constant ``speed`` [m/s] of A (amigo_gym.policies.tracking's
    module docstring): ``||h||_1 delta``."""
    ki = gain * gain / 4.0 if integral_gain is None else integral_gain
    l3 = params.robot.l3
    dt = params.dt
    w_dot = speed * speed * max_curvature_rate / (1.0 - (l3 * max_curvature) ** 2) ** 2
    delta = l3 * w_dot * dt * dt * (0.5 + w_dot / (2.0 * params.actuators.rot_acceleration))
    h1 = float(np.abs(closed_loop_impulse_response(gain, ki, dt)).sum())
    return h1 * delta


def pure_pursuit_circle_offset(radius: float, l3: float, direction: int = 1) -> float:
    """Steady cross-track error [m] of H under pure pursuit on a circle: ``-direction (sqrt(R^2 + l3^2) - R)``."""
    return -direction * (math.hypot(radius, l3) - radius)


def rollout(policy_cls: Any, steps: int, pkw: dict[str, Any] | None = None, seed: int = 1, **kw: Any) -> dict[str, Any]:
    """Run one episode with ``policy.predict`` (state threaded through); H's true error, speeds, poses per step."""
    env = AmigoBotV1Env(**kw)
    pol = policy_cls(env.params, **(pkw or {}))
    obs, _ = env.reset(seed=seed)
    state = None
    err, speed, ref, pose, actions = [], [], [], [], []
    for _ in range(steps):
        a, state = pol.predict(obs, state)
        actions.append(a)
        obs, _, term, _, info = env.step(a)
        err.append(info["cross_track_error"])
        speed.append(info["speed"])
        ref.append(info["reference_speed"])
        pose.append(info["pose"])
        if term:
            break
    return {
        "err": np.array(err),
        "speed": np.array(speed),
        "ref": np.array(ref),
        "pose": np.array(pose),
        "actions": np.array(actions),
        "env": env,
    }


# --------------------------------------------------------------------------- analytic policy on circles


@pytest.mark.parametrize("radius", [0.5, 1.0, 2.0])
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("speed", [0.1, 0.2, 0.4])
def test_analytic_holds_h_on_circles(radius: float, direction: int, speed: float) -> None:
    # 2 cm / 0.1 rad start offsets, wheels at rest; critically damped at k = 1 1/s: below 1e-6 m after ~25 s
    r = rollout(AnalyticTrackingPolicy, 400, radius=radius, direction=direction, speed=speed)
    assert len(r["err"]) == 400
    assert np.abs(r["err"][350:]).max() < 1e-6
    assert np.abs(r["speed"][350:] - speed).max() < 1e-7  # the observation is float32
    assert np.abs(r["actions"]).max() <= 1.0


@pytest.mark.parametrize("radius", [0.5, 1.0, 2.0])
@pytest.mark.parametrize("direction", [1, -1])
def test_analytic_integral_removes_mismatch_offset(radius: float, direction: int) -> None:
    # true wheel radii and track 5 % larger: the robot drives 5 % faster; the integral removes the offset
    r = rollout(AnalyticTrackingPolicy, 400, radius=radius, direction=direction, speed=0.3, true_robot=TRUE_PLUS_5)
    assert np.abs(r["err"][350:]).max() <= 1e-3
    assert np.abs(r["err"][350:]).max() < 1e-6  # the integral converges
    # without the integral the same mismatch leaves a steady offset (the test can fail)
    p = rollout(
        AnalyticTrackingPolicy,
        400,
        pkw={"integral_gain": 0.0},
        radius=radius,
        direction=direction,
        speed=0.3,
        true_robot=TRUE_PLUS_5,
    )
    assert np.abs(p["err"][350:]).min() > 1e-5


# --------------------------------------------------------------------------- paths whose curvature changes


def _path_extremes(path: Any) -> tuple[float, float]:
    s = np.linspace(0.0, path.length, 40001)
    return float(np.abs(path.curvature(s)).max()), float(np.abs(path.curvature_rate(s)).max())


@pytest.mark.parametrize("family", ["figure8", "lane_change", "random"])
@pytest.mark.parametrize("speed", [0.1, 0.2, 0.4])
def test_analytic_within_derived_zoh_bound(family: str, speed: float) -> None:
    errors = {}
    for ff in (False, True):
        r = rollout(AnalyticTrackingPolicy, 600, pkw={"feedforward": ff}, path=family, speed=speed, **QUIET)
        errors[ff] = float(np.abs(r["err"][50:]).max())  # after the 0.7 s speed ramp from rest
    env = r["env"]
    k_max, k_rate = _path_extremes(env.path)
    bound = zoh_error_bound(env.params, speed, k_max, k_rate)
    mm = {"bound": bound * 1e3, "plain": errors[False] * 1e3, "feedforward": errors[True] * 1e3}
    print(family, speed, {k: float(f"{v:.3g}") for k, v in mm.items()})  # docs/baselines.md's table (-s)
    # the turn-rate rate used by the bound covers the exact solution's peak (independent RK4 computation)
    w_dot = speed**2 * k_rate / (1.0 - (env.params.robot.l3 * k_max) ** 2) ** 2
    peak = feasibility(env.path, speed, env.params.robot, "A").peaks["rotational_acceleration"]
    assert peak <= w_dot
    assert w_dot <= 1.05 * peak
    assert errors[False] <= bound
    assert errors[True] <= bound
    # the bound is not vacuous: the plain law's error is within a factor 20 of it (1.1-7.2x, printed with -s)
    assert errors[False] >= bound / 20
    # the mid-step feedforward removes most of the first-order hold error
    assert errors[True] < errors[False]


def test_impulse_response_norm_matches_continuous_loop() -> None:
    h = closed_loop_impulse_response(2.0, 1.0, 0.1)
    assert abs(h).sum() == pytest.approx(4.0 / (math.e * 2.0 * 0.1), rel=0.03)
    assert abs(h[-1]) < 1e-12


def test_analytic_follows_trapezoid() -> None:
    r = rollout(AnalyticTrackingPolicy, 420, speed=0.3, speed_profile="trapezoid", **QUIET)
    p = r["env"].params
    d = np.abs(r["speed"] - r["ref"])
    t = np.arange(1, len(d) + 1) * p.dt
    t_brake = p.profile_duration - 0.3 / p.profile_decel
    # exact on the ramp up, its corner and the cruise; within one step of braking near the stop (docstring)
    assert d[t < t_brake - 1.0].max() < 1e-6
    assert d.max() <= p.profile_decel * p.dt + 1e-9
    assert r["ref"].max() == pytest.approx(0.3)
    assert np.abs(r["err"]).max() < 1e-3


# --------------------------------------------------------------------------- pure pursuit


@pytest.mark.parametrize("radius", [0.5, 1.0, 2.0])
@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("speed", [0.2, 0.4])
def test_pure_pursuit_steady_offset_closed_form(radius: float, direction: int, speed: float) -> None:
    r = rollout(PurePursuitPolicy, 400, radius=radius, direction=direction, speed=speed)
    expected = pure_pursuit_circle_offset(radius, 0.08, direction)
    assert expected == pytest.approx(-direction * 0.08**2 / (2 * radius), rel=0.01)
    assert r["err"][-1] == pytest.approx(expected, abs=1e-5)
    # A runs on the path circle itself (centre (0, direction R) for the default start)
    a = r["pose"][-1]
    assert math.hypot(a[0], a[1] - direction * radius) == pytest.approx(radius, abs=1e-5)


def test_pure_pursuit_lookahead_must_be_a_preview_distance() -> None:
    p = tracking.TrackingParams()
    assert PurePursuitPolicy(p).lookahead == 0.5
    assert PurePursuitPolicy(p, lookahead=1.0).lookahead == 1.0
    with pytest.raises(ValueError, match="preview distances"):
        PurePursuitPolicy(p, lookahead=0.7)


# --------------------------------------------------------------------------- predict interface


def _batch_obs(n: int = 5) -> tuple[tracking.TrackingParams, np.ndarray]:
    rows = []
    env = AmigoBotV1Env(path="mixed", speed=(0.1, 0.4))
    pol = PurePursuitPolicy(env.params)
    for seed in range(n):
        obs, _ = env.reset(seed=seed)
        for _ in range(seed * 3):
            obs, *_ = env.step(pol.predict(obs)[0])
        rows.append(obs)
    return env.params, np.stack(rows)


@pytest.mark.parametrize("cls", [AnalyticTrackingPolicy, PurePursuitPolicy])
def test_batched_predict_equals_single(cls: Any) -> None:
    params, obs = _batch_obs()
    n = len(obs)
    pol = cls(params)
    state = np.array([[0.0], [0.01], [-0.02], [0.005], [0.0]]) if cls is AnalyticTrackingPolicy else None
    a, s = pol.predict(obs, state)
    assert a.shape == (n, 2)
    assert a.dtype == np.float32
    for i in range(n):
        si = None if state is None else state[i : i + 1]
        ai, s1 = pol.predict(obs[i], si)
        assert ai.shape == (2,)
        np.testing.assert_array_equal(ai, a[i])
        if state is not None:
            np.testing.assert_array_equal(s1, s[i : i + 1])


def test_analytic_state_and_episode_start() -> None:
    params, obs = _batch_obs(3)
    pol = AnalyticTrackingPolicy(params)
    e = obs[:, tracking.obs_fields(params).index("cross_track_error")].astype(np.float64) * params.error_scale
    state = np.array([[0.03], [0.03], [0.03]])
    _, s = pol.predict(obs, state, episode_start=np.array([False, True, False]))
    assert s.shape == (3, 1)
    np.testing.assert_allclose(s[:, 0], [0.03 + 0.1 * e[0], 0.1 * e[1], 0.03 + 0.1 * e[2]])
    np.testing.assert_array_equal(state, [[0.03]] * 3)  # input not modified
    # anti-windup: k_i |z| <= integral_limit
    _, s = pol.predict(obs, np.full((3, 1), 10.0))
    assert np.all(s <= pol.integral_limit / pol.integral_gain)
    # internal state: carried between calls without state, reset at episode_start and by batch size
    pol.reset()
    _, s1 = pol.predict(obs)
    _, s2 = pol.predict(obs)
    np.testing.assert_allclose(s2, 2 * s1)
    _, s3 = pol.predict(obs, episode_start=np.array([True, False, True]))
    np.testing.assert_allclose(s3[:, 0], [s1[0, 0], 3 * s1[1, 0], s1[2, 0]])
    _, s4 = pol.predict(obs[0])
    np.testing.assert_allclose(s4, s1[:1])


def test_limits_keep_turn_to_speed_ratio() -> None:
    p = tracking.TrackingParams()
    a = limit_wheel_rates(np.array([0.4, 0.4, 0.0]), np.array([0.5, 20.0, -30.0]), p)
    assert np.abs(a).max() <= 1.0
    assert np.abs(a[1]).max() == pytest.approx(1.0)
    r = p.robot
    w1, w2 = (0.4 + r.l1 * 20.0) / r.r1, (0.4 - r.l1 * 20.0) / r.r2
    assert a[1, 0] / a[1, 1] == pytest.approx(w1 / w2)
    np.testing.assert_allclose(a[0], [(0.4 + r.l1 * 0.5) / r.r1 / 15, (0.4 - r.l1 * 0.5) / r.r2 / 15])


def test_bad_inputs_refused() -> None:
    p = tracking.TrackingParams()
    pol = AnalyticTrackingPolicy(p)
    with pytest.raises(ValueError, match="shape"):
        pol.predict(np.zeros(5))
    with pytest.raises(ValueError, match="finite"):
        pol.predict(np.full(len(tracking.obs_fields(p)), np.nan))
    with pytest.raises(ValueError, match="gain"):
        AnalyticTrackingPolicy(p, gain=0.0)


def test_the_textbook_pure_pursuit_preset() -> None:
    """Cao et al. (2024)'s values (``benchmark --random-paths`` reproduces their failure rate with it)."""
    import gymnasium as gym

    env = gym.make("AmigoBot-v1", preview=(0.2, 0.5, 1.0))
    pp = PurePursuitPolicy.textbook(env.unwrapped.params)
    assert (pp.lookahead, pp.origin, pp.max_turn_rate, pp.lookahead_time) == (0.2, "axle", 1.0, None)
    with pytest.raises(ValueError, match=r"lookahead must be one of the preview distances"):
        PurePursuitPolicy.textbook(gym.make("AmigoBot-v1", preview=(0.5, 1.0)).unwrapped.params)
