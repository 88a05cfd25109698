"""The column functions the environments run: the array functions (step_pose, project) are thin wrappers over
them; AmigoBot-v0's reference step (AmigoBot-v1's ideal
column step with v0's settings) against the closed forms of its motion and reward."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from v0_reference import Reference, start_pose

from amigo_gym.model.kinematics import (
    arc_step,
    body_velocity,
    body_velocity_columns,
    castor_rate,
    castor_rate_columns,
    col_tan,
    half_tan_cos_sin,
    pack,
    step_pose,
)
from amigo_gym.model.params import RobotParams
from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.task import v0 as task
from amigo_gym.task.v1 import TrackingParams

ROBOT = RobotParams()
PATHS = [
    CirclePath(),
    CirclePath(1.2, (0.5, -0.5), 0.4, -1),
    ManoeuvrePath(1.0, 1.0, 1),
    ManoeuvrePath(0.6, 0.0, -1),
]


def rng() -> np.random.Generator:
    return np.random.default_rng(11)


def cos_sin(x: Any) -> tuple[Any, Any]:
    # (cos x, sin x) from t = tan(x / 2), within about 2e-16 of numpy's
    return half_tan_cos_sin(col_tan(0.5 * x))


def test_cos_sin_from_the_half_angle_tangent() -> None:
    x = np.concatenate((rng().uniform(-100.0, 100.0, 20000), [0.0, -0.0, 1e-300, math.pi, -math.pi, 1e5]))
    c, s = cos_sin(x)
    np.testing.assert_allclose(c, np.cos(x), rtol=0, atol=5e-16)
    np.testing.assert_allclose(s, np.sin(x), rtol=0, atol=5e-16)
    assert cos_sin(0.0) == (1.0, 0.0)
    # small angles: the sine to a few units in the last place, relative
    h = np.geomspace(1e-12, 0.5, 200)
    np.testing.assert_allclose(cos_sin(h)[1], np.sin(h), rtol=1e-15, atol=0)


def test_arc_step_is_step_pose_and_carries_the_heading() -> None:
    g = rng()
    n = 300
    pose = np.column_stack((g.normal(size=(n, 2)), g.uniform(-60, 60, n)))
    w = g.uniform(-15, 15, (n, 2))
    w[:5, 1] = w[:5, 0]  # straight lines: betadot = 0
    v, bd = body_velocity(w, ROBOT)
    for dt in (0.01, 0.1, 2.0):
        arc = arc_step(pose[:, 0], pose[:, 1], pose[:, 2], v, bd, dt)
        np.testing.assert_array_equal(pack(arc.x, arc.y, arc.beta), step_pose(pose, w, dt, ROBOT))
        # to the rounding of beta' itself (|beta| up to 60 rad: a unit in the last place is 7e-15)
        tol = 1e-15 + 2.0 * np.spacing(np.abs(arc.beta))
        assert np.all(np.abs(arc.cos_beta - np.cos(arc.beta)) <= tol)
        assert np.all(np.abs(arc.sin_beta - np.sin(arc.beta)) <= tol)
        light = arc_step(pose[:, 0], pose[:, 1], pose[:, 2], v, bd, dt, with_heading=False)
        np.testing.assert_array_equal(pack(light.x, light.y, light.beta), pack(arc.x, arc.y, arc.beta))
        assert math.isnan(light.cos_beta) and math.isnan(light.sin_beta)


def test_velocity_and_castor_columns() -> None:
    w = rng().uniform(-15, 15, (50, 2))
    v, bd = body_velocity_columns(w[:, 0], w[:, 1], ROBOT)
    v2, bd2 = body_velocity(w, ROBOT)
    np.testing.assert_array_equal(v, v2)
    np.testing.assert_array_equal(bd, bd2)
    np.testing.assert_array_equal(castor_rate_columns(v, bd, ROBOT), castor_rate(v, bd, ROBOT))
    np.testing.assert_allclose(
        castor_rate(v, bd, ROBOT), np.sign(v) * np.hypot(ROBOT.l5 * bd, v) / ROBOT.r3, rtol=1e-15
    )
    # positive unless v_A < 0: -0.0 counts as forward in the public function
    assert float(castor_rate(-0.0, 1.5, ROBOT)) == pytest.approx(ROBOT.l5 * 1.5 / ROBOT.r3, rel=1e-15)


@pytest.mark.parametrize("path", PATHS)
def test_project_xy_is_project_and_minimal_keeps_what_the_envs_need(path: Any) -> None:
    q = rng().uniform(-2.0, 3.0, (400, 2))
    full = path.project(q)
    cp = path.project_xy(q[:, 0], q[:, 1])
    for name in ("s", "tangent_angle", "curvature", "cross_track_error", "cos_theta", "sin_theta"):
        np.testing.assert_array_equal(np.broadcast_to(getattr(cp, name), (400,)), getattr(full, name), err_msg=name)
    np.testing.assert_array_equal(pack(cp.x, cp.y), full.point)
    np.testing.assert_allclose(full.cos_theta, np.cos(full.tangent_angle), atol=1e-14)
    np.testing.assert_allclose(full.sin_theta, np.sin(full.tangent_angle), atol=1e-14)
    mini = path.project_xy(q[:, 0], q[:, 1], minimal=True)
    for name in ("curvature", "cross_track_error", "cos_theta", "sin_theta"):
        np.testing.assert_array_equal(getattr(mini, name), getattr(cp, name), err_msg=name)
    for name in ("x", "y", "tangent_angle"):
        assert np.all(np.isnan(getattr(mini, name))), name


def test_circle_projection_at_the_centre_is_the_start_point() -> None:
    c = CirclePath(1.2, (0.5, -0.5), 0.4, -1)
    cx, cy = c.center
    for pr in (c.project(np.array([cx, cy])), c.project(np.array([[cx, cy], [cx + 0.3, cy]]))):
        s = np.atleast_1d(pr.s)[0]
        np.testing.assert_allclose(np.atleast_2d(pr.point)[0], c.start, atol=1e-15)
        assert s == 0.0
        assert abs(np.atleast_1d(pr.cross_track_error)[0]) == pytest.approx(1.2)
        assert np.atleast_1d(pr.tangent_angle)[0] == pytest.approx(0.4)
    one = c.project_xy(cx, cy)
    assert (one.x, one.y) == pytest.approx(c.start, abs=1e-15)


@pytest.mark.parametrize("path_name", ["circle", "manoeuvre"])
def test_v0_reference_step_is_the_closed_forms(path_name: str) -> None:
    """AmigoBot-v0's reference step (AmigoBot-v1's ideal column step with v0's settings, tests/v0_reference.py):
    the motion is the exact arc step of the clipped, scaled action (:func:`step_pose`), the wheel angles advance by
    ``w dt``; the reward is the product of its four terms, each in [0, 1]; a start state's H is
    ``A + l3 (cos b, sin b)``."""
    p = TrackingParams.v0(path=path_name, dt=0.2)
    g = rng()
    n = 64
    pose = start_pose(p, g.uniform(-1, 1, (n, 3)))
    pose[:, 0] += g.uniform(0.0, 2.0, n)  # along the straight part and onto the circle
    angles = g.normal(size=(n, 3))
    prev = g.uniform(-15, 15, (n, 2))
    action = g.uniform(-1.3, 1.3, (n, 2))
    state = np.column_stack((pose, angles, prev))
    rows, _record, out = Reference(p, state).step(action)
    w = np.clip(action, -1.0, 1.0) * p.robot.max_wheel_rate
    np.testing.assert_array_equal(rows[:, :3], step_pose(pose, w, p.dt, p.robot))
    np.testing.assert_array_equal(rows[:, 3:5], angles[:, :2] + w * p.dt)
    np.testing.assert_array_equal(rows[:, 6:], w)
    t = dict(zip(task.REWARD_TERMS, out.terms, strict=True))  # the reward is the product of its named terms
    np.testing.assert_array_equal(out.reward, ((t["track"] * t["speed"]) * t["heading"]) * t["smooth"])
    assert all(np.all((t[name] >= 0.0) & (t[name] <= 1.0)) for name in task.REWARD_TERMS)
    assert np.any(t["smooth"] < 1.0)  # the rates changed
    # the evaluation of a start state: H l3 ahead of A, no smoothness loss
    ref = Reference(p, state)
    start_record, _start = ref.start()
    np.testing.assert_array_equal(start_record[:, 3], pose[:, 0] + p.robot.l3 * np.cos(pose[:, 2]))
    np.testing.assert_array_equal(start_record[:, 4], pose[:, 1] + p.robot.l3 * np.sin(pose[:, 2]))
    np.testing.assert_array_equal(start_record[:, 14], 1.0)


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize("n", [1, 5])
def test_vector_env_equals_sync_on_the_manoeuvre_path(mode: AutoresetMode, n: int) -> None:
    kw: dict[str, Any] = {
        "path": "manoeuvre",
        "straight_length": 0.3,
        "init_position_noise": 0.1,
        "termination_distance": 0.2,
        "max_episode_steps": 30,
    }
    vec = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="vector_entry_point", autoreset_mode=mode, **kw)
    sync = gym.make_vec(  # the reference: single envs on the numpy float path
        "AmigoBot-v0",
        num_envs=n,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": mode},
        kernel="numpy",
        **kw,
    )
    g = np.random.default_rng(3)
    rv, rs = vec.reset(seed=9), sync.reset(seed=9)
    close = {"rtol": 1e-9, "atol": 1e-9, "strict": True}  # the compiled step against the reference
    np.testing.assert_allclose(rv[0], rs[0], rtol=2.5e-7, atol=2.5e-7, strict=True)
    ends = 0
    for _ in range(80):
        a = g.uniform(-0.2, 1.0, (n, 2))
        rv, rs = vec.step(a), sync.step(a)
        np.testing.assert_allclose(rv[0], rs[0], rtol=2.5e-7, atol=2.5e-7, strict=True)
        np.testing.assert_allclose(rv[1], rs[1], **close)
        for x, y in zip(rv[2:4], rs[2:4], strict=True):
            np.testing.assert_array_equal(x, y, strict=True)
        for key in ("pose", "h_position", "cross_track_error", "wheel_angles", "castor_angle", "time"):
            np.testing.assert_allclose(rv[4][key], rs[4][key], err_msg=key, **close)
        for name in task.REWARD_TERMS:
            np.testing.assert_allclose(rv[4]["reward_terms"][name], rs[4]["reward_terms"][name], err_msg=name, **close)
        ends += int(np.sum(rv[2] | rv[3]))
    assert ends >= 3
