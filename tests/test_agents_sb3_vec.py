"""The SB3 VecEnv adapter over the native vector env: SB3's contract and equality with DummyVecEnv."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3.common.vec_env import DummyVecEnv, VecEnv, VecMonitor

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym.tools.training.sb3_vec import AmigoBotSB3VecEnv

SETTINGS: dict[str, Any] = {"max_episode_steps": 25, "termination_distance": 0.05, "init_position_noise": 0.02}


def pair(n: int) -> tuple[AmigoBotSB3VecEnv, DummyVecEnv]:
    a = AmigoBotSB3VecEnv(n, **SETTINGS)
    b = DummyVecEnv([lambda: gym.make("AmigoBot-v0", **SETTINGS) for _ in range(n)])
    return a, b


#: the stated tolerance between the vector env and single envs (tests/golden_compare.py): 1e-9 relative; the
#: vector step evaluates tan and exp over whole blocks (numpy's SIMD loops), a single step per robot
RTOL = 1e-9


def assert_close(a: Any, b: Any, what: str) -> None:
    """Floats within :data:`RTOL` (float32 within one rounding), everything else equal."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.dtype == b.dtype and a.shape == b.shape, what
    if a.dtype.kind == "f":
        rtol = max(RTOL, 2 * float(np.finfo(a.dtype).eps))
        np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * float(np.max(np.abs(b), initial=1.0)), err_msg=what)
    else:
        np.testing.assert_array_equal(a, b, err_msg=what)


def assert_infos_equal(ia: list[dict[str, Any]], ib: list[dict[str, Any]]) -> None:
    assert len(ia) == len(ib)
    for da, db in zip(ia, ib, strict=True):
        assert da.keys() == db.keys()
        for k in da:
            assert type(da[k]) is type(db[k]), k
            if isinstance(da[k], dict):
                assert da[k].keys() == db[k].keys(), k
                for j in da[k]:
                    assert_close(da[k][j], db[k][j], f"{k}[{j}]")
            else:
                assert_close(da[k], db[k], k)


def test_rollouts_equal_dummy_vec_env() -> None:
    n = 4
    a, b = pair(n)
    a.seed(11)
    b.seed(11)
    np.testing.assert_array_equal(a.reset(), b.reset())
    assert_infos_equal(a.reset_infos, b.reset_infos)
    rng = np.random.default_rng(0)
    ends = {"terminated": 0, "truncated": 0}
    for _ in range(120):
        act = rng.uniform(-0.1, 0.6, (n, 2)).astype(np.float32)
        oa, ra, da, ia = a.step(act)
        ob, rb, db, ib = b.step(act)
        assert_close(oa, ob, "obs")
        assert_close(ra, rb, "reward")
        np.testing.assert_array_equal(da, db)
        assert_infos_equal(ia, ib)
        assert_infos_equal(a.reset_infos, b.reset_infos)
        for info, done in zip(ia, da, strict=True):
            if done:
                ends["truncated" if info["TimeLimit.truncated"] else "terminated"] += 1
    # the random actions must have exercised both kinds of episode end
    assert ends["terminated"] > 0 and ends["truncated"] > 0


def test_contract() -> None:
    n = 3
    a = AmigoBotSB3VecEnv(n, max_episode_steps=25)  # straight for 25 steps stays within 0.25 m
    assert isinstance(a, VecEnv) and a.num_envs == n
    assert a.observation_space.shape == (10,) and a.action_space.shape == (2,)
    a.seed(3)
    obs = np.asarray(a.reset())
    assert obs.shape == (n, 10) and obs.dtype == np.float32
    for t in range(1, 30):
        vobs, rew, done, infos = a.step(np.full((n, 2), 0.2, dtype=np.float32))  # straight: no turn
        obs = np.asarray(vobs)
        assert obs.shape == (n, 10) and rew.shape == (n,) and rew.dtype == np.float32
        assert done.shape == (n,) and done.dtype == np.bool_
        assert isinstance(infos, list) and len(infos) == n
        for i, info in enumerate(infos):
            assert isinstance(info["TimeLimit.truncated"], bool)
            assert ("terminal_observation" in info) == bool(done[i])
            if done[i]:
                term = info["terminal_observation"]
                assert term.shape == (10,) and not np.array_equal(term, obs[i])
                # the new episode starts at time 0 (its info went to reset_infos)
                assert a.reset_infos[i]["time"] == 0.0 and info["time"] > 0.0
        assert bool(done.all()) if t == 25 else not done.any()
    a.close()


def test_seeds_are_used_once_and_match_single_env() -> None:
    a = AmigoBotSB3VecEnv(2)
    a.seed(7)
    o1 = np.asarray(a.reset())
    o2 = np.asarray(a.reset())  # no pending seed: a new draw
    assert not np.array_equal(o1, o2)
    a.seed(7)
    np.testing.assert_array_equal(a.reset(), o1)
    single = gym.make("AmigoBot-v0")
    np.testing.assert_array_equal(single.reset(seed=8)[0], o1[1])  # env i gets seed + i


def test_pose_option_and_attributes() -> None:
    a = AmigoBotSB3VecEnv(2)
    pose = np.array([-0.08, 0.0, 0.0])
    a.set_options({"pose": pose})
    a.reset()
    for info in a.reset_infos:
        np.testing.assert_array_equal(info["pose"], pose)
        assert abs(info["cross_track_error"]) < 1e-12
    assert a.get_attr("params") == [a.params, a.params]
    assert a.env_is_wrapped(gym.Wrapper) == [False, False]
    with pytest.raises(ValueError, match="pose"):
        a.set_options({"bogus": 1})
        a.reset()


def test_vec_monitor_reports_episodes() -> None:
    m = VecMonitor(AmigoBotSB3VecEnv(2, max_episode_steps=5))
    m.seed(0)
    m.reset()
    episodes = []
    for _ in range(5):
        _, _, _, infos = m.step(np.full((2, 2), 0.27, dtype=np.float32))
        episodes += [i["episode"] for i in infos if "episode" in i]
    assert len(episodes) == 2 and all(e["l"] == 5 for e in episodes)


def test_bad_action_is_refused() -> None:
    a = AmigoBotSB3VecEnv(2)
    a.reset()
    with pytest.raises(ValueError, match="finite"):
        a.step(np.array([[np.nan, 0.0], [0.0, 0.0]]))
