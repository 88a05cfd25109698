"""``amigo-gym benchmark``: a versioned scenario suite, many agents and training seeds, rliable statistics.

Usage, the suite and its versions, agents, seeds, metrics, statistics and the output files:
docs/benchmark.md, "Reference: `amigo-gym benchmark`".

``benchmark.json``'s ``paired`` (:func:`paired_differences`): every agent against the analytic controller, per cell
where both ran, on the same episodes (the cell's reset seeds, hence start offsets): ``baseline`` ("analytic"),
``metric`` ("h_rms_m"), ``unit`` ("mm"), the bootstrap's ``reps`` and ``seed`` (``--reps``, ``--bootstrap-seed``),
``agents``: per agent ``cells`` and ``trimmed_mean_mm`` (``{"baseline", "agent"}``: the 25 % trimmed mean of the
per-cell means [mm], ``scipy.stats.trim_mean``). Each cell: ``scenario``, ``held_out``, ``seeds`` (the agent's
training seeds), ``episodes`` (paired: finite for both), ``baseline_mm`` and ``agent_mm`` (mean H RMS [mm], the
agent's over seeds and episodes), ``agent_seeds_mm`` (per training seed [mm]), ``ratio`` (``agent_mm / baseline_mm``
[-], ``None`` for a zero baseline), ``diff_mm`` (paired mean difference [mm]: per episode the agent's mean over its
seeds minus the analytic value, averaged over the episodes), ``diff_ci95_mm`` (its 95 % percentile bootstrap
interval over the episodes [mm]), ``baseline_ci95_mm`` / ``agent_ci95_mm`` (each side's own 95 % interval of its
mean over its episodes, the agent's seeds pooled [mm]), ``overlap`` (of these two), ``failed`` of ``agent_episodes``
(the agent's failed episodes, all seeds), ``baseline_failed`` (of ``episodes``), ``chatter_settled_rms`` (the
agent's settled command chatter, mean over seeds [rad/s]). One ``numpy.random.default_rng(seed)`` per agent draws,
cell after cell in suite order, the paired resamples, then the analytic side's, then the agent's
(``experiments/paired_cells.py`` prints these tables).
"""

from __future__ import annotations

import glob
import json
import math
import re
import sys
import tempfile
import time
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any, Literal

import numpy as np
from scipy.stats import trim_mean

from amigo_gym.data import pretrained_dir
from amigo_gym.io import atomic_write, atomic_write_json, json_safe
from amigo_gym.paths.points import cached_file_path, is_points_file
from amigo_gym.tools.options import cli, parse_settings, run_guarded
from amigo_gym.tools.plots import pyplot, save_figure
from amigo_gym.tools.runs import RunLock, publish, remove_matching, verify_manifest
from amigo_gym.tools.training import curvature, protocol
from amigo_gym.tools.training import random_paths as rp
from amigo_gym.tools.training import task_metrics as tm
from amigo_gym.tools.training.evaluate import ALGOS, CLASSICAL, FAST_ALGO, AgentSpec, one_torch_thread
from amigo_gym.tools.training.intervals import Array, iqm, optimality_gap, score_distribution, stratified_bootstrap
from amigo_gym.tools.training.task_metrics import METRIC_NAMES, SUITE_VERSION, Scenario, run_grid, run_scenario
from amigo_gym.tools.training.task_metrics import Unavailable as Unavailable
from amigo_gym.tools.training.task_metrics import make_env as make_env

#: the shipped AmigoBot-v1 generalists: folder under ``agents/pretrained/v1`` -> the label of its algorithm
V1_AGENTS: dict[str, str] = {
    "td3lp": "SB3 TD3 low-pass",
    "ppo_fast": "fast PPO",
    "residual": "fast PPO residual",
    "robust_residual": "fast PPO robust residual",
    "compensator_residual": "fast PPO residual on the delay compensator",
}
#: retired v1 generalists, labels only (``--agents ppo_v1=...`` and older documents)
RETIRED_V1_AGENTS: dict[str, str] = {"ppo": "SB3 PPO", "sac": "SB3 SAC", "td3": "SB3 TD3"}
#: target of the H-error optimality gap [m]
H_TARGET_M = 0.01
#: thresholds of the H-error performance profile [m]
PROFILE_TAUS = tuple(float(x) for x in np.logspace(-6, math.log10(0.25), 41))

#: the training distribution of the v1 generalists; "held out" scenarios lie outside it
TRAINING_DISTRIBUTION: dict[str, Any] = {
    "env_id": "AmigoBot-v1",
    "env_kwargs": {"path": "mixed", "speed": [0.1, 0.4], "randomize": "mild"},
    "paths": "mixed: circles R 0.5-3 m either direction, figure-8 size 3-6 m, lane change +-1 m over 3-6 m, "
    "random paths of the default pool (ids 0-1023, |kappa| <= 1 1/m, |dkappa/ds| <= 1 1/m^2)",
    "speed_m_s": [0.1, 0.4],
    "speed_profile": "constant",
    "dt_s": 0.1,
    "randomize": "mild (wheel radii and track +-2 %, slip <= 2 %, delay <= 50 ms, small noise)",
    "not_trained_on": [
        "the manoeuvre path",
        "random paths of higher curvature",
        "the trapezoid speed profile",
        "dt other than 0.1 s",
        "wheel radii and track beyond +-2 %",
        "slip beyond 2 %",
        "delays beyond 50 ms",
        "noise beyond 'mild'",
        "'hard'",
        "AmigoBot-v0 (another observation)",
    ],
}


# --------------------------------------------------------------------------- scenarios
def user_scenarios(
    files: Sequence[str], speed: float, feasibility: str = "off", goal_tolerance: float = 0.0, duration: float = 60.0
) -> tuple[Scenario, ...]:
    """One ``AmigoBot-v1`` scenario per points file, named after the file, at ``speed`` [m/s], ``feasibility``,
    ``goal_tolerance`` [m] and ``duration`` [s]. Raises ``FileNotFoundError`` / ``ValueError`` (one line)."""
    for f in files:
        if not is_points_file(str(f)):
            raise ValueError(f"--path {f}: a points file must end in .csv or .json")
        if not Path(f).is_file():
            raise FileNotFoundError(f"--path {f}: no such points file")
        try:
            cached_file_path(f)  # read and fitted now (kept for gym.make): a bad file is the user's error, exit 2
        except ValueError as exc:
            raise ValueError(f"--path {exc}") from None
    if not (0.0 < duration <= 3600.0):
        raise ValueError(f"--duration must be in (0, 3600] s, got {duration}")
    stems = [Path(f).stem for f in files]
    return tuple(
        _v1(f"path:{s}" if stems.count(s) == 1 else f"path:{f}", f"points of {f} at {speed:g} m/s", True,
            duration=duration, path=str(f), speed=speed, feasibility=feasibility, goal_tolerance=goal_tolerance)
        for f, s in zip(files, stems, strict=True)
    )  # fmt: skip


