"""Direct kinematics against closed forms and independent formulas (docs/model.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray

from amigo_gym.model.kinematics import (
    body_velocity,
    castor_position,
    castor_rate,
    circle_steady_state,
    contact_points,
    h_position,
    sinc,
    step_pose,
    wheel_rates,
)
from amigo_gym.model.params import RobotParams

ROBOT = RobotParams()
L1, L3, L5, R1, R2, R3 = ROBOT.l1, ROBOT.l3, ROBOT.l5, ROBOT.r1, ROBOT.r2, ROBOT.r3
Array = NDArray[np.float64]


def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


# ---------------------------------------------------------------------------------------------- steady state


def test_model_md_steady_state_values() -> None:
    """docs/model.md's example: v_A = 0.2 m/s, R = 1 m, 6 decimals."""
    ss = circle_steady_state(1.0, 0.2, ROBOT)
    assert round(float(ss.betadot), 6) == 0.200643
    assert round(float(ss.wheel_rates[0]), 6) == 4.481543
    assert round(float(ss.wheel_rates[1]), 6) == 3.518457
    assert round(float(ss.castor_rate), 6) == 6.714802


def test_steady_state_closed_form_any_radius() -> None:
    """R_A = sqrt(R^2 - l3^2), betadot = d v/R_A, lag = d atan(l3/R_A), rates by the rolling relations."""
    for radius, v, d in ((0.5, 0.3, 1), (2.0, 0.1, -1), (0.09, 0.05, 1)):
        ss = circle_steady_state(radius, v, ROBOT, d)
        ra = math.sqrt(radius**2 - L3**2)
        assert float(ss.radius_a) == pytest.approx(ra, rel=1e-14)
        assert float(ss.betadot) == pytest.approx(d * v / ra, rel=1e-14)
        assert float(ss.heading_lag) == pytest.approx(d * math.atan(L3 / ra), rel=1e-14)
        assert float(ss.wheel_rates[0]) == pytest.approx((v + L1 * d * v / ra) / R1, rel=1e-14)
        assert float(ss.wheel_rates[1]) == pytest.approx((v - L1 * d * v / ra) / R2, rel=1e-14)
        assert float(ss.castor_rate) == pytest.approx(math.sqrt((L5 * v / ra) ** 2 + v * v) / R3, rel=1e-14)
        assert float(ss.speed_h) == pytest.approx(v * radius / ra, rel=1e-14)
    with pytest.raises(ValueError, match="radius"):
        circle_steady_state(0.08, 0.2, ROBOT)


def _steady_start(radius: float, phases: Array) -> tuple[Array, Array, Array]:
    """Poses (N, 3) on the steady circle about (0, R): A at radius R_A, heading along A's circle (left)."""
    c = np.array([0.0, radius])
    ra = math.sqrt(radius**2 - L3**2)
    a = c + ra * np.column_stack((np.cos(phases), np.sin(phases)))
    return np.column_stack((a, phases + math.pi / 2)), c, np.full(phases.shape, ra)


@pytest.mark.parametrize("dt", [0.01, 0.1, 0.5])
def test_exact_step_keeps_h_on_circle_for_10_laps(dt: float) -> None:
    """The closed-form steady rates, held, keep H on the circle to 1e-9 m over 10 laps; Euler does not."""
    radius, v = 1.0, 0.2
    ss = circle_steady_state(radius, v, ROBOT)
    pose, c, _ = _steady_start(radius, np.linspace(0.0, 2.0 * math.pi, 4, endpoint=False))
    # H must start on the circle: |A + l3 u - c|^2 = R_A^2 + l3^2 = R^2
    assert np.max(np.abs(np.linalg.norm(h_position(pose, ROBOT) - c, axis=-1) - radius)) < 1e-14
    w = np.broadcast_to(ss.wheel_rates, (pose.shape[0], 2))
    lap = 2.0 * math.pi * float(ss.radius_a) / v
    n = math.ceil(10 * lap / dt)
    bd = float(ss.betadot)
    exact = np.empty((n, *pose.shape))
    euler = np.empty((n, *pose.shape))
    p_exact, p_euler = pose, pose.copy()
    for i in range(n):
        exact[i] = p_exact = step_pose(p_exact, w, dt, ROBOT)
        # counter-example: an explicit Euler step of the same unicycle
        b = p_euler[:, 2]
        euler[i] = p_euler = p_euler + dt * np.column_stack((v * np.cos(b), v * np.sin(b), np.full_like(b, bd)))
    err = float(np.max(np.abs(np.linalg.norm(h_position(exact, ROBOT) - c, axis=-1) - radius)))
    err_euler = float(np.max(np.abs(np.linalg.norm(h_position(euler, ROBOT) - c, axis=-1) - radius)))
    assert err <= 1e-9
    assert err_euler > 1e-4  # Euler drifts off the circle (1e-3 m at dt = 0.01 s, growing with dt)


