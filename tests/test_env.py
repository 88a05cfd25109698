"""Tests of the single environment ``AmigoBot-v0`` (:class:`amigo_gym.envs.AmigoBotEnv`).

References are independent of the env's code: closed forms of the steady circle written out here,
a closed-loop look-ahead law written out here, and gymnasium's / SB3's checkers.
"""

from __future__ import annotations

import copy
import math
import pickle
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym import MAX_EPISODE_STEPS, RobotParams
from amigo_gym.envs import AmigoBotEnv
from amigo_gym.task.v1 import TrackingParams

L1, L3, R_WHEEL = 0.12, 0.08, 0.05
W_MAX = 15.0  # 0.75 m/s over r = 0.05 m


# ---------------------------------------------------------------- independent references
def steady_start(radius: float, direction: int = 1) -> tuple[tuple[float, float, float], np.ndarray]:
    """Pose with H at the origin on the circle (centre (0, d R)) and the steady heading lag.

    Closed form (docs/model.md): R_A = sqrt(R^2 - l3^2), lag = d atan(l3 / R_A), beta = theta - lag with
    theta = 0 at the origin; A = H - l3 (cos b, sin b).
    """
    ra = math.sqrt(radius**2 - L3**2)
    beta = -direction * math.atan2(L3, ra)
    return (-L3 * math.cos(beta), -L3 * math.sin(beta), beta), np.array([ra])


def steady_action(radius: float, speed: float, direction: int = 1) -> np.ndarray:
    """Normalised steady wheel rates: betadot = d v / R_A, r w1 = v + l1 betadot, r w2 = v - l1 betadot."""
    ra = math.sqrt(radius**2 - L3**2)
    bd = direction * speed / ra
    return np.array([(speed + L1 * bd) / R_WHEEL, (speed - L1 * bd) / R_WHEEL], dtype=np.float64) / W_MAX


def lookahead_action(pose: np.ndarray, radius: float, speed: float, direction: int = 1, k: float = 2.0) -> np.ndarray:
    """Closed-loop inverse law: desired H velocity = tangent * v R / R_A - k e n, through the 2x2 map.

    H_dot = [[cos b, -l3 sin b], [sin b, l3 cos b]] (v_A, betadot); ``direction`` < 0 drives the
    circle (centre (0, R)) clockwise, i.e. the wrong way for the default task.
    """
    x, y, b = pose
    hx, hy = x + L3 * math.cos(b), y + L3 * math.sin(b)
    ux, uy = hx, hy - radius  # from the centre (0, R)
    rho = math.hypot(ux, uy)
    t = np.array([-uy, ux]) / rho * direction  # unit tangent (counter-clockwise for direction = +1)
    n_left = np.array([-t[1], t[0]])
    e = (radius - rho) * direction  # signed, positive left of the travel direction
    vh = t * speed * radius / math.sqrt(radius**2 - L3**2) - k * e * n_left
    v_a = math.cos(b) * vh[0] + math.sin(b) * vh[1]
    bdot = (-math.sin(b) * vh[0] + math.cos(b) * vh[1]) / L3
    return np.array([(v_a + L1 * bdot) / R_WHEEL, (v_a - L1 * bdot) / R_WHEEL]) / W_MAX


def run_episode(env: gym.Env[Any, Any], policy: Any, pose: tuple[float, float, float] | None = None) -> float:
    _, info = env.reset(seed=0, options=None if pose is None else {"pose": pose})
    total = 0.0
    while True:
        _, r, term, trunc, info = env.step(policy(info["pose"]))
        total += float(r)
        if term or trunc:
            return total


# ---------------------------------------------------------------- checkers
def test_gymnasium_check_env_no_warnings() -> None:
    settings: list[dict[str, Any]] = [{}, {"path": "manoeuvre", "dt": 0.05, "direction": -1}]
    for kw in settings:
        env = gym.make("AmigoBot-v0", **kw)  # made outside: test_making_v0_is_silent covers gym.make itself
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            check_env(env.unwrapped)


def test_sb3_check_env_no_warnings() -> None:
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    env = gym.make("AmigoBot-v0")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb3_checker.check_env(env)


def test_making_v0_is_silent() -> None:
    """v1 does not deprecate v0: registered under a name of its own, it makes Gymnasium warn nothing about v0."""
    import subprocess
    import sys

    code = "import gymnasium as gym, amigo_gym; gym.make('AmigoBot-v0'); gym.make('AmigoBot-v1')"
    r = subprocess.run([sys.executable, "-W", "default", "-c", code], capture_output=True, text=True, check=True)
    assert r.stderr == ""


