"""The random-path protocol of Cao et al. (Sensors 24(2) 561, 2024) as scenarios (``benchmark --random-paths``).

The protocol, its sources, the two conditions and the outputs: docs/benchmark.md, "Random paths: the published
protocol (Cao et al., Sensors 2024)".

``random_paths.json``'s ``seed_spread`` (:func:`seed_spread`; issue 36's "no failed seed"), per agent with two or
more training seeds, path set (``paths``: ``"accepted"``, within the wheel limits, or ``"all"``) and ``tolerance``
[m]: ``seed_rates`` (each seed's failure rate [-] on those paths; seeds without any left out), ``median_rate`` (over
the seeds [-]; of an even number, the mean of the two middle ones), ``worst_rate`` and ``worst_seed`` (the highest
rate [-], its first seed), ``ratio`` (worst / median [-], ``None`` for a median of 0), ``within`` (``worst_rate <=
factor * median_rate``, ``factor`` = :data:`SEED_FACTOR` = 1.5: with a median of 0 no seed may fail on any path;
``None`` with fewer than two seeds on those paths).
"""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from amigo_gym.paths import from_points
from amigo_gym.tools.training.intervals import failure_rate
from amigo_gym.tools.training.task_metrics import Scenario, md_row, run_grid

#: the authors' failure_rate.npy at 0.2 m/s: tolerance [m] -> failure rate
PUBLISHED = {0.1: 0.276, 0.2: 0.053, 0.3: 0.002}
TOLERANCES: tuple[float, ...] = (0.1, 0.2, 0.3)
CONDITIONS: tuple[str, ...] = ("paper", "firmware")
#: bins of a path's peak |curvature| [1/m]
CURVATURE_BINS: tuple[float, ...] = (0.0, 2.0, 5.0, 10.0, 20.0, 60.0)
#: episode length [s], success when H is this close to the end [m], the paper's stream seed
DURATION_S, GOAL_M, SEED = 20.0, 0.02, 100
#: no failed seed: every training seed's failure rate is at most this times the median seed's
SEED_FACTOR = 1.5


def draw_path(rng: np.random.RandomState, spacing: float = 0.01) -> tuple[np.ndarray[Any, Any], float]:
    """One path from the authors' ``RandomState`` calls: points ``(n, 2)`` [m] every ``spacing`` [m] and its peak
    |curvature| [1/m]. Five waypoints, legs U(0.5, 2) m in direction U[0, 2 pi), a natural cubic spline redrawn
    while |kappa| > 50 1/m, re-splined in arc length (8-point Gauss)."""
    while True:
        legs = rng.randint(4, 5)  # always 4: the authors' draw, kept for their stream
        x, y = [0.0], [0.0]
        for _ in range(legs):
            d, th = rng.uniform(0.5, 2.0), 2 * np.pi * rng.rand()
            x.append(x[-1] + d * np.cos(th))
            y.append(y[-1] + d * np.sin(th))
        s = np.linspace(0.0, np.hypot(np.diff(x), np.diff(y)).sum(), len(x))
        fx, fy = CubicSpline(s, x, bc_type="natural"), CubicSpline(s, y, bc_type="natural")
        u = np.linspace(0.0, s[-1], 200)
        dx, dy = fx(u, 1), fy(u, 1)
        if np.all(np.abs((fy(u, 2) * dx - fx(u, 2) * dy) / (dx**2 + dy**2) ** 1.5) <= 50.0):
            break
    g, w = np.polynomial.legendre.leggauss(8)
    h, m = np.diff(u) / 2, (u[:-1] + u[1:])[:, None] / 2
    arc = np.concatenate([[0.0], np.cumsum(h * (np.hypot(fx(m + h[:, None] * g, 1), fy(m + h[:, None] * g, 1)) @ w))])
    X, Y = CubicSpline(arc, fx(u), bc_type="natural"), CubicSpline(arc, fy(u), bc_type="natural")
    t = np.linspace(0.0, arc[-1], math.ceil(arc[-1] / spacing) + 1)
    k = (Y(t, 2) * X(t, 1) - X(t, 2) * Y(t, 1)) / (X(t, 1) ** 2 + Y(t, 1) ** 2) ** 1.5
    return np.column_stack([X(t), Y(t)]), float(np.abs(k).max())


