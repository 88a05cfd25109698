"""How far AmigoBot-v1 is from AmigoBot-v0 in its closest configurations (issue 19, item 1; docs/architecture.md).

    PYTHONPATH=. python experiments/v0_as_v1.py [--seeds 5] [--steps 200] [--speed-only]

Steps ``AmigoBot-v0`` and ``AmigoBot-v1`` side by side on the same seeds and actions (random ones, and a smooth
proportional controller on v0's observation) and prints, per quantity, the largest difference in ulp of v0's scale
over the episode (tests/golden_compare.py's measure; the golden tolerance is 8), for three configurations of v1:

* ``ramps``: the closest one without the v0 options: the fastest ramps ``ActuatorParams`` allows (10 m/s^2,
  100 rad/s^2), no randomisation, wheels rolling at the start, v0's preview, the ``"circle"`` family;
* ``inf-ramps``: the same with infinite ramp rates (set past the validation: v1's own step with ideal actuators),
  which isolates the formulas: v1's quadrature of the arc and ``cos(beta)``, its clothoid projection of the
  circle, its smoothness scale;
* ``v0-config``: ``ideal_actuators=True, observation="v0", reward="v0"`` and ``path=CirclePath(...)``
  (tests/test_v0_as_v1.py).

Then the formula differences one by one on the same inputs (start pose, arc step, wheel rates, projection), and the
speed of the envs (:func:`speed`: v1 configured as v0 runs AmigoBot-v0's compiled step).
Observation fields are compared by v0's names (``curvature_ahead_i`` against v1's ``preview_curvature_<d>m``).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.model import fresnel
from amigo_gym.model.actuators import ActuatorParams, step_subintervals
from amigo_gym.model.kinematics import arc_step, body_velocity_of, wheel_rates_of
from amigo_gym.model.params import RobotParams
from amigo_gym.paths import CirclePath
from amigo_gym.paths.families import circle as family_circle
from amigo_gym.task import v0 as task_v0
from amigo_gym.task import v1 as tracking

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from golden_compare import relative_distance

COMMON: dict[str, Any] = {"randomize": "none", "start_at_rest": False, "preview": (0.2, 0.4), "speed": 0.2}


def v1_kwargs(config: str) -> dict[str, Any]:
    """The ``gym.make("AmigoBot-v1", ...)`` keywords of a configuration (module docstring)."""
    if config == "v0-config":
        return {**COMMON, "path": CirclePath(1.0), "ideal_actuators": True, "observation": "v0", "reward": "v0"}
    act = ActuatorParams(acceleration=10.0, deceleration=10.0, rot_acceleration=100.0, rot_deceleration=100.0)
    if config == "inf-ramps":
        for f in ("acceleration", "deceleration", "rot_acceleration", "rot_deceleration"):
            object.__setattr__(act, f, math.inf)  # past the validation: ideal actuators through v1's ramp code
        tracking.check_feasible = lambda p, path: {}  # (its report refuses an infinite ramp rate)
    return {**COMMON, "path": "circle", "actuators": act, "feasibility": "off", "kernel": "numpy"}


def action(pname: str, obs: Any, rng: np.random.Generator) -> Any:
    """Uniform random actions, or a smooth proportional controller on v0's observation (error, sin psi)."""
    if pname == "random":
        return rng.uniform(-1.0, 1.0, 2).astype(np.float32)
    w, d = 0.2 / 0.05 / 15.0, 0.15 * float(obs[0]) + 0.5 * float(obs[1])
    return np.array([1.1 * w - d, 0.9 * w + d], dtype=np.float32)


def measure(config: str, seeds: int, steps: int) -> dict[str, float]:
    """The largest ulp distance of each quantity over the seeds and both policies."""
    worst: dict[str, float] = {}
    for pname in ("random", "controller"):
        for seed in range(seeds):
            for k, u in episode_pair(config, seed, pname, steps).items():
                worst[k] = float(np.fmax(worst.get(k, 0.0), u))
    return worst