def test_spaces_and_metadata() -> None:
    env = gym.make("AmigoBot-v0", dt=0.05)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    obs_space = env.observation_space
    assert isinstance(obs_space, gym.spaces.Box)
    assert obs_space.dtype == np.float32 and obs_space.shape == (10,)
    assert np.all(np.isfinite(obs_space.low)) and np.all(np.isfinite(obs_space.high))
    assert env.metadata["render_modes"] == ["human", "rgb_array"]
    assert env.metadata["render_fps"] == pytest.approx(20.0)
    assert gym.make("AmigoBot-v0", preview=(0.1, 0.2, 0.3)).observation_space.shape == (11,)


# ---------------------------------------------------------------- reset, info
def test_reset_start_state_and_info() -> None:
    env = gym.make("AmigoBot-v0")
    obs, info = env.reset(seed=3)
    assert env.observation_space.contains(obs)
    p = env.unwrapped.params  # type: ignore[attr-defined]
    x, y, b = info["pose"]
    # H within the seeded perturbation of the origin, heading within the heading noise
    assert abs(x + L3 * math.cos(b)) <= p.init_position_noise and abs(y + L3 * math.sin(b)) <= p.init_position_noise
    assert abs(b) <= p.init_heading_noise
    assert info["pose"].dtype == np.float64 and info["pose"].shape == (3,)
    np.testing.assert_array_equal(info["h_position"], [x + L3 * math.cos(b), y + L3 * math.sin(b)])
    # cross-track error on the circle of centre (0, 1): R - |H - c|, positive left (inside)
    hx, hy = info["h_position"]
    assert info["cross_track_error"] == pytest.approx(1.0 - math.hypot(hx, hy - 1.0))
    np.testing.assert_array_equal(info["wheel_rates"], [0.2 / 0.05, 0.2 / 0.05])
    np.testing.assert_array_equal(info["wheel_angles"], [0.0, 0.0])
    assert info["castor_angle"] == 0.0 and info["time"] == 0.0
    assert set(info["reward_terms"]) == {"track", "speed", "heading", "smooth"}
    assert info["reward_terms"]["smooth"] == 1.0 and info["reward_terms"]["speed"] == 1.0
    assert all(isinstance(v, float) for v in info["reward_terms"].values())


def test_reset_pose_option_is_exact() -> None:
    env = gym.make("AmigoBot-v0")
    pose = (0.1234567890123, -0.02, 0.3)
    _, info = env.reset(options={"pose": pose})
    np.testing.assert_array_equal(info["pose"], pose)
    _, info = env.reset(options={"pose": np.array(pose)})
    np.testing.assert_array_equal(info["pose"], pose)


def test_step_info_and_clipping() -> None:
    env = gym.make("AmigoBot-v0")
    env.reset(seed=0)
    a = np.array([2.0, -3.0])  # clipped to [1, -1]
    _, r, term, trunc, info = env.step(a)
    np.testing.assert_array_equal(info["wheel_rates"], [W_MAX, -W_MAX])
    np.testing.assert_array_equal(info["wheel_angles"], [W_MAX * 0.1, -W_MAX * 0.1])
    assert info["castor_angle"] > 0.0  # rolling without forward motion, spin only
    assert info["time"] == pytest.approx(0.1)
    assert isinstance(r, float) and 0.0 <= r <= 1.0
    assert r == pytest.approx(math.prod(info["reward_terms"].values()), rel=1e-12)
    assert isinstance(term, bool) and trunc is False


def test_float64_actions_applied_exactly() -> None:
    env = gym.make("AmigoBot-v0")
    env.reset(seed=0)
    a = np.array([0.1234567890123456, 0.2345678901234567])
    _, _, _, _, info = env.step(a)
    np.testing.assert_array_equal(info["wheel_rates"], a * W_MAX)
    assert not np.array_equal(info["wheel_rates"], a.astype(np.float32).astype(np.float64) * W_MAX)


def test_termination_distance() -> None:
    env = gym.make("AmigoBot-v0", termination_distance=0.1, init_position_noise=0.0, init_heading_noise=0.0)
    env.reset(seed=0)
    n = 0
    while True:  # straight ahead leaves the circle (it curves left)
        _, _, term, trunc, info = env.step(np.array([0.5, 0.5]))
        n += 1
        if term or trunc:
            break
    assert term and abs(info["cross_track_error"]) > 0.1
    # one step earlier it was still within: H moves 0.75 m/s * 0.1 s per step
    assert abs(info["cross_track_error"]) < 0.1 + 0.075


