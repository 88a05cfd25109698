"""AmigoBot-v1 through the environment: exact integration, feasibility, checks of Gymnasium and SB3, seeding."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import amigo_gym  # noqa: F401  (registers the environments)
from amigo_gym.envs import AmigoBotV1Env
from amigo_gym.task import v1 as tracking


def test_registered_with_time_limit() -> None:
    env = gym.make("AmigoBot-v1")
    assert env.spec is not None and env.spec.max_episode_steps == 600
    assert isinstance(env.unwrapped, AmigoBotV1Env)


@pytest.mark.parametrize(
    "kwargs",
    [
        {},
        {"path": "mixed", "randomize": "hard"},
        {"path": "figure8", "speed": (0.1, 0.4)},
        {"path": "lane_change", "speed_profile": "trapezoid"},
        {"path": "random", "randomize": "mild"},
        {"path": "manoeuvre", "direction": -1},
    ],
)
def test_gymnasium_check_env(kwargs: dict[str, object]) -> None:
    with warnings.catch_warnings():  # the checkers report most findings as warnings: each fails the test
        warnings.simplefilter("error")
        check_env(gym.make("AmigoBot-v1", **kwargs).unwrapped, skip_render_check=True)


def test_sb3_check_env() -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_check_env(gym.make("AmigoBot-v1", path="mixed", randomize="hard"))


def _pose_run(dt: float, actions: np.ndarray, repeat: int, **kw: object) -> np.ndarray:
    env = AmigoBotV1Env(dt=dt, termination_distance=10.0, init_position_noise=0.0, init_heading_noise=0.0, **kw)
    env.reset(seed=0, options={"pose": (0.0, 0.0, 0.3)})
    poses = []
    for a in actions:
        for _ in range(repeat):
            _, _, _, _, info = env.step(a)
        poses.append(info["pose"])
    return np.array(poses)


def test_one_step_equals_two_half_steps_through_the_env() -> None:
    """With randomisation off, a command held over dt gives the pose of two steps of dt/2 (exact integration)."""
    rng = np.random.default_rng(5)
    actions = rng.uniform(-1.0, 1.0, size=(300, 2))
    actions[::7] = actions[::7, ::-1]  # reversals
    actions[::11, 1] = actions[::11, 0]  # straight
    full = _pose_run(0.1, actions, 1)
    half = _pose_run(0.05, actions, 2)
    assert np.max(np.abs(full[:, :2] - half[:, :2])) < 1e-12
    assert np.max(np.abs(full[:, 2] - half[:, 2])) < 1e-12


def test_from_rest_full_forward_is_half_a_t_squared() -> None:
    """From rest with both wheels at full forward, A travels 0.3 t^2 / 2 until 0.75 m/s, then 0.75 m/s (to 1e-12 m)."""
    for dt in (0.1, 0.07, 0.25):
        n = math.ceil(4.0 / dt)
        poses = _pose_run(dt, np.ones((n, 2)), 1, radius=100.0)
        t = dt * np.arange(1, n + 1)
        # the pose option put A at the origin with heading 0.3
        d = np.where(t <= 2.5, 0.5 * 0.3 * t * t, 0.5 * 0.3 * 2.5**2 + 0.75 * (t - 2.5))
        along = poses[:, 0] * math.cos(0.3) + poses[:, 1] * math.sin(0.3)
        across = -poses[:, 0] * math.sin(0.3) + poses[:, 1] * math.cos(0.3)
        assert np.max(np.abs(along - d)) < 1e-12
        assert np.max(np.abs(across)) < 1e-12
        assert np.all(poses[:, 2] == 0.3)


def test_true_wheel_radius_five_percent_larger_is_five_percent_faster() -> None:
    nominal = _pose_run(0.1, np.full((60, 2), 0.5), 1, radius=100.0)
    larger = _pose_run(0.1, np.full((60, 2), 0.5), 1, radius=100.0, true_robot={"r1": 0.0525, "r2": 0.0525})
    d0 = np.hypot(*(nominal[-1, :2] - nominal[-2, :2]))
    d1 = np.hypot(*(larger[-1, :2] - larger[-2, :2]))
    assert d1 / d0 == pytest.approx(1.05, rel=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"speed": 0.74}, "needs 16.6 rad/s on the outer wheel, above the robot's limit of 15 rad/s"),
        ({"radius": 0.085}, "needs 20.7 rad/s on the outer wheel"),
        ({"speed": (0.1, 0.74)}, "needs 16.6 rad/s"),
    ],
)
def test_infeasible_tasks_are_refused_in_one_line(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message) as err:
        gym.make("AmigoBot-v1", **kwargs)
    assert "\n" not in str(err.value)


def test_remembered_feasibility_is_the_analysis_and_still_refuses() -> None:
    """The per-process memory of a fixed path's feasibility (task.v1._feasibility) gives the report a fresh
    analysis gives, and refuses or warns at every construction, not only the first."""
    from amigo_gym.paths import feasibility

    for _ in range(2):
        with pytest.raises(ValueError, match=r"needs 16\.6 rad/s"):
            gym.make("AmigoBot-v1", speed=0.74)
        with pytest.warns(UserWarning, match=r"needs 16\.6 rad/s"):
            gym.make("AmigoBot-v1", speed=0.74, feasibility="warn")
    env = gym.make("AmigoBot-v1", speed=0.3)
    u = env.unwrapped
    p = u.params  # type: ignore[attr-defined]
    fresh = feasibility(u.path, 0.3, p.robot, "A", max_rotational_acceleration=p.actuators.rot_acceleration)  # type: ignore[attr-defined]
    assert u.feasibility == fresh.report()  # type: ignore[attr-defined]
    assert gym.make("AmigoBot-v1", speed=0.3).unwrapped.feasibility == fresh.report()  # type: ignore[attr-defined]


def test_mixed_families_are_feasible_at_the_highest_speed() -> None:
    """The extremes of the ranges drawn by path="mixed" (and the random pool's defaults) are feasible at 0.4 m/s."""
    from amigo_gym.paths import feasibility, make_family_path

    robot = tracking.TrackingParams().robot
    limits = {"max_rotational_acceleration": 0.87}
    for fam, ranges in tracking.MIXED_RANGES.items():
        for corner in ((lo for lo, _ in ranges.values()), (hi for _, hi in ranges.values())):
            params = dict(zip(ranges, corner, strict=True))
            for direction in (1, -1) if fam == "circle" else (None,):
                kw = {**params, **({} if direction is None else {"direction": direction})}
                f = feasibility(make_family_path(fam, None, **kw), 0.4, robot, "A", **limits)
                assert f.feasible, (fam, kw, f.message())
    for pid in range(8):
        f = feasibility(
            tracking.random_pool_path(tracking.TrackingParams(path="random"), pid), 0.4, robot, "A", **limits
        )
        assert f.feasible, f.message()


def test_same_seed_same_episode_and_seeds_differ() -> None:
    def episode(seed: int) -> list[np.ndarray]:
        env = gym.make("AmigoBot-v1", path="mixed", randomize="hard", speed=(0.1, 0.4))
        obs, info = env.reset(seed=seed)
        out = [obs, info["pose"]]
        rng = np.random.default_rng(0)
        for _ in range(50):
            obs, r, term, trunc, info = env.step(rng.uniform(-1, 1, 2))
            out += [obs, np.array([r]), info["pose"], info["slip"], info["measured_pose"]]
            if term or trunc:
                break
        return out

    a, b, c = episode(3), episode(3), episode(4)
    assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not all(np.array_equal(x, y) for x, y in zip(a, c, strict=False))


def test_randomisation_is_in_info_not_in_observation() -> None:
    env = gym.make("AmigoBot-v1", randomize="hard")
    _, info = env.reset(seed=1)
    r = info["true_robot"]
    assert r["r1"] != 0.05 and 0.95 * 0.05 <= r["r1"] <= 1.05 * 0.05
    assert 0.0 <= info["delay"] <= 0.15
    names = tracking.obs_fields(env.unwrapped.params)  # type: ignore[attr-defined]
    assert not any(("radius" in n) or ("delay" in n) or ("slip" in n) for n in names)
    _, _, _, _, info = env.step(np.zeros(2))
    assert np.all(info["slip"] >= 0.0) and np.all(info["slip"] <= 0.1)
    assert not np.array_equal(info["measured_pose"], info["pose"])  # noisy measurement


def test_delay_shifts_the_motion_by_the_delay() -> None:
    """A delay of 0.15 s (1.5 steps) gives, from rest, the motion without delay 0.15 s later (to 1e-12 m)."""
    actions = np.tile([[0.8, 0.6]], (40, 1))
    fast = _pose_run(0.05, np.repeat(actions, 2, axis=0), 1, radius=100.0)
    slow = _pose_run(0.05, np.repeat(actions, 2, axis=0), 1, radius=100.0, actuators={"delay": 0.15})
    # slow at step k + 3 equals fast at step k
    assert np.max(np.abs(slow[3:, :2] - fast[:-3, :2])) < 1e-12


def test_ignoring_the_reference_speed_costs_reward() -> None:
    """On a straight line, driving at 0.2 m/s when 0.4 m/s is asked for loses most of the reward."""
    env = AmigoBotV1Env(
        path="lane_change", path_params={"lead": 10.0}, speed=0.4, init_position_noise=0.0, init_heading_noise=0.0
    )
    env.reset(seed=0)
    slow = [env.step(np.array([4.0, 4.0]) / 15.0)[1] for _ in range(40)]  # 0.2 m/s
    env.reset(seed=0)
    right = [env.step(np.array([8.0, 8.0]) / 15.0)[1] for _ in range(40)]  # 0.4 m/s
    assert np.mean(right[-10:]) > 0.99
    assert np.mean(slow[-10:]) < 0.05


def test_step_before_reset_and_after_termination() -> None:
    env = AmigoBotV1Env()
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(2))
    env.reset(seed=0)
    done = False
    for _ in range(200):
        *_, done, _, _ = env.step(np.array([1.0, -0.2]))
        if done:
            break
    assert done
    with pytest.warns(UserWarning, match="already returned terminated"):
        env.step(np.zeros(2))