def start_offset(seed: int = SEED) -> tuple[float, float, float]:
    """The start of every path relative to its first pose: ``(dx [m], dy [m], dbeta [rad])`` of A, as the authors'
    ``Unicycle.reset(flag="random")`` seeded with ``seed``."""
    r = np.random.RandomState(seed)
    x, y = r.uniform(-0.1, 0.1), r.uniform(-0.1, 0.1)
    return float(x), float(y), float(r.uniform(-np.deg2rad(5.0), np.deg2rad(0.1)))


@dataclass(frozen=True)
class PathSet:
    """The scenarios of :func:`path_set`; ``tags`` per scenario: ``path`` (its index), ``length`` [m],
    ``max_curvature`` [1/m] (the spline's), ``fit_step`` [m]; ``skipped`` the paths ``from_points`` refused."""

    scenarios: tuple[Scenario, ...]
    tags: Mapping[str, Mapping[str, float]]
    skipped: tuple[int, ...]
    settings: Mapping[str, Any]


def path_set(
    paths: int, condition: str = "paper", seed: int = SEED, speed: float = 0.2, tolerances: Sequence[float] = TOLERANCES
) -> PathSet:
    """One AmigoBot-v1 scenario per path of ``RandomState(seed)`` at ``speed`` [m/s], one episode from
    :func:`start_offset`, ended past the largest tolerance [m]. ``condition`` ``"paper"``: H on A, ideal actuators,
    rolling start, dt 0.05 s; ``"firmware"``: AmigoBot-v1's defaults. Raises ``ValueError`` naming the flag."""
    if isinstance(paths, bool) or not isinstance(paths, int) or paths < 0:
        raise ValueError(f"--random-paths must be an integer >= 0, got {paths!r}")
    if condition not in CONDITIONS:
        raise ValueError(f"--condition must be one of {list(CONDITIONS)}, got {condition!r}")
    if not tolerances or any(not (0.0 < t <= 10.0) for t in tolerances):
        raise ValueError(f"--tolerance must be in (0, 10] m each, got {list(tolerances)}")
    dt = 0.05 if condition == "paper" else 0.1
    kw: dict[str, Any] = {"speed": speed, "dt": dt, "feasibility": "off", "goal_tolerance": GOAL_M}
    kw["termination_distance"] = max(tolerances) + 0.01  # past the largest tolerance nothing more is learnt
    if condition == "paper":
        kw |= {"ideal_actuators": True, "start_at_rest": False, "robot": {"l3": 1e-3}}
    rng, (dx, dy, db) = np.random.RandomState(seed), start_offset()
    out, tags, skipped = [], {}, []
    for i in range(paths):
        pts, kmax = draw_path(rng)
        try:  # the sharpest corners (|kappa| ~ 50 1/m) need finer clothoid steps to stay within 1 mm
            path, step = from_points(pts), 0.02
        except ValueError:
            try:
                path, step = from_points(pts, step=0.005), 0.005
            except ValueError:  # a cusp between the 200 samples the protocol checks: not a path to drive
                skipped.append(i)
                continue
        name, desc = f"rp{seed}_{i:04d}", f"random path {i} of RandomState({seed}), peak |kappa| {kmax:.3g} 1/m"
        pose = (dx, dy, float(path.pose_columns(0.0).theta) + db)
        steps, length = round(DURATION_S / dt), round(float(path.length), 5)
        out.append(Scenario(name, "AmigoBot-v1", kw | {"path": path}, (0,), steps, True, desc, pose=pose))
        tags[name] = {"path": i, "length": length, "max_curvature": round(kmax, 5), "fit_step": step}
    settings = {"paths": paths, "condition": condition, "seed": seed, "speed": speed, "tolerances": list(tolerances)}
    return PathSet(tuple(out), tags, tuple(skipped), settings | {"duration_s": DURATION_S, "goal_m": GOAL_M})