def _v1(name: str, desc: str, held_out: bool = False, env_id: str = "AmigoBot-v1", **kw: Any) -> Scenario:
    """A suite 1.0 scenario: :func:`protocol.cell` on seeds 100-109."""
    return protocol.cell(name, desc, env_id, held_out, seeds=tuple(range(100, 110)), version="1.0", **kw)


_WHEELS_PLUS5 = {"r1": 0.0525, "r2": 0.0525, "l1": 0.126}
_WHEELS_MINUS5 = {"r1": 0.0475, "r2": 0.0475, "l1": 0.114}
_WHEELS_UNEQUAL = {"r1": 0.0525, "r2": 0.0475}
_CIRCLE: dict[str, Any] = {"path": "circle", "speed": 0.2}
_MIXED: dict[str, Any] = {"path": "mixed", "speed": (0.1, 0.4)}

# fmt: off
SUITE_1_0: tuple[Scenario, ...] = (
    # the paper's task on the exact v0 environment (the v0 specialists were trained on it)
    _v1("v0_paper_circle", "v0: the paper's circle R = 1 m, 0.2 m/s, dt 0.1 s", False, "AmigoBot-v0"),
    _v1("v0_speed_0.1", "v0: paper circle at 0.1 m/s", True, "AmigoBot-v0", speed=0.1),
    _v1("v0_speed_0.4", "v0: paper circle at 0.4 m/s", True, "AmigoBot-v0", speed=0.4),
    _v1("v0_dt_0.2", "v0: paper circle, dt 0.2 s", True, "AmigoBot-v0", dt=0.2, max_steps=200),
    # circles: radii and both directions
    _v1("circle_r1_ccw", "paper circle on v1 (actuator limits)", path="circle", radius=1.0, direction=1, speed=0.2),
    _v1("circle_r0.5_ccw", "circle R 0.5 m, left", path="circle", radius=0.5, direction=1, speed=0.2),
    _v1("circle_r0.5_cw", "circle R 0.5 m, right", path="circle", radius=0.5, direction=-1, speed=0.2),
    _v1("circle_r2_cw", "circle R 2 m, right", path="circle", radius=2.0, direction=-1, speed=0.3),
    # speeds
    _v1("circle_v0.1", "circle R 1 m at 0.1 m/s", path="circle", radius=1.0, speed=0.1),
    _v1("circle_v0.4", "circle R 1 m at 0.4 m/s", path="circle", radius=1.0, speed=0.4),
    _v1("circle_v_random", "circle R 1 m, speed drawn in [0.1, 0.4]", path="circle", radius=1.0, speed=(0.1, 0.4)),
    _v1("manoeuvre_trapezoid", "paper manoeuvre, start-cruise-brake at 0.2 m/s (held out)", True, path="manoeuvre",
        speed=0.2, speed_profile="trapezoid"),
    # path families
    _v1("manoeuvre", "paper manoeuvre (straight, circle), 0.2 m/s (held out)", True, path="manoeuvre", speed=0.2),
    _v1("figure8", "figure-8, 0.2 m/s", path="figure8", speed=0.2),
    _v1("random_paths", "seeded random smooth paths, 0.2 m/s", path="random", speed=0.2),
    _v1("random_paths_sharp", "random paths of higher curvature (1.5 1/m, rate 1.5 1/m^2), 0.2 m/s (held out)",
        True, path="random", speed=0.2, path_params={"max_curvature": 1.5, "max_curvature_rate": 1.5}),
    _v1("lane_change", "lane change, 0.3 m/s", path="lane_change", speed=0.3),
    _v1("mixed", "path family drawn per episode, speed in [0.1, 0.4]", **_MIXED),
    # control period
    _v1("circle_dt_0.05", "circle R 1 m, dt 0.05 s (held out)", True, dt=0.05, path="circle", radius=1.0, speed=0.2),
    _v1("circle_dt_0.2", "circle R 1 m, dt 0.2 s (held out)", True, dt=0.2, path="circle", radius=1.0, speed=0.2),
    # the robot is not the model
    _v1("wheels_plus5", "true wheel radii and track +5 % (held out)", True, **_CIRCLE, true_robot=_WHEELS_PLUS5),
    _v1("wheels_minus5", "true wheel radii and track -5 % (held out)", True, **_CIRCLE, true_robot=_WHEELS_MINUS5),
    _v1("wheels_unequal", "right wheel +5 %, left -5 % (held out)", True, path="figure8", speed=0.2,
        true_robot=_WHEELS_UNEQUAL),
    _v1("slip", "wheel slip up to 5 % per step (held out)", True, **_CIRCLE, randomize={"slip": (0.0, 0.05)}),
    _v1("delay_0.1", "actuation delay 0.1 s (held out)", True, **_CIRCLE, randomize={"delay": (0.1, 0.1)}),
    _v1("delay_0.25", "actuation delay 0.25 s (held out)", True, path="figure8", randomize={"delay": (0.25, 0.25)}),
    _v1("noise", "measurement noise: 5 mm, 0.01 rad, 0.2 rad/s (held out)", True, **_CIRCLE,
        randomize={"position_noise": 0.005, "heading_noise": 0.01, "wheel_rate_noise": 0.2}),
    _v1("mild", "'mild' randomisation on mixed paths", **_MIXED, randomize="mild"),
    _v1("hard", "'hard' randomisation on mixed paths (held out)", True, **_MIXED, randomize="hard"),
)
# fmt: on

#: released suites by version (never edited)
SUITES: dict[str, tuple[Scenario, ...]] = {"1.0": SUITE_1_0, protocol.VERSION: protocol.TEST}
SUITE: tuple[Scenario, ...] = SUITES[SUITE_VERSION]
#: the scenarios of ``--quick`` (run with 2 episodes of at most 120 steps)
QUICK_SCENARIOS: tuple[str, ...] = ("v0_paper_circle", "v0_speed_0.4", "circle_r1_ccw")


