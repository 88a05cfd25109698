"""``amigo-gym curves``: learning curves over training seeds and the time to reach a tracking threshold (usage, the
run folders read, the aggregation over seeds, the threshold, the output files: docs/benchmark.md, "Reference:
`amigo-gym curves`")."""

from __future__ import annotations

import itertools
import math
import re
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.io import atomic_write, atomic_write_json
from amigo_gym.tools import runs
from amigo_gym.tools.options import cli, run_command, say
from amigo_gym.tools.plots import pyplot, save_figure
from amigo_gym.tools.training.intervals import stratified_bootstrap
from amigo_gym.tools.training.task_metrics import md_table

#: the metric of the tracking threshold: H's cross-track RMS once settled (t >= 5 s) [m]
THRESHOLD_METRIC = "h_rms_settled_m"
#: the tracking threshold [m], fixed in advance (module docstring)
DEFAULT_THRESHOLD_M = 0.005
#: the plotted metrics and their labels
CURVE_METRICS: dict[str, str] = {"h_rms_m": "H cross-track RMS [m]", "mean_reward": "evaluation return"}
#: the x axes and their labels
AXES: dict[str, str] = {"timesteps": "environment steps", "wall_time_s": "wall time [s]"}
_NAME = re.compile(r"^(?P<algo>[A-Za-z][A-Za-z0-9]*)_s(?P<seed>\d+)$")


@dataclass(frozen=True)
class Run:
    """One training run: its ``eval.json`` evaluations (sorted by ``timesteps``, the last kept per step) and the
    ``group`` it is aggregated under (the algorithm, with the env id if the runs differ in it)."""

    algo: str
    seed: int
    path: Path
    env_id: str | None
    evals: tuple[dict[str, Any], ...]
    group: str = ""


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(float(x))


def _read_run(run_dir: Path) -> Run:
    """The run in ``run_dir`` (its group not set); ``ValueError`` saying why it is none."""
    if not (run_dir / "eval.json").is_file():
        raise ValueError("no eval.json")
    cfg: Any = runs.read_json(run_dir / "config.json") if (run_dir / "config.json").is_file() else None
    settings: Any = cfg.get("settings") if isinstance(cfg, dict) else None
    algo, seed = (settings.get("algo"), settings.get("seed")) if isinstance(settings, dict) else (None, None)
    if isinstance(algo, str) and isinstance(seed, int) and not isinstance(seed, bool):
        env = cfg.get("env_id", settings.get("env_id"))
    elif m := _NAME.match(run_dir.name):
        algo, seed, env = m.group("algo").lower(), int(m.group("seed")), None
    else:
        raise ValueError("no config.json with settings.algo and settings.seed, and the name is not <algo>_s<seed>")
    data = runs.read_json(run_dir / "eval.json")
    if not isinstance(data, list) or not all(isinstance(e, dict) and _finite(e.get("timesteps")) for e in data):
        raise ValueError("eval.json is not a list of evaluations with 'timesteps'")
    if not (by_step := {int(e["timesteps"]): e for e in data}):  # a repeated step (resumed run) keeps its later one
        raise ValueError("eval.json holds no evaluation yet")
    return Run(algo, seed, run_dir, env if isinstance(env, str) else None, tuple(by_step[k] for k in sorted(by_step)))


def find_runs(folders: Sequence[str | Path]) -> tuple[list[Run], list[dict[str, str]]]:
    """The run folders in ``folders``: ``(runs, skipped)``, each skip with its reason. Raises
    ``FileNotFoundError`` for a missing folder, ``ValueError`` for the same (group, seed) twice."""
    found: list[Run] = []
    skipped: list[dict[str, str]] = []
    for folder in map(Path, folders):
        if not folder.is_dir():
            raise FileNotFoundError(f"--runs: no directory {folder}")
        candidates = [folder] if (folder / "eval.json").is_file() else sorted(p for p in folder.iterdir() if p.is_dir())
        for run_dir in candidates:
            try:
                found.append(_read_run(run_dir))
            except ValueError as exc:  # includes CorruptFileError
                skipped.append({"path": str(run_dir), "reason": " ".join(str(exc).split())})
    several_envs = len({r.env_id for r in found if r.env_id is not None}) > 1
    runs_out = [replace(r, group=f"{r.algo} {r.env_id}" if several_envs and r.env_id else r.algo) for r in found]
    seen: dict[tuple[str, int], Run] = {}
    for r in runs_out:
        if (first := seen.setdefault((r.group, r.seed), r)) is not r:
            raise ValueError(f"--runs: {r.group} seed {r.seed} twice ({first.path} and {r.path})")
    runs_out.sort(key=lambda r: (r.group, r.seed))
    return runs_out, skipped


