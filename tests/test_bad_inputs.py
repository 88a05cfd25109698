"""Every bad input gets a clear one-line error naming the field, the value and the range (issue 11).

Table-driven: every ``RobotParams`` field and AmigoBot-v0 setting against wrong types and extremes, every form
of action, every order of calls. None may give a traceback from inside numpy, NaN or inf, or be accepted
silently; valid inputs of other numeric types are converted to Python floats.
"""

from __future__ import annotations

import copy
import math
import pickle
import re
import warnings
from dataclasses import fields
from fractions import Fraction
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym
from amigo_gym.envs import AmigoBotEnv, AmigoBotVectorEnv
from amigo_gym.model.params import HEADING_LIMIT, RobotParams
from amigo_gym.task.v0 import V0_DEFAULTS, validate_action
from amigo_gym.task.v1 import TrackingParams, obs_bounds

PACKAGE = Path(amigo_gym.__file__).resolve().parent

#: wrong types for any numeric field
WRONG_TYPES: list[Any] = [
    True,
    np.bool_(False),
    "0.1",
    b"0.1",
    None,
    1 + 0j,
    np.complex128(1),
    [0.1],
    np.array([0.1, 0.2]),
]
#: non-finite values and extremes for any numeric field
NON_FINITE: list[Any] = [math.nan, math.inf, -math.inf, np.float32("nan")]

ROBOT_EXTREMES: dict[str, list[Any]] = {
    "l1": [0.0, -0.12, 1e-310, 1e308],
    "l3": [0.0, 1e-310, 1e308],
    "l4": [0.0, 0.05, 1e-310, 1e308],
    "l5": [0.0, 1e-310, 1e308],
    "r1": [0.0, -0.05, 1e-310, 1e308],
    "r2": [0.0, 1e-310, 1e308],
    "r3": [0.0, 1e-310, 1e308],
    "max_speed": [0.0, 1e-310, 1e308],
    "max_acceleration": [0.0, 1e308],
    "max_deceleration": [-1.0, 1e308],
    "max_rotation_rate": [0.0, 1e308],
    "body_length": [0.0, 1e308],
    "body_width": [0.0, 1e-310],
}
ENV_EXTREMES: dict[str, list[Any]] = {
    "dt": [0.0, -0.1, 2.5, 1e-310],
    "radius": [-1.0, 0.08, 1e-310, 1e308],
    "speed": [0.0, 1e-310, 0.76, 1e308],
    "straight_length": [-0.1, 1e308],
    "termination_distance": [0.0, 1e-310, 11.0],
    "init_position_noise": [-0.01, 0.2],
    "init_heading_noise": [-0.1, 1.0],
    "error_scale": [0.0, 1e-40, 11.0],
    "sigma_track": [0.0, 1e-310, 1e308],
    "sigma_speed": [-1.0, 1e-310, 1e308],
    "sigma_smooth": [0.0, 1e-310, 1e308],
    "smooth_weight": [-0.1, 1.0],
}
RANGE = re.compile(r"[\[(]-?[0-9.e+-]+, -?[0-9.e+-]+[\])]")


def robot_cases() -> list[tuple[str, Any]]:
    names = [f.name for f in fields(RobotParams)]
    assert sorted(names) == sorted(ROBOT_EXTREMES)  # every field has its extremes
    return [(n, v) for n in names for v in [*WRONG_TYPES, *NON_FINITE, *ROBOT_EXTREMES[n]]]


def env_cases() -> list[tuple[str, Any]]:
    numeric = list(ENV_EXTREMES)
    assert sorted([*numeric, "robot", "direction", "path", "preview"]) == sorted(V0_DEFAULTS)
    return [(n, v) for n in numeric for v in [*WRONG_TYPES, *NON_FINITE, *ENV_EXTREMES[n]]]