def quick_suite(suite: Sequence[Scenario] = SUITE, episodes: int = 2, max_steps: int = 120) -> tuple[Scenario, ...]:
    """The ``--quick`` subset: :data:`QUICK_SCENARIOS` with at most ``episodes`` seeds and ``max_steps`` steps."""
    return tuple(sc.cut(episodes, max_steps) for sc in suite if sc.name in QUICK_SCENARIOS)


# --------------------------------------------------------------------------- agents
def _model_spec(name: str | None, path: Path, index: int) -> AgentSpec:
    manifest_file = path.with_suffix(".json")
    manifest = json.loads(manifest_file.read_text()) if manifest_file.is_file() else None
    algo = (manifest or {}).get("algo")
    try:  # a FastPolicy zip holds model.json
        with zipfile.ZipFile(path) as z:
            fast = "model.json" in z.namelist()
    except (OSError, zipfile.BadZipFile):
        fast = False
    if fast:
        algo = algo if isinstance(algo, str) and algo.startswith(FAST_ALGO) else FAST_ALGO
    elif algo not in ALGOS:  # the first algorithm named by the file, its folder or the agent
        algo = next((a for c in (path.stem, path.parent.name, name or "") for a in ALGOS if a in c.lower()), algo)
    if algo not in ALGOS and not str(algo).startswith(FAST_ALGO):
        raise ValueError(f"{path}: cannot tell its algorithm (no manifest 'algo', no ppo/sac/td3 in the names)")
    seed = (manifest or {}).get("seed")
    if not isinstance(seed, int):
        m = re.search(r"(?:seed_?|_s)(\d+)", path.stem)
        seed = int(m.group(1)) if m else index
    return AgentSpec(name or str(algo), int(seed), str(path), str(algo), manifest)


def parse_agents(specs: Sequence[str]) -> list[AgentSpec]:
    """Agent specs from ``--agents`` (module docstring). Raises ``ValueError`` / ``FileNotFoundError``."""
    out: list[AgentSpec] = []
    for spec in specs:
        if spec in CLASSICAL:
            out.append(AgentSpec(spec))
            continue
        name, sep, pattern = spec.partition("=")
        if not sep:
            name, pattern = "", spec
        p = Path(pattern)
        if p.is_dir():
            zips = sorted(p.glob("*.zip")) + sorted(p.glob("*/*.zip"))
            if not zips:
                raise FileNotFoundError(f"--agents {spec}: no .zip in {p}")
            out += [_model_spec(name or (z.parent.name if z.parent != p else z.stem), z, i) for i, z in enumerate(zips)]
            continue
        files = sorted(glob.glob(pattern))
        if not files:
            if not sep and not pattern.endswith(".zip"):
                raise ValueError(f"--agents: unknown classical policy {spec!r} (choose from {', '.join(CLASSICAL)})")
            raise FileNotFoundError(f"--agents {spec}: no file matches {pattern!r}")
        out += [_model_spec(name or None, Path(f), i) for i, f in enumerate(files)]
    names_seeds = [(a.name, a.seed) for a in out]
    if dup := sorted({x for x in names_seeds if names_seeds.count(x) > 1}):
        raise ValueError(f"--agents: the same (agent, seed) twice: {dup}")
    return out


def generalists(root: Path) -> list[AgentSpec]:
    """The v1 generalists ``root/<folder>/*.zip`` of every folder of :data:`V1_AGENTS`, named ``<folder>_v1``."""
    return [_model_spec(f"{f}_v1", z, i) for f in V1_AGENTS for i, z in enumerate(sorted((root / f).glob("*.zip")))]


def default_agents() -> list[AgentSpec]:
    """The classical policies, the shipped v0 specialists (``<algo>_v0``) and v1 generalists (``<folder>_v1``)."""
    d = pretrained_dir()
    out = [AgentSpec(n) for n in ("analytic", "analytic_ff", "pure_pursuit", "delay_compensated")]
    out += [_model_spec(f"{a}_v0", d / f"{a}.zip", 0) for a in ALGOS if (d / f"{a}.zip").is_file()]
    return out + generalists(d / "v1")


def agent_label(name: str, algo: str | None = None) -> str:
    """What an agent is, in words (``ppo_fast_v1`` -> "fast PPO generalist", ``sac_v0`` -> "SB3 SAC v0 specialist",
    "classical", "model"); the algorithm ``algo``, when known, decides over the name."""
    if name in CLASSICAL:
        return "classical"
    labels = {**RETIRED_V1_AGENTS, **V1_AGENTS}
    v1 = name.endswith("_v1") and name[:-3] in labels
    v0 = name.endswith("_v0") and name[:-3] in ALGOS
    if algo is not None and str(algo).startswith(FAST_ALGO):
        kind = "fast PPO" + (" residual" if "residual" in str(algo) else "")
        if v1 and labels[name[:-3]].startswith("fast PPO"):  # a variant, e.g. "fast PPO robust residual"
            kind = labels[name[:-3]]
    elif algo in ALGOS:
        kind = f"SB3 {str(algo).upper()}"
        if v1 and labels[name[:-3]].startswith(kind):  # a variant, e.g. "SB3 TD3 low-pass"
            kind = labels[name[:-3]]
    elif v1:
        kind = labels[name[:-3]]
    elif v0:
        kind = f"SB3 {name[:-3].upper()}"
    else:
        return "model"
    return kind + (" generalist" if v1 else " v0 specialist" if v0 else "")


# --------------------------------------------------------------------------- evaluation
def evaluate(agent: Any, env: Any, sc: Scenario) -> list[dict[str, float]]:
    """The metrics of one episode per seed of ``sc`` (``env``, the env ``agent`` was built for, is not stepped)."""
    return [r.metrics() for r in run_scenario(agent, sc)]


def _record(spec: AgentSpec, sc: Scenario, eps: list[dict[str, float]]) -> dict[str, Any]:
    col = {k: [e[k] for e in eps] for k in eps[0]}
    rec: dict[str, Any] = {"agent": spec.name, "seed": spec.seed, "scenario": sc.name, "held_out": sc.held_out}
    rec["episodes"] = len(eps)
    for k in METRIC_NAMES[:-1]:  # means over the finite values (None: none)
        rec[{"failure": "failure_rate", "steps": "mean_steps"}.get(k, k)] = v = _finite_mean(col[k])
        if k == "return":
            rec["return_per_step"] = None if v is None else v / sc.max_steps
    rec["terminated"] = int(sum(col["terminated"]))
    rec["per_episode"] = {k: json_safe(v) for k, v in col.items()}
    return rec