def curve(runs: Sequence[Run], axis: str, metric: str, *, reps: int = 10_000, seed: int = 0) -> dict[str, Any] | None:
    """Mean over ``runs`` of ``metric`` against ``axis`` (step functions on the range every seed covers) with its
    pointwise 95 % bootstrap band over seeds; ``None`` if the seeds share no range."""
    series: dict[int, tuple[np.ndarray[Any, Any], np.ndarray[Any, Any]]] = {}
    for r in runs:  # each seed's (x, y) points, sorted by x
        pts = [(float(e[axis]), float(e[metric])) for e in r.evals if _finite(e.get(axis)) and _finite(e.get(metric))]
        xy = np.asarray(sorted(pts, key=lambda p: p[0]), dtype=np.float64).reshape(-1, 2)
        series[r.seed] = xy[:, 0], xy[:, 1]
    series = {s: xy for s, xy in series.items() if xy[0].size}
    if not series:
        return None
    lo, hi = max(float(x[0]) for x, _ in series.values()), min(float(x[-1]) for x, _ in series.values())
    if lo > hi:
        return None
    grid = np.unique(np.concatenate([x[(x >= lo) & (x <= hi)] for x, _ in series.values()]))
    values = np.stack([y[np.searchsorted(x, grid, side="right") - 1] for x, y in series.values()])
    point, ci = stratified_bootstrap(values, lambda s: np.mean(s, axis=-2), reps=reps, seed=seed)
    return {
        "x": grid.tolist(),
        "mean": point.tolist(),
        "ci95_low": ci[0].tolist(),
        "ci95_high": ci[1].tolist(),
        "seeds": sorted(series),
        "n_seeds": len(series),
        "per_seed": {str(s): {"x": x.tolist(), "y": y.tolist()} for s, (x, y) in sorted(series.items())},
    }


def threshold_summary(
    runs: Sequence[Run], metric: str = THRESHOLD_METRIC, threshold: float = DEFAULT_THRESHOLD_M
) -> dict[str, Any]:
    """Per seed the first evaluation with ``metric <= threshold``, how many seeds reached it and the medians (a seed
    that never did counting as later than any that did; ``None``: the median is not reached)."""
    per_seed = []
    for run in runs:
        hit = next((e for e in run.evals if _finite(e.get(metric)) and float(e[metric]) <= threshold), None)
        p: dict[str, Any] = {"seed": run.seed, "reached": hit is not None, "timesteps": None, "wall_time_s": None}
        if hit is not None:
            wall = float(hit["wall_time_s"]) if _finite(hit.get("wall_time_s")) else None
            p |= {"timesteps": int(hit["timesteps"]), "wall_time_s": wall}
        else:
            last = run.evals[-1]
            value = float(last[metric]) if _finite(last.get(metric)) else None
            p |= {"last_timesteps": int(last["timesteps"]), "last_value": value}
        per_seed.append(p)

    def median(key: str) -> float | None:
        med = float(np.median([math.inf if p[key] is None else p[key] for p in per_seed] or [math.inf]))
        return None if math.isinf(med) else med

    return {
        "n_seeds": len(per_seed),
        "n_reached": sum(p["reached"] for p in per_seed),
        "median_timesteps": median("timesteps"),
        "median_wall_time_s": median("wall_time_s"),
        "per_seed": per_seed,
    }