def episode_pair(config: str, seed: int, pname: str, steps: int) -> dict[str, float]:
    """Both envs stepped together (the actions of v0's observation), the ulp distance per quantity."""
    e0 = gym.make("AmigoBot-v0", max_episode_steps=10**6).unwrapped
    e1 = gym.make("AmigoBot-v1", max_episode_steps=10**6, **v1_kwargs(config)).unwrapped
    names1 = [
        n.replace("preview_curvature_0.2m", "curvature_ahead_1").replace("preview_curvature_0.4m", "curvature_ahead_2")
        for n in tracking.obs_fields(e1.params)
    ]
    names0 = task_v0.obs_names(e0.params)
    want: dict[str, list[Any]] = {}
    got: dict[str, list[Any]] = {}

    def add(rec: dict[str, list[Any]], names: list[str], obs: Any, info: dict[str, Any], reward: Any) -> None:
        for k in ("pose", "h_position", "wheel_rates"):
            rec.setdefault(k, []).append(np.asarray(info[k], dtype=np.float64))
        rec.setdefault("cross_track_error", []).append(float(info["cross_track_error"]))
        for k, v in info["reward_terms"].items():
            rec.setdefault(k, []).append(float(v))
        if reward is not None:
            rec.setdefault("reward", []).append(float(reward))
        for n in names0:
            rec.setdefault("obs." + n, []).append(obs[names.index(n)] if n in names else np.float32(np.nan))

    o0, i0 = e0.reset(seed=seed)
    o1, i1 = e1.reset(seed=seed)
    add(want, names0, o0, i0, None)
    add(got, names1, o1, i1, None)
    rng = np.random.default_rng(seed + 1000)
    for _ in range(steps):
        a = action(pname, o0, rng)
        o0, r0, t0, _, i0 = e0.step(a)
        o1, r1, t1, _, i1 = e1.step(a)
        add(want, names0, o0, i0, r0)
        add(got, names1, o1, i1, r1)
        if t0 or t1:
            break
    w = {k: np.array(v) for k, v in want.items()}
    g = {k: np.array(v) for k, v in got.items()}
    return relative_distance(g, w)


def formulas(n: int = 2000) -> list[str]:
    """The differences of the single formulas on the same inputs (ulp of the scale named)."""
    rng = np.random.default_rng(0)
    robot = RobotParams()
    out = []
    e0 = gym.make("AmigoBot-v0").unwrapped
    e1 = gym.make("AmigoBot-v1", kernel="numpy", **COMMON).unwrapped
    p0 = np.array([e0.reset(seed=s)[1]["pose"] for s in range(200)])
    p1 = np.array([e1.reset(seed=s)[1]["pose"] for s in range(200)])
    out.append(f"start pose, 200 seeds: bits equal {np.array_equal(p0, p1)}")
    x, y, b = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(-4, 4, n)
    w = rng.uniform(-1, 1, (n, 2)) * robot.max_wheel_rate
    v, bd = body_velocity_of(w[:, 0], w[:, 1], robot.r1, robot.r2, 2 * robot.l1)
    arc = arc_step(x, y, b, v, bd, 0.1)
    ns = step_subintervals(0.1, robot)
    fx, fy, fb = fresnel.advance(x, y, b, v, 0.0 * v, bd, 0.0 * v, 0.1, ns)

    def u(got: Any, want: Any, scale: float) -> float:
        return float(np.max(np.abs(np.asarray(got) - np.asarray(want))) / np.spacing(scale))

    out.append(
        f"arc step (v0, tan half-angles) vs fresnel.advance (v1, Gauss-Legendre, n_sub={ns}), {n} states: "
        f"x {u(fx, arc.x, 1.0):.3g}, y {u(fy, arc.y, 1.0):.3g} ulp of 1 m, beta {u(fb, arc.beta, 4.0):.3g} ulp of 4 rad"
    )
    out.append(f"cos beta' by angle addition (v0) vs np.cos (v1): {u(np.cos(fb), arc.cos_beta, 1.0):.3g} ulp of 1")
    w1n, w2n = wheel_rates_of(v, bd, robot.l1, robot.r1, robot.r2)
    out.append(
        f"wheel rates a w_max (v0) vs the nominal inverse of their (v, w) (v1): {u(w1n, w[:, 0], 15.0):.3g}, "
        f"{u(w2n, w[:, 1], 15.0):.3g} ulp of 15 rad/s"
    )
    c0, c1 = CirclePath(1.0), family_circle(radius=1.0, direction=1)
    phi, rad = rng.uniform(0, 2 * np.pi, n), 1.0 + rng.uniform(-0.25, 0.25, n)
    hx, hy = rad * np.sin(phi), 1.0 - rad * np.cos(phi)
    cp = c0.project_xy(hx, hy)
    loc = c1.locate(hx, hy, phi * 1.0, 0.5, 0.5)
    out.append(
        "projection on the unit circle, CirclePath (v0) vs the circle family's ClothoidPath (v1): e "
        f"{u(loc.cross_track_error, cp.cross_track_error, 1.0):.3g} ulp of 1 m, cos theta "
        f"{u(loc.cos_theta, cp.cos_theta, 1.0):.3g}, sin theta {u(loc.sin_theta, cp.sin_theta, 1.0):.3g} ulp of 1"
    )
    return out