def check_clean(exc: pytest.ExceptionInfo[BaseException], *needles: str) -> str:
    """One line, raised from amigo_gym (not from inside numpy), no chained numpy error, names the needles."""
    msg = str(exc.value)
    assert msg and "\n" not in msg, msg
    assert len(msg) < 400, msg
    assert Path(str(exc.traceback[-1].path)).resolve().is_relative_to(PACKAGE), exc.traceback[-1]
    assert exc.value.__cause__ is None and (exc.value.__context__ is None or exc.value.__suppress_context__)
    for n in needles:
        assert n in msg, (n, msg)
    return msg


@pytest.mark.parametrize(("name", "value"), robot_cases())
def test_robot_field_refused(name: str, value: Any) -> None:
    with pytest.raises(ValueError) as exc:
        RobotParams(**{name: value})
    msg = check_clean(exc, f"RobotParams.{name}")
    assert RANGE.search(msg), msg


@pytest.mark.parametrize(("name", "value"), env_cases())
def test_env_field_refused(name: str, value: Any) -> None:
    with pytest.raises(ValueError) as exc:
        TrackingParams.v0(**{name: value})
    msg = check_clean(exc)
    drivability = "TrackingParams.v0: speed" in msg and name in ("speed", "radius")
    assert f"TrackingParams.v0.{name}" in msg or drivability, msg


@pytest.mark.parametrize(
    ("name", "value", "needle"),
    [
        ("direction", 0, "TrackingParams.v0.direction"),
        ("direction", 2, "TrackingParams.v0.direction"),
        ("direction", True, "TrackingParams.v0.direction"),
        ("direction", 1.0, "TrackingParams.v0.direction"),
        ("direction", "1", "TrackingParams.v0.direction"),
        ("direction", None, "TrackingParams.v0.direction"),
        ("path", "square", "TrackingParams.v0.path"),
        ("path", None, "TrackingParams.v0.path"),
        ("path", ["circle"], "TrackingParams.v0.path"),
        ("path", 1, "TrackingParams.v0.path"),
        ("preview", None, "TrackingParams.v0.preview"),
        ("preview", "0.2", "TrackingParams.v0.preview"),
        ("preview", 0.2, "TrackingParams.v0.preview"),
        ("preview", {"a": 0.2}, "TrackingParams.v0.preview"),
        ("preview", np.array(0.2), "TrackingParams.v0.preview"),
        ("preview", (0.2, "x"), "TrackingParams.v0.preview[1]"),
        ("preview", (0.2, True), "TrackingParams.v0.preview[1]"),
        ("preview", (math.nan,), "TrackingParams.v0.preview[0]"),
        ("preview", ((0.1, 0.2),), "TrackingParams.v0.preview[0]"),
        ("preview", (11.0,), "TrackingParams.v0.preview[0]"),
        ("robot", "amigobot", "TrackingParams.v0.robot"),
        ("robot", None, "TrackingParams.v0.robot"),
        ("robot", {"l1": 0.12}, "TrackingParams.v0.robot"),
    ],
)
def test_env_structured_field_refused(name: str, value: Any, needle: str) -> None:
    with pytest.raises(ValueError) as exc:
        TrackingParams.v0(**{name: value})
    check_clean(exc, needle)


