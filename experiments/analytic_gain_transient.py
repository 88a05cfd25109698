"""Where the analytic controller's H error comes from, and what its feedback gain trades: on the validation cells,
per gain ``k`` [1/s], the mean over episodes of H's cross-track RMS over the whole episode, its first 5 s and after
10 s [mm], and the episodes ended early (terminated: |e| past the limit; the lane change's path also ends).

    python experiments/analytic_gain_transient.py [--seeds 10] [--gains 1 1.5 2]

Then the same on two training conditions with a 0.3 s delay (circle R 1 m at 0.2 m/s, figure-8 at 0.3 m/s, the
validation seeds), where a higher gain loses stability. Validation seeds only: no test cell or seed is run.
"""

from __future__ import annotations

import argparse
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.tools.training.protocol import VALIDATION_SEEDS, validation_cells


def errors(env_id: str, kwargs: dict[str, Any], seeds: tuple[int, ...], steps: int, gain: float) -> list[np.ndarray]:
    """H's cross-track error [m] per step of one deterministic episode per seed."""
    out = []
    for seed in seeds:
        env = gym.make(env_id, **kwargs)
        pol = AnalyticTrackingPolicy(env.unwrapped.params, gain=gain)  # type: ignore[attr-defined]
        obs, _ = env.reset(seed=seed)
        state, e = None, []
        for t in range(steps):
            a, state = pol.predict(obs, state, episode_start=np.array([t == 0]), deterministic=True)
            obs, _, terminated, truncated, info = env.step(a)
            e.append(info["cross_track_error"])
            if terminated or truncated:
                break
        out.append(np.asarray(e))
    return out


def row(name: str, gain: float, es: list[np.ndarray], steps: int, dt: float) -> str:
    def rms(part: slice) -> str:
        v = [float(np.sqrt(np.mean(x[part] ** 2))) for x in es if x[part].size]
        return f"{1e3 * np.mean(v):.2f}" if v else "–"

    early = sum(x.size < steps for x in es)
    return f"| {name} | {gain:g} | {rms(slice(None))} | {rms(slice(0, round(5 / dt)))} | " + (
        f"{rms(slice(round(10 / dt), None))} | {early} of {len(es)} |"
    )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--gains", type=float, nargs="+", default=[1.0, 1.5, 2.0])
    a = p.parse_args()
    print("| cell | k [1/s] | whole [mm] | first 5 s [mm] | after 10 s [mm] | ended early |")
    print("|---|---:|---:|---:|---:|---:|")
    for sc in validation_cells("AmigoBot-v1", a.seeds):
        for g in a.gains:
            print(row(sc.name, g, errors(sc.env_id, dict(sc.env_kwargs), sc.seeds, sc.max_steps, g), sc.max_steps, 0.1))
    delayed = {
        "circle R 1 m, 0.2 m/s, delay 0.3 s": {"path": "circle", "speed": 0.2},
        "figure-8, 0.3 m/s, delay 0.3 s": {"path": "figure8", "speed": 0.3},
    }
    for name, kw in delayed.items():
        kw = {**kw, "dt": 0.1, "randomize": {"delay": (0.3, 0.3)}}
        for g in a.gains:
            print(row(name, g, errors("AmigoBot-v1", kw, VALIDATION_SEEDS[: a.seeds], 400, g), 400, 0.1))


if __name__ == "__main__":
    main()