def run_benchmark(
    agents: Sequence[AgentSpec],
    scenarios: Sequence[Scenario],
    *,
    progress: bool = True,
    reps: int = 10_000,
    profile_reps: int = 2_000,
    bootstrap_seed: int = 0,
    quick: bool = False,
) -> dict[str, Any]:
    """Evaluate every agent seed on every scenario and aggregate; the JSON document (docs/benchmark.md)."""
    names = [sc.name for sc in scenarios]
    if len(set(names)) != len(names):
        raise ValueError(f"scenario names must be unique, got {names}")
    t0 = time.perf_counter()
    grid = run_grid(agents, scenarios, progress=progress)
    results = [_record(spec, sc, eps) for spec, sc, eps in grid.runs]
    versions = sorted({sc.version for sc in scenarios})
    doc: dict[str, Any] = {
        "suite_version": versions[0] if len(versions) == 1 else "mixed",
        "quick": quick,
        "protocol": {
            "deterministic": True,
            "episode_metric_average": "mean over the scenario's episodes (NaN-free)",
            "settle_time_s": "per scenario (default 5 s)",
            "failure": "terminated, or |e| > failure_tolerance_m at some t >= settle_time_s",
            "h_target_m": H_TARGET_M,
            "bootstrap": "stratified over training seeds within each scenario (rliable), percentile 95 % intervals",
            "reps": reps,
            "profile_reps": profile_reps,
            "bootstrap_seed": bootstrap_seed,
            "training_distribution": TRAINING_DISTRIBUTION,
        },
        "scenarios": [sc.to_json() | {"status": grid.status[sc.name]} for sc in scenarios],
        "agents": [a.describe() for a in agents],
        "results": results,
        "unavailable": grid.unavailable,
        "feasibility": grid.feasibility,
    }
    held = {sc.name: sc.held_out for sc in scenarios}
    doc["aggregates"], doc["performance_profiles"] = aggregate(
        results, held, reps=reps, profile_reps=profile_reps, seed=bootstrap_seed
    )
    doc["paired"] = paired_differences(doc, reps=reps, seed=bootstrap_seed)
    doc["wall_time_s"] = round(time.perf_counter() - t0, 2)
    if "torch" in sys.modules:  # a network's outputs depend on torch's thread count in the last bits
        doc["torch_threads"] = int(sys.modules["torch"].get_num_threads())
    return doc


