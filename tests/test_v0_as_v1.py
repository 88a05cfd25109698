"""AmigoBot-v0 as a configuration of AmigoBot-v1 side by side, within the golden tolerance.

``gym.make("AmigoBot-v1", **V0_CONFIG)`` (ideal actuators, v0's observation layout and reward, no randomisation,
wheels rolling at the start, v0's preview and the circle as a :class:`~amigo_gym.paths.CirclePath`) is stepped
beside ``gym.make("AmigoBot-v0")`` on the same seeds and actions (random ones and the analytic policy's); every
quantity both report (observation, reward, its terms, pose, H, cross-track error, wheel rates, the end) must
agree within tests/golden_compare.py's rule (1e-9 of each quantity's scale over the episode): the tolerance
v0's own golden tests allow.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from golden_compare import mismatches

from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.policies import AnalyticPolicy
from amigo_gym.sim.fast_v1 import numba_available
from amigo_gym.task import v0 as task_v0
from amigo_gym.task import v1 as tracking

#: the settings of AmigoBot-v1 that make it AmigoBot-v0 (its defaults: a 1 m left circle at 0.2 m/s)
V0_CONFIG: dict[str, Any] = {
    "path": CirclePath(radius=1.0, direction=1),
    "ideal_actuators": True,
    "observation": "v0",
    "reward": "v0",
    "randomize": "none",
    "start_at_rest": False,
    "preview": (0.2, 0.4),
    "speed": 0.2,
}

STEPS = 120


#: AmigoBot-v0's info keys (its env card), which AmigoBot-v1 with these settings reports too
V0_INFO_KEYS = {"pose", "h_position", "cross_track_error", "wheel_rates", "wheel_angles", "castor_angle"}
V0_INFO_KEYS |= {"reward_terms", "time"}


def _record(env: Any, obs: Any, info: dict[str, Any], rec: dict[str, list[Any]], reward: float | None) -> None:
    assert set(info) == V0_INFO_KEYS
    assert all(type(info[k]) is float for k in ("cross_track_error", "castor_angle", "time"))
    rec["obs"].append(np.asarray(obs))
    for key in ("pose", "h_position", "wheel_rates", "wheel_angles"):
        assert info[key].dtype == np.float64
        rec[key].append(np.asarray(info[key], dtype=np.float64))
    for key in ("cross_track_error", "castor_angle", "time"):
        rec[key].append(info[key])
    for name, value in info["reward_terms"].items():
        rec[name].append(float(value))
    if reward is not None:
        rec["reward"].append(float(reward))


def _episode(env_id: str, kwargs: dict[str, Any], seed: int, actions: Any) -> dict[str, np.ndarray]:
    """One episode of ``STEPS`` steps (or until it ends): every quantity per step, as arrays."""
    env = gym.make(env_id, **kwargs).unwrapped
    rec: dict[str, list[Any]] = {
        k: []
        for k in (
            "obs",
            "pose",
            "h_position",
            "wheel_rates",
            "wheel_angles",
            "castor_angle",
            "time",
            "cross_track_error",
            "track",
            "speed",
            "heading",
            "smooth",
            "reward",
            "terminated",
        )
    }
    obs, info = env.reset(seed=seed)
    _record(env, obs, info, rec, None)
    rng = np.random.default_rng(seed + 100)
    for _ in range(STEPS):
        obs, reward, terminated, _, info = env.step(actions(obs, rng))
        _record(env, obs, info, rec, reward)
        rec["terminated"].append(bool(terminated))
        if terminated:
            break
    return {k: np.array(v) for k, v in rec.items()}


def _random(obs: Any, rng: np.random.Generator) -> Any:
    """Random actions around the steady state's (most episodes last tens of steps, some end early)."""
    return (0.27 + 0.3 * rng.uniform(-1.0, 1.0, 2)).astype(np.float32)


def _wild(obs: Any, rng: np.random.Generator) -> Any:
    """Uniform actions in [-1.2, 1.2] (clipped by both envs), float64."""
    return rng.uniform(-1.2, 1.2, 2)


#: AmigoBot-v1's two routes for these settings: the reference (task/v1.py) and the compiled step
ROUTES = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(not numba_available(), reason="needs numba"))]


@pytest.mark.parametrize("kernel", ROUTES)
@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("policy", ["random", "wild", "analytic"])
def test_v1_configured_as_v0_steps_as_v0(seed: int, policy: str, kernel: str) -> None:
    v0 = gym.make("AmigoBot-v0").unwrapped
    actions = {"random": _random, "wild": _wild}.get(policy)
    if actions is None:
        pol = AnalyticPolicy(v0.params)
        actions = lambda obs, rng: pol.action(obs)  # noqa: E731
    want = _episode("AmigoBot-v0", {}, seed, actions)
    got = _episode("AmigoBot-v1", {**V0_CONFIG, "kernel": kernel}, seed, actions)
    assert len(want["reward"]) >= 10
    assert mismatches(got, want) == []