@pytest.mark.parametrize(
    ("settings", "needles"),
    [
        ({"speed": 0.74}, ["speed 0.74 m/s on a 1 m circle needs 16.6 rad/s on the outer wheel", "limit 15 rad/s"]),
        ({"radius": 0.085}, ["on a 0.085 m circle needs 20.7 rad/s on the outer wheel", "limit 15 rad/s"]),
        ({"radius": 0.085, "direction": -1}, ["needs 20.7 rad/s"]),
        ({"robot": RobotParams(r2=0.03), "speed": 0.6}, ["rolling straight needs 20 rad/s", "limit 15 rad/s"]),
        ({"robot": RobotParams(r2=0.03), "speed": 0.6, "path": "manoeuvre"}, ["rolling straight"]),
    ],
)
def test_infeasible_task_refused(settings: dict[str, Any], needles: list[str]) -> None:
    """A task the robot cannot drive: the exact steady state's wheel rate is over the limit."""
    with pytest.raises(ValueError) as exc:
        TrackingParams.v0(**settings)
    check_clean(exc, *needles)
    with pytest.raises(ValueError, match="needs"):
        gym.make("AmigoBot-v0", **settings)


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"robot": {"l1": "0.12"}}, "RobotParams.l1"),
        ({"robot": {"max_speed": 1e308}}, "RobotParams.max_speed"),
        ({"robot": {"l1": 1e-310}}, "RobotParams.l1"),
        ({"robot": {"r1": 1e-300, "r2": 1e-300}}, "RobotParams.r1"),
        ({"dt": True}, "TrackingParams.v0.dt"),
        ({"dt": "0.1"}, "TrackingParams.v0.dt"),
        ({"radius": "1"}, "TrackingParams.v0.radius"),
        ({"dt": np.array([0.1])}, "TrackingParams.v0.dt"),
        ({"preview": None}, "TrackingParams.v0.preview"),
        ({"error_scale": 1e-40}, "TrackingParams.v0.error_scale"),
    ],
)
def test_issue_cases_through_gym_make(kwargs: dict[str, Any], needle: str) -> None:
    for make in (lambda: gym.make("AmigoBot-v0", **kwargs), lambda: AmigoBotVectorEnv(2, **kwargs)):
        with pytest.raises(ValueError) as exc:
            make()
        check_clean(exc, needle)


@pytest.mark.parametrize(
    ("value", "stored"),
    [
        (np.float32(0.1), float(np.float32(0.1))),
        (np.float64(0.1), 0.1),
        (np.array(0.1), 0.1),
        (np.array(0.1, dtype=np.float32), float(np.float32(0.1))),
        (Fraction(1, 10), 0.1),
        (1, 1.0),
        (np.int64(1), 1.0),
    ],
)
def test_numbers_are_stored_as_python_floats(value: Any, stored: float) -> None:
    p = TrackingParams.v0(dt=value)
    assert type(p.dt) is float and p.dt == stored
    r = RobotParams(l1=value * 0.12 if not isinstance(value, np.ndarray) else float(value) * 0.12)
    assert type(r.l1) is float
    assert type(TrackingParams.v0(direction=np.int64(-1)).direction) is int
    assert all(type(d) is float for d in TrackingParams.v0(preview=np.array([0.2, 0.4], dtype=np.float32)).preview)


def test_float32_setting_keeps_the_state_float64_and_cache_keys_apart() -> None:
    p32, p64 = TrackingParams.v0(dt=np.float32(0.1)), TrackingParams.v0(dt=0.1)
    assert p32 != p64 and hash(TrackingParams.v0(dt=0.1)) == hash(p64)
    env = AmigoBotEnv(dt=np.float32(0.1))
    ref = AmigoBotEnv(dt=float(np.float32(0.1)))
    for e in (env, ref):
        e.reset(seed=3)
    for _ in range(50):
        o1, r1, term, *_ = env.step(np.array([0.3, 0.24]))
        o2, r2, *_ = ref.step(np.array([0.3, 0.24]))
        assert np.array_equal(o1, o2) and r1 == r2
        if term:
            break
    st = env._current_state()  # the state: Python floats (the step count an int), never float32
    assert all(type(x) is float for x in st[:-1]) and type(st.steps) is int


