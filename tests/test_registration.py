"""Registration of ``AmigoBot-v0``: spec, keywords of gym.make / make_vec, wrappers."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import pytest
from gymnasium.wrappers import TimeLimit

import amigo_gym
from amigo_gym import RobotParams
from amigo_gym.envs import AmigoBotEnv, AmigoBotVectorEnv
from amigo_gym.task.v0 import V0_DEFAULTS
from amigo_gym.task.v1 import TrackingParams


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
    assert (p.dt, p.radius, p.speed, p.direction, type(p.path).__name__) == (0.05, 1.5, 0.3, -1, "ManoeuvrePath")
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
    assert set(values) == set(V0_DEFAULTS)
    u = gym.make("AmigoBot-v0", **values).unwrapped
    assert isinstance(u, AmigoBotEnv)
    assert u.params == TrackingParams.v0(**values)


def test_params_object_and_overrides() -> None:
    base = TrackingParams.v0(radius=3.0, speed=0.4)
    u = gym.make("AmigoBot-v0", params=base).unwrapped
    assert isinstance(u, AmigoBotEnv) and u.params == base
    u2 = gym.make("AmigoBot-v0", params=base, speed=0.1).unwrapped
    assert isinstance(u2, AmigoBotEnv) and (u2.params.radius, u2.params.speed) == (3.0, 0.1)


def test_unknown_keyword_and_bad_value() -> None:
    with pytest.raises(TypeError, match="radious"):
        gym.make("AmigoBot-v0", radious=1.0)
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.radius"):
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
    """Making AmigoBot-v0 warns nothing "out of date": AmigoBot-v1 is another task, not an upgrade, registered so that
    gymnasium does not take it for v0's successor (checked here on every Python .ci/run names)."""
    import warnings

    with warnings.catch_warnings(record=True) as seen:  # the filters pytest set up for this test, unchanged
        gym.make("AmigoBot-v0").close()
        gym.make_vec("AmigoBot-v0", num_envs=2).close()
    assert not [w for w in seen if "out of date" in str(w.message)], [str(w.message) for w in seen]


def test_the_readme_envs_step_on_the_compiled_route() -> None:
    """What the README promises on every Python it names (.ci/run runs this file on CPython 3.10-3.13, each in a
    fresh venv with the core install): AmigoBot-v0, AmigoBot-v1 and a mixed-path v1 vector env of 256 make, reset
    and step, and their steps ran numba-compiled code of the package (a compiled function of amigo_gym with at
    least one compiled signature after the steps, none before)."""
    import subprocess
    import sys

    code = """
import sys
import gymnasium as gym, numpy as np
import amigo_gym
from numba.core.registry import CPUDispatcher

def compiled():
    return sorted(f"{m}.{k}" for m, mod in list(sys.modules.items()) if m.startswith("amigo_gym")
                  for k, v in vars(mod).items() if isinstance(v, CPUDispatcher) and v.signatures)

print(len(compiled()))
for env in (gym.make("AmigoBot-v0"), gym.make("AmigoBot-v1")):
    env.reset(seed=0)
    for _ in range(3):
        obs, r, term, trunc, info = env.step(env.action_space.sample())
    assert np.isfinite(r) and obs in env.observation_space
vec = gym.make_vec("AmigoBot-v1", 256, path="mixed")
vec.reset(seed=0)
for _ in range(3):
    obs, r, term, trunc, info = vec.step(vec.action_space.sample())
assert r.shape == (256,) and np.isfinite(r).all()
print(len(compiled()))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    before, after = (int(x) for x in out.stdout.split()[-2:])
    assert before == 0 and after > 0, (before, after)