def learning_curves(
    folders: Sequence[str | Path],
    *,
    metric: str = THRESHOLD_METRIC,
    threshold: float = DEFAULT_THRESHOLD_M,
    reps: int = 10_000,
    bootstrap_seed: int = 0,
    progress: bool = False,
) -> dict[str, Any]:
    """Every curve and the threshold table of the runs in ``folders``; the JSON document. Raises ``ValueError``: no
    usable run, bad ``threshold`` or ``reps``."""
    from tqdm.auto import tqdm

    if not (math.isfinite(threshold) and threshold > 0):
        raise ValueError(f"--threshold must be a finite number > 0 [m], got {threshold}")
    if isinstance(reps, bool) or not isinstance(reps, int) or reps < 1:
        raise ValueError(f"--reps must be an integer >= 1, got {reps}")
    t0 = time.perf_counter()
    found, skipped = find_runs(folders)
    for s in skipped:
        say(f"amigo-gym curves: skipping {s['path']}: {s['reason']}")
    if not found:
        raise ValueError(f"--runs: no run folder with an eval.json in {', '.join(map(str, folders))}")
    groups = {g: list(rs) for g, rs in itertools.groupby(found, key=lambda r: r.group)}  # found is sorted by group
    say(f"{len(found)} runs: " + ", ".join(f"{g} ({len(rs)} seeds)" for g, rs in groups.items()))
    curves: dict[str, Any] = {}
    jobs = [(g, axis, m) for g in groups for axis in AXES for m in CURVE_METRICS]
    for g, axis, m in tqdm(jobs, desc="curves", unit="curve", file=sys.stderr, disable=not progress):
        curves.setdefault(g, {}).setdefault(axis, {})[m] = curve(groups[g], axis, m, reps=reps, seed=bootstrap_seed)
    return {
        "protocol": {
            "curve": "mean over training seeds of each seed's latest evaluation at or before x; drawn where every "
            "seed has evaluations",
            "interval": "pointwise 95 % percentile bootstrap over training seeds (seeds resampled with replacement)",
            "reps": reps,
            "bootstrap_seed": bootstrap_seed,
            "threshold_metric": metric,
            "threshold_m": threshold,
            "threshold_rule": "first evaluation with metric <= threshold; median over all seeds, a seed that never "
            "reached it counting as later than any that did",
        },
        "runs": [
            {"group": r.group, "algo": r.algo, "seed": r.seed, "env_id": r.env_id, "path": str(r.path)}
            | {"evaluations": len(r.evals), "last_timesteps": int(r.evals[-1]["timesteps"])}
            for r in found
        ],
        "skipped": skipped,
        "curves": curves,
        "threshold": {g: threshold_summary(rs, metric, threshold) for g, rs in groups.items()},
        "wall_time_s": round(time.perf_counter() - t0, 3),
    }


def markdown_report(doc: Mapping[str, Any]) -> str:
    """Markdown: the time-to-threshold table, the final values with their intervals, the skipped folders."""
    p = doc["protocol"]
    thr_mm = 1e3 * p["threshold_m"]
    lines = [
        "# Learning curves",
        "",
        f"Mean over training seeds; intervals: {p['interval']} ({p['reps']} replications). Threshold: first "
        f"evaluation with `{p['threshold_metric']}` <= {thr_mm:g} mm; median over all seeds (a seed that never "
        "reached it counts as later than any that did; 'not reached': fewer than half did).",
        "",
    ]
    rows = []
    for g, t in doc["threshold"].items():
        per = ", ".join(
            f"s{q['seed']}: {q['timesteps']}" if q["reached"] else f"s{q['seed']}: not by {q['last_timesteps']}"
            for q in t["per_seed"]
        )
        med = ("not reached" if t[k] is None else f"{t[k]:.0f}" for k in ("median_timesteps", "median_wall_time_s"))
        rows.append((g, f"{t['n_reached']}/{t['n_seeds']}", *med, per))
    header = ("algorithm", f"seeds reaching {thr_mm:g} mm", "median steps", "median wall time [s]", "per seed: steps")
    lines += [*md_table(header, rows), "", "Final values (last step every seed reached; mean [95 % interval]):", ""]
    rows = []
    for g, axes in doc["curves"].items():
        h, ret = axes["timesteps"]["h_rms_m"], axes["timesteps"]["mean_reward"]
        c = h or ret
        final = (
            "–" if x is None else f"{s * x['mean'][-1]:.3g} [{s * x['ci95_low'][-1]:.3g}, {s * x['ci95_high'][-1]:.3g}]"
            for x, s in ((h, 1e3), (ret, 1.0))
        )
        rows.append((g, c["n_seeds"] if c else 0, f"{c['x'][-1]:.0f}" if c else "–", *final))
    lines += md_table(("algorithm", "seeds", "step", "H RMS [mm]", "return"), rows)
    lines += ["", "![against steps](curves_steps.png)", "", "![against wall time](curves_wall.png)", ""]
    if doc["skipped"]:
        lines += ["Skipped folders:", ""] + [f"- {s['path']}: {s['reason']}" for s in doc["skipped"]] + [""]
    return "\n".join(lines)


