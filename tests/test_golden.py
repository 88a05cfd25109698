"""Golden episodes: ``AmigoBot-v0`` keeps its observations, rewards and poses.

``tests/data/golden_v0.npz`` was recorded by ``tests/data/make_golden.py`` from the code before the
refactors of issue 8 (commit 7a293c8, on an AVX-512 CPU); every later version must reproduce it, in the
single environment and in the native vector environment, for fixed float64 action sequences and for the
analytic policy (whose float32 actions are recorded too). Across machines the comparison allows a few
ulps of each quantity's scale (tests/golden_compare.py says why and how much), and so does the vector
env against the single envs (test_vector_env_reproduces_golden).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from golden_compare import mismatch, mismatches

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


def _close(got: Any, want: np.ndarray, what: str) -> None:
    """Within the portable tolerance of tests/golden_compare.py (the scale: the whole recorded episode)."""
    line = mismatch(what, got, want)
    assert line is None, line


def _recorded(golden: dict[str, np.ndarray], key: str, steps: int | None = None) -> dict[str, np.ndarray]:
    """The recorded episode ``key`` (its first ``steps`` steps if given), by quantity."""
    out = {}
    for name in ("reward", "terminated", "obs", "reward_terms", *INFO_KEYS):
        v = golden[f"{key}/{name}"]
        out[name] = v if steps is None else v[: steps + (name not in ("reward", "terminated"))]
    return out


def single_episode(config: str, seed: int, actions: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """One episode of ``gym.make`` driven by ``actions``: its quantities, and the analytic policy's actions."""
    env = gym.make("AmigoBot-v0", max_episode_steps=1000, **CONFIGS[config])
    policy = AnalyticPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
    obs, info = env.reset(seed=seed)
    rows: dict[str, list[Any]] = {k: [info[k]] for k in INFO_KEYS}
    rows["obs"] = [obs]
    rows["reward_terms"] = [[info["reward_terms"][n] for n in TERMS]]
    rewards, terms, decoded = [], [], []
    for a in actions:
        decoded.append(policy.predict(obs)[0])
        obs, r, term, trunc, info = env.step(a)
        assert not trunc
        rewards.append(r)
        terms.append(term)
        rows["obs"].append(obs)
        for k in INFO_KEYS:
            rows[k].append(info[k])
        rows["reward_terms"].append([info["reward_terms"][n] for n in TERMS])
    out = {k: np.array(v) for k, v in rows.items()}
    out["reward"] = np.array(rewards, dtype=np.float64)
    out["terminated"] = np.array(terms, dtype=np.bool_)
    return out, np.array(decoded)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("config", list(CONFIGS))
def test_single_env_reproduces_golden(golden: dict[str, np.ndarray], config: str, seed: int, kind: str) -> None:
    key = f"{config}/{seed}/{kind}"
    actions = golden[f"{key}/action"]
    got, decoded = single_episode(config, seed, actions)
    problems = mismatches(got, _recorded(golden, key))
    if kind == "analytic":  # the policy still decodes the observation into the same (float32) action
        line = mismatch("analytic action", decoded, actions.astype(np.float32))
        problems += [line] if line else []
    assert not problems, f"{key}: " + "; ".join(problems)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("config", list(CONFIGS))
def test_vector_env_reproduces_golden(golden: dict[str, np.ndarray], config: str, kind: str) -> None:
    """The native vector env, one robot per seed, steps the same episodes (until the first one ends).

    Against the recording and against single envs stepped with the same actions: the stated tolerance.
    """
    keys = [f"{config}/{s}/{kind}" for s in SEEDS]
    n = min(len(golden[f"{k}/reward"]) for k in keys)
    envs = gym.make_vec("AmigoBot-v0", num_envs=len(SEEDS), autoreset_mode="Disabled", **CONFIGS[config])
    obs, info = envs.reset(seed=list(SEEDS))
    rows: list[dict[str, list[Any]]] = [{} for _ in keys]

    def record(obs: np.ndarray, info: dict[str, Any], reward: Any = None, term: Any = None) -> None:
        for i, row in enumerate(rows):
            row.setdefault("obs", []).append(obs[i])
            for name in INFO_KEYS:
                row.setdefault(name, []).append(info[name][i])
            row.setdefault("reward_terms", []).append([info["reward_terms"][m][i] for m in TERMS])
            if reward is not None:
                row.setdefault("reward", []).append(reward[i])
                row.setdefault("terminated", []).append(term[i])

    record(obs, info)
    for t in range(n):
        actions = np.stack([golden[f"{k}/action"][t] for k in keys])
        obs, reward, term, _trunc, info = envs.step(actions)
        record(obs, info, reward, term)
    envs.close()
    for seed, key, row in zip(SEEDS, keys, rows, strict=True):
        got = {name: np.array(v) for name, v in row.items()}
        problems = mismatches(got, _recorded(golden, key, n))
        assert not problems, f"{key} vector: " + "; ".join(problems)
        single, _ = single_episode(config, seed, golden[f"{key}/action"][:n])
        problems = mismatches(got, {name: np.asarray(v) for name, v in single.items()})
        assert not problems, f"{key} vector against single: " + "; ".join(problems)
