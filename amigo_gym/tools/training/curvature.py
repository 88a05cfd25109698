r"""Failure rate binned by path curvature: ``amigo-gym benchmark --curvature``.

The cells, tags and bins: docs/baselines.md, "Reference: `amigo-gym benchmark
--curvature`".
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from amigo_gym.task.v1 import feasible_random_curvature
from amigo_gym.tools.training.intervals import failure_rate
from amigo_gym.tools.training.task_metrics import Scenario, md_table, run_grid, run_scenario

#: speeds of the cells [m/s]: the ends of the training distribution's range
CURVATURE_SPEEDS: tuple[float, ...] = (0.1, 0.4)
#: curvature levels per speed (``max_curvature = K(v) j / LEVELS``)
LEVELS = 4
#: bin edges of ``path_max_kappa / K(v)`` [-] (the last bin closed)
BIN_EDGES: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)
#: episodes per cell (seeds 100, 101, ...)
CURVATURE_EPISODES = 50
#: episode length [s] and control period [s] of the cells
DURATION_S = 60.0
DT_S = 0.1
#: path ids the cells draw from (ids [0, 2**20))
POOL = 2**20


def cell_specs(episodes: int = CURVATURE_EPISODES) -> tuple[Scenario, ...]:
    """The held-out cells: AmigoBot-v1 random paths at each of :data:`CURVATURE_SPEEDS` ``v``, ``max_curvature =
    K(v) j / LEVELS``, ``episodes`` seeds from 100."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or not 1 <= episodes <= 10_000:
        raise ValueError(f"curvature cells: episodes must be an integer in [1, 10000], got {episodes!r}")
    out = []
    for v in CURVATURE_SPEEDS:
        k_v = feasible_random_curvature(v)
        for j in range(1, LEVELS + 1):
            k = k_v * j / LEVELS
            kw = {"dt": DT_S, "randomize": "none", "path": "random", "speed": float(v), "random_pool": POOL}
            kw["path_params"] = {"max_curvature": k, "max_curvature_rate": k, "length": float(v) * DURATION_S}
            desc = f"random paths, |kappa| <= {k:.3g} 1/m (level {j}/{LEVELS} of K = {k_v:.4g} 1/m), {v:g} m/s"
            seeds = tuple(range(100, 100 + episodes))
            out.append(Scenario(f"curv_v{v:g}_k{j}", "AmigoBot-v1", kw, seeds, round(DURATION_S / DT_S), True, desc))
    return tuple(out)


def evaluate_tagged(agent: Any, sc: Any) -> list[dict[str, Any]]:
    """Per episode of the cell ``sc`` the benchmark's metrics plus ``seed_env``, ``path_id``, ``path_max_kappa``
    [1/m], ``kappa_end`` [1/m] and ``progress_end`` [m]."""
    paths: list[Any] = []
    ids: list[int] = []
    progress = np.zeros(len(sc.seeds))

    def read_paths(venv: Any, _infos: Any) -> None:
        paths.extend(venv.unwrapped.paths.paths)
        ids.extend(int(d["id"]) for d in venv.unwrapped.path_infos)

    def read_progress(i: int, info: dict[str, Any], _ended: bool, _obs: Any) -> None:
        progress[i] = float(info["progress"])

    recs = run_scenario(agent, sc, on_reset=read_paths, on_row=read_progress)
    out: list[dict[str, Any]] = []
    for i, (r, path) in enumerate(zip(recs, paths, strict=True)):
        k_end = float(abs(np.asarray(path.curvature(min(max(progress[i], 0.0), float(path.length))))))
        tags = {"seed_env": int(sc.seeds[i]), "path_id": ids[i], "path_max_kappa": float(path.max_abs_curvature)}
        out.append(r.metrics() | tags | {"kappa_end": k_end, "progress_end": float(progress[i])})
    return out