def corner_params() -> list[dict[str, Any]]:
    """Settings at the edges of the ranges that are still drivable."""
    tiny = {"l1": 1e-3, "l3": 1e-3, "l4": 1e-6, "l5": 1e-3, "r1": 1e-3, "r2": 1e-3, "r3": 1e-3, "max_speed": 100.0}
    big = {"l1": 100.0, "l3": 100.0, "l5": 100.0, "r1": 100.0, "r2": 100.0, "r3": 100.0, "max_speed": 1e-3}
    return [
        {"robot": tiny, "radius": 1e3, "speed": 1.0, "dt": 2.0, "error_scale": 1e-6, "sigma_smooth": 1e-6},
        {"robot": tiny, "radius": 2e-3, "speed": 1e-6, "dt": 1e-6, "sigma_track": 1e6, "sigma_speed": 1e-6},
        {"robot": big, "radius": 1e3, "speed": 1e-6, "dt": 2.0, "termination_distance": 10.0, "sigma_smooth": 1e6},
        {"robot": {"max_speed": 100.0, "r1": 1e-3, "l4": 5e-4}, "speed": 1e-3, "radius": 1e3, "path": "manoeuvre"},
        {"termination_distance": 1e-3, "init_position_noise": 5e-4, "error_scale": 10.0, "preview": ()},
    ]


@pytest.mark.parametrize("settings", corner_params())
def test_corner_settings_stay_finite(settings: dict[str, Any]) -> None:
    """At the edges of every range, observations, rewards and infos stay finite and inside the bounds."""
    env = AmigoBotEnv(**settings)
    low, high = obs_bounds(env.params)
    assert np.isfinite(low).all() and np.isfinite(high).all() and np.isfinite(env.observation_space.high).all()
    rng = np.random.default_rng(0)
    actions = [np.array([1.0, -1.0]), np.array([-1.0, 1.0]), np.array([1.0, 1.0]), np.array([0.0, 0.0])]
    for ep in range(2):
        obs, info = env.reset(seed=ep)
        for t in range(60):
            a = actions[t % 4] if ep == 0 else rng.uniform(-1, 1, 2)
            obs, reward, term, _, info = env.step(a)
            assert np.isfinite(obs).all() and math.isfinite(reward) and 0.0 <= reward <= 1.0
            assert np.all(obs >= env.observation_space.low) and np.all(obs <= env.observation_space.high), obs
            assert np.isfinite(info["pose"]).all() and all(math.isfinite(v) for v in info["reward_terms"].values())
            if term:
                break


# --------------------------------------------------------------------------- actions
ACTIONS: list[tuple[Any, type[Exception], str]] = [
    ("ab", TypeError, "string"),
    (b"ab", TypeError, "string"),
    (["0.1", "0.2"], TypeError, "str values"),
    ([1 + 1j, 0.0], TypeError, "complex"),
    (np.array([1 + 0j, 0.0]), TypeError, "complex"),
    ([True, False], TypeError, "bool"),
    (np.array([True, False]), TypeError, "bool"),
    (None, TypeError, "object"),
    (object(), TypeError, "object"),
    ({"a": 1}, TypeError, "object"),
    ([Fraction(1, 2), 0.1], TypeError, "object"),
    ([[0.1], [0.2, 0.3]], ValueError, "rectangular"),
    ([0.1, [0.2]], ValueError, "rectangular"),
    ([0.1], ValueError, "shape"),
    ([0.1, 0.2, 0.3], ValueError, "shape"),
    (np.zeros((1, 2)), ValueError, "shape"),
    (0.5, ValueError, "shape"),
    ([math.nan, 0.0], ValueError, "finite"),
    (np.array([0.0, -math.inf], dtype=np.float32), ValueError, "finite"),
]


@pytest.mark.parametrize(("action", "kind", "needle"), ACTIONS)
def test_single_env_refuses_action(action: Any, kind: type[Exception], needle: str) -> None:
    env = AmigoBotEnv()
    env.reset(seed=0)
    before = env.pose
    with pytest.raises(kind) as exc:
        env.step(action)
    check_clean(exc, "action", needle)
    assert np.array_equal(env.pose, before)  # the state is untouched