# ---------------------------------------------------------------------------------------------- closed forms


def test_straight_line() -> None:
    w = np.array([3.0, 3.0])
    pose = np.array([0.3, -0.2, 0.7])
    for dt in (0.01, 0.5, 3.0):
        out = step_pose(pose, w, dt, ROBOT)
        d = R1 * 3.0 * dt
        np.testing.assert_allclose(out, [0.3 + d * math.cos(0.7), -0.2 + d * math.sin(0.7), 0.7], atol=1e-15)


def test_spin_in_place() -> None:
    w = np.array([2.0, -2.0])  # r1 = r2: v_A = 0, betadot = r w / l1
    pose = np.array([1.0, 2.0, -0.3])
    out = step_pose(pose, w, 0.4, ROBOT)
    np.testing.assert_allclose(out, [1.0, 2.0, -0.3 + R1 * 2.0 / L1 * 0.4], atol=1e-15)


def test_arcs_against_circle_geometry() -> None:
    """A moves on the circle of centre A + rho (-sin b, cos b), rho = v/betadot, by the angle betadot dt."""
    g = rng()
    n = 200
    w = g.uniform(-15.0, 15.0, (n, 2))
    v, bd = (R1 * w[:, 0] + R2 * w[:, 1]) / 2.0, (R1 * w[:, 0] - R2 * w[:, 1]) / (2.0 * L1)
    keep = np.abs(bd) > 1e-3
    w, v, bd = w[keep], v[keep], bd[keep]
    pose = np.column_stack((g.uniform(-5, 5, (w.shape[0], 2)), g.uniform(-10, 10, w.shape[0])))
    dt = g.uniform(0.01, 2.0, w.shape[0])
    out = step_pose(pose, w, dt, ROBOT)
    rho = v / bd
    b = pose[:, 2]
    cx, cy = pose[:, 0] - rho * np.sin(b), pose[:, 1] + rho * np.cos(b)
    b1 = b + bd * dt
    np.testing.assert_allclose(out[:, 0], cx + rho * np.sin(b1), atol=1e-11)
    np.testing.assert_allclose(out[:, 1], cy - rho * np.cos(b1), atol=1e-11)
    np.testing.assert_allclose(out[:, 2], b1, atol=1e-12)


def test_step_composes() -> None:
    """Exactness: with rates held, one step of dt1 + dt2 equals a step of dt1 followed by dt2."""
    g = rng()
    pose = g.normal(size=(50, 3))
    w = g.uniform(-15, 15, (50, 2))
    two = step_pose(step_pose(pose, w, 0.3, ROBOT), w, 0.9, ROBOT)
    np.testing.assert_allclose(step_pose(pose, w, 1.2, ROBOT), two, atol=1e-12)


def test_small_turn_rate_is_continuous_with_straight() -> None:
    v = 0.5
    pose = np.array([0.1, 0.2, 1.1])
    dt = 0.5
    straight = pose + np.array([v * dt * math.cos(1.1), v * dt * math.sin(1.1), 0.0])
    for bd in (0.0, 1e-15, -1e-13, 1e-12):
        w = np.array([(v + L1 * bd) / R1, (v - L1 * bd) / R2])
        out = step_pose(pose, w, dt, ROBOT)
        assert np.all(np.isfinite(out))
        np.testing.assert_allclose(out[:2], straight[:2], rtol=0, atol=1e-12)
        assert abs(out[2] - (1.1 + bd * dt)) <= 1e-15
    assert float(sinc(0.0)) == 1.0
    np.testing.assert_allclose(sinc([1e-8, 0.5, 2.0]), [1.0, math.sin(0.5) / 0.5, math.sin(2.0) / 2.0], rtol=1e-15)


# ---------------------------------------------------------------------------------------------- relations


def test_rolling_constraints_system_29() -> None:
    """Wheel rates make the contact points' velocities vanish (docs/model.md's corrected system 29)."""
    g = rng()
    v, bd, b = g.uniform(-0.7, 0.7, 30), g.uniform(-3, 3, 30), g.uniform(-4, 4, 30)
    w = wheel_rates(v, bd, ROBOT)
    xd, yd = v * np.cos(b), v * np.sin(b)
    np.testing.assert_allclose(xd - R1 * w[:, 0] * np.cos(b) + L1 * bd * np.cos(b), 0.0, atol=1e-14)
    np.testing.assert_allclose(yd - R1 * w[:, 0] * np.sin(b) + L1 * bd * np.sin(b), 0.0, atol=1e-14)
    np.testing.assert_allclose(xd - R2 * w[:, 1] * np.cos(b) - L1 * bd * np.cos(b), 0.0, atol=1e-14)
    np.testing.assert_allclose(yd - R2 * w[:, 1] * np.sin(b) - L1 * bd * np.sin(b), 0.0, atol=1e-14)


