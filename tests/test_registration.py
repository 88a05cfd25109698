"""Registration of ``AmigoBot-v0``: spec, keywords of gym.make / make_vec, wrappers."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import pytest
from gymnasium.wrappers import TimeLimit

import amigo_gym
from amigo_gym import EnvParams, RobotParams
from amigo_gym.envs import AmigoBotEnv, AmigoBotVectorEnv


def test_spec() -> None:
    spec = gym.spec("AmigoBot-v0")
    assert spec.entry_point == "amigo_gym.envs:AmigoBotEnv"
    assert spec.vector_entry_point == "amigo_gym.envs:AmigoBotVectorEnv"
    assert spec.max_episode_steps == 400


def test_make_wraps_time_limit_and_passes_settings() -> None:
    env = gym.make("AmigoBot-v0", dt=0.05, radius=1.5, speed=0.3, direction=-1, path="manoeuvre")
    assert isinstance(env, TimeLimit) and env._max_episode_steps == 400
    u = env.unwrapped
    assert isinstance(u, AmigoBotEnv)
    p = u.params
    assert (p.dt, p.radius, p.speed, p.direction, p.path) == (0.05, 1.5, 0.3, -1, "manoeuvre")
    assert env.metadata["render_fps"] == pytest.approx(20.0)
    assert gym.make("AmigoBot-v0", max_episode_steps=30)._max_episode_steps == 30  # type: ignore[attr-defined]


def test_every_env_params_field_is_a_keyword() -> None:
    values: dict[str, Any] = {
        "robot": RobotParams(l3=0.1),
        "dt": 0.2,
        "radius": 2.0,
        "speed": 0.25,
        "direction": -1,
        "path": "manoeuvre",
        "straight_length": 0.5,
        "termination_distance": 0.3,
        "init_position_noise": 0.01,
        "init_heading_noise": 0.05,
        "error_scale": 0.1,
        "preview": (0.3,),
        "sigma_track": 0.03,
        "sigma_speed": 0.04,
        "sigma_smooth": 0.2,
        "smooth_weight": 0.1,
    }
    assert set(values) == set(EnvParams.__dataclass_fields__)
    u = gym.make("AmigoBot-v0", **values).unwrapped
    assert isinstance(u, AmigoBotEnv)
    assert u.params == EnvParams(**values)


def test_params_object_and_overrides() -> None:
    base = EnvParams(radius=3.0, speed=0.4)
    u = gym.make("AmigoBot-v0", params=base).unwrapped
    assert isinstance(u, AmigoBotEnv) and u.params == base
    u2 = gym.make("AmigoBot-v0", params=base, speed=0.1).unwrapped
    assert isinstance(u2, AmigoBotEnv) and (u2.params.radius, u2.params.speed) == (3.0, 0.1)


def test_unknown_keyword_and_bad_value() -> None:
    with pytest.raises(TypeError, match="radious"):
        gym.make("AmigoBot-v0", radious=1.0)
    with pytest.raises(ValueError, match=r"EnvParams\.radius"):
        gym.make("AmigoBot-v0", radius=0.0)
    with pytest.raises(TypeError, match="radious"):
        gym.make_vec("AmigoBot-v0", num_envs=2, radious=1.0)


def test_make_vec_modes() -> None:
    v = gym.make_vec("AmigoBot-v0", num_envs=3, speed=0.3)
    assert isinstance(v, AmigoBotVectorEnv) and v.params.speed == 0.3 and v.max_episode_steps == 400
    s = gym.make_vec("AmigoBot-v0", num_envs=2, vectorization_mode="sync", speed=0.3)
    assert isinstance(s, gym.vector.SyncVectorEnv)
    assert s.single_observation_space == v.single_observation_space
    assert s.single_action_space == v.single_action_space


def test_package_registers_on_import() -> None:
    assert "AmigoBot-v0" in gym.registry
    assert amigo_gym.MAX_EPISODE_STEPS == 400


def test_making_v0_gives_no_out_of_date_warning_under_the_projects_settings() -> None:
    """gymnasium calls AmigoBot-v0 "out of date" because AmigoBot-v1 exists (a different task, not an upgrade); the
    project's pytest settings (pyproject.toml) silence exactly that message, which had filled the test summary."""
    import warnings

    with warnings.catch_warnings(record=True) as seen:  # the filters pytest set up for this test, unchanged
        gym.make("AmigoBot-v0").close()
        gym.make_vec("AmigoBot-v0", num_envs=2).close()
    assert not [w for w in seen if "out of date" in str(w.message)], [str(w.message) for w in seen]