def test_truncation_by_time_limit() -> None:
    env = gym.make("AmigoBot-v0", max_episode_steps=7)
    env.reset(seed=0)
    pose, _ = steady_start(1.0)
    env.reset(options={"pose": pose})
    a = steady_action(1.0, 0.2)
    flags = [env.step(a)[2:4] for _ in range(7)]
    assert flags[-1] == (False, True) and all(f == (False, False) for f in flags[:-1])


# ---------------------------------------------------------------- determinism, pickling
def _rollout(env: gym.Env[Any, Any], n: int, seed: int | None = None) -> list[Any]:
    rng = np.random.default_rng(1)
    out: list[Any] = []
    if seed is not None:
        out.append(env.reset(seed=seed))
    for _ in range(n):
        res = env.step(rng.uniform(-0.2, 0.8, 2))
        out.append(res)
        if res[2] or res[3]:
            out.append(env.reset())
    return out


def _same(a: Any, b: Any) -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            _same(a[k], b[k])
    elif isinstance(a, tuple | list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _same(x, y)
    else:
        assert type(a) is type(b)
        np.testing.assert_array_equal(a, b)


def test_determinism_under_seed() -> None:
    e1, e2 = gym.make("AmigoBot-v0"), gym.make("AmigoBot-v0")
    _same(_rollout(e1, 120, seed=5), _rollout(e2, 120, seed=5))
    o1, _ = e1.reset(seed=6)
    o2, _ = e2.reset(seed=7)
    assert not np.array_equal(o1, o2)


@pytest.mark.parametrize("clone", [copy.deepcopy, lambda e: pickle.loads(pickle.dumps(e))])
def test_pickle_and_deepcopy_mid_episode(clone: Any) -> None:
    env = gym.make("AmigoBot-v0", init_position_noise=0.05)
    _rollout(env, 30, seed=11)
    twin = clone(env)
    _same(_rollout(env, 80), _rollout(twin, 80))


# ---------------------------------------------------------------- exactness of the step through the env
@pytest.mark.parametrize("dt", [0.01, 0.1, 0.5])
@pytest.mark.parametrize("direction", [1, -1])
def test_steady_rates_keep_h_on_circle(dt: float, direction: int) -> None:
    radius, speed = 0.5, 0.5
    ra = math.sqrt(radius**2 - L3**2)
    lap = 2 * math.pi * ra / speed
    n = math.ceil(10 * lap / dt)
    env = gym.make("AmigoBot-v0", dt=dt, radius=radius, speed=speed, direction=direction, max_episode_steps=n + 1)
    pose, _ = steady_start(radius, direction)
    env.reset(options={"pose": pose})
    a = steady_action(radius, speed, direction)
    centre = np.array([0.0, direction * radius])
    worst = 0.0
    for _ in range(n):
        _, _, term, trunc, info = env.step(a)
        worst = max(worst, abs(float(np.linalg.norm(info["h_position"] - centre)) - radius))
        assert not (term or trunc)
    assert worst <= 1e-9
    assert abs(info["cross_track_error"]) <= 1e-9
    # 10 laps done: the heading advanced by 10 * 2 pi (closed form: betadot * t)
    assert info["pose"][2] - pose[2] == pytest.approx(direction * speed / ra * n * dt, rel=1e-12)


# ---------------------------------------------------------------- reward ordering
def test_analytic_inverse_solution_earns_99_percent() -> None:
    env = gym.make("AmigoBot-v0")
    pose, _ = steady_start(1.0)
    n = MAX_EPISODE_STEPS
    a = steady_action(1.0, 0.2)
    rets = {
        "inverse law": run_episode(env, lambda p: lookahead_action(p, 1.0, 0.2), pose),
        # from the paper's start (H at the origin, beta = 0): the law converges at once
        "inverse law, paper's start": run_episode(env, lambda p: lookahead_action(p, 1.0, 0.2), (-L3, 0.0, 0.0)),
        "open-loop steady rates": run_episode(env, lambda p: a, pose),  # exact, near 1 per step
    }
    print(rets)  # docs/env_card.md's table: python -m pytest tests/test_env.py -k earn -s -q
    assert min(rets.values()) >= 0.99 * n


@pytest.mark.parametrize(
    "name",
    ["spin", "stand", "wrong_way", "reverse"],
)
def test_bad_behaviours_earn_at_most_20_percent(name: str) -> None:
    env = gym.make("AmigoBot-v0")
    n = MAX_EPISODE_STEPS
    pose, _ = steady_start(1.0)
    if name == "spin":
        ret = run_episode(env, lambda p: np.array([0.5, -0.5]), pose)
    elif name == "stand":
        ret = run_episode(env, lambda p: np.zeros(2), pose)
    elif name == "wrong_way":  # turned around, forward at v_ref, H follows the circle clockwise
        ret = run_episode(env, lambda p: lookahead_action(p, 1.0, 0.2, direction=-1), (L3, 0.0, math.pi))
    else:  # backwards along the path
        ret = run_episode(env, lambda p: -steady_action(1.0, 0.2), pose)
    print(f"{name}: {ret:.2f}")
    assert ret <= 0.2 * n


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"foo": 1}, TypeError, "foo"),
        ({"params": "x"}, TypeError, "TrackingParams.v0"),
        ({"robot": {"wheel": 1}}, TypeError, "wheel"),
        ({"dt": 0.0}, ValueError, "dt"),
        ({"dt": float("nan")}, ValueError, "dt"),
        ({"dt": 3.0}, ValueError, "dt"),
        ({"radius": 0.05}, ValueError, "radius"),
        ({"speed": 1.0}, ValueError, "speed"),
        ({"speed": float("inf")}, ValueError, "speed"),
        ({"direction": 0}, ValueError, "direction"),
        ({"path": "square"}, ValueError, "path"),
        ({"robot": {"l1": -0.1}}, ValueError, "l1"),
        ({"termination_distance": -1.0}, ValueError, "termination_distance"),
    ],
)
def test_bad_settings(kwargs: dict[str, Any], exc: type[Exception], match: str) -> None:
    with pytest.raises(exc, match=match):
        gym.make("AmigoBot-v0", **kwargs)