def failure_table(episodes: Sequence[Mapping[str, Any]], tolerances: Sequence[float]) -> list[dict[str, Any]]:
    """Failure rates (peak |e| >= tolerance) with Wilson 95 % intervals per agent and tolerance, in groups ``all``,
    ``accepted`` (feasible paths), ``seed`` (agents with several) and ``curvature`` (bin ``kappa``)."""
    rows = []
    for agent in dict.fromkeys(e["agent"] for e in episodes):
        mine = [e for e in episodes if e["agent"] == agent]
        seeds = list(dict.fromkeys(e["seed"] for e in mine))
        groups: list[tuple[dict[str, Any], list[Mapping[str, Any]]]] = [
            ({"group": "all"}, mine),
            ({"group": "accepted"}, [e for e in mine if e["feasible"]]),
        ]
        groups += [({"group": "seed", "seed": s}, [e for e in mine if e["seed"] == s]) for s in seeds if len(seeds) > 1]
        for lo, hi in itertools.pairwise(CURVATURE_BINS):
            groups.append(
                ({"group": "curvature", "kappa": [lo, hi]}, [e for e in mine if lo <= e["max_curvature"] < hi])
            )
        rows += [
            {"agent": agent, "tolerance": t, **key, **failure_rate(sum(e["peak_m"] >= t for e in eps), len(eps))}
            for key, eps in groups
            for t in tolerances
        ]
    return rows


def seed_spread(
    episodes: Sequence[Mapping[str, Any]], tolerances: Sequence[float], factor: float = SEED_FACTOR
) -> list[dict[str, Any]]:
    """The rows of ``seed_spread`` (module docstring), every seed within ``factor`` of the median seed or not."""
    rows = []
    for agent in dict.fromkeys(e["agent"] for e in episodes):
        mine = [e for e in episodes if e["agent"] == agent]
        seeds = list(dict.fromkeys(e["seed"] for e in mine))
        for paths, t in itertools.product(("accepted", "all") if len(seeds) > 1 else (), tolerances):
            chosen = [e for e in mine if paths == "all" or e["feasible"]]
            fails = {s: [e["peak_m"] >= t for e in chosen if e["seed"] == s] for s in seeds}
            rates = [{"seed": s, "rate": sum(f) / len(f)} for s, f in fails.items() if f]
            row: dict[str, Any] = {"agent": agent, "paths": paths, "tolerance": t, "seed_rates": rates}
            row |= dict.fromkeys(("median_rate", "worst_rate", "worst_seed", "ratio", "within"))
            if len(rates) >= 2:
                median = float(np.median([r["rate"] for r in rates]))
                worst = max(rates, key=lambda r: r["rate"])  # the first seed of the highest rate
                row |= {"median_rate": median, "worst_rate": worst["rate"], "worst_seed": worst["seed"]}
                row["ratio"] = worst["rate"] / median if median > 0 else None
                row["within"] = bool(worst["rate"] <= factor * median + 1e-12)  # 1e-12: rounding of the rates
            rows.append(row)
    return rows


def run_random_paths(agents: Sequence[Any], ps: PathSet, *, progress: bool = True) -> dict[str, Any]:
    """Every agent seed on every path; the JSON document (``table``: :func:`failure_table`)."""
    t0 = time.perf_counter()
    grid = run_grid(agents, ps.scenarios, desc="random paths", progress=progress)
    ok = {name: bool(r["feasible"]) for name, r in grid.feasibility.items()}
    episodes = [
        {"agent": spec.name, "seed": spec.seed, "scenario": sc.name, **ps.tags[sc.name], "feasible": ok[sc.name]}
        | {"peak_m": round(ep["h_max_m"], 5), "steps": int(ep["steps"]), "terminated": bool(ep["terminated"])}
        for spec, sc, eps in grid.runs
        for ep in eps
    ]
    tolerances = ps.settings["tolerances"]
    return {
        "protocol": {
            **ps.settings,
            "start_offset": start_offset(),
            "failure": "peak |cross-track error| of H over the episode >= tolerance",
            "interval": "Wilson score 95 %, episodes of every training seed pooled",
            "published": {str(t): r for t, r in PUBLISHED.items()},
            "seed_factor": SEED_FACTOR,
        },
        "agents": [a.describe() for a in agents],
        "accepted": sum(ok.values()),
        "skipped": list(ps.skipped),
        "table": failure_table(episodes, tolerances),
        "seed_spread": seed_spread(episodes, tolerances),
        "episodes": episodes,
        "unavailable": grid.unavailable,
        "wall_time_s": round(time.perf_counter() - t0, 2),
    }