def test_observation_names_and_bounds_are_v0s() -> None:
    v0 = gym.make("AmigoBot-v0").unwrapped
    v1 = gym.make("AmigoBot-v1", **V0_CONFIG).unwrapped
    assert list(tracking.obs_fields(v1.params)) == task_v0.obs_names(v0.params)
    assert v1.observation_space == v0.observation_space
    # a controller reads the layout by name from either settings: the same action on the same observation
    o0, _ = v0.reset(seed=1)
    o1, _ = v1.reset(seed=1)
    np.testing.assert_array_equal(AnalyticPolicy(v1.params).action(o1), AnalyticPolicy(v0.params).action(o0))


def test_v0_keywords_are_these_settings() -> None:
    """``gym.make("AmigoBot-v0")`` (single and vector) runs AmigoBot-v1's classes with exactly :data:`V0_CONFIG`'s
    settings (:meth:`amigo_gym.task.v1.TrackingParams.v0`): the same task, hence the same steps on every route."""
    want = tracking.make_tracking_params("test", **{**V0_CONFIG, "feasibility": "off"})
    assert gym.make("AmigoBot-v0").unwrapped.params == want
    envs = gym.make_vec("AmigoBot-v0", num_envs=2, vectorization_mode="vector_entry_point")
    assert envs.unwrapped.params == want


@pytest.mark.parametrize("kernel", ROUTES)
def test_heading_past_the_limit_is_reduced_as_v0_reduces_it(kernel: str) -> None:
    """A robot spinning past |beta| = 1e6 rad: its heading reduced by whole turns on both routes, as AmigoBot-v0."""
    v0 = gym.make("AmigoBot-v0", termination_distance=10.0).unwrapped
    v1 = gym.make("AmigoBot-v1", **{**V0_CONFIG, "termination_distance": 10.0}, kernel=kernel).unwrapped
    for e in (v0, v1):
        e.reset(seed=0, options={"pose": (0.0, 0.0, 1e6 - 0.05)})
    a = np.array([1.0, -1.0])  # spin: the heading crosses 1e6 rad
    for _ in range(3):
        (o0, r0, t0, _, i0), (o1, r1, t1, _, i1) = v0.step(a), v1.step(a)
        np.testing.assert_array_equal(o1, o0)
        assert (r1, t1) == (r0, t0)
        np.testing.assert_array_equal(i1["pose"], i0["pose"])
    assert abs(i1["pose"][2]) < 7.0


def test_v0_settings_are_checked() -> None:
    with pytest.raises(ValueError, match=r"TrackingParams.observation must be one of \['v1', 'v0'\], got 'v2'"):
        tracking.TrackingParams(observation="v2")
    with pytest.raises(ValueError, match=r"TrackingParams.reward must be one of"):
        tracking.TrackingParams(reward=0)
    with pytest.raises(ValueError, match=r"ideal_actuators must be True or False, got 1"):
        tracking.TrackingParams(ideal_actuators=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"ideal_actuators needs .* randomize.slip \(0.0, 0.05\)"):
        tracking.make_tracking_params("t", ideal_actuators=True, randomize={"slip": (0.0, 0.05)})
    with pytest.raises(ValueError, match=r"ideal_actuators needs .* actuators.delay 0.1"):
        tracking.make_tracking_params("t", ideal_actuators=True, actuators={"delay": 0.1})
    v0p = tracking.make_tracking_params("t", **V0_CONFIG)
    assert tracking.v0_settings(v0p) == task_v0.V0_DEFAULTS
    for off in ({"start_at_rest": True}, {"path": CirclePath(radius=1.0, start_angle=0.1)}, {"goal_tolerance": 0.1}):
        assert tracking.v0_settings(tracking.make_tracking_params("t", **{**V0_CONFIG, **off})) is None


@pytest.mark.parametrize(
    "edge",
    [
        {"dt": 1e-6},
        {"dt": 2.0, "radius": 3.0},
        {"error_scale": 1e-6},
        {"preview": (0.0, 10.0)},
        {"sigma_track": 1e6, "sigma_speed": 1e6, "sigma_smooth": 1e6},
        {"path": "manoeuvre", "straight_length": 0.0, "direction": -1},
    ],
)
def test_v0_configuration_keeps_v0s_ranges_and_v1s_messages(edge: dict[str, Any]) -> None:
    """AmigoBot-v0's settings at the edges of their ranges are its configuration of AmigoBot-v1
    (TrackingParams.v0 and v0_settings are inverse), and gym.make("AmigoBot-v0") runs them; the same values without
    v0's configuration keep AmigoBot-v1's ranges and messages."""
    p = tracking.TrackingParams.v0(**edge)
    assert tracking.TrackingParams.v0(**tracking.v0_settings(p) or {}) == p
    assert tracking.constants(p).ring_length == 2  # ideal actuators: no delay to keep, whatever dt
    env = gym.make("AmigoBot-v0", max_episode_steps=3, **edge)
    env.reset(seed=0)
    for _ in range(3):
        obs, reward, *_ = env.step(np.array([0.3, 0.3]))
        assert np.all(np.isfinite(obs)) and np.isfinite(reward)
    assert env.unwrapped.params == p  # type: ignore[attr-defined]
    v1_only = {k: v for k, v in edge.items() if k in ("dt", "error_scale", "preview", "sigma_track")}
    messages = {
        "dt": r"^TrackingParams.dt must be a finite number in \[0.001, 1\], got ",
        "error_scale": r"^TrackingParams.error_scale must be a finite number in \[0.0001, 10\], got 1e-06$",
        "preview": r"^TrackingParams.preview\[0\] must be a finite number in \(0, 5\], got 0.0$",
        "sigma_track": r"^TrackingParams.sigma_track must be a finite number in \[1e-06, 10\], got 1000000.0$",
    }
    for name, value in v1_only.items():
        with pytest.raises(ValueError, match=messages[name]):
            tracking.TrackingParams(**{name: value})
        with pytest.raises(ValueError, match=messages[name]):  # v0's layouts alone do not widen them
            tracking.TrackingParams(observation="v0", reward="v0", **{name: value})
    with pytest.raises(ValueError, match=r"^TrackingParams.dt must be a finite number in \[1e-06, 2\], got 2.5$"):
        tracking.TrackingParams(ideal_actuators=True, observation="v0", reward="v0", dt=2.5)


