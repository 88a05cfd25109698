"""Tests of the analytic inverse-solution policy (amigo_gym/policies/analytic.py).

References: the closed-form steady state on a circle, the continuous-time error law
``e(t) = e0 exp(-k t)``, and the paper's inverse ODE integrated independently with SciPy.
Rollouts use AmigoBot-v0's reference column step (AmigoBot-v1's ideal step with v0's settings, what the environment
runs with ``kernel="numpy"``; tests/v0_reference.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from v0_reference import Reference, start_pose

from amigo_gym.model.kinematics import body_velocity, circle_steady_state
from amigo_gym.model.params import RobotParams
from amigo_gym.policies.analytic import AnalyticPolicy, analytic_body_velocity
from amigo_gym.task import v0 as task
from amigo_gym.task.v1 import TrackingParams


def lap_time(p: TrackingParams) -> float:
    """Time of one steady lap of the circle [s]: ``2 pi R_A / v_A``."""
    return 2 * math.pi * math.sqrt(p.radius**2 - p.robot.l3**2) / float(p.speed)


def steady_pose(p: TrackingParams) -> np.ndarray:
    """Pose with H at the circle's start point and the steady heading lag (closed form)."""
    ss = circle_steady_state(p.radius, p.speed, p.robot, p.direction)
    beta = -float(ss.heading_lag)  # theta(0) = 0, beta = theta - lag
    return np.array([-p.robot.l3 * math.cos(beta), -p.robot.l3 * math.sin(beta), beta])