@pytest.mark.parametrize(
    ("action", "error"),
    [
        ("ab", TypeError),
        ([1.0, 2.0, 3.0], ValueError),
        ([1 + 2j, 0], TypeError),
        ([np.nan, 0.0], ValueError),
        ([[1, 2], [3]], ValueError),
    ],
)
def test_bad_actions_are_refused(action: object, error: type[Exception]) -> None:
    env = AmigoBotV1Env()
    env.reset(seed=0)
    with pytest.raises(error, match="action"):
        env.step(action)  # type: ignore[arg-type]


def test_docs_observation_table_matches_the_field_names() -> None:
    """docs/amigobot_v1.md lists exactly obs_fields() of the default settings, in order."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "amigobot_v1.md").read_text()
    section = text.split("## Observation", 1)[1].split("## Reward", 1)[0]
    rows = re.findall(r"^\| (\d+) \| `([^`]+)` \|", section, flags=re.MULTILINE)
    assert [int(i) for i, _ in rows] == list(range(len(rows)))
    assert tuple(name for _, name in rows) == tracking.obs_fields(tracking.TrackingParams())


def test_a_users_own_path_object() -> None:
    """Any object with length, closed, pose_columns and locate is a path (here a ClothoidPath built by hand)."""
    from amigo_gym.paths import ClothoidPath, ClothoidSegment
    from amigo_gym.policies import AnalyticTrackingPolicy

    mine = ClothoidPath(
        (ClothoidSegment.line(1.0), ClothoidSegment.transition(1.0, 0.0, 1.0), ClothoidSegment.arc(6.0, 1.0)),
        start=(0.0, 0.0),
        start_angle=0.0,
    )
    env = gym.make("AmigoBot-v1", path=mine, speed=0.2, max_episode_steps=300)
    policy = AnalyticTrackingPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
    obs, info = env.reset(seed=0)
    assert info["path"]["family"] == "ClothoidPath"
    state, start, errors = None, np.array([True]), []
    for _ in range(300):
        a, state = policy.predict(obs[None, :], state, start)
        start = np.array([False])
        obs, _, term, trunc, info = env.step(a[0])
        errors.append(abs(info["cross_track_error"]))
        if term or trunc:
            break
    assert max(errors[150:]) < 1e-3  # settled on the user's path
    with pytest.raises(ValueError, match="path must be"):
        gym.make("AmigoBot-v1", path=object())


def test_trapezoid_reference_speed_is_the_closed_form_through_its_braking():
    """info["reference_speed"] over a whole trapezoid (accelerate, cruise, brake to 0 at T, then 0), against the
    profile written out here: a_up t, v, v - a_down (t - T + v / a_down). The rates differ (0.2 and 0.5 m/s^2), so a
    braking slope at the wrong rate ends at v (1 - a_up / a_down) = 0.18 m/s, not 0, at T."""
    v, a_up, a_down, big_t = 0.3, 0.2, 0.5, 4.0
    env = gym.make("AmigoBot-v1", speed=v, speed_profile="trapezoid", profile_accel=a_up, profile_decel=a_down,
                   profile_duration=big_t)  # fmt: skip
    env.reset(seed=0)
    seen = []
    for _ in range(50):  # 5 s: past T
        _, _, terminated, truncated, info = env.step(np.zeros(2))
        t = info["time"]
        if t <= v / a_up:
            want = a_up * t
        elif t <= big_t - v / a_down:
            want = v
        else:
            want = max(0.0, v - a_down * (t - (big_t - v / a_down)))
        seen.append((t, info["reference_speed"], want))
        assert terminated is False and truncated is False
    got = np.array(seen)
    assert got[-1, 0] > big_t and np.any(np.isclose(got[:, 0], big_t)), got[:, 0]
    np.testing.assert_allclose(got[:, 1], got[:, 2], rtol=0, atol=1e-12)
    assert got[np.isclose(got[:, 0], big_t), 1] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
@pytest.mark.parametrize("reward", ["v1", "v0"])
def test_smoothness_term_is_its_closed_form(kernel: str, reward: str) -> None:
    # 1 - w_s (1 - exp(-(|change| / scale)^2)), w_s = 0.2: reward "v1" the normalised command's change over
    # 2 sigma_smooth = 0.2, "v0" the wheel rates' change over w_max sigma_smooth = 1.5 rad/s (module docstring)
    env = gym.make("AmigoBot-v1", kernel=kernel, reward=reward)
    env.reset(seed=0)
    first, second = np.array([0.3, 0.5]), np.array([0.45, 0.38])
    before = env.step(first)[4]
    info = env.step(second)[4]
    if reward == "v1":
        change, scale = float(np.hypot(*(second - first))), 0.2
    else:
        change, scale = float(np.hypot(*(info["wheel_rates"] - before["wheel_rates"]))), 15.0 * 0.1
    expected = 1.0 - 0.2 * (1.0 - math.exp(-((change / scale) ** 2)))
    assert expected < 0.95 and info["reward_terms"]["smooth"] == pytest.approx(expected, rel=1e-12)