@pytest.mark.parametrize(("action", "kind", "needle"), ACTIONS)
def test_vector_env_refuses_action(action: Any, kind: type[Exception], needle: str) -> None:
    envs = AmigoBotVectorEnv(2)
    envs.reset(seed=0)
    batch = action if isinstance(action, str | bytes) or action is None else [action, action]
    if needle == "shape":
        batch = [action]
    with pytest.raises(kind) as exc:
        envs.step(batch)
    check_clean(exc, "action")


@pytest.mark.parametrize(
    "action",
    [[0.3, -0.2], (0.3, -0.2), np.array([0.3, -0.2], dtype=np.float32), np.array([1, 0]), [np.float64(0.3), 1]],
)
def test_valid_action_forms_are_applied_exactly(action: Any) -> None:
    """Other real forms give the same result as the float64 array of their values."""
    a, b = AmigoBotEnv(), AmigoBotEnv()
    a.reset(seed=1)
    b.reset(seed=1)
    ref = np.asarray(action, dtype=np.float64)
    assert np.array_equal(validate_action(action), ref)
    o1, r1, *_ = a.step(action)
    o2, r2, *_ = b.step(ref)
    assert np.array_equal(o1, o2) and r1 == r2


# --------------------------------------------------------------------------- reset options
@pytest.mark.parametrize(
    ("pose", "needle"),
    [
        ((1e300, 0.0, 0.0), "x_A, y_A in [-1e+06, 1e+06] m"),
        ((0.0, -2e6, 0.0), "x_A, y_A in"),
        ((0.0, 0.0, 1e17), "beta in [-1e+06, 1e+06] rad"),
        (("0", "0", "0"), "str"),
        ((0.0, 0.0, 1j), "complex"),
        ((True, 0.0, 0.0), "bool"),
        ((0.0, (0.0, 1.0), 0.0), "rectangular"),
        ((0.0, 0.0), "shape"),
        ((0.0, math.nan, 0.0), "finite"),
        (None, "object"),
    ],
)
def test_reset_pose_refused(pose: Any, needle: str) -> None:
    for env in (AmigoBotEnv(), AmigoBotVectorEnv(2)):
        with pytest.raises(ValueError) as exc:
            env.reset(options={"pose": pose})
        check_clean(exc, 'options["pose"]', needle)


def test_pose_at_the_limits_is_accepted_and_turns() -> None:
    env = AmigoBotEnv()
    env.reset(options={"pose": (1e6, -1e6, -1e6)})
    assert np.array_equal(env.pose, [1e6, -1e6, -1e6])
    env.step(np.array([1.0, -1.0]))  # spin left: the turn of one step is resolved
    assert env.pose[2] - (-1e6) == pytest.approx(0.625, rel=1e-6)


def test_heading_beyond_the_limit_is_reduced_by_whole_turns_alike_in_both_envs() -> None:
    """A robot spinning past 1e6 rad keeps turning (the heading is reduced by whole turns, documented)."""
    start = (0.0, 0.0, HEADING_LIMIT - 0.3)
    single = AmigoBotEnv()
    single.reset(options={"pose": start})
    vec = AmigoBotVectorEnv(2, max_episode_steps=None)
    vec.reset(options={"pose": start})
    betas = []
    for _ in range(5):
        o1, r1, *_ = single.step(np.array([1.0, -1.0]))  # spinning left at 6.25 rad/s
        o2, r2, *_ = vec.step(np.array([[1.0, -1.0], [1.0, -1.0]]))
        assert np.array_equal(o1, o2[0]) and r1 == r2[0]
        assert single.pose[2] == vec._state.beta[0]
        betas.append(single.pose[2])
    assert abs(betas[-1]) <= HEADING_LIMIT and np.all(np.abs(np.diff(np.unwrap(betas)) - 0.625) < 1e-6)