def test_round_trip_wheel_rates_body_velocity() -> None:
    g = rng()
    w = g.uniform(-15, 15, (100, 2))
    np.testing.assert_allclose(wheel_rates(*body_velocity(w, ROBOT), ROBOT), w, atol=1e-12)
    v, bd = g.uniform(-1, 1, 100), g.uniform(-5, 5, 100)
    v2, bd2 = body_velocity(wheel_rates(v, bd, ROBOT), ROBOT)
    np.testing.assert_allclose(v2, v, atol=1e-14)
    np.testing.assert_allclose(bd2, bd, atol=1e-13)
    # unequal wheels: the relations use each wheel's own radius
    odd = RobotParams(r1=0.05, r2=0.04, l4=0.02)
    np.testing.assert_allclose(wheel_rates(*body_velocity(w, odd), odd), w, atol=1e-12)


def test_castor_rate() -> None:
    assert float(castor_rate(0.2, 0.0, ROBOT)) == pytest.approx(0.2 / R3, rel=1e-15)
    assert float(castor_rate(0.0, 1.5, ROBOT)) == pytest.approx(L5 * 1.5 / R3, rel=1e-15)
    assert float(castor_rate(-0.3, 0.4, ROBOT)) == pytest.approx(-math.hypot(0.3, L5 * 0.4) / R3, rel=1e-15)


def test_points_on_the_body() -> None:
    g = rng()
    pose = np.column_stack((g.normal(size=(40, 2)), g.uniform(-7, 7, 40)))
    a = pose[:, :2]
    u = np.column_stack((np.cos(pose[:, 2]), np.sin(pose[:, 2])))
    k, l_ = contact_points(pose, ROBOT)
    np.testing.assert_allclose(np.linalg.norm(k - a, axis=1), L1, rtol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(l_ - a, axis=1), L1, rtol=1e-14)
    np.testing.assert_allclose(np.sum((k - a) * u, axis=1), 0.0, atol=1e-15)  # on the axle
    np.testing.assert_allclose(u[:, 0] * (k - a)[:, 1] - u[:, 1] * (k - a)[:, 0], -L1, atol=1e-15)  # K right
    np.testing.assert_allclose((k + l_) / 2.0, a, atol=1e-15)
    np.testing.assert_allclose(h_position(pose, ROBOT), a + L3 * u, atol=1e-15)  # paper eq. 4
    np.testing.assert_allclose(castor_position(pose, ROBOT), a - L5 * u, atol=1e-15)


# ---------------------------------------------------------------------------------------------- batching


def test_batch_equals_loop() -> None:
    g = rng()
    n = 7
    pose = np.column_stack((g.normal(size=(n, 2)), g.uniform(-4, 4, n)))
    w = g.uniform(-15, 15, (n, 2))
    g.normal(size=(n, 3))  # (the draws that follow stay as they were)
    dt = g.uniform(0.01, 1.0, n)
    v, bd = body_velocity(w, ROBOT)
    k, l_ = contact_points(pose, ROBOT)
    batched = {
        "step_pose": step_pose(pose, w, dt, ROBOT),
        "h": h_position(pose, ROBOT),
        "castor": castor_position(pose, ROBOT),
        "wr": wheel_rates(v, bd, ROBOT),
        "cr": castor_rate(v, bd, ROBOT),
        "ss": circle_steady_state(np.full(n, 1.3), np.abs(v), ROBOT).wheel_rates,
    }
    for i in range(n):
        single = {
            "step_pose": step_pose(pose[i], w[i], dt[i], ROBOT),
            "h": h_position(pose[i], ROBOT),
            "castor": castor_position(pose[i], ROBOT),
            "wr": wheel_rates(v[i], bd[i], ROBOT),
            "cr": castor_rate(v[i], bd[i], ROBOT),
            "ss": circle_steady_state(1.3, abs(v[i]), ROBOT).wheel_rates,
        }
        for name, val in single.items():
            assert np.shape(val) == np.shape(batched[name])[1:], name
            np.testing.assert_array_equal(val, batched[name][i], err_msg=name)
        vi, bdi = body_velocity(w[i], ROBOT)
        assert (vi, bdi) == (v[i], bd[i])
        ki, li = contact_points(pose[i], ROBOT)
        np.testing.assert_array_equal(ki, k[i])
        np.testing.assert_array_equal(li, l_[i])
    # two leading axes behave like one
    np.testing.assert_array_equal(
        step_pose(pose.reshape(1, n, 3), w.reshape(1, n, 2), 0.1, ROBOT)[0], step_pose(pose, w, 0.1, ROBOT)
    )
