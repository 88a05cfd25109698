"""Record the golden episodes of ``AmigoBot-v0`` (tests/data/golden_v0.npz) for tests/test_golden.py.

Run once from the repository root (``python tests/data/make_golden.py``) on the code whose
behaviour is to be kept; the test then asserts that later code reproduces every number within the stated tolerance
(tests/golden_compare.py).
Recorded at commit 7a293c8 (before the refactors of issue 8). May import numpy and amigo_gym.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.envs import AmigoBotEnv
from amigo_gym.policies import AnalyticPolicy

#: name -> settings of gym.make
CONFIGS: dict[str, dict[str, Any]] = {
    "default": {},
    "manoeuvre_right_fine": {"path": "manoeuvre", "direction": -1, "dt": 0.05},
    "wide_fast": {"radius": 1.5, "speed": 0.3, "preview": (0.1, 0.3, 0.5)},
}
SEEDS = (0, 1, 7)
#: steps per episode (fewer if it terminates); the manoeuvre at dt = 0.05 s needs 120 to reach the circle
STEPS = {"default": 60, "manoeuvre_right_fine": 160, "wide_fast": 60}
TERMS = ("track", "speed", "heading", "smooth")
INFO_KEYS = ("pose", "h_position", "cross_track_error", "wheel_rates", "wheel_angles", "castor_angle", "time")


def noisy_actions(env: AmigoBotEnv, seed: int, steps: int) -> np.ndarray:
    """float64 actions: noise around the straight roll, some beyond [-1, 1] (clipped by the env)."""
    rng = np.random.default_rng(1000 + seed)
    roll = env.params.speed / env.params.robot.r1 / env.params.robot.max_wheel_rate
    return roll + rng.uniform(-0.9, 0.9, size=(steps, 2))


def record(out: Path) -> None:
    arrays: dict[str, np.ndarray] = {}
    for name, kwargs in CONFIGS.items():
        for seed in SEEDS:
            for kind in ("noisy", "analytic"):
                env = AmigoBotEnv(**kwargs)
                policy = AnalyticPolicy(env.params)
                steps = STEPS[name]
                noisy = noisy_actions(env, seed, steps)
                obs, info = env.reset(seed=seed)
                rows: dict[str, list[Any]] = {k: [info[k]] for k in INFO_KEYS}
                rows["obs"] = [obs]
                rows["reward_terms"] = [[info["reward_terms"][n] for n in TERMS]]
                actions, rewards, terms = [], [], []
                for t in range(steps):
                    a = policy.predict(obs)[0] if kind == "analytic" else noisy[t]
                    obs, r, term, _trunc, info = env.step(a)
                    actions.append(np.asarray(a, dtype=np.float64))
                    rewards.append(r)
                    terms.append(term)
                    rows["obs"].append(obs)
                    for k in INFO_KEYS:
                        rows[k].append(info[k])
                    rows["reward_terms"].append([info["reward_terms"][n] for n in TERMS])
                    if term:
                        break
                key = f"{name}/{seed}/{kind}"
                arrays[f"{key}/action"] = np.array(actions)
                arrays[f"{key}/reward"] = np.array(rewards, dtype=np.float64)
                arrays[f"{key}/terminated"] = np.array(terms, dtype=np.bool_)
                for k, v in rows.items():
                    arrays[f"{key}/{k}"] = np.array(v)
    np.savez_compressed(out, **arrays)


if __name__ == "__main__":
    record(Path(__file__).with_name("golden_v0.npz"))