def markdown_random_paths(doc: Mapping[str, Any]) -> str:
    """The tables: failure rate [%] per agent and tolerance, per curvature bin and per training seed."""
    p, rows = doc["protocol"], doc["table"]
    tols = p["tolerances"]
    agents = list(dict.fromkeys(r["agent"] for r in rows))

    def cell(agent: str, group: str, tol: float, **key: Any) -> str:
        r = next(r for r in rows if (r["agent"], r["group"], r["tolerance"]) == (agent, group, tol)
                 and all(r.get(k) == v for k, v in key.items()))  # fmt: skip
        lo, hi = r["ci95"] or (0.0, 0.0)
        return f"{100 * r['rate']:.1f} [{100 * lo:.1f}, {100 * hi:.1f}] ({r['failures']}/{r['n']})" if r["n"] else "–"

    bins = [list(b) for b in itertools.pairwise(CURVATURE_BINS)]
    lines = [
        f"# Random paths (Cao et al. 2024): {p['paths'] - len(doc['skipped'])} paths of RandomState({p['seed']}), "
        f"condition {p['condition']}",
        "",
        f"{p['speed']:g} m/s, {p['duration_s']:g} s; a path fails when {p['failure']}. Failure rate in % with its "
        f"95 % Wilson interval (failures/episodes, training seeds pooled); AmigoBot-v1 accepts {doc['accepted']} of "
        "the paths.",
        "",
        md_row("agent", *(f"{t:g} m" for t in tols), f"accepted paths, {tols[0]:g} m"),
        md_row(*["---"] * (len(tols) + 2)),
    ]
    if p["condition"] == "paper" and p["speed"] == 0.2:
        lines.append(md_row("published (Cao et al.)", *(f"{100 * PUBLISHED.get(t, math.nan):.1f}" for t in tols), ""))
    lines += [md_row(a, *(cell(a, "all", t) for t in tols), cell(a, "accepted", tols[0])) for a in agents]
    lines += ["", f"Per bin of the path's peak |kappa| [1/m], {tols[0]:g} m:", ""]
    lines += [md_row("agent", *(f"[{lo:g}, {hi:g})" for lo, hi in bins)), md_row(*["---"] * (len(bins) + 1))]
    lines += [md_row(a, *(cell(a, "curvature", tols[0], kappa=b) for b in bins)) for a in agents]
    if seeds := [(r["agent"], r["seed"]) for r in rows if r["group"] == "seed" and r["tolerance"] == tols[0]]:
        lines += ["", "Per training seed:", "", md_row("agent", "seed", *(f"{t:g} m" for t in tols))]
        lines += [md_row(*["---"] * (len(tols) + 2))] + [
            md_row(a, s, *(cell(a, "seed", t, seed=s) for t in tols)) for a, s in seeds
        ]
    if spread := doc.get("seed_spread"):
        f = p.get("seed_factor", SEED_FACTOR)
        lines += [
            "",
            f"No failed seed: every training seed's failure rate within {f:g}x of the median seed's (worst <= {f:g} x "
            "median; a median of 0 asks every seed to fail on no path), on the paths within the wheel limits "
            "(accepted) and on all paths:",
            "",
            md_row("agent", "paths", "tolerance", "seeds", "median seed [%]", "worst seed [%]", f"within {f:g}x"),
            md_row(*["---"] * 7),
            *(md_row(r["agent"], r["paths"], f"{r['tolerance']:g} m", len(r["seed_rates"]),
                     "–" if r["median_rate"] is None else f"{100 * r['median_rate']:.1f}",
                     "–" if r["worst_rate"] is None else f"{100 * r['worst_rate']:.1f} (seed {r['worst_seed']})",
                     {True: "yes", False: "**no**", None: "–"}[r["within"]]) for r in spread),
        ]  # fmt: skip
    runs = Counter((u["agent"], u["seed"], u["reason"]) for u in doc["unavailable"])
    lines += [""] * bool(runs) + [f"- unavailable: {a} s{s} on {n} paths: {why}" for (a, s, why), n in runs.items()]
    return "\n".join(lines) + "\n"
