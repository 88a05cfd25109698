"""The published random-path protocol (Cao et al., Sensors 2024, 24(2), 561) on AmigoBot-v1; a textbook pure pursuit.

Protocol, from the authors' code (github.com/cao-yu/Path-Following-for-Autonomous-Mobile-Robots-with-Deep-
Reinforcement-Learning: param_fcn.py RandPath, reference_path.py ArcReferencePath, kinematics.py Unicycle,
pure_pursuit/control_law_arc.py, pure_pursuit/performance/plot_performance.py, whose failure_rate.npy holds 0.276
at 0.2 m/s and 0.1 m; results/random_paths/NOTES.md has the table of sources):

* path: 5 waypoints from (0, 0), 4 legs of length U(0.5, 2) m in direction U[0, 2 pi); a natural cubic spline through
  them in a parameter spaced evenly over the polyline's length; redrawn while |curvature| > 50 1/m at 200 samples;
  then re-splined (natural) in arc length through 200 samples. One RandomState(100) stream for the 1000 paths.
* robot: unicycle at the axle midpoint, dt 0.05 s (Euler), v and omega taken at once (v clipped to [0, 0.4] m/s,
  omega to +-1 rad/s); start: the same offset for every path (the model is reseeded with 100 each run):
  x, y += U(-0.1, 0.1) m, heading = path heading + U(-5 deg, 0.1 deg) (a typo of the code: deg2rad(DEFAULT_X)).
* pure pursuit: goal at arc length d = 0.2 m ahead of the closest point, omega = 2 v sin(alpha) / L_d, L_d the
  distance to the goal; constant v.
* episode: 400 steps (20 s), or until less than 2 cm of arc length is left. Failure at tolerance e_tol: |cte| >= e_tol
  at any step (checked after each step); tolerances 0.1, 0.2, 0.3 m, one run each.

Here: the paths are sampled every 1 cm and fitted by ``amigo_gym.paths.from_points``; the robot is AmigoBot-v1
(``gym.make``) with the paper's start pose (``reset(options={"pose": ...})``). Conditions: ``paper`` (ideal
actuators, rolling start, dt 0.05 s) and ``firmware`` (AmigoBot-v1's defaults: firmware ramps, start at rest,
dt 0.1 s). The pure pursuit preset tracks the axle midpoint A: a nominal robot with ``l3`` = 1 mm puts H (the point the
env measures and observes from) on A. The analytic controller runs on AmigoBot's geometry (``l3`` = 0.08 m) and
is judged on its point H.

    PYTHONPATH=$PWD python experiments/random_paths.py [--paths 1000] [--generator paper|numpy] [--seed 100]
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np
from scipy.interpolate import CubicSpline

import amigo_gym  # noqa: F401  (registers AmigoBot-v1)
from amigo_gym.model.params import RobotParams
from amigo_gym.paths import from_points
from amigo_gym.policies import AnalyticTrackingPolicy, PurePursuitPolicy
from amigo_gym.task import v1 as _task
from amigo_gym.tools.machine import machine_line

# The env's feasibility report at construction analyses H's heading lag at the nominal robot's l3: at l3 = 1 mm
# (the preset's robot, H on A) that takes ~1.3 s per path and answers nothing asked here. Both agents' envs are
# reported with AmigoBot's geometry (l3 = 0.08 m), the question "does AmigoBot-v1 accept this path".
_feasibility = _task._feasibility
_task._feasibility = lambda path, v, robot, rot: _feasibility(path, v, dataclasses.replace(robot, l3=0.08), rot)


@dataclass(frozen=True)
class Settings:
    paths: int = 1000
    seed: int = 100  # the paper's stream: RandomState(100); generator="numpy" draws fresh paths from default_rng(seed)
    generator: str = "paper"
    speed: float = 0.2  # [m/s]
    tolerances: tuple[float, ...] = (0.1, 0.2, 0.3)  # [m]
    duration: float = 20.0  # [s]
    goal: float = 0.02  # [m] left to the end: success
    lookahead: float = 0.2  # [m] the preset's d
    max_turn_rate: float = 1.0  # [rad/s] the paper's omega clip
    start_seed: int = 100  # the paper's Unicycle seed: one start offset for every path
    spacing: float = 0.01  # [m] sample spacing handed to from_points
    conditions: tuple[str, ...] = ("paper", "firmware")
    out: str = "experiments/results/random_paths"


# --- (a) the path generator ----------------------------------------------------------------------------------
def _natural(s, v):
    return CubicSpline(s, v, bc_type=((2, 0.0), (2, 0.0)))


def draw_waypoints(rng, legs=(4, 4), leg=(0.5, 2.0), max_curvature=50.0):
    """Waypoints and the spline of one path; ``rng`` a RandomState (the authors' exact calls) or a Generator."""
    legacy = isinstance(rng, np.random.RandomState)
    while True:
        n = rng.randint(legs[0], legs[1] + 1) if legacy else rng.integers(legs[0], legs[1] + 1)
        x, y = [0.0], [0.0]
        for _ in range(n):
            d, th = rng.uniform(*leg), 2 * np.pi * (rng.rand() if legacy else rng.random())
            x.append(x[-1] + d * np.cos(th))
            y.append(y[-1] + d * np.sin(th))
        x, y = np.array(x), np.array(y)
        s = np.linspace(0.0, np.hypot(np.diff(x), np.diff(y)).sum(), len(x))
        fx, fy = _natural(s, x), _natural(s, y)
        u = np.linspace(0.0, s[-1], 200)
        dx, dy, ddx, ddy = fx(u, 1), fy(u, 1), fx(u, 2), fy(u, 2)
        if np.all(np.abs((ddy * dx - ddx * dy) / (dx**2 + dy**2) ** 1.5) <= max_curvature):
            return np.column_stack([x, y]), fx, fy, s[-1]


def arc_points(fx, fy, length, spacing):
    """The authors' arc-length re-spline (200 samples; arc length by 8-point Gauss per interval, their quad to
    ~1e-12), sampled every ``spacing``; returns the points and the largest |curvature| [1/m]."""
    u = np.linspace(0.0, length, 200)
    g, w = np.polynomial.legendre.leggauss(8)
    a, b = u[:-1, None], u[1:, None]
    t = (a + b) / 2 + (b - a) / 2 * g
    seg = ((b - a)[:, 0] / 2) * (np.hypot(fx(t, 1), fy(t, 1)) @ w)
    arc = np.concatenate([[0.0], np.cumsum(seg)])
    X, Y = _natural(arc, fx(u)), _natural(arc, fy(u))
    s = np.linspace(0.0, arc[-1], math.ceil(arc[-1] / spacing) + 1)
    k = (Y(s, 2) * X(s, 1) - X(s, 2) * Y(s, 1)) / (X(s, 1) ** 2 + Y(s, 1) ** 2) ** 1.5
    return np.column_stack([X(s), Y(s)]), float(np.abs(k).max())


def generate(st: Settings):
    rng = np.random.RandomState(st.seed) if st.generator == "paper" else np.random.default_rng(st.seed)
    for _ in range(st.paths):
        wp, fx, fy, length = draw_waypoints(rng)
        pts, kmax = arc_points(fx, fy, length, st.spacing)
        yield wp, pts, kmax


def paper_start(st: Settings, heading: float):
    """Pose of A: the authors' Unicycle.reset(flag='random') with the model seeded by ``start_seed``."""
    r = np.random.RandomState(st.start_seed)
    x, y = r.uniform(-0.1, 0.1), r.uniform(-0.1, 0.1)
    return float(x), float(y), float(heading + r.uniform(-np.deg2rad(5.0), np.deg2rad(0.1)))


# --- (b) the runner --------------------------------------------------------------------------------------------
def env_kwargs(st: Settings, condition: str, point_at_axle: bool) -> dict:
    dt = 0.05 if condition == "paper" else 0.1
    kw = dict(
        speed=st.speed,
        dt=dt,
        feasibility="off",
        goal_tolerance=st.goal,
        termination_distance=max(st.tolerances) + 0.01,  # past the largest tolerance nothing more is learnt
        max_episode_steps=round(st.duration / dt),
        preview=(st.lookahead, 0.5, 1.0),
    )
    if condition == "paper":
        kw.update(ideal_actuators=True, start_at_rest=False)
    if point_at_axle:
        kw["robot"] = RobotParams(l3=1e-3)
    return kw


def pure_pursuit_preset(params, st: Settings) -> PurePursuitPolicy:
    """(c) The textbook preset (:meth:`PurePursuitPolicy.textbook`: Coulter's arc from A to the point d = 0.2 m along
    the path ahead of the closest point, omega = 2 v sin(alpha) / L_d, |omega| <= 1 rad/s), or the variant that other
    ``--lookahead`` / ``--max-turn-rate`` give; on a nominal robot with l3 = 1 mm."""
    if (st.lookahead, st.max_turn_rate) == (0.2, 1.0):
        return PurePursuitPolicy.textbook(params)
    return PurePursuitPolicy(params, lookahead=st.lookahead, origin="axle", max_turn_rate=st.max_turn_rate)


def run_episode(env, policy, pose):
    obs, info = env.reset(seed=0, options={"pose": pose})
    peak, steps = 0.0, 0
    policy_state = None
    while True:
        act, policy_state = policy.predict(obs, policy_state, episode_start=(steps == 0))
        obs, _, term, trunc, info = env.step(act)
        steps += 1
        peak = max(peak, abs(info["cross_track_error"]))
        if term or trunc:
            return peak, steps, info.get("end_condition", "") or ("time" if trunc else "")


def wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    if n == 0:
        return (float("nan"), float("nan"))
    p, d = k / n, 1 + z * z / n
    c, h = (p + z * z / (2 * n)) / d, z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


PUBLISHED = (0.276, 0.053, 0.002)  # the authors' failure_rate.npy[2]: 0.2 m/s, tolerances 0.1/0.2/0.3 m
#: name: (runs on the 1 mm robot, H on A; the policy from the env's settings)
AGENTS = {
    "pure_pursuit_cao2024": (True, pure_pursuit_preset),
    "analytic": (False, lambda p, st: AnalyticTrackingPolicy(p)),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--paths", type=int, default=Settings.paths)
    ap.add_argument("--generator", choices=("paper", "numpy"), default="paper")
    ap.add_argument("--seed", type=int, default=Settings.seed)
    ap.add_argument("--out", default=Settings.out)
    ap.add_argument("--replot", metavar="JSON", help="only redraw the plot of a results file")
    a = ap.parse_args()
    if a.replot:
        doc = json.loads(Path(a.replot).read_text())
        st = Settings(**{k: tuple(v) if isinstance(v, list) else v for k, v in doc["settings"].items()})
        by_curvature(st, doc["episodes"])
        return plot(st, doc["summary"], Path(a.replot).with_suffix(".png"))
    st = Settings(paths=a.paths, generator=a.generator, seed=a.seed, out=a.out)
    print(machine_line(), flush=True)
    t0 = time.time()
    paths = list(generate(st))
    print(f"{len(paths)} paths generated in {time.time() - t0:.1f} s", flush=True)
    rows, skipped = [], []  # rows: one per (path, condition, agent)
    for i, (_wp, pts, kmax) in enumerate(paths):
        try:
            path, step = from_points(pts), 0.02
        except ValueError:  # the sharpest corners (|k| ~ 50 1/m) need finer clothoid steps to stay within 1 mm
            try:
                path, step = from_points(pts, step=0.005), 0.005
            except ValueError as e:  # a cusp between the 200 samples the protocol checks: not a path to drive
                print(f"path {i} skipped: {e}", flush=True)
                skipped.append(i)
                continue
        pose = paper_start(st, float(path.pose_columns(0.0).theta))
        for cond in st.conditions:
            for name, (axle, make) in AGENTS.items():
                env = gym.make("AmigoBot-v1", path=path, **env_kwargs(st, cond, axle))
                feas = bool(env.unwrapped.feasibility["feasible"])
                pol = make(env.unwrapped.params, st)
                peak, steps, end = run_episode(env, pol, pose)
                env.close()
                rows.append(
                    dict(
                        path=i,
                        condition=cond,
                        agent=name,
                        peak=peak,
                        steps=steps,
                        end=end,
                        feasible=feas,
                        length=float(path.length),
                        max_curvature=kmax,
                        fit_step=step,
                    )
                )
        if (i + 1) % 25 == 0 or i + 1 == len(paths):
            done = [r for r in rows if r["agent"] == "pure_pursuit_cao2024" and r["condition"] == "paper"]
            f = np.mean([r["peak"] >= st.tolerances[0] for r in done])
            print(
                f"{i + 1}/{len(paths)} paths, {time.time() - t0:.0f} s; preset (paper) fails {f:.1%} at "
                f"{st.tolerances[0]} m so far",
                flush=True,
            )
    summary = summarise(st, rows)
    by_curvature(st, rows)
    out = Path(st.out)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"{st.generator}{st.seed}_{st.paths}"
    accepted = {
        c: sum(r["feasible"] for r in rows if r["condition"] == c and r["agent"] == "analytic") for c in st.conditions
    }
    print(f"paths AmigoBot-v1's feasibility check accepts: {accepted} of {len(paths) - len(skipped)} fitted")
    pp = next(r for r in summary if r["agent"] == "pure_pursuit_cao2024" and r["condition"] == "paper")
    print(
        f"preset, paper's conditions, {pp['tolerance']} m: {pp['rate']:.1%} against the published {PUBLISHED[0]:.1%}"
        f" ({100 * (pp['rate'] - PUBLISHED[0]):+.1f} points)"
    )
    for r in rows:  # compact: 4 conditions x agents x paths rows
        r["peak"], r["length"], r["max_curvature"] = (round(r[k], 5) for k in ("peak", "length", "max_curvature"))
    doc = dict(
        settings=dataclasses.asdict(st),
        machine=machine_line(),
        runtime_s=round(time.time() - t0, 1),
        start_pose_offset=paper_start(st, 0.0),
        published=dict(zip(map(str, st.tolerances), PUBLISHED, strict=True)),
        accepted=accepted,
        skipped=skipped,
        summary=summary,
        episodes=rows,
    )
    (out / f"random_paths_{tag}.json").write_text(json.dumps(doc, separators=(",", ":")))
    plot(st, summary, out / f"random_paths_{tag}.png")
    print(f"wrote {out}/random_paths_{tag}.json and .png; {time.time() - t0:.0f} s")


def summarise(st: Settings, rows: list[dict]) -> list[dict]:
    res = []
    print(f"\n{'agent':22} {'condition':9} {'paths':>10} {'tol':>5}  failure [95% Wilson]   (feasible paths only)")
    for name in AGENTS:
        for cond in st.conditions:
            sel = [r for r in rows if r["agent"] == name and r["condition"] == cond]
            ok = [r for r in sel if r["feasible"]]
            for tol in st.tolerances:
                k, kf = sum(r["peak"] >= tol for r in sel), sum(r["peak"] >= tol for r in ok)
                lo, hi = wilson(k, len(sel))
                flo, fhi = wilson(kf, len(ok))
                rec = dict(
                    agent=name,
                    condition=cond,
                    tolerance=tol,
                    n=len(sel),
                    failures=k,
                    rate=k / len(sel),
                    ci95=(lo, hi),
                    feasible=len(ok),
                    failures_feasible=kf,
                    rate_feasible=kf / len(ok) if ok else float("nan"),
                    ci95_feasible=(flo, fhi),
                )
                res.append(rec)
                print(
                    f"{name:22} {cond:9} {len(sel):>5} {tol:>9.1f}  {k / len(sel):6.1%} [{lo:.1%}, {hi:.1%}]"
                    f"   ({len(ok)} feasible: {rec['rate_feasible']:.1%} [{flo:.1%}, {fhi:.1%}])"
                )
    return res


#: bins of a path's peak curvature [1/m] for :func:`by_curvature`
CURVATURE_BINS = (0.0, 2.0, 5.0, 10.0, 20.0, 60.0)


def by_curvature(st: Settings, rows: list[dict]) -> None:
    """Print the failure rate at the first tolerance per bin of the path's peak curvature (:data:`CURVATURE_BINS`)."""
    bins = list(itertools.pairwise(CURVATURE_BINS))
    print(f"\nfailure rate at {st.tolerances[0]} m per peak-curvature bin [1/m] (paths in the bin):")
    print(f"{'agent':22} {'condition':9} " + " ".join(f"{f'[{lo:g}, {hi:g})':>15}" for lo, hi in bins))
    for name in AGENTS:
        for cond in st.conditions:
            sel = [r for r in rows if r["agent"] == name and r["condition"] == cond]
            cells = []
            for lo, hi in bins:
                b = [r["peak"] >= st.tolerances[0] for r in sel if lo <= r["max_curvature"] < hi]
                cells.append(f"{np.mean(b):6.1%} ({len(b):>4})" if b else f"{'-':>15}")
            print(f"{name:22} {cond:9} " + " ".join(f"{c:>15}" for c in cells))


def plot(st: Settings, summary: list[dict], file: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    tols = np.array(st.tolerances)
    for j, (name, cond) in enumerate((n, c) for n in AGENTS for c in st.conditions):
        r = [x for x in summary if x["agent"] == name and x["condition"] == cond]
        y = np.array([x["rate"] for x in r])
        err = np.clip([[x["rate"] - x["ci95"][0], x["ci95"][1] - x["rate"]] for x in r], 0.0, None).T
        ax.errorbar(tols + (j - 1.5) * 0.008, y, yerr=err, fmt="o-", capsize=3, label=f"{name} ({cond})")
    ax.plot(tols, PUBLISHED, "k*", ms=12, label="published (Cao et al. 2024)")
    ax.set_xlabel("tolerance on |cross-track error| [m]")
    ax.set_ylabel("failure rate")
    ax.set_xticks(tols)
    ax.set_title(f"{st.paths} random paths ({st.generator} {st.seed}), {st.speed} m/s, {st.duration:g} s")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(file, dpi=120)


if __name__ == "__main__":
    main()