def test_v0_reward_setting_quarters_the_smoothness_scale() -> None:
    """The two smoothness settings on one change of command: v0's loss is v1's with the change doubled."""
    k1 = tracking.constants(tracking.TrackingParams())
    k0 = tracking.constants(tracking.TrackingParams(reward="v0"))
    w_max = k1.w_max
    da = 0.05  # a change of the normalised command
    v1_arg = (da * da) / k1.smooth_scale_sq
    v0_arg = (da * w_max) ** 2 / k0.smooth_scale_sq
    assert v0_arg == pytest.approx(4.0 * v1_arg, rel=1e-12)


def test_circle_locate_is_its_projection() -> None:
    """:meth:`CirclePath.locate` (what AmigoBot-v1 calls) against the closed form, floats and columns, with laps."""
    c = CirclePath(radius=2.0, direction=-1)
    rng = np.random.default_rng(1)
    phi = rng.uniform(0.0, 2.0 * np.pi, 50)
    rho = 2.0 + rng.uniform(-0.3, 0.3, 50)
    cx, cy = c.center
    x = cx + rho * np.sin(phi)
    y = cy + rho * np.cos(phi)
    hint = rng.uniform(-30.0, 30.0, 50)
    loc = c.locate(x, y, hint, 0.5, 0.5)
    np.testing.assert_allclose(np.abs(loc.cross_track_error), np.abs(rho - 2.0), atol=1e-12)
    np.testing.assert_allclose(loc.distance, np.abs(rho - 2.0), atol=1e-12)
    assert np.all(np.abs(loc.progress - hint) <= np.pi * 2.0 + 1e-9)  # the lap nearest the hint
    np.testing.assert_allclose(np.mod(loc.progress, c.length), np.mod(loc.s, c.length), atol=1e-9)
    px, py = c.point(loc.s).T
    np.testing.assert_allclose(loc.x, px, atol=1e-12)
    np.testing.assert_allclose(loc.y, py, atol=1e-12)
    one = c.locate(float(x[0]), float(y[0]), float(hint[0]), 0.5, 0.5)
    assert type(one.progress) is float and one.cross_track_error == loc.cross_track_error[0]
    pose = c.pose_columns(np.array([0.0, 1.0]))
    np.testing.assert_allclose(np.stack([pose.x, pose.y], -1), c.point([0.0, 1.0]), atol=1e-15)


@pytest.mark.parametrize(
    ("v0_kwargs", "path"),
    [
        (
            {"radius": 1.5, "direction": -1, "speed": 0.3, "dt": 0.05, "preview": (0.3,), "sigma_smooth": 0.2},
            CirclePath(radius=1.5, direction=-1),
        ),
        ({"path": "manoeuvre"}, ManoeuvrePath()),
        (
            {"path": "manoeuvre", "radius": 0.8, "direction": -1, "straight_length": 0.5, "speed": 0.15},
            ManoeuvrePath(radius=0.8, straight_length=0.5, direction=-1),
        ),
    ],
)
@pytest.mark.parametrize("policy", ["random", "analytic"])
@pytest.mark.parametrize("kernel", ROUTES)
def test_other_v0_settings(v0_kwargs: dict[str, Any], path: Any, policy: str, kernel: str) -> None:
    """Other radii, directions, speeds, periods, previews, scales and the manoeuvre path: the same agreement."""
    v0 = gym.make("AmigoBot-v0", **v0_kwargs).unwrapped
    same = {k: v for k, v in v0_kwargs.items() if k not in ("path", "radius", "direction", "straight_length")}
    config = {**V0_CONFIG, **same, "path": path, "kernel": kernel}
    actions = _random
    if policy == "analytic":
        pol = AnalyticPolicy(v0.params)
        actions = lambda obs, rng: pol.action(obs)  # noqa: E731
    for seed in range(3):
        want = _episode("AmigoBot-v0", v0_kwargs, seed, actions)
        got = _episode("AmigoBot-v1", config, seed, actions)
        assert mismatches(got, want) == []
