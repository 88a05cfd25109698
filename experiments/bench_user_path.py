"""Step time of AmigoBot-v1 on a path from points (amigo_gym.paths.from_points) against the built-in family it was
sampled from, single env and native vector env, measured in the same run (docs/amigobot_v1.md quotes it).

    PYTHONPATH=. python experiments/bench_user_path.py [--steps 3000] [--n 64] [--repeats 5]

Prints, for each pair, the fit (points every 5 cm: the measured bound against the points, the length and the largest
curvature error against the family's exact path) and the median over repeats of the time per step [us] (single) and
per robot-step [us] (vector).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.paths import fit_points, make_family_path
from amigo_gym.task import v1 as tracking


def _single(kw: dict[str, Any], steps: int, repeats: int) -> float:
    env = gym.make("AmigoBot-v1", max_episode_steps=10**9, **kw).unwrapped
    rng = np.random.default_rng(0)
    acts = rng.uniform(0.2, 0.4, (steps, 2))
    times = []
    for _ in range(repeats):
        env.reset(seed=0)
        t0 = time.perf_counter()
        for a in acts:
            _, _, term, _, _ = env.step(a)
            if term:
                env.reset()
        times.append((time.perf_counter() - t0) / steps)
    return 1e6 * float(np.median(times))


def _vector(kw: dict[str, Any], n: int, steps: int, repeats: int) -> float:
    env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", **kw)
    acts = np.random.default_rng(0).uniform(0.2, 0.4, (steps, n, 2))
    times = []
    for _ in range(repeats):
        env.reset(seed=0)
        t0 = time.perf_counter()
        for a in acts:
            env.step(a)
        times.append((time.perf_counter() - t0) / (steps * n))
    return 1e6 * float(np.median(times))


def _samples(length: float, closed: bool) -> np.ndarray:
    """Arc lengths about 5 cm apart: a closed path's lap without its end (the start again), an open path's ends."""
    n = int(np.ceil(length / 0.05))
    return np.linspace(0.0, length, n, endpoint=False) if closed else np.linspace(0.0, length, n + 1)


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--steps", type=int, default=3000)
    p.add_argument("--n", type=int, default=64)
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()
    circle = make_family_path("circle", None, radius=1.0)
    rnd = tracking.random_pool_path(tracking.TrackingParams(path="random"), 3)
    pairs = {
        "circle R 1 m": ({"path": "circle", "radius": 1.0}, circle, True),
        "random path 3": ({"path": rnd}, rnd, False),
    }
    base = {"speed": 0.2, "randomize": "none"}
    for name, (_, ref, closed) in pairs.items():
        fit = fit_points(ref.point(_samples(ref.length, closed)), closed=closed)
        q = np.linspace(0.0, min(ref.length, fit.path.length), 20001)[:-1]
        dk = float(np.max(np.abs(fit.path.curvature(q) - ref.curvature(q))))
        print(
            f"fit {name}: {len(fit.point_s)} points, max point error {fit.max_error:.2g} m, length error "
            f"{fit.path.length - ref.length:.2g} m, max curvature error {dk:.2g} 1/m "
            f"(max |kappa| {ref.max_abs_curvature:.3g} 1/m), {len(fit.path.segments)} segments"
        )
    print(f"{'path':<16} {'built-in single':>16} {'points single':>14} {'built-in vec':>13} {'points vec':>11}  [us]")
    for name, (kw, ref, closed) in pairs.items():
        mine = fit_points(ref.point(_samples(ref.length, closed)), closed=closed).path
        mkw = {**base, "path": mine}
        bkw = {**base, **kw}
        cells = [
            _single(bkw, a.steps, a.repeats),
            _single(mkw, a.steps, a.repeats),
            _vector(bkw, a.n, a.steps // 10, a.repeats),
            _vector(mkw, a.n, a.steps // 10, a.repeats),
        ]
        print(f"{name:<16} {cells[0]:>16.1f} {cells[1]:>14.1f} {cells[2]:>13.2f} {cells[3]:>11.2f}")


if __name__ == "__main__":
    main()