def test_bad_render_mode() -> None:
    with pytest.raises(ValueError, match="render_mode"):
        AmigoBotEnv(render_mode="ascii")


def test_settings_keywords_params_and_robot() -> None:
    base = TrackingParams.v0(radius=2.0, speed=0.3)
    env = AmigoBotEnv(params=base, dt=0.2, robot={"l3": 0.1})
    p = env.params
    assert (p.radius, p.speed, p.dt, p.robot.l3, p.robot.l1) == (2.0, 0.3, 0.2, 0.1, 0.12)
    env2 = AmigoBotEnv(robot=RobotParams(max_speed=0.5))
    assert env2.params.robot.max_wheel_rate == pytest.approx(10.0)


@pytest.mark.parametrize(
    "action",
    [
        np.array([np.nan, 0.0]),
        np.array([0.0, np.inf]),
        np.array([-np.inf, 0.0], dtype=np.float32),
        np.zeros(3),
        np.zeros((1, 2)),
        0.5,
    ],
)
def test_bad_actions(action: Any) -> None:
    env = AmigoBotEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"pose": (0.0, 0.0)}, "shape"),
        ({"pose": (0.0, np.nan, 0.0)}, "finite"),
        ({"pose": (0.0, 0.0, np.inf)}, "finite"),
        ({"pose": "abc"}, "pose"),
        ({"pose": None}, "pose"),
        ({"start": 1}, "start"),
        ("pose", "dict"),
    ],
)
def test_bad_reset_options(options: Any, match: str) -> None:
    env = AmigoBotEnv()
    with pytest.raises(ValueError, match=match):
        env.reset(options=options)


def test_env_card_mirrors_the_docstring() -> None:
    """Every section of the class docstring appears in docs/env_card.md (text equal up to markup and spacing)."""
    import inspect
    import re
    from pathlib import Path

    def plain(text: str) -> str:
        text = re.sub(r":(?:func|class|data|mod|attr):", "", text)
        return " ".join(text.replace("`", "").split())

    card = plain((Path(__file__).resolve().parents[1] / "docs" / "env_card.md").read_text(encoding="utf-8"))
    doc = inspect.getdoc(AmigoBotEnv)
    assert doc is not None
    sections = [s for s in doc.partition("\n\n")[2].split("## ") if s.strip()]
    assert len(sections) >= 9
    for sec in sections:
        assert plain(sec) in card, sec.splitlines()[0]