def speed(steps: int = 3000, n: int = 4096) -> list[str]:
    """The speed of AmigoBot-v0 and of AmigoBot-v1 configured as v0, on its two routes (AmigoBot-v0's compiled step,
    ``kernel="auto"``, and the reference, ``kernel="numpy"``), and of AmigoBot-v1's defaults, with the machine's load.

    Single env: time per step [us], resets excluded (each step timed alone; best of 5 runs of ``steps`` actions
    around the steady state's, the last two alternating between the envs). Vector env of ``n`` robots
    (``vector_entry_point``, autoreset in the step): robot-steps per second, median of 3 runs of at least 0.5 s, the
    two envs alternating.
    """
    import os
    import statistics
    import time

    from amigo_gym.tools.machine import machine_line

    clock = time.perf_counter_ns
    acts = (0.27 + 0.1 * np.random.default_rng(0).uniform(-1.0, 1.0, (steps, 2))).astype(np.float32)

    def run(env: Any) -> float:
        env.reset(seed=0)
        total = 0
        for a in acts:
            t = clock()
            ended = env.step(a)[2]
            total += clock() - t
            if ended:
                env.reset()
        return total / steps / 1e3

    v0_config = v1_kwargs("v0-config")
    single = {
        name: gym.make(env_id, **kw).unwrapped
        for name, env_id, kw in (
            ("AmigoBot-v0", "AmigoBot-v0", {}),
            ("AmigoBot-v1 as v0 (v0's compiled step)", "AmigoBot-v1", v0_config),
            ("AmigoBot-v1 as v0 (reference step)", "AmigoBot-v1", {**v0_config, "kernel": "numpy"}),
            ("AmigoBot-v1", "AmigoBot-v1", {}),
        )
    }
    times = {name: min(run(env) for _ in range(3)) for name, env in single.items()}  # warm-up and best
    for _ in range(2):  # the envs alternating, so that a busy moment does not hit one of them only
        times = {name: min(times[name], run(env)) for name, env in single.items()}
    lines = [
        f"{machine_line()}, load average {os.getloadavg()[0]:.2f} (1 min)",
        "single env, us per step: " + ", ".join(f"{name} {t:.1f}" for name, t in times.items()),
    ]
    vec = {
        name: gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kw)
        for name, env_id, kw in (("AmigoBot-v0", "AmigoBot-v0", {}), ("AmigoBot-v1 as v0", "AmigoBot-v1", v0_config))
    }
    batch = [np.broadcast_to(a, (n, 2)).copy() for a in acts[:16]]
    rates: dict[str, list[float]] = {name: [] for name in vec}
    for env in vec.values():
        env.reset(seed=0)
        for a in batch:
            env.step(a)
    for _ in range(3):
        for name, env in vec.items():
            k = 0
            t0 = time.perf_counter()
            while (elapsed := time.perf_counter() - t0) < 0.5:
                env.step(batch[k % 16])
                k += 1
            rates[name].append(k * n / elapsed)
    lines.append(
        f"vector env, N = {n}, M robot-steps/s: "
        + ", ".join(f"{name} {statistics.median(r) / 1e6:.2f}" for name, r in rates.items())
    )
    lines.append(f"load average {os.getloadavg()[0]:.2f} (1 min) after")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5, help="seeds per policy (default 5)")
    ap.add_argument("--steps", type=int, default=200, help="steps per episode at most (default 200)")
    ap.add_argument("--speed-only", action="store_true", help="only the speed of the envs (about 10 s)")
    a = ap.parse_args()
    if a.speed_only:
        print("\n".join(speed()))
        return
    for config in ("ramps", "inf-ramps", "v0-config"):
        worst = measure(config, a.seeds, a.steps)
        print(f"{config}: largest |v1 - v0| in ulp of v0's scale (tolerance 8)")
        print("  " + ", ".join(f"{k} {v:.3g}" for k, v in worst.items()))
    for line in formulas():
        print(line)
    print("\n".join(speed()))


if __name__ == "__main__":
    main()