def observe(p: TrackingParams, pose: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """The observation of start states ``pose (..., 3)`` with wheel rates ``rates (..., 2)`` (float64), by AmigoBot-v0's
    reference evaluation (tests/v0_reference.py)."""
    pose = np.atleast_2d(pose)
    rows = np.column_stack((pose, np.zeros((len(pose), 3)), np.broadcast_to(rates, (len(pose), 2))))
    ref = Reference(p, rows)
    return ref.obs(ref.start()[1])


def rollout(
    policy: AnalyticPolicy, p: TrackingParams, pose: np.ndarray, n: int, rates: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """Closed loop with AmigoBot-v0's exact reference step (tests/v0_reference.py, what
    ``gym.make("AmigoBot-v0", kernel="numpy")`` runs) from ``pose`` and ``rates``; observations cast to float32 like
    the env."""
    rates = np.array([p.speed / p.robot.r1, p.speed / p.robot.r2]) if rates is None else rates
    ref = Reference(p, np.concatenate((pose, np.zeros(3), rates)))
    _, out = ref.start()
    obs = ref.obs(out).astype(np.float32)
    es, poses, ws = [out.error], [pose], []
    for _ in range(n):
        action, _ = policy.predict(obs)
        rows, _, out = ref.step(action)
        obs = ref.obs(out).astype(np.float32)
        es.append(out.error)
        poses.append(rows[:3])
        ws.append(rows[6:8])
    return {"e": np.array(es), "pose": np.array(poses), "rates": np.array(ws)}


CASES = [
    TrackingParams.v0(),
    TrackingParams.v0(radius=0.5, speed=0.3, direction=-1),
    TrackingParams.v0(radius=2.0, speed=0.1, dt=0.05, robot=RobotParams(l3=0.1, r1=0.06)),
]


@pytest.mark.parametrize("p", CASES)
@pytest.mark.parametrize("speed_reference", ["A", "H"])
def test_steady_state_rates_match_closed_form(p: TrackingParams, speed_reference: str) -> None:
    ss = circle_steady_state(p.radius, p.speed, p.robot, p.direction)
    obs = observe(p, steady_pose(p), ss.wheel_rates)[0].astype(np.float32)
    for feedforward_only in (False, True):
        pol = AnalyticPolicy(p, feedforward_only=feedforward_only, speed_reference=speed_reference)
        np.testing.assert_allclose(pol.wheel_rates(obs), ss.wheel_rates, atol=1e-5)
        np.testing.assert_allclose(pol.predict(obs)[0], ss.wheel_rates / p.robot.max_wheel_rate, atol=1e-6)


def test_modelmd_example_rates() -> None:
    # docs/model.md: v_A = 0.2 m/s, R = 1 m: alpha1dot = 4.481543, alpha2dot = 3.518457 rad/s
    p = TrackingParams.v0()
    obs = observe(p, steady_pose(p), np.array([4.481543, 3.518457]))[0]
    np.testing.assert_allclose(AnalyticPolicy(p).wheel_rates(obs), [4.481543, 3.518457], atol=1e-5)


@pytest.mark.parametrize("p", CASES)
@pytest.mark.parametrize("feedforward_only", [False, True])
def test_nominal_lap_stays_on_circle(p: TrackingParams, feedforward_only: bool) -> None:
    ss = circle_steady_state(p.radius, p.speed, p.robot, p.direction)
    n = math.ceil(lap_time(p) / p.dt) + 1
    out = rollout(AnalyticPolicy(p, feedforward_only=feedforward_only), p, steady_pose(p), n, ss.wheel_rates)
    assert np.abs(out["e"]).max() <= 1e-6
    # and H went once around: heading advanced by 2 pi (beyond a lap by the extra step)
    assert abs(out["pose"][-1, 2] - out["pose"][0, 2]) >= 2 * math.pi


@pytest.mark.parametrize("speed_reference", ["A", "H"])
def test_error_follows_continuous_decay(speed_reference: str) -> None:
    """For small dt the closed loop approaches edot = -k e, e(t) = e0 exp(-k t); error O(dt)."""
    k = 3.0
    devs = []
    for dt in (0.01, 0.005):
        p = TrackingParams.v0(dt=dt)
        pose = start_pose(p, [0.5, 1.0, -1.0])
        n = round(2.0 / dt)
        e = rollout(AnalyticPolicy(p, gain=k, speed_reference=speed_reference), p, pose, n)["e"]
        t = np.arange(n + 1) * dt
        devs.append(np.abs(e - e[0] * np.exp(-k * t)).max() / abs(e[0]))
    assert devs[1] < 0.01
    assert 0.35 < devs[1] / devs[0] < 0.65  # first order in dt: halving dt halves the deviation


def test_perturbed_start_converges_at_default_dt() -> None:
    p = TrackingParams.v0()
    rng = np.random.default_rng(0)
    for u in rng.uniform(-1, 1, size=(5, 3)):
        e = rollout(AnalyticPolicy(p), p, start_pose(p, u), 60)["e"]
        # halves at least every 0.5 s between 1 s and 4 s (measured about every 0.33 s)
        assert abs(e[40]) <= abs(e[10]) * 2.0**-6 + 1e-9
        assert np.abs(e).max() <= abs(e[0]) + 2e-3


def test_feedforward_only_keeps_offset_and_aligns_heading() -> None:
    """k = 0 keeps Hdot . n = 0: H keeps its offset while psi -> psi_ss at rate v/l3 (small dt)."""
    p = TrackingParams.v0(dt=0.005)
    path = p.path
    pose = start_pose(p, [0.0, 1.0, 1.0])
    out = rollout(AnalyticPolicy(p, feedforward_only=True), p, pose, round(3.0 / p.dt))
    e = out["e"]
    assert np.abs(e - e[0]).max() < 0.01 * abs(e[0])
    # heading error at the end against the steady lag of the parallel circle H runs on
    radius_h = p.radius - e[-1]
    h = out["pose"][-1]
    proj = path.project(h[:2] + p.robot.l3 * np.array([math.cos(h[2]), math.sin(h[2])]))
    psi = (h[2] - proj.tangent_angle + math.pi) % (2 * math.pi) - math.pi
    assert abs(psi + math.asin(p.robot.l3 / radius_h)) < 1e-3


def test_feedforward_only_is_the_papers_inverse_ode() -> None:
    """From the paper's start (H at the origin, beta = 0) the k = 0 closed loop tracks the inverse ODE

    sdot = v / cos(theta - beta), betadot = v tan(theta - beta) / l3, theta = s / R,
    integrated here independently with SciPy; the discrete loop differs by O(dt).
    """
    p = TrackingParams.v0(dt=0.005, init_position_noise=0.0, init_heading_noise=0.0)
    l3, v, radius = p.robot.l3, p.speed, p.radius
    n = round(5.0 / p.dt)
    t = np.arange(n + 1) * p.dt

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        d = y[0] / radius - y[1]
        return [v / math.cos(d), v * math.tan(d) / l3]

    ref = solve_ivp(rhs, (0.0, t[-1]), [0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12)
    pose0 = np.array([-l3, 0.0, 0.0])
    out = rollout(AnalyticPolicy(p, feedforward_only=True), p, pose0, n)
    np.testing.assert_allclose(out["pose"][:, 2], ref.y[1], atol=2e-3)
    v_a, betadot = body_velocity(out["rates"], p.robot)
    np.testing.assert_allclose(v_a, v, atol=1e-6)
    ref_bd = v * np.tan(ref.y[0] / radius - ref.y[1]) / l3
    np.testing.assert_allclose(betadot, ref_bd[:-1], atol=0.01)
    assert np.abs(out["e"]).max() < 1e-3


def test_batch_equals_loop() -> None:
    p = TrackingParams.v0()
    rng = np.random.default_rng(1)
    poses = start_pose(p, rng.uniform(-1, 1, size=(7, 3)))
    rates = rng.uniform(0, 8, size=(7, 2))
    obs = observe(p, poses, rates).astype(np.float32)
    for pol in (AnalyticPolicy(p), AnalyticPolicy(p, feedforward_only=True), AnalyticPolicy(p, speed_reference="H")):
        batch, state = pol.predict(obs)
        assert state is None and batch.shape == (7, 2) and batch.dtype == np.float32
        loop = np.stack([pol.predict(o)[0] for o in obs])
        np.testing.assert_array_equal(batch, loop)


def test_law_solves_the_velocity_map() -> None:
    """The commanded (v_A, betadot) give H the requested path-frame velocity (tangential, -k e)."""
    p = TrackingParams.v0()
    rng = np.random.default_rng(2)
    n = 50
    psi = rng.uniform(-1.2, 1.2, n)
    e = rng.uniform(-0.1, 0.1, n)
    kl3 = rng.uniform(-0.5, 0.5, n)
    obs = np.zeros((n, len(task.obs_names(p))))
    obs[:, 0], obs[:, 1], obs[:, 2], obs[:, 3] = e / p.error_scale, np.sin(psi), np.cos(psi), kl3
    obs[:, -1] = p.speed / p.robot.max_speed
    l3, k = p.robot.l3, 2.5
    for sr in ("A", "H"):
        v, bd = analytic_body_velocity(obs, p, gain=k, speed_reference=sr)
        h_t = np.cos(psi) * v - l3 * np.sin(psi) * bd
        h_n = np.sin(psi) * v + l3 * np.cos(psi) * bd
        np.testing.assert_allclose(h_n, -k * e, atol=1e-12)
        if sr == "A":
            np.testing.assert_allclose(v, p.speed, atol=1e-12)
        else:
            np.testing.assert_allclose(h_t, p.speed / np.sqrt(1 - kl3**2), atol=1e-12)


@pytest.mark.parametrize("direction", [1, -1])
def test_law_from_plain_geometry(direction: int) -> None:
    """The policy's wheel rates equal the law evaluated by hand from the pose, with no observation code.

    Replaces a mirror test that ran the policy twice. Here the cross-track error and the heading
    error come from the circle's centre and radius directly (H = A + l3 (cos b, sin b); e > 0 left of
    the path), and the rates from ``r w = v_A +- l1 betadot`` with ``betadot = (-k e - v sin psi) /
    (l3 cos psi)``.
    """
    p = TrackingParams.v0(direction=direction)
    robot, k = p.robot, 3.0
    rng = np.random.default_rng(3)
    u = rng.uniform(-1, 1, size=(6, 3))
    pose = start_pose(p, u)
    rates = np.full((6, 2), 4.0)
    obs = observe(p, pose, rates)
    cx, cy = 0.0, direction * p.radius  # eq. 6: through the origin, tangent to x0, centre left (or right)
    hx = pose[:, 0] + robot.l3 * np.cos(pose[:, 2])
    hy = pose[:, 1] + robot.l3 * np.sin(pose[:, 2])
    dist = np.hypot(hx - cx, hy - cy)
    e = direction * (p.radius - dist)  # inside a left circle is left of the path
    phi = np.arctan2(hy - cy, hx - cx)
    theta = phi + direction * math.pi / 2  # tangent of the circle travelled in `direction`
    psi = np.angle(np.exp(1j * (pose[:, 2] - theta)))
    v = p.speed
    betadot = (-k * e - v * np.sin(psi)) / (robot.l3 * np.maximum(np.cos(psi), 0.2))
    want = np.stack([(v + robot.l1 * betadot) / robot.r1, (v - robot.l1 * betadot) / robot.r2], axis=-1)
    np.testing.assert_allclose(AnalyticPolicy(p, gain=k).wheel_rates(obs), want, rtol=1e-5, atol=1e-5)


def test_bad_input() -> None:
    p = TrackingParams.v0()
    pol = AnalyticPolicy(p)
    with pytest.raises(ValueError, match="shape"):
        pol.predict(np.zeros(5))
    with pytest.raises(ValueError, match="finite"):
        pol.predict(np.full(len(task.obs_names(p)), np.nan))
    with pytest.raises(ValueError, match=r"AnalyticPolicy\.gain"):
        AnalyticPolicy(p, gain=-1.0)
    with pytest.raises(ValueError, match=r"AnalyticPolicy\.gain"):
        AnalyticPolicy(p, gain=math.inf)
    with pytest.raises(ValueError, match="speed_reference"):
        AnalyticPolicy(p, speed_reference="B")


def test_action_is_clipped() -> None:
    p = TrackingParams.v0()
    obs = np.zeros(len(task.obs_names(p)))
    obs[0], obs[1], obs[2], obs[-1] = 4.0, math.sin(1.5), math.cos(1.5), 1.0  # far off, facing across
    a, _ = AnalyticPolicy(p).predict(obs)
    assert np.all(np.abs(a) <= 1.0) and np.isclose(np.abs(a).max(), 1.0)


def test_env_lap_from_steady_pose_via_reset_options() -> None:
    """In AmigoBot-v0 itself: started on the steady state (reset option "pose"), H stays on the circle."""
    import gymnasium as gym

    import amigo_gym  # noqa: F401

    p = TrackingParams.v0()
    env = gym.make("AmigoBot-v0", max_episode_steps=None)
    pol = AnalyticPolicy(p)
    obs, info = env.reset(options={"pose": steady_pose(p)})
    assert abs(info["cross_track_error"]) < 1e-15
    n = math.ceil(lap_time(p) / p.dt)
    es, rates = [], []
    for _ in range(n):
        obs, _, terminated, _, info = env.step(pol.predict(obs)[0])
        es.append(info["cross_track_error"])
        rates.append(info["wheel_rates"])
        assert not terminated
    assert np.abs(es).max() <= 1e-6
    ss = circle_steady_state(p.radius, p.speed, p.robot)
    np.testing.assert_allclose(np.array(rates)[1:], np.broadcast_to(ss.wheel_rates, (n - 1, 2)), atol=1e-5)
