"""Record the golden episodes of ``AmigoBot-v1`` (tests/data/golden_v1.npz) for tests/test_golden_v1.py.

Run once from the repository root (``python tests/data/make_golden_v1.py``) on the code whose behaviour
is to be kept (the code the shipped v1 generalists were trained and benchmarked on); the test then
asserts that later code (e.g. faster kernels) reproduces every number within the stated tolerance
(tests/golden_compare.py). May import numpy and
amigo_gym.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.envs import AmigoBotV1Env
from amigo_gym.policies import AnalyticTrackingPolicy

#: name -> settings of gym.make("AmigoBot-v1")
CONFIGS: dict[str, dict[str, Any]] = {
    "circle": {},
    "mixed_hard": {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"},
    "lane_trapezoid": {"path": "lane_change", "speed_profile": "trapezoid", "profile_duration": 8.0, "dt": 0.05},
    "random_delay": {"path": "random", "speed": 0.3, "actuators": {"delay": 0.13}, "randomize": "mild"},
}
SEEDS = (0, 3)
STEPS = 80
INFO_KEYS = ("pose", "h_position", "cross_track_error", "progress", "speed", "wheel_rates", "command", "slip")


def episode(name: str, seed: int, kind: str) -> dict[str, np.ndarray]:
    env = AmigoBotV1Env(**CONFIGS[name])
    policy = AnalyticTrackingPolicy(env.params)
    rng = np.random.default_rng(500 + seed)
    obs, info = env.reset(seed=seed)
    rows: dict[str, list[Any]] = {k: [info[k]] for k in INFO_KEYS}
    rows["obs"] = [obs]
    rewards, actions = [], []
    state = None
    for t in range(STEPS):
        if kind == "analytic":
            a, state = policy.predict(obs[None, :], state, np.array([t == 0]))
            action = np.asarray(a[0], dtype=np.float64)
        else:
            action = rng.uniform(-1.2, 1.2, size=2)
        obs, r, term, _trunc, info = env.step(action)
        actions.append(action)
        rewards.append(r)
        rows["obs"].append(obs)
        for k in INFO_KEYS:
            rows[k].append(info[k])
        if term:
            break
    out = {k: np.asarray(v, dtype=np.float64) for k, v in rows.items()}
    out["actions"] = np.asarray(actions)
    out["rewards"] = np.asarray(rewards)
    return out


def record(path: Path) -> None:
    arrays: dict[str, np.ndarray] = {}
    for name in CONFIGS:
        for seed in SEEDS:
            for kind in ("noisy", "analytic"):
                for key, value in episode(name, seed, kind).items():
                    arrays[f"{name}/{seed}/{kind}/{key}"] = value
    np.savez_compressed(path, **arrays)


if __name__ == "__main__":
    record(Path(__file__).resolve().parent / "golden_v1.npz")