# --------------------------------------------------------------------------- order of calls
def test_step_and_render_before_reset_raise() -> None:
    env = AmigoBotEnv(render_mode="rgb_array")
    with pytest.raises(gym.error.ResetNeeded) as exc:
        env.step(np.zeros(2))
    check_clean(exc, "reset")
    with pytest.raises(gym.error.ResetNeeded):
        env.render()
    envs = AmigoBotVectorEnv(2, render_mode="rgb_array")
    with pytest.raises(gym.error.ResetNeeded):
        envs.step(np.zeros((2, 2)))
    with pytest.raises(gym.error.ResetNeeded):
        envs.render()
    with pytest.raises(gym.error.ResetNeeded):
        envs.reset(options={"reset_mask": np.array([True, False])})


def test_stepping_a_terminated_episode_warns_once() -> None:
    env = AmigoBotEnv()
    env.reset(options={"pose": (0.0, -0.2, 0.0)})  # H 0.2 m outside... drive away from the circle
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        term = False
        for _ in range(100):
            *_, term, _, _ = env.step(np.array([1.0, 1.0]))
            if term:
                break
    assert term
    with pytest.warns(UserWarning, match="after the episode was terminated"):
        env.step(np.zeros(2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # once per episode
        env.step(np.zeros(2))
        env.reset(seed=0)
        env.step(np.zeros(2))  # a new episode: no warning


def test_vector_env_refuses_stepping_a_truncated_robot_without_autoreset() -> None:
    envs = AmigoBotVectorEnv(2, max_episode_steps=2, autoreset_mode="Disabled")
    envs.reset(seed=0)
    for _ in range(2):
        *_, trunc, _ = envs.step(np.full((2, 2), 0.27))
    assert trunc.all()
    with pytest.raises(RuntimeError) as exc:
        envs.step(np.full((2, 2), 0.27))
    check_clean(exc, "finished their episodes")


def test_envs_pickle_and_deepcopy_after_render() -> None:
    env = gym.make("AmigoBot-v0", render_mode="rgb_array")
    env.reset(seed=0)
    env.step(np.array([0.3, 0.25]))
    frame = env.render()
    for clone in (pickle.loads(pickle.dumps(env)), copy.deepcopy(env)):
        assert np.array_equal(clone.render(), frame)
        assert np.array_equal(clone.step(np.array([0.3, 0.2]))[0], copy.deepcopy(env).step(np.array([0.3, 0.2]))[0])
    envs = AmigoBotVectorEnv(2, render_mode="rgb_array")
    envs.reset(seed=0)
    envs.step(np.full((2, 2), 0.3))
    frames: Any = envs.render()
    for clone in (pickle.loads(pickle.dumps(envs)), copy.deepcopy(envs)):
        assert all(np.array_equal(a, b) for a, b in zip(clone.render(), frames, strict=True))
    env.close()
    envs.close()


def test_vector_render_trail_memory_is_flat() -> None:
    """The rgb_array trail is a ring buffer: memory does not grow with the number of rendered steps."""
    import tracemalloc

    envs = AmigoBotVectorEnv(64, render_mode="rgb_array", max_episode_steps=None)
    envs.trail_length = 50
    envs.reset(seed=0)
    action = np.tile([0.27, 0.24], (64, 1))
    for _ in range(200):
        envs.step(action)
    envs.render()
    tracemalloc.start()
    try:
        for _ in range(300):
            envs.step(action)
        first, _ = tracemalloc.get_traced_memory()
        for _ in range(3000):
            envs.step(action)
        envs.render()
        second, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the former list grew by 1 KiB per step at N = 64 (3 MiB here); what remains is numpy's small caches
    assert second - first < 256 * 1024, (first, second)
    assert envs._trail is not None and envs._trail.nbytes == 50 * 64 * 2 * 8
    assert 0 < len(envs._trail_of(0)) <= 50
    single = AmigoBotEnv(render_mode="rgb_array")
    single.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the episode may end: stepping on is what this measures
        for _ in range(1100):
            single.step(np.array([0.27, 0.24]))
    assert len(single._trail) == 1000
