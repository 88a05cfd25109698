"""The analytic inverse solution against closed forms and the exact direct step."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray

from amigo_gym.model.params import RobotParams
from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.task.inverse import (
    COLUMNS,
    ConstantSpeed,
    InverseSolution,
    TrapezoidProfile,
    circle_steady_state,
    manoeuvre_profile,
    paper_circle,
    solve_inverse,
    time_grid,
)
from amigo_gym.tools.analysis.verify import round_trip_error

ROBOT = RobotParams()
L1, L3, R1, R2 = ROBOT.l1, ROBOT.l3, ROBOT.r1, ROBOT.r2


def _h(sol: InverseSolution) -> NDArray[np.float64]:
    return np.column_stack((sol.x_H, sol.y_H))


@pytest.mark.parametrize(("radius", "speed", "d"), [(1.0, 0.2, 1), (0.5, 0.3, -1), (3.0, 0.5, 1)])
def test_steady_state_reached_on_circle(radius: float, speed: float, d: int) -> None:
    path = CirclePath(radius=radius, direction=d)
    ss = circle_steady_state(radius, speed, ROBOT, d)
    # the heading error decays over a distance of the order of l3: 20 m of travel is plenty
    sol = solve_inverse(path, ConstantSpeed(speed), time_grid(20.0 / speed, 0.5), ROBOT)
    assert sol.betadot[-1] == pytest.approx(float(ss.betadot), abs=1e-9)
    np.testing.assert_allclose(sol.wheel_rates[-1], ss.wheel_rates, atol=1e-9)
    assert sol.alpha3_dot[-1] == pytest.approx(float(ss.castor_rate), abs=1e-9)
    lag = float(path.tangent_angle(sol.s[-1])) - sol.beta[-1]
    assert lag == pytest.approx(float(ss.heading_lag), abs=1e-9)
    # A on the concentric circle of radius R_A
    c = np.array(path.center)
    assert math.hypot(sol.x_A[-1] - c[0], sol.y_A[-1] - c[1]) == pytest.approx(float(ss.radius_a), abs=1e-9)


def test_paper_start_and_model_md_values() -> None:
    sol = paper_circle(duration=100.0, dt=1.0)
    assert (sol.x_H[0], sol.y_H[0], sol.beta[0], sol.s[0]) == (0.0, 0.0, 0.0, 0.0)
    assert (sol.x_A[0], sol.y_A[0]) == (-L3, 0.0)
    np.testing.assert_array_equal(sol.v_A, 0.2)
    assert round(float(sol.betadot[-1]), 6) == 0.200643
    assert round(float(sol.alpha1_dot[-1]), 6) == 4.481543
    assert round(float(sol.alpha2_dot[-1]), 6) == 3.518457
    assert round(float(sol.alpha3_dot[-1]), 6) == 6.714802


def test_h_stays_on_the_path() -> None:
    """H computed from the integrated pose of A (eq. 4) lies on the path, at the integrated arc length."""
    for path, prof in (
        (CirclePath(radius=0.4, direction=-1), ConstantSpeed(0.4)),
        (ManoeuvrePath(1.0, 1.0, 1), manoeuvre_profile(ManoeuvrePath(1.0, 1.0, 1))),
    ):
        sol = solve_inverse(path, prof, time_grid(40.0, 0.05), ROBOT)
        assert np.max(np.abs(path.project(_h(sol)).cross_track_error)) <= 1e-8
        assert np.max(np.linalg.norm(path.point(sol.s) - _h(sol), axis=1)) <= 1e-8


def test_wheel_angles_match_distance_and_heading() -> None:
    """r1 a1 + r2 a2 = 2 x distance of A (closed form of the profile); r1 a1 - r2 a2 = 2 l1 (beta - beta0)."""
    path = ManoeuvrePath(0.7, 0.5, -1)
    prof = TrapezoidProfile(speed=0.25, accel=0.3, decel=0.75, t_start=0.5, t_brake=20.0)
    sol = solve_inverse(path, prof, time_grid(22.0, 0.1), ROBOT)
    np.testing.assert_allclose((R1 * sol.alpha1 + R2 * sol.alpha2) / 2, prof.distance(sol.t), atol=1e-9)
    np.testing.assert_allclose((R1 * sol.alpha1 - R2 * sol.alpha2) / (2 * L1), sol.beta - sol.beta[0], atol=1e-9)
    # on the straight H moves with A (beta = theta = 0): s = distance, betadot = 0
    straight = sol.s < 0.5 - 1e-9
    np.testing.assert_allclose(sol.s[straight], prof.distance(sol.t[straight]), atol=1e-12)
    np.testing.assert_allclose(sol.betadot[straight], 0.0, atol=1e-12)
    # at rest after braking
    rest = sol.t >= prof.t_stop
    assert rest.any()
    np.testing.assert_allclose(sol.wheel_rates[rest], 0.0, atol=1e-15)
    np.testing.assert_allclose(np.ptp(sol.alpha1[rest]), 0.0, atol=1e-12)


def test_transient_round_trip_second_order() -> None:
    e1 = round_trip_error(0.1)
    e2 = round_trip_error(0.05)
    assert e1 <= 1e-4
    assert 3.5 <= e1 / e2 <= 4.5  # second order in dt


def test_manoeuvre_continuity() -> None:
    """Across the straight->circle junction: s, beta, rates continuous; the heading error starts at zero."""
    path = ManoeuvrePath(1.0, 1.0, 1)
    prof = ConstantSpeed(0.2)
    dt = 1e-3
    sol = solve_inverse(path, prof, time_grid(10.0, dt), ROBOT)
    j = int(np.argmax(sol.s >= 1.0))  # first sample on the circle, at t = 5 s
    assert sol.t[j] == pytest.approx(5.0, abs=1.5 * dt)  # the first sample at s >= 1 may fall one step late by rounding
    # largest possible change of a rate per sample: betaddot <= v kappa sdot / l3 (at zero heading error)
    bound = L1 * 0.2 * 1.0 * 0.2 / L3 / R1 * dt * 1.01
    assert np.max(np.abs(np.diff(sol.wheel_rates, axis=0))) <= bound
    assert np.max(np.abs(np.diff(sol.beta))) <= 0.21 * dt
    assert np.max(np.abs(np.diff(sol.s))) <= 0.2 * 1.01 * dt
    before = sol.s < 1.0
    np.testing.assert_allclose(sol.wheel_rates[before], 4.0, atol=1e-12)
    np.testing.assert_allclose(sol.beta[before], 0.0, atol=1e-12)  # 1e-13 at the junction sample
    assert np.all(sol.betadot[~before] > 0.0)


def test_step_start_equals_shifted_constant_speed() -> None:
    """A speed step at t_start (accel=None) is the constant-speed solution delayed by t_start."""
    path = CirclePath(radius=0.8)
    prof = TrapezoidProfile(speed=0.3, accel=None, t_start=1.25)
    sol = solve_inverse(path, prof, time_grid(10.0, 0.05), ROBOT)
    ref = solve_inverse(path, ConstantSpeed(0.3), time_grid(10.0 - 1.25, 0.05), ROBOT)
    moving = sol.t >= 1.25 - 1e-12
    for name in ("s", "beta", "x_A", "y_A", "alpha1", "alpha2", "alpha3", "alpha1_dot", "alpha2_dot"):
        got = getattr(sol, name)[moving]
        want = getattr(ref, name)[: got.size]
        np.testing.assert_allclose(got, want, atol=1e-9, err_msg=name)
    np.testing.assert_allclose(sol.alpha1[~moving], 0.0)


def test_given_start() -> None:
    """A start off the steady heading converges to the same steady state; H stays on the path."""
    path = CirclePath(radius=1.0)
    sol = solve_inverse(path, ConstantSpeed(0.2), time_grid(80.0, 1.0), ROBOT, s0=2.0, beta0=2.0 - 1.2)
    assert sol.s[0] == 2.0
    assert sol.beta[0] == pytest.approx(0.8)
    np.testing.assert_allclose(_h(sol)[0], path.point(2.0), atol=1e-15)
    assert np.max(np.abs(path.project(_h(sol)).cross_track_error)) <= 1e-8
    ss = circle_steady_state(1.0, 0.2, ROBOT)
    np.testing.assert_allclose(sol.wheel_rates[-1], ss.wheel_rates, atol=1e-9)


def test_speed_profile_closed_forms() -> None:
    from scipy.integrate import quad

    p = TrapezoidProfile(speed=0.2, accel=0.1, decel=0.4, t_start=1.0, t_brake=10.0)
    assert p.breakpoints() == (1.0, 3.0, 10.0, 10.5)
    np.testing.assert_allclose(
        p([0.0, 1.0, 2.0, 3.0, 7.0, 10.0, 10.25, 10.5, 12.0]), [0, 0, 0.1, 0.2, 0.2, 0.2, 0.1, 0, 0]
    )
    for te in (0.5, 2.0, 5.0, 10.3, 15.0):
        want = quad(lambda x: float(p(x)), 0.0, te, points=[b for b in p.breakpoints() if b < te], epsabs=1e-13)[0]
        assert float(p.distance(te)) == pytest.approx(want, abs=1e-11)
    q = TrapezoidProfile.from_distance(0.2, 7.0, accel=0.3, decel=0.75, t_start=2.0)
    assert float(q.distance(1e3)) == pytest.approx(7.0, abs=1e-12)
    step = TrapezoidProfile(speed=0.2, accel=None, t_start=1.0)
    np.testing.assert_allclose(step([0.999, 1.0, 50.0]), [0.0, 0.2, 0.2])
    assert float(step.distance(3.0)) == pytest.approx(0.4, abs=1e-15)
    c = ConstantSpeed(0.3)
    np.testing.assert_allclose(c(np.arange(3.0)), 0.3)
    assert c.breakpoints() == ()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"speed": 0.0}, "TrapezoidProfile.speed"),
        ({"speed": math.nan}, "TrapezoidProfile.speed"),
        ({"accel": -0.1}, "TrapezoidProfile.accel"),
        ({"decel": math.inf}, "TrapezoidProfile.decel"),
        ({"t_start": -1.0}, "TrapezoidProfile.t_start"),
        ({"t_brake": 0.5}, "TrapezoidProfile.t_brake"),  # before cruise speed is reached (0.2/0.3 s)
    ],
)
def test_profile_rejects(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        TrapezoidProfile(**kwargs)


def test_bad_inputs_raise() -> None:
    t = time_grid(1.0, 0.1)
    with pytest.raises(ValueError, match=r"path\.radius.*\(0\.08"):
        solve_inverse(CirclePath(radius=0.08), ConstantSpeed(0.2), t)
    with pytest.raises(ValueError, match=r"peak_speed"):
        solve_inverse(CirclePath(), ConstantSpeed(0.8), t)
    with pytest.raises(ValueError, match=r"beta0.*pi/2"):
        solve_inverse(CirclePath(), ConstantSpeed(0.2), t, beta0=math.pi / 2)
    with pytest.raises(ValueError, match=r"beta0.*pi/2"):
        solve_inverse(CirclePath(), ConstantSpeed(0.2), t, s0=1.0, beta0=1.0 + 2.0)
    with pytest.raises(ValueError, match=r"beta0"):
        solve_inverse(CirclePath(), ConstantSpeed(0.2), t, beta0=math.nan)
    with pytest.raises(ValueError, match=r"s0"):
        solve_inverse(CirclePath(), ConstantSpeed(0.2), t, s0=-1.0)
    with pytest.raises(ValueError, match=r"increasing"):
        solve_inverse(CirclePath(), ConstantSpeed(0.2), t[::-1])
    with pytest.raises(ValueError, match=r"finite"):
        solve_inverse(CirclePath(), ConstantSpeed(0.2), np.array([0.0, math.nan]))
    with pytest.raises(ValueError, match=r"time_grid\.dt"):
        time_grid(1.0, 0.0)
    with pytest.raises(ValueError, match=r"time_grid\.dt"):
        time_grid(1.0, 2.0)
    with pytest.raises(ValueError, match=r"time_grid\.duration"):
        time_grid(math.inf, 0.1)
    with pytest.raises(ValueError, match=r"points"):
        time_grid(1e4, 1e-4)
    # a wrap-around start is fine: theta - beta = 2 pi - 0.1 is a heading error of -0.1
    sol = solve_inverse(CirclePath(), ConstantSpeed(0.2), t, beta0=2 * math.pi + 0.1)
    assert np.all(np.isfinite(sol.beta))


def test_csv_round_trip_and_atomic(tmp_path: Path) -> None:
    sol = paper_circle(duration=3.0, dt=0.5)
    assert tuple(sol.columns()) == COLUMNS
    target = tmp_path / "sol.csv"
    sol.to_csv(target)
    with open(target) as fh:
        assert fh.readline().strip().split(",") == list(COLUMNS)
    data = np.loadtxt(target, delimiter=",", skiprows=1)
    assert data.shape == (7, len(COLUMNS))
    for i, name in enumerate(COLUMNS):
        np.testing.assert_allclose(data[:, i], getattr(sol, name), rtol=1e-14, atol=1e-300, err_msg=name)
    sol.to_csv(target, columns=("t", "alpha1"))
    assert np.loadtxt(target, delimiter=",", skiprows=1).shape == (7, 2)
    assert sorted(os.listdir(tmp_path)) == ["sol.csv"]  # no temporary file left
    with pytest.raises(ValueError, match="unknown column"):
        sol.to_csv(target, columns=("t", "gamma"))
    with pytest.raises(OSError):
        sol.to_csv(tmp_path / "missing" / "x.csv")
    assert sorted(os.listdir(tmp_path)) == ["sol.csv"]


def test_solution_is_read_only() -> None:
    sol = paper_circle(duration=1.0, dt=0.5)
    with pytest.raises(ValueError, match="read-only"):
        sol.alpha1[0] = 1.0
    with pytest.raises(ValueError, match=r"InverseSolution\.s"):
        InverseSolution(**{**sol.columns(), "s": np.zeros(2)})
