"""Every configuration keyword accepts a plain mapping, and the spec's JSON round trip rebuilds the env."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym import RobotParams
from amigo_gym.task.v1 import TrackingParams


def _rollout(env: gym.Env[Any, Any]) -> list[float]:
    obs, _ = env.reset(seed=3)
    out = obs.tolist()
    for _ in range(5):
        obs, r, *_ = env.step(np.array([0.3, 0.2]))
        out += [*obs.tolist(), float(r)]
    return out


@pytest.mark.parametrize(
    "kwargs",
    [
        {"params": {"radius": 1.5, "speed": 0.3, "preview": (0.1, 0.3, 0.5)}},
        {"params": {"dt": 0.05, "robot": {"l3": 0.1}}, "radius": 2.0},
        {"robot": {"l3": 0.1, "max_speed": 0.5}},
        {"robot": {"l1": 0.1}, "direction": -1, "path": "manoeuvre"},
    ],
)
def test_spec_json_round_trip(kwargs: dict[str, Any]) -> None:
    env = gym.make("AmigoBot-v0", **kwargs)
    assert env.spec is not None
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    assert again.unwrapped.params == env.unwrapped.params  # type: ignore[attr-defined]
    assert _rollout(again) == _rollout(env)


def test_mapping_equals_dataclass() -> None:
    """A mapping means the same as the dataclass built from it, for the single and the vector env."""
    want = TrackingParams.v0(radius=1.5, dt=0.05, robot=RobotParams(l3=0.1), preview=(0.3,))
    as_map = {"radius": 1.5, "dt": 0.05, "robot": {"l3": 0.1}, "preview": [0.3]}
    assert gym.make("AmigoBot-v0", params=as_map).unwrapped.params == want  # type: ignore[attr-defined]
    vec = gym.make_vec("AmigoBot-v0", num_envs=2, params=as_map)
    assert vec.unwrapped.params == want  # type: ignore[attr-defined]
    # rl-zoo's --env-kwargs params:"dict(radius=0.5)" arrives as a dict
    assert gym.make("AmigoBot-v0", params={"radius": 0.5}).unwrapped.params.radius == 0.5  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"params": {"radious": 1.0}}, "radious"),
        ({"params": {"robot": {"wheel": 1}}}, "wheel"),
        ({"params": [("radius", 1.0)]}, "mapping"),
        ({"robot": 3}, "mapping"),
    ],
)
def test_bad_mappings(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(TypeError, match=match):
        gym.make("AmigoBot-v0", **kwargs)
