"""One home per contract: observation names, info schema, spaces, and A ``l3`` behind H."""

from __future__ import annotations

import math
import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym.model.kinematics import a_from_h, h_from_a, h_position
from amigo_gym.task import v0 as task
from amigo_gym.task.v1 import TrackingParams

ROOT = Path(__file__).resolve().parents[1]


def test_env_card_table_lists_the_observation_names_in_order() -> None:
    card = (ROOT / "docs" / "env_card.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| (\d+)\s+\| `(\w+)`\s+\|", card, flags=re.M)
    assert [int(i) for i, _ in rows] == list(range(len(rows)))
    assert [name for _, name in rows] == task.obs_names(TrackingParams.v0())
    assert len(rows) == gym.make("AmigoBot-v0").observation_space.shape[0]  # type: ignore[index]


def test_observation_fields_mean_what_their_names_say() -> None:
    """Decode a known state by names: H 1 cm left of the circle, heading along the tangent, rolling straight."""
    p = TrackingParams.v0(preview=(0.5,))
    env = gym.make("AmigoBot-v0", params=p)
    beta = 0.0
    xa, ya = a_from_h(0.0, 0.01, math.cos(beta), math.sin(beta), p.robot.l3)
    obs, _ = env.reset(options={"pose": (xa, ya, beta)})
    i = task.obs_index(p)
    assert list(i) == task.obs_names(p) and len(i) == obs.shape[0]
    assert obs[i["cross_track_error"]] == pytest.approx(0.01 / p.error_scale, rel=1e-4)
    assert obs[i["sin_heading_error"]] == pytest.approx(0.0, abs=1e-6)
    assert obs[i["cos_heading_error"]] == pytest.approx(1.0)
    assert obs[i["curvature"]] == pytest.approx(p.robot.l3 / p.radius)
    assert obs[i["curvature_ahead_1"]] == pytest.approx(p.robot.l3 / p.radius)
    assert obs[i["wheel_rate_1"]] == obs[i["wheel_rate_2"]] == pytest.approx(4.0 / 15.0)
    assert obs[i["speed_error"]] == pytest.approx(0.0, abs=1e-7)
    assert obs[i["reference_speed"]] == pytest.approx(0.2 / 0.75)


def test_info_schema_is_the_same_everywhere() -> None:
    from amigo_gym.tools.training.sb3_vec import AmigoBotSB3VecEnv

    single = gym.make("AmigoBot-v0")
    _, info = single.reset(seed=0)
    assert list(info) == list(task.INFO_KEYS)
    _, _, _, _, info = single.step(np.zeros(2))
    assert list(info) == list(task.INFO_KEYS)
    assert list(info["reward_terms"]) == list(task.REWARD_TERMS)
    vec = gym.make_vec("AmigoBot-v0", num_envs=2)
    _, vinfo = vec.reset(seed=0)
    assert [k for k in vinfo if not k.startswith("_")] == list(task.INFO_KEYS)
    sb3 = AmigoBotSB3VecEnv(2)
    sb3.reset()
    _, _, _, infos = sb3.step(np.zeros((2, 2)))
    assert set(infos[0]) - {"TimeLimit.truncated"} == set(task.INFO_KEYS)
    for key, kind in task.INFO_KEYS.items():
        want = dict if kind == "terms" else float if kind == "scalar" else np.ndarray
        assert isinstance(info[key], want) and isinstance(infos[0][key], want), key


def test_spaces_are_the_same_for_both_envs() -> None:
    single = gym.make("AmigoBot-v0", preview=(0.1, 0.2, 0.3))
    vec = gym.make_vec("AmigoBot-v0", num_envs=3, preview=(0.1, 0.2, 0.3))
    assert vec.single_observation_space == single.observation_space
    assert vec.single_action_space == single.action_space
    assert single.observation_space.shape == (11,)


def test_a_lies_l3_behind_h() -> None:
    g = np.random.default_rng(4)
    x, y, b = g.uniform(-3, 3, 50), g.uniform(-3, 3, 50), g.uniform(-4, 4, 50)
    hx, hy = h_from_a(x, y, np.cos(b), np.sin(b), 0.08)
    np.testing.assert_allclose(np.hypot(hx - x, hy - y), 0.08, rtol=1e-12)
    np.testing.assert_allclose(np.arctan2(hy - y, hx - x), np.arctan2(np.sin(b), np.cos(b)), atol=1e-12)
    ax, ay = a_from_h(hx, hy, np.cos(b), np.sin(b), 0.08)
    np.testing.assert_allclose(ax, x, atol=1e-15)
    np.testing.assert_allclose(ay, y, atol=1e-15)
    from amigo_gym import RobotParams

    np.testing.assert_array_equal(h_position(np.stack([x, y, b], -1), RobotParams()), np.stack([hx, hy], -1))