def plot_curves(doc: Mapping[str, Any], axis: str, path: Path) -> None:
    """H error (log scale) and return against ``axis`` into ``path``: mean over seeds, 95 % bootstrap band, thin
    seed lines."""
    fig, axs = pyplot().subplots(1, 2, figsize=(11, 4.2))
    for ax, (metric, label) in zip(axs, CURVE_METRICS.items(), strict=True):
        for i, (g, axes) in enumerate(doc["curves"].items()):
            if (c := axes[axis][metric]) is None:
                continue
            color = f"C{i}"
            for s in c["per_seed"].values():
                ax.step(s["x"], s["y"], where="post", color=color, alpha=0.25, lw=0.7)
            marker = "o" if len(c["x"]) < 3 else None  # a curve of one or two points is still visible
            seeds = f"{c['n_seeds']} seed" + ("s" if c["n_seeds"] != 1 else "")
            ax.step(c["x"], c["mean"], where="post", color=color, lw=1.8, marker=marker, label=f"{g} ({seeds})")
            ax.fill_between(c["x"], c["ci95_low"], c["ci95_high"], step="post", color=color, alpha=0.2)
        ax.set(xlabel=AXES[axis], ylabel=label, yscale="log" if metric == "h_rms_m" else "linear")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Learning curves against {AXES[axis]}")
    reps = doc["protocol"]["reps"]
    note = (f"Thick: mean over training seeds; band: pointwise 95 % percentile bootstrap over seeds ({reps} "
            "replications); thin: each seed (latest evaluation at or before x).")  # fmt: skip
    fig.text(0.5, 0.01, note, ha="center", fontsize=8)
    fig.tight_layout(rect=(0, 0.04, 1, 0.96))
    save_figure(fig, path)


def write_outputs(doc: Mapping[str, Any], out: Path, *, plots: bool = True) -> list[Path]:
    """``curves.json``, ``curves.md`` and (``plots``) ``curves_steps.png`` and ``curves_wall.png``
    (:func:`plot_curves`); the paths."""
    written = [out / "curves.json", out / "curves.md"]
    atomic_write_json(written[0], doc, parents=True)
    atomic_write(written[1], markdown_report(doc), parents=True)
    for axis, name in (("timesteps", "curves_steps.png"), ("wall_time_s", "curves_wall.png")) if plots else ():
        plot_curves(doc, axis, out / name)
        written.append(out / name)
    return written


@dataclass(frozen=True)
class CurvesSettings:
    """Options of ``amigo-gym curves``; checked by :func:`learning_curves`.

    Attributes:
        runs: folders of run folders, or run folders (with eval.json) [dir] (required).
        out: output folder [dir].
        metric: metric of the threshold.
        threshold: tracking threshold [m], > 0.
        reps: bootstrap replications of the bands [reps], >= 1.
        bootstrap_seed: seed of the bootstrap [-].
        plots: draw the plots; --no-plots: skip the plots.
        progress: show a progress bar on a terminal; --no-progress: no progress bar.
    """

    runs: list[str]
    out: str = "results/curves"
    metric: str = field(default=THRESHOLD_METRIC, metadata=cli(choices=("h_rms_settled_m", "h_rms_m")))
    threshold: float = DEFAULT_THRESHOLD_M
    reps: int = 10_000
    bootstrap_seed: int = 0
    plots: bool = field(default=True, metadata=cli("--no-plots"))
    progress: bool = field(default=True, metadata=cli("--no-progress"))


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym curves``."""
    args = list(sys.argv[1:] if argv is None else argv)

    def run(a: CurvesSettings) -> None:
        tty = a.progress and sys.stderr.isatty()
        doc = learning_curves(
            a.runs, metric=a.metric, threshold=a.threshold, reps=a.reps, bootstrap_seed=a.bootstrap_seed, progress=tty
        )
        doc["command"] = "amigo-gym curves " + " ".join(args)
        written = write_outputs(doc, Path(a.out), plots=a.plots)
        print(markdown_report(doc), end="")
        print("wrote " + ", ".join(map(str, written)))

    about = "Learning curves over training seeds, time to threshold."
    return run_command(CurvesSettings, run, args, "amigo-gym curves", about)