def bin_table(episodes: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Failure rate per (agent, speed, bin) of tagged episodes, binned by ``x = path_max_kappa / k_limit`` in
    ``[e[b], e[b+1])`` of :data:`BIN_EDGES` (the last bin closed; an ``x`` outside them is an error): rows with
    ``x_lo``, ``x_hi``, ``kappa_lo``, ``kappa_hi`` [1/m], :func:`~amigo_gym.tools.training.intervals.failure_rate`'s
    keys and ``kappa_end_failed`` (median ``kappa_end`` of the failures [1/m])."""
    e = np.asarray(BIN_EDGES)
    groups: dict[tuple[str, float], list[Mapping[str, Any]]] = {}
    limits: dict[float, float] = {}
    for ep in episodes:
        key = (str(ep["agent"]), float(ep["speed"]))
        groups.setdefault(key, []).append(ep)
        limits[float(ep["speed"])] = float(ep["k_limit"])
    rows = []
    for (agent, v), eps in groups.items():
        k_v = limits[v]
        x = np.array([float(ep["path_max_kappa"]) / k_v for ep in eps])
        if np.any(x < e[0]) or np.any(x > e[-1] * (1 + 1e-12)):
            raise ValueError(f"bin_table: path_max_kappa / K outside [{e[0]:g}, {e[-1]:g}] for {agent} at {v:g} m/s")
        b = np.clip(np.searchsorted(e, x, side="right") - 1, 0, e.size - 2)
        fail = np.array([bool(ep["failure"]) for ep in eps])
        k_end = np.array([float(ep.get("kappa_end", math.nan)) for ep in eps])
        for j in range(e.size - 1):
            sel = b == j
            kf = k_end[sel & fail]
            rows.append({
                "agent": agent, "speed": v, "bin": j, "x_lo": float(e[j]), "x_hi": float(e[j + 1]),
                "kappa_lo": float(e[j] * k_v), "kappa_hi": float(e[j + 1] * k_v),
                **failure_rate(int(fail[sel].sum()), int(sel.sum())),
                "kappa_end_failed": float(np.median(kf)) if kf.size else None,
            })  # fmt: skip
    return rows


def run_curvature(agents: Sequence[Any], scenarios: Sequence[Any], *, progress: bool = True) -> dict[str, Any]:
    """Every agent seed on every cell; the JSON document (``episodes`` tagged, ``table``: :func:`bin_table`)."""
    t0 = time.perf_counter()
    grid = run_grid(agents, scenarios, evaluate_tagged, desc="curvature", progress=progress)
    episodes = [
        {"agent": spec.name, "seed": spec.seed, "scenario": sc.name, "speed": float(sc.env_kwargs["speed"])}
        | {"k_limit": feasible_random_curvature(float(sc.env_kwargs["speed"])), **ep}
        for spec, sc, eps in grid.runs
        for ep in eps
    ]
    bins = [f"[{a:g}, {b:g})" for a, b in itertools.pairwise(BIN_EDGES)]
    bins[-1] = bins[-1][:-1] + "]"
    return {
        "protocol": {
            "speeds_m_s": sorted({float(sc.env_kwargs["speed"]) for sc in scenarios}),
            "bins": "path_max_kappa / K(v) in " + ", ".join(bins),
            "k_limit": "amigo_gym.task.v1.feasible_random_curvature(v) (max_curvature_rate = max_curvature x 1 m^-1)",
            "failure": "terminated off the path, or |e| > 0.10 m at some t >= 5 s",
            "interval": "Wilson score 95 %, episodes of every training seed pooled",
        },
        "scenarios": [sc.to_json() for sc in scenarios],
        "agents": [a.describe() for a in agents],
        "episodes": episodes,
        "table": bin_table(episodes) if episodes else [],
        "unavailable": grid.unavailable,
        "wall_time_s": round(time.perf_counter() - t0, 2),
    }


def markdown_curvature(doc: Mapping[str, Any]) -> str:
    """The table: per speed, one row per bin, one column per agent: ``rate [lo, hi] (f/n)``."""
    rows = doc["table"]
    agents = list(dict.fromkeys(r["agent"] for r in rows))
    lines = [
        "# Failure rate per curvature bin (amigo-gym benchmark --curvature)",
        "",
        f"Bins of the path's max |kappa| / K(v) (K(v): the feasible limit at speed v); failure rate [95 % Wilson "
        f"interval] (failures / episodes, training seeds pooled). {doc['protocol']['failure']}.",
    ]
    for v in sorted({r["speed"] for r in rows}):
        sub, table = [r for r in rows if r["speed"] == v], []
        for j in sorted({r["bin"] for r in sub}):
            by = {r["agent"]: r for r in sub if r["bin"] == j}
            r = next(iter(by.values()))
            head = f"[{r['kappa_lo']:.2f}, {r['kappa_hi']:.2f}{']' if j == len(BIN_EDGES) - 2 else ')'}"
            table.append([head] + [
                "–" if (c := by.get(a)) is None else "– (0)" if c["n"] == 0
                else f"{c['rate']:.3f} [{c['ci95'][0]:.3f}, {c['ci95'][1]:.3f}] ({c['failures']}/{c['n']})"
                for a in agents
            ])  # fmt: skip
        lines += ["", f"## {v:g} m/s", "", *md_table(["max \\|kappa\\| [1/m]", *agents], table)]
    if doc.get("unavailable"):
        lines += ["", "## Unavailable", ""]
        lines += [f"- {u['agent']} s{u['seed']} on {u['scenario']}: {u['reason']}" for u in doc["unavailable"]]
    return "\n".join(lines) + "\n"