# --------------------------------------------------------------------------- aggregation
def aggregate(
    results: Sequence[dict[str, Any]],
    held_out: Mapping[str, bool],
    *,
    reps: int = 10_000,
    profile_reps: int = 2_000,
    seed: int = 0,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Per-agent aggregates (IQM, optimality gap, mean with 95 % bootstrap intervals) and H-error profiles."""
    aggregates: dict[str, Any] = {}
    profiles: dict[str, Any] = {"taus_m": list(PROFILE_TAUS), "agents": {}}
    keys = ("h_rms_m", "speed_err_rms", "failure_rate", "return_per_step")
    for agent in dict.fromkeys(r["agent"] for r in results):
        rs = [r for r in results if r["agent"] == agent and all(r[k] is not None for k in keys)]
        seeds = sorted({r["seed"] for r in rs})
        table = {(r["seed"], r["scenario"]): r for r in rs}
        common = [c for c in dict.fromkeys(r["scenario"] for r in rs) if all((s, c) in table for s in seeds)]
        groups = {
            "all": common,
            "in_distribution": [c for c in common if not held_out.get(c, False)],
            "held_out": [c for c in common if held_out.get(c, False)],
        }
        entry: dict[str, Any] = {"n_runs": len(seeds), "seeds": seeds}
        for g, scen in groups.items():
            if not scen:
                entry[g] = None
                continue
            m = {k: np.array([[table[(s, c)][k] for c in scen] for s in seeds]) for k in keys}
            h, mean = m["h_rms_m"], lambda s: np.mean(s, axis=(-2, -1))
            stats = {  # name: (scores, higher-is-better statistic)
                "h_rms_m_iqm": (h, iqm),
                "h_rms_m_optimality_gap": (-h, lambda s: optimality_gap(s, -H_TARGET_M)),
                "speed_err_rms_iqm": (m["speed_err_rms"], iqm),
                "failure_rate_mean": (m["failure_rate"], mean),
                "return_per_step_iqm": (m["return_per_step"], iqm),
                "return_per_step_optimality_gap": (m["return_per_step"], optimality_gap),
            }
            gi = {"n_scenarios": len(scen), "scenarios": scen}
            for name, (x, stat) in stats.items():
                pt, ci = stratified_bootstrap(x, stat, reps=reps, seed=seed)
                gi[name] = {"value": float(pt), "ci95": [float(ci[0]), float(ci[1])]}
            entry[g] = gi
            if g == "all":
                profile = partial(score_distribution, taus=-np.asarray(PROFILE_TAUS))  # fraction of -H above -tau
                prof, band = stratified_bootstrap(-h, profile, reps=profile_reps, seed=seed)
                keys_ = ("fraction_below", "ci95_low", "ci95_high")
                profiles["agents"][agent] = dict(zip(keys_, (prof.tolist(), *band.tolist()), strict=True))
        if entry["all"] is not None:
            top = entry["all"]["h_rms_m_iqm"]
            entry = {"metric": "h_rms_m", "iqm": top["value"], "ci95": top["ci95"], **entry}
        aggregates[str(agent)] = entry
    return aggregates, profiles


# --------------------------------------------------------------------------- paired difference to the analytic
#: the agent every other one is paired with
BASELINE = "analytic"


def _episodes_mm(runs: Sequence[Mapping[str, Any]]) -> Array | None:
    """H RMS [mm] of ``runs`` as ``(runs, episodes)`` (``None`` -> NaN); ``None`` for no runs or unequal counts."""
    h = [r["per_episode"]["h_rms_m"] for r in runs]
    return np.array(h, dtype=np.float64) * 1e3 if len({len(x) for x in h}) == 1 else None


def _failures(runs: Iterable[Mapping[str, Any]]) -> list[float]:
    """The finite per-episode failure flags (1: failed) of ``runs``."""
    return [f for r in runs for f in r["per_episode"]["failure"] if f is not None and math.isfinite(f)]


def _finite_mean(values: Iterable[Any]) -> float | None:
    """The mean of the finite ``values`` (``None`` -> NaN); ``None`` if there is none."""
    x = np.asarray(list(values), dtype=np.float64)
    return float(x[np.isfinite(x)].mean()) if np.isfinite(x).any() else None


def paired_differences(doc: Mapping[str, Any], *, reps: int = 10_000, seed: int = 0) -> dict[str, Any]:
    """The JSON ``paired`` (module docstring) of a benchmark document ``doc`` (its ``scenarios`` and ``results``):
    every agent against :data:`BASELINE`, ``reps`` bootstrap resamples."""
    by: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in sorted(doc["results"], key=lambda r: r["seed"]):
        by.setdefault((r["agent"], r["scenario"]), []).append(r)
    agents: dict[str, Any] = {}
    for agent in dict.fromkeys(r["agent"] for r in doc["results"] if r["agent"] != BASELINE):
        rng, cells = np.random.default_rng(seed), []
        for sc in doc["scenarios"]:
            base_runs, runs = by.get((BASELINE, sc["name"]), []), by.get((agent, sc["name"]), [])
            base, ag = _episodes_mm(base_runs), _episodes_mm(runs)
            if base is None or ag is None or base.shape[1] != ag.shape[1]:
                continue
            if not (keep := np.isfinite(base).all(axis=0) & np.isfinite(ag).all(axis=0)).any():
                continue
            base, ag = base[:, keep].mean(axis=0), ag[:, keep]
            diff = ag.mean(axis=0) - base
            diff_ci, base_ci, ag_ci = (  # percentile 95 % intervals of the mean, in this order from rng
                [float(v) for v in np.percentile(x[rng.integers(0, x.size, (reps, x.size))].mean(axis=1), [2.5, 97.5])]
                for x in (diff, base, ag.ravel())
            )
            cells.append({
                "scenario": sc["name"], "held_out": bool(sc["held_out"]), "seeds": [r["seed"] for r in runs],
                "episodes": int(diff.size), "baseline_mm": float(base.mean()), "agent_mm": float(ag.mean()),
                "agent_seeds_mm": [float(x) for x in ag.mean(axis=1)],
                "ratio": float(ag.mean() / base.mean()) if base.mean() != 0 else None, "diff_mm": float(diff.mean()),
                "diff_ci95_mm": diff_ci, "baseline_ci95_mm": base_ci, "agent_ci95_mm": ag_ci,
                "overlap": base_ci[0] <= ag_ci[1] and ag_ci[0] <= base_ci[1], "failed": int(sum(_failures(runs))),
                "agent_episodes": int(ag.size), "baseline_failed": int(sum(_failures(base_runs[:1]))),
                "chatter_settled_rms": _finite_mean(r.get("chatter_settled_rms") for r in runs),
            })  # fmt: skip
        if cells:
            trimmed = {k: float(trim_mean([c[f"{k}_mm"] for c in cells], 0.25)) for k in ("baseline", "agent")}
            agents[str(agent)] = {"cells": cells, "trimmed_mean_mm": trimmed}
    return {"baseline": BASELINE, "metric": "h_rms_m", "unit": "mm", "reps": reps, "seed": seed, "agents": agents}


def paired_lines(paired: Mapping[str, Any]) -> list[str]:
    """The Markdown section "Paired difference to the analytic controller" of ``paired`` (empty: no agent)."""
    if not paired.get("agents"):
        return []
    base = paired["baseline"]
    lines = [
        "",
        f"## Paired difference to the {'analytic controller' if base == BASELINE else f'`{base}`'}",
        "",
        f"H RMS [mm] per cell where both ran, on the same episodes (reset seeds, start offsets). Δ: the paired mean "
        f"difference, agent minus {base}, per episode averaged over the agent's training seeds, with its 95 % "
        f"percentile bootstrap interval over the episodes ({paired['reps']} resamples, seed {paired['seed']}); "
        f"ratio: of the means; failed: the agent's failed episodes over all its seeds; {base} failed: its own.",
        "",
    ]
    rows, summary = [], []
    for agent, a in paired["agents"].items():
        rows += [(
            agent, c["scenario"], "yes" if c["held_out"] else "", f"{c['baseline_mm']:.2f}", f"{c['agent_mm']:.2f}",
            "–" if c["ratio"] is None else f"{c['ratio']:.2f}",
            "{:+.2f} [{:+.2f}, {:+.2f}]".format(c["diff_mm"], *c["diff_ci95_mm"]),
            f"{c['failed']} of {c['agent_episodes']}", f"{c['baseline_failed']} of {c['episodes']}",
        ) for c in a["cells"]]  # fmt: skip
        t, cis = a["trimmed_mean_mm"], [c["diff_ci95_mm"] for c in a["cells"]]
        summary.append(
            f"- `{agent}`: interval below 0 on {sum(h < 0 for _, h in cis)}, above 0 on {sum(lo > 0 for lo, _ in cis)}"
            f" of {len(cis)} cells; trimmed mean (25 %) of the per-cell means {t['agent']:.2f} mm against {base}'s "
            f"{t['baseline']:.2f} mm"
        )
    header = ("agent", "cell", "held out", f"{base} [mm]", "agent [mm]", "ratio", "Δ [mm] (95 % CI)", "failed")
    return lines + tm.md_table((*header, f"{base} failed"), rows, right=6) + ["", *summary]


# --------------------------------------------------------------------------- reports
def failed_episodes(doc: Mapping[str, Any], agent: str) -> tuple[int, int]:
    """``(failed, episodes)`` of ``agent`` on the scenarios its aggregate covers."""
    scenarios = set(doc["aggregates"][agent]["all"]["scenarios"])
    flags = _failures(r for r in doc["results"] if r["agent"] == agent and r["scenario"] in scenarios)
    return int(sum(flags)), len(flags)


def _mm(x: float | None) -> str:
    return "–" if x is None else f"{1e3 * x:.3g}"


def _iv(d: Mapping[str, Any] | None, scale: float = 1e3, fmt: str = ".3g") -> str:
    """``value [low, high]`` of an aggregate times ``scale``; "–" for none."""
    if d is None:
        return "–"
    lo, hi = d["ci95"]
    return f"{scale * d['value']:{fmt}} [{scale * lo:{fmt}}, {scale * hi:{fmt}}]"


def _values(doc: Mapping[str, Any], agent: str, scenario: str, key: str) -> list[Any]:
    """``key`` of every training seed's run of ``agent`` on ``scenario`` (``None`` left out)."""
    rs = doc["results"]
    return [r[key] for r in rs if (r["agent"], r["scenario"]) == (agent, scenario) and r.get(key) is not None]


def markdown_report(doc: Mapping[str, Any]) -> str:
    """Markdown: the aggregate table, the per-scenario table of H RMS, the unavailable scenarios."""
    lines = [
        f"# AmigoBot benchmark, suite {doc['suite_version']}" + (" (quick subset)" if doc.get("quick") else ""),
        "",
        f"IQM and optimality gap over (training seed, scenario) runs; [95 % stratified-bootstrap interval, "
        f"{doc['protocol']['reps']} replications]. H-error gap target {1e3 * H_TARGET_M:g} mm.",
        "",
    ]
    rows = []
    for agent, a in doc["aggregates"].items():
        if (g := a.get("all")) is None:
            continue
        h = a.get("held_out")
        failed, episodes = failed_episodes(doc, agent)
        rows.append((
            agent, a["n_runs"], g["n_scenarios"], f"{failed} of {episodes}", _iv(g["h_rms_m_iqm"]),
            _iv(g["h_rms_m_optimality_gap"]), _iv(g["speed_err_rms_iqm"]), _iv(g["failure_rate_mean"], 1.0, ".2f"),
            _iv(g["return_per_step_iqm"], 1.0, ".3f"), _iv(h["h_rms_m_iqm"]) if h else "–",
        ))  # fmt: skip
    header: tuple[str, ...] = ("agent", "seeds", "scenarios", "failed episodes", "H RMS IQM [mm]", "H gap [mm]")
    header += ("speed err IQM [mm/s]", "failure rate", "return/step IQM", "held-out H RMS IQM [mm]")
    lines += tm.md_table(header, rows)
    algos = {a["agent"]: a.get("algo") for a in doc.get("agents", [])}
    legend = [f"`{name}`: {agent_label(name, algos.get(name))}" for name in doc["aggregates"]]
    lines += ["", "Agents: " + "; ".join(legend) + "."]
    lines += paired_lines(doc.get("paired") or {})
    agents = list(doc["aggregates"])
    per_scenario = (
        ("h_rms_m", "H cross-track RMS per scenario [mm]", _mm),
        ("speed_err_rms", "Speed error RMS per scenario [mm/s]", _mm),
        ("h_rms_settled_m", "H cross-track RMS after settling (t >= 5 s) per scenario [mm]", _mm),
        ("speed_err_settled_rms", "Speed error RMS after settling (t >= 5 s) per scenario [mm/s]", _mm),
        ("chatter_settled_rms", "Command chatter after settling per scenario [rad/s]", lambda x: f"{x:.3g}"),
    )
    for key, title, fmt in per_scenario:
        rows = []
        for sc in doc["scenarios"]:
            cells = (fmt(float(np.mean(v))) if (v := _values(doc, a, sc["name"], key)) else "–" for a in agents)
            rows.append((sc["name"], "yes" if sc["held_out"] else "", *cells))
        lines += [
            "",
            f"## {title} (mean over training seeds)",
            "",
            *tm.md_table(("scenario", "held out", *agents), rows),
        ]
    if infeasible := {n: r for n, r in doc.get("feasibility", {}).items() if not r["feasible"]}:
        lines += ["", "## Paths beyond the robot's limits (feasibility='warn' or 'off')", ""]
        for name, r in infeasible.items():
            where = "; ".join(
                f"{q.replace('_', ' ')} at s = " + ", ".join(f"[{a:.2f}, {b:.2f}]" for a, b in ivs) + " m"
                for q, ivs in r["exceeded"].items()
                if ivs
            )
            lines.append(f"- {name}: {r['message']}; exceeded: {where}")
    if doc["unavailable"]:
        lines += ["", "## Unavailable", ""]
        lines += [f"- {line}" for line in unavailable_lines(doc["unavailable"])]
    return "\n".join(lines) + "\n"


#: the README's labels of the agents of its v1 table (the generalists under either name, bare or ``_v1``)
README_ROWS = (
    ("analytic", "analytic tracking (exact inverse solution + PI feedback)"),
    ("pure_pursuit", "pure pursuit (of A)"),
    ("delay_compensated", "delay compensator (analytic on the predicted error)"),
    *((f"{folder}_v1", label) for folder, label in V1_AGENTS.items()),
)


def readme_table(doc: Mapping[str, Any]) -> str:
    """The README's AmigoBot-v1 table from a benchmark JSON (``--table-from``), the best of each column in bold.
    Raises ``ValueError`` if the document lacks the classical rows or every generalist."""
    aggs = doc["aggregates"]
    rows: list[tuple[str, Mapping[str, Any], int, str]] = []
    for name, label in README_ROWS:
        key = name if name in aggs else name.removesuffix("_v1")
        agg = aggs.get(key)
        if agg is None or agg.get("all") is None:
            continue
        n = int(agg["n_runs"])
        bad, episodes = failed_episodes(doc, key)
        rows.append((label if n == 1 else f"{label}, {n} seeds", agg, n, f"{bad} of {episodes}"))
    if len(rows) < 3:
        raise ValueError("the benchmark document lacks the analytic, pure pursuit or generalist rows")
    cols = (("all", "h_rms_m_iqm", ".2f"), ("held_out", "h_rms_m_iqm", ".2f"), ("all", "speed_err_rms_iqm", ".1f"))
    best = [min(1e3 * agg[g][k]["value"] for _, agg, _, _ in rows if agg.get(g)) for g, k, _ in cols]
    table: list[tuple[str, ...]] = []
    for label, agg, n, failed in rows:
        cells = []
        for (g, k, fmt), low in zip(cols, best, strict=True):
            d = agg.get(g)
            v = f"{1e3 * d[k]['value']:{fmt}}" if d else "–"
            text = _iv(d[k], fmt=fmt) if d and n > 1 else v
            cells.append(f"**{text}**" if d and v == f"{low:{fmt}}" else text)
        table.append((label, failed, *cells))
    header = ("agent", "failed episodes", "H RMS IQM [mm] (95 % CI)", "held-out H RMS IQM [mm]")
    return "\n".join(tm.md_table((*header, "speed error IQM [mm/s]"), table, right=4)) + "\n"


def unavailable_lines(unavailable: Sequence[Mapping[str, Any]]) -> list[str]:
    """The unavailable runs, one line per agent and reason, its seeds and scenarios listed once."""
    groups: dict[tuple[Any, str], list[Mapping[str, Any]]] = {}
    for u in unavailable:
        groups.setdefault((u["agent"], str(u["reason"])), []).append(u)
    out = []
    for (agent, reason), us in groups.items():
        seeds = list(dict.fromkeys(u.get("seed") for u in us))
        who = f"{agent} (seed {seeds[0]})" if len(seeds) == 1 else f"{agent} ({len(seeds)} training seeds)"
        scenarios = ", ".join(dict.fromkeys(u["scenario"] for u in us))
        out.append(f"{'all agents' if agent is None else who} on {scenarios}: {reason}")
    return out


def plot_scenarios(doc: Mapping[str, Any], path: Path, reps: int = 2_000, seed: int = 0) -> None:
    """:func:`scenarios_figure` saved as PNG (the evaluation notebook draws it)."""
    save_figure(scenarios_figure(doc, reps, seed), path)


def scenarios_figure(doc: Mapping[str, Any], reps: int = 2_000, seed: int = 0) -> Any:
    """Per-scenario bars of H RMS (mean over training seeds, 95 % bootstrap interval), log scale."""
    plt = pyplot()
    scen = [s["name"] for s in doc["scenarios"] if s["status"] == "ok"]
    agents = list(doc["aggregates"])
    size = (min(18.0, max(6.0, 0.45 * len(scen) + 2.0)) + 1.6, 4.8)  # at most 19.6 in wide: fits a page
    fig, ax = plt.subplots(figsize=size, layout="constrained")
    width = 0.8 / max(1, len(agents))
    floor = 1e-7
    for j, agent in enumerate(agents):
        xs, ys, lo, hi = [], [], [], []
        for i, name in enumerate(scen):
            if not (vals := _values(doc, agent, name, "h_rms_m")):
                continue
            m = np.asarray(vals, dtype=np.float64).reshape(-1, 1)
            pt, ci = stratified_bootstrap(m, lambda s: np.mean(s, axis=(-2, -1)), reps=reps, seed=seed)
            xs.append(i + (j - (len(agents) - 1) / 2) * width)
            ys.append(max(float(pt), floor))
            lo.append(max(float(pt), floor) - max(float(ci[0]), floor))
            hi.append(max(float(ci[1]), floor) - max(float(pt), floor))
        ax.bar(xs, ys, width, yerr=[lo, hi], capsize=2, label=agent)
    ax.set_xticks(range(len(scen)), scen, rotation=60, ha="right", fontsize=8)
    quick = " (quick subset)" if doc.get("quick") else ""
    title = f"AmigoBot benchmark {doc['suite_version']}{quick}: H error per scenario\n"
    ax.set(yscale="log", ylabel="H cross-track RMS [m]")
    ax.set_title(title + "mean over training seeds, 95 % bootstrap interval", fontsize=10)
    fig.legend(loc="outside right upper", fontsize=8, title="agent", title_fontsize=8)
    return fig


def plot_profiles(doc: Mapping[str, Any], path: Path) -> None:
    """Performance profiles: fraction of (seed, scenario) runs with H RMS below tau, with bootstrap bands."""
    plt = pyplot()
    prof = doc["performance_profiles"]
    taus = np.asarray(prof["taus_m"])
    fig, ax = plt.subplots(figsize=(6, 4))
    for agent, p in prof["agents"].items():
        (line,) = ax.plot(taus, p["fraction_below"], label=agent)
        ax.fill_between(taus, p["ci95_low"], p["ci95_high"], color=line.get_color(), alpha=0.2)
    ax.set(xscale="log", xlabel=r"threshold $\tau$ on H cross-track RMS [m]", ylim=(-0.02, 1.02))
    ax.set(ylabel=r"fraction of runs with RMS $< \tau$", title="Performance profiles (rliable score distributions)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_all(doc: Mapping[str, Any], folder: Path) -> list[str]:
    """Draw ``benchmark_scenarios.png`` and ``benchmark_profiles.png`` into ``folder``; their names."""
    plot_scenarios(doc, folder / "benchmark_scenarios.png", seed=int(doc["protocol"]["bootstrap_seed"]))
    plot_profiles(doc, folder / "benchmark_profiles.png")
    return ["benchmark_scenarios.png", "benchmark_profiles.png"]


#: the manifest naming a published set of benchmark outputs (in ``--out``)
MANIFEST = "benchmark_manifest.json"
#: names of the temporary files and folders a benchmark writes in ``--out`` (removed by the next run)
_TEMPORARY = re.compile(r"^\.(staging-benchmark-.*|benchmark[._].*|benchmark_manifest\..*)$")


def write_outputs(
    doc: Mapping[str, Any], out: Path, json_path: Path, md_path: Path, *, plots: bool = True
) -> list[Path]:
    """Publish the JSON, the Markdown and (``plots``) the two figures as one set with :data:`MANIFEST` written last
    (:func:`amigo_gym.tools.runs.publish`); the paths written."""
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out, prefix=".staging-benchmark-", ignore_cleanup_errors=True) as tmp:
        staging = Path(tmp)
        targets = {json_path: staging / "benchmark.json", md_path: staging / "benchmark.md"}
        atomic_write_json(targets[json_path], doc)
        atomic_write(targets[md_path], markdown_report(doc))
        if plots and doc["results"]:
            targets |= {out / name: staging / name for name in plot_all(doc, staging)}
        publish(targets, out, MANIFEST, command=doc.get("command"))
    return list(targets)


def verify_outputs(out: Path) -> dict[str, str]:
    """The manifest's ``{file: sha256}`` after checking every file (:func:`amigo_gym.tools.runs.verify_manifest`)."""
    return verify_manifest(out, MANIFEST)


# --------------------------------------------------------------------------- command line
@dataclass(frozen=True)
class BenchmarkSettings:
    """Options of ``amigo-gym benchmark``, each the option of the same name unless its ``cli(flag)`` names one.

    Attributes:
        agents: classical names, NAME=GLOB of zips, zips or folders [agents] (default: the classical policies and
            the shipped models).
        scenarios: scenario names [names] (default: the whole suite).
        suite: suite version.
        quick: small subset: 3 scenarios, 2 episodes of <= 120 steps.
        out: output folder [dir].
        json: JSON file [file] (default: <out>/benchmark.json).
        markdown: Markdown file [file] (default: <out>/benchmark.md).
        reps: bootstrap replications of the intervals [reps], >= 1.
        profile_reps: bootstrap replications of the profiles [reps], >= 1.
        bootstrap_seed: seed of the bootstrap [-].
        plots: draw the plots; --no-plots: skip the plots.
        progress: show a progress bar; --no-progress: no progress bar.
        list_suite: print the suite and exit.
        table_from: run nothing: print the README's v1 table from this benchmark.json [file] (default: none).
        path: run on paths of your own instead of the suite: points files (.csv/.json, columns x, y [m];
            amigo_gym.paths.from_file), one AmigoBot-v1 scenario each [files] (default: none, the suite).
        speed: reference speed on --path [m/s].
        feasibility: --path beyond the robot's limits: refuse, warn or run (default off: run; the report lists
            them).
        goal_tolerance: open --path: success within this of the end [m] (default 0: off).
        duration: episode length on --path [s].
        curvature: run the curvature cells instead of the suite: failure rate per path-curvature bin
            (amigo_gym.tools.training.curvature; writes <out>/curvature.json and .md).
        curvature_episodes: episodes per curvature cell [episodes], >= 1.
        random_paths: run this many paths of the published random-path protocol instead of the suite (Cao et al.
            2024; amigo_gym.tools.training.random_paths; writes <out>/random_paths.json and .md) [paths] (default 0:
            off).
        random_paths_seed: seed of the paths' RandomState (100: the paper's 1000 paths) [-].
        condition: --random-paths: "paper" (ideal actuators, rolling start, dt 0.05 s, H on the axle) or
            "firmware" (AmigoBot-v1's defaults).
        tolerance: --random-paths: a path fails when the peak |cross-track error| reaches this [m].
    """

    agents: list[str] | None = None
    scenarios: list[str] | None = None
    suite: str = field(default=SUITE_VERSION, metadata=cli(choices=tuple(sorted(SUITES))))
    quick: bool = False
    out: str = "results/benchmark"
    json: str | None = None
    markdown: str | None = None
    reps: int = 10_000
    profile_reps: int = 2_000
    bootstrap_seed: int = 0
    plots: bool = field(default=True, metadata=cli("--no-plots"))
    progress: bool = field(default=True, metadata=cli("--no-progress"))
    list_suite: bool = field(default=False, metadata=cli("--list"))
    table_from: str | None = field(default=None, metadata=cli(metavar="FILE"))
    path: list[str] | None = field(default=None, metadata=cli(metavar="FILE"))
    speed: float = 0.2
    feasibility: Literal["error", "warn", "off"] = "off"
    goal_tolerance: float = 0.0
    duration: float = 60.0
    curvature: bool = False
    curvature_episodes: int = 50
    random_paths: int = field(default=0, metadata=cli(metavar="N"))
    random_paths_seed: int = rp.SEED
    condition: Literal["paper", "firmware"] = "paper"
    tolerance: tuple[float, ...] = rp.TOLERANCES

    def validate(self) -> None:
        """Raise ``ValueError`` naming the option, its allowed range and the value."""
        for name in ("reps", "profile_reps", "curvature_episodes"):
            if getattr(self, name) < 1:
                raise ValueError(f"--{name.replace('_', '-')} must be >= 1, got {getattr(self, name)}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym benchmark``."""
    args = list(sys.argv[1:] if argv is None else argv)
    a = parse_settings(BenchmarkSettings, args, "amigo-gym benchmark", "Run the AmigoBot benchmark suite.")
    command = "amigo-gym benchmark " + " ".join(args)

    def run() -> int:
        one_torch_thread()
        suite = SUITES[a.suite]
        if a.table_from is not None:
            print(readme_table(json.loads(Path(a.table_from).read_text(encoding="utf-8"))), end="")
            return 0
        if a.list_suite:
            for sc in suite:
                size, flag = f"{sc.episodes:>3} ep {sc.max_steps:>4} steps", "held out" if sc.held_out else ""
                print(f"{sc.name:<22} {sc.env_id:<12} {size} {flag:<9}{sc.description}")
            return 0
        if sum(map(bool, (a.curvature, a.random_paths, a.path or a.scenarios))) > 1:
            raise ValueError("--curvature, --random-paths and --path/--scenarios exclude each other")
        if a.path and a.scenarios:
            raise ValueError("--path and --scenarios exclude each other")
        paths = rp.path_set(a.random_paths, a.condition, a.random_paths_seed, a.speed, a.tolerance)
        if a.curvature:
            scenarios = curvature.cell_specs(episodes=a.curvature_episodes)
        elif a.random_paths:
            scenarios = paths.scenarios
        elif a.path:
            scenarios = user_scenarios(a.path, a.speed, a.feasibility, a.goal_tolerance, a.duration)
        else:
            scenarios = tuple(sc for sc in suite if not a.quick or sc.name in QUICK_SCENARIOS)
        if a.quick:  # every cell, shorter
            scenarios = tuple(sc.cut(2, 120) for sc in scenarios)
        if a.scenarios:
            known = {sc.name: sc for sc in suite}
            if bad := [n for n in a.scenarios if n not in known]:
                raise ValueError(f"--scenarios: unknown {bad}; see amigo-gym benchmark --list")
            chosen = {sc.name: sc for sc in scenarios}
            scenarios = tuple(chosen.get(n, known[n]) for n in a.scenarios)
        agents = parse_agents(a.agents) if a.agents else default_agents()
        out = Path(a.out)
        with RunLock(out):  # one benchmark at a time on --out (a second one stops with one line)
            if a.curvature:
                name, doc = "curvature", curvature.run_curvature(agents, scenarios, progress=a.progress)
            elif a.random_paths:
                ps = replace(paths, scenarios=scenarios)
                name, doc = "random_paths", rp.run_random_paths(agents, ps, progress=a.progress)
            else:
                remove_matching(out, _TEMPORARY)  # what killed benchmarks left
                kw = {"reps": a.reps, "profile_reps": a.profile_reps, "bootstrap_seed": a.bootstrap_seed}
                name, doc = "benchmark", run_benchmark(agents, scenarios, progress=a.progress, quick=a.quick, **kw)
            doc["command"] = command
            if name == "benchmark":
                json_path = Path(a.json) if a.json else out / "benchmark.json"
                md_path = Path(a.markdown) if a.markdown else out / "benchmark.md"
                written = write_outputs(doc, out, json_path, md_path, plots=a.plots)
                report = markdown_report(doc)
            else:
                report = (curvature.markdown_curvature if a.curvature else rp.markdown_random_paths)(doc)
                written = [out / f"{name}.json", out / f"{name}.md"]
                atomic_write_json(written[0], doc)
                atomic_write(written[1], report)
        print(report, end="")
        print("wrote " + ", ".join(map(str, written)))
        return 0

    return run_guarded(run, "amigo-gym benchmark")
