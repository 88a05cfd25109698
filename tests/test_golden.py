"""Golden episodes: ``AmigoBot-v0`` keeps its observations, rewards and poses bit for bit.

``tests/data/golden_v0.npz`` was recorded by ``tests/data/make_golden.py`` from the code before the
refactors of issue 8 (commit 7a293c8); every later version must reproduce it exactly, in the single
environment and in the native vector environment, for fixed float64 action sequences and for the
analytic policy (whose float32 actions are recorded too).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym.policies import AnalyticPolicy

GOLDEN = Path(__file__).parent / "data" / "golden_v0.npz"
CONFIGS: dict[str, dict[str, Any]] = {
    "default": {},
    "manoeuvre_right_fine": {"path": "manoeuvre", "direction": -1, "dt": 0.05},
    "wide_fast": {"radius": 1.5, "speed": 0.3, "preview": (0.1, 0.3, 0.5)},
}
SEEDS = (0, 1, 7)
KINDS = ("noisy", "analytic")
TERMS = ("track", "speed", "heading", "smooth")
INFO_KEYS = ("pose", "h_position", "cross_track_error", "wheel_rates", "wheel_angles", "castor_angle", "time")


@pytest.fixture(scope="module")
def golden() -> dict[str, np.ndarray]:
    with np.load(GOLDEN) as d:
        return {k: d[k] for k in d.files}


def _same(got: Any, want: np.ndarray, what: str) -> None:
    got = np.asarray(got)
    assert got.dtype == want.dtype, what
    np.testing.assert_array_equal(got, want, err_msg=what, strict=True)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("config", list(CONFIGS))
def test_single_env_reproduces_golden(golden: dict[str, np.ndarray], config: str, seed: int, kind: str) -> None:
    key = f"{config}/{seed}/{kind}"
    env = gym.make("AmigoBot-v0", max_episode_steps=1000, **CONFIGS[config])
    policy = AnalyticPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
    actions = golden[f"{key}/action"]
    obs, info = env.reset(seed=seed)
    rows: dict[str, list[Any]] = {k: [info[k]] for k in INFO_KEYS}
    rows["obs"] = [obs]
    rows["reward_terms"] = [[info["reward_terms"][n] for n in TERMS]]
    rewards, terms = [], []
    for a in actions:
        if kind == "analytic":  # the policy still decodes the observation into the same action
            _same(policy.predict(obs)[0].astype(np.float64), a, f"{key} analytic action")
        obs, r, term, trunc, info = env.step(a)
        assert not trunc
        rewards.append(r)
        terms.append(term)
        rows["obs"].append(obs)
        for k in INFO_KEYS:
            rows[k].append(info[k])
        rows["reward_terms"].append([info["reward_terms"][n] for n in TERMS])
    _same(np.array(rewards, dtype=np.float64), golden[f"{key}/reward"], f"{key} reward")
    _same(np.array(terms, dtype=np.bool_), golden[f"{key}/terminated"], f"{key} terminated")
    for k, v in rows.items():
        _same(np.array(v), golden[f"{key}/{k}"], f"{key} {k}")


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("config", list(CONFIGS))
def test_vector_env_reproduces_golden(golden: dict[str, np.ndarray], config: str, kind: str) -> None:
    """The native vector env, one robot per seed, steps the same episodes (until the first one ends)."""
    keys = [f"{config}/{s}/{kind}" for s in SEEDS]
    n = min(len(golden[f"{k}/reward"]) for k in keys)
    envs = gym.make_vec("AmigoBot-v0", num_envs=len(SEEDS), autoreset_mode="Disabled", **CONFIGS[config])
    obs, info = envs.reset(seed=list(SEEDS))

    def check(t: int) -> None:
        for i, k in enumerate(keys):
            _same(obs[i], golden[f"{k}/obs"][t], f"{k} vector obs {t}")
            for name in INFO_KEYS:
                _same(info[name][i], golden[f"{k}/{name}"][t], f"{k} vector {name} {t}")
            got_terms = [info["reward_terms"][m][i] for m in TERMS]
            _same(np.array(got_terms), golden[f"{k}/reward_terms"][t], f"{k} vector reward terms {t}")

    check(0)
    for t in range(n):
        actions = np.stack([golden[f"{k}/action"][t] for k in keys])
        obs, reward, term, _trunc, info = envs.step(actions)
        for i, k in enumerate(keys):
            _same(reward[i], golden[f"{k}/reward"][t], f"{k} vector reward {t}")
            _same(term[i], golden[f"{k}/terminated"][t], f"{k} vector terminated {t}")
        check(t + 1)
    envs.close()
