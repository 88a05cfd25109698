"""How far below the analytic controller a controller can get under actuation delay when it knows the future exactly:
the analytic controller fed the observation the robot will have when its command takes effect (a Smith predictor
whose model is the simulator itself), on the validation delay conditions, per gain ``k`` [1/s].

    python experiments/oracle_delay.py [--seeds 20] [--gains 1 1.5 2 3]

The oracle steps a deep copy of the env ``floor(delay / dt)`` steps ahead (holding the last command; a command
issued now acts only after the delay, so the copy's state then is exact, its draws included) and gives the
analytic policy that observation. Rows: mean H cross-track RMS over the episodes [mm] and its ratio to the plain
analytic controller at the first gain (``k = 1``, issue 36's reference), for the plain controller, the oracle, and
the same cell without delay (``randomize="none"``). Conditions: the validation cells ``val_delay_0.1`` and
``val_delay_0.25``, and the two 0.3 s conditions of ``experiments/analytic_gain_transient.py`` on the validation
seeds: no test cell or seed is run.
"""

from __future__ import annotations

import argparse
import copy
import math
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.protocol import VALIDATION_SEEDS, validation_cells


def h_rms(env_id: str, kwargs: dict[str, Any], seed: int, steps: int, gain: float, ahead: int) -> tuple[float, bool]:
    """H's cross-track RMS [m] of one deterministic episode and whether it ended early; ``ahead`` steps of oracle."""
    env = gym.make(env_id, **kwargs)
    u = env.unwrapped
    pol = AnalyticTrackingPolicy(u.params, gain=gain)  # type: ignore[attr-defined]
    obs, _ = env.reset(seed=seed)
    state, e, a = None, [], np.zeros(2, dtype=np.float32)
    for t in range(steps):
        seen = obs
        if ahead:
            sim = copy.deepcopy(u)
            for _ in range(ahead):
                seen = sim.step(a)[0]
        a, state = pol.predict(seen, state, episode_start=np.array([t == 0]), deterministic=True)
        obs, _, terminated, truncated, info = env.step(a)
        e.append(info["cross_track_error"])
        if terminated or truncated:
            break
    return float(np.sqrt(np.mean(np.square(e)))), len(e) < steps


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--gains", type=float, nargs="+", default=[1.0, 1.5, 2.0, 3.0])
    a = p.parse_args()
    cells = {sc.name: sc for sc in validation_cells("AmigoBot-v1", a.seeds)}
    conditions = [
        (n, cells[n].env_kwargs, cells[n].seeds, cells[n].max_steps) for n in ("val_delay_0.1", "val_delay_0.25")
    ]
    for name, kw in (("circle R 1 m, 0.2 m/s", {"path": "circle", "speed": 0.2}),
                     ("figure-8, 0.3 m/s", {"path": "figure8", "speed": 0.3})):  # fmt: skip
        kw = {**kw, "dt": 0.1, "randomize": {"delay": (0.3, 0.3)}}  # as experiments/analytic_gain_transient.py
        conditions.append((f"{name}, delay 0.3 s", kw, VALIDATION_SEEDS[: a.seeds], 400))
    print(machine_line())
    print("| condition | controller | k [1/s] | H RMS [mm] | / plain k = 1 | ended early |")
    print("|---|---|---:|---:|---:|---:|")
    for name, kw, seeds, steps in conditions:
        delay = kw["randomize"]["delay"][0]
        ahead = math.floor(delay / kw["dt"] + 1e-9)
        ideal = {**kw, "randomize": "none"}
        base = None
        for label, kwargs, look in (("plain", kw, 0), ("oracle", kw, ahead), ("no delay", ideal, 0)):
            for g in a.gains:
                runs = [h_rms("AmigoBot-v1", dict(kwargs), s, steps, g, look) for s in seeds]
                mean = 1e3 * float(np.mean([r[0] for r in runs]))
                base = mean if base is None else base
                early = sum(r[1] for r in runs)
                print(
                    f"| {name} | {label} | {g:g} | {mean:.2f} | {mean / base:.2f} | {early} of {len(runs)} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
