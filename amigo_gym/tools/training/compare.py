"""The main job: the pretrained agents (and optionally a freshly trained one) against the analytic solution.

Usage, the training run reused or started, the output set and its manifest, the lock and the targets checked:
docs/baselines.md, "Reference: `amigo-gym compare`".
"""

from __future__ import annotations

import json
import shlex
import shutil
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from amigo_gym.data import pretrained_dir
from amigo_gym.io import atomic_write, json_safe
from amigo_gym.tools import runs
from amigo_gym.tools.options import cli, parse_settings, run_guarded, say
from amigo_gym.tools.training import benchmark as bm
from amigo_gym.tools.training import evaluate as ev
from amigo_gym.tools.training.hyperparams import load_hyperparams
from amigo_gym.tools.training.task_metrics import md_table
from amigo_gym.tools.training.train import HYPERPARAMS_DIR, env_kwargs, versions

PROG, MANIFEST = "amigo-gym compare", "manifest.json"

#: targets for the best learned agent on the perturbed scenario
TARGETS = {"h_rms_m": 2e-3, "wheel_rate_dev_rms": 0.1}


def agent_legend(names: Sequence[str], gain: float) -> list[str]:
    """One line per agent name of a report: what it is."""
    fixed = {
        "analytic": f"the exact analytic inverse solution with feedback (gain k = {gain:g}/s): the reference",
        "analytic_ff": "the same inverse solution feed-forward only (k = 0): it never corrects a start error",
        "pure_pursuit": "pure pursuit of the axle midpoint A (AmigoBot-v1's classical baseline)",
        "delay_compensated": "the analytic controller (k = 2/s while the nominal model explains the measurements,"
        " else 1/s) on the error predicted over the actuation delay it estimates online (a Smith predictor)",
        "ppo_fresh": "the PPO agent trained by this run (AmigoBot-v0, --train-steps)",
    }
    how = {
        "ppo_fast": " (amigo-gym train-fast; a numpy policy)",
        "residual": " (amigo-gym train-fast --residual-bound: a bounded learned correction of the analytic"
        " controller's command; a numpy policy)",
        "robust_residual": " (the residual trained over delays to 0.3 s, wheels and track ±7 % and noise; a numpy"
        " policy)",
        "compensator_residual": " (the robust residual's recipe on the delay compensator, its correction only where"
        " the nominal model explains the measurements; a numpy policy)",
    }
    out = []
    for name in dict.fromkeys(names):
        stem = name[:-3]
        if name in fixed:
            text = fixed[name]
        elif name.endswith("_v0"):
            text = f"pretrained SB3 {stem.upper()} AmigoBot-v0 specialist (agents/pretrained/{stem}.zip)"
        elif name.endswith("_v1"):
            label = {**bm.RETIRED_V1_AGENTS, **bm.V1_AGENTS}.get(stem, stem.upper())
            text = f"pretrained {label} AmigoBot-v1 generalists{how.get(stem, '')} (agents/pretrained/v1/{stem}/)"
        else:
            text = "a model from --models"
        out.append(f"`{name}`: {text}")
    return out


def display_command(command: str, root: Path | None = None) -> str:
    """``command``, its absolute paths relative to ``root`` (default: the current folder) if inside, else their last
    two parts (no printed command shows a machine's temporary folders)."""
    base = (root or Path.cwd()).resolve()
    words = []
    for word in shlex.split(command):
        if word.startswith("/"):
            p, full = Path(word), Path(word).resolve()
            short = str(Path(*p.parts[-2:])) if len(p.parts) > 2 else p.name
            word = str(full.relative_to(base)) if full.is_relative_to(base) else short
        words.append(shlex.quote(word))
    return " ".join(words)


def best_learned(results: Sequence[dict[str, Any]], scenario: str = "perturbed") -> dict[str, Any] | None:
    """The learned agent with the smallest H RMS error on ``scenario`` (``None`` if there is none)."""
    rows = [r for r in results if r["scenario"] == scenario and r["agent"] not in ("analytic", "analytic_ff")]
    return min(rows, key=lambda r: r["h_rms_m"]) if rows else None


def _met(best: Mapping[str, Any]) -> tuple[str, ...]:
    return tuple("met" if best[k] <= TARGETS[k] else "NOT met" for k in ("h_rms_m", "wheel_rate_dev_rms"))


def report_markdown(doc: dict[str, Any]) -> str:
    """The Markdown report of a compare run (``doc`` as written to ``results.json``)."""
    proto = doc["protocol"]
    lines = [
        "# AmigoBot-v0: learned agents against the analytic inverse solution",
        "",
        f"Protocol: {proto['steps']} steps of {proto['env_params']['dt']} s ({proto['duration_s']:.0f} s, "
        f"one lap = {proto['lap_time_s']:.1f} s) on the circle R = {proto['env_params']['radius']} m at "
        f"v_ref = {proto['env_params']['speed']} m/s; scenarios `nominal` (H on the circle, steady heading), "
        f"`paper_start` (H at the origin, beta = 0), `perturbed` (seeds {proto['scenarios']['perturbed']['seeds']}). "
        f"Wheel-rate deviation: {proto['wheel_rate_reference']}.",
        "",
        "Agents: " + "; ".join(agent_legend([r["agent"] for r in doc["results"]], proto["analytic_gain"])) + ".",
        "",
        ev.markdown_table(doc["results"]),
    ]
    if best := doc.get("best_learned"):
        ok_h, ok_w = _met(best)
        lines += [
            "## Targets (best learned agent, perturbed starts)",
            "",
            f"- agent: **{best['agent']}**",
            f"- H RMS error: {best['h_rms_m'] * 1e3:.3f} mm (target <= {TARGETS['h_rms_m'] * 1e3:g} mm): {ok_h}",
            f"- RMS wheel-rate deviation: {best['wheel_rate_dev_rms']:.4f} rad/s (target <= "
            f"{TARGETS['wheel_rate_dev_rms']} rad/s): {ok_w}",
        ]
        if rec := doc.get("training", {}).get(best["agent"]):
            lines.append(
                f"- training: {rec['timesteps']} steps in {rec['wall_time_s']:.0f} s wall time "
                f"({rec.get('cpu_count', '?')} CPU cores, {rec.get('torch_threads', '?')} torch thread(s))"
            )
        lines.append("")
    if doc.get("training"):
        rows = []
        for name, rec in doc["training"].items():
            model = f"{rec.get('exported_model', 'final')} @ {rec.get('exported_timesteps', rec['timesteps'])}"
            cmds = [rec["command"], *(r["command"] for r in rec.get("resumes", []))]
            cmd = "<br>".join(f"`{display_command(c)}`" for c in cmds)
            rows.append((name, rec["timesteps"], f"{rec['wall_time_s']:.0f}", model, cmd))
        header = ("agent", "steps", "wall time [s]", "model", "command (then resumes)")
        lines += ["## Training records", "", *md_table(header, rows), ""]
    lines += ["![trajectories](eval_trajectories.png)", "", "![wheels](eval_wheels.png)", ""]
    if bench := doc.get("benchmark"):
        table = bm.markdown_report(bench).splitlines()
        lines += [
            "#" + table[0],  # one level down
            "",
            f"`amigo-gym benchmark --quick` on the agents above ({len(bench['scenarios'])} scenarios, "
            f"{bench['scenarios'][0]['episodes']} episodes each; {bench['wall_time_s']:.0f} s). A smoke-sized view: "
            "the whole suite is `amigo-gym benchmark` (docs/benchmark.md).",
        ]
        if new_names := [a for a in bench["aggregates"] if a not in {r["agent"] for r in doc["results"]}]:
            legend = agent_legend(new_names, proto["analytic_gain"])
            lines += ["", "Agents (besides those above): " + "; ".join(legend) + "."]
        lines += [("#" + ln if ln.startswith("#") else ln) for ln in table[1:]]
        if doc.get("benchmark_plots"):
            lines += ["", "![benchmark scenarios](benchmark_scenarios.png)", ""]
            lines += ["![benchmark profiles](benchmark_profiles.png)", ""]
    return "\n".join(lines)


def summary_text(doc: dict[str, Any], out: Path) -> str:
    """What ``amigo-gym compare`` prints: the perturbed starts, the targets, the quick benchmark, the agents, files."""
    proto = doc["protocol"]
    rows = [r for r in doc["results"] if r["scenario"] == "perturbed"]
    lines = [
        f"AmigoBot-v0, {len(proto['scenarios']['perturbed']['seeds'])} perturbed starts of {proto['duration_s']:.0f} s "
        f"on the circle R = {proto['env_params']['radius']} m (H within 2 cm, heading within 0.1 rad):",
        "",
        *md_table(
            ("agent", "H RMS error [mm]", "wheel-rate deviation from the analytic policy, RMS [rad/s]"),
            [(r["agent"], f"{r['h_rms_m'] * 1e3:.3f}", f"{r['wheel_rate_dev_rms']:.3f}") for r in rows],
            right=2,
        ),
        "",
    ]
    if best := doc.get("best_learned"):
        ok_h, ok_w = _met(best)
        lines.append(
            f"Best learned agent: {best['agent']}, {best['h_rms_m'] * 1e3:.3f} mm (target <= "
            f"{TARGETS['h_rms_m'] * 1e3:g} mm: {ok_h}), {best['wheel_rate_dev_rms']:.3f} rad/s (target <= "
            f"{TARGETS['wheel_rate_dev_rms']:g} rad/s: {ok_w})."
        )
    names = [r["agent"] for r in rows]
    if bench := doc.get("benchmark"):
        cells = []
        for agent, a in bench["aggregates"].items():
            if (g := a.get("all")) is not None:
                runs_ = f", {a['n_runs']} seeds" if a["n_runs"] > 1 else ""
                failed, episodes = bm.failed_episodes(bench, agent)
                cells.append(f"{agent} {g['h_rms_m_iqm']['value'] * 1e3:.3g} ({failed} of {episodes} failed{runs_})")
            names.append(agent)
        lines.append(
            f"Quick benchmark ({len(bench['scenarios'])} scenarios x {bench['scenarios'][0]['episodes']} short "
            f"episodes on v0 and v1, a smoke test, not the benchmark's result), H RMS IQM [mm] (failed episodes): "
            f"{', '.join(cells)}. {len(bench['unavailable'])} (agent, seed, scenario) runs could not run (a v0 model "
            "on a v1 scenario or the reverse: other observations); report.md lists them."
        )
    lines += ["", "Agents:", *(f"  {x}" for x in agent_legend(names, proto["analytic_gain"])), ""]
    plots = ", plots eval_*.png" + (", benchmark_*.png" if doc.get("benchmark_plots") else "")
    lines.append(
        f"Files in {out}/: report.md (every scenario, the training records, the benchmark's tables), results.json "
        f"(all numbers), eval.md{plots if (out / 'eval_trajectories.png').is_file() else ''}."
    )
    return "\n".join(lines)


def fresh_run_request(train_steps: int, seed: int, hyperparams: Path | None = None) -> dict[str, Any]:
    """What the fresh PPO run must have been trained with to be reused (compared with its ``config.json``)."""
    return {
        "algo": "ppo",
        "timesteps": train_steps,
        "seed": seed,
        "env_kwargs": env_kwargs(),
        "hyperparams": load_hyperparams(hyperparams or HYPERPARAMS_DIR / "ppo.yml"),
        "versions": versions(),
    }


def reuse_mismatch(run_dir: Path, request: dict[str, Any]) -> str | None:
    """Why the run in ``run_dir`` cannot serve ``request`` (``None``: it can): its ``config.json`` must record the
    same settings, hyperparameters and versions, and it must have a checkpoint."""
    cfg_file, short = run_dir / "config.json", ("algo", "timesteps", "seed")
    if not cfg_file.is_file() or not (run_dir / "checkpoint.json").is_file():
        return "no complete earlier run"
    try:
        cfg = json.loads(cfg_file.read_text())
        recorded = {k: cfg["settings"][k] for k in short} | {"env_kwargs": cfg.get("env_kwargs")}
        recorded |= {k: cfg[k] for k in ("hyperparams", "versions")}
    except (ValueError, KeyError, TypeError):
        return f"unreadable {cfg_file}"
    differ = [k for k in request if json.dumps(recorded[k], sort_keys=True) != json.dumps(request[k], sort_keys=True)]
    reasons = [f"{k} {recorded[k]!r} != {request[k]!r}" if k in short else f"{k} differ" for k in differ]
    return ", ".join(reasons) if reasons else None


def verify_outputs(out: Path) -> dict[str, str]:
    """The manifest of the output set, after checking every file (:func:`amigo_gym.tools.runs.verify_manifest`)."""
    return runs.verify_manifest(out, MANIFEST)


@dataclass(frozen=True)
class CompareSettings:
    """Options of ``amigo-gym compare``, each the option of the same name unless its ``cli(flag)`` names one.

    Attributes:
        out: output directory [dir].
        models: pretrained models, as for evaluate --models [path], '' for none. Model zips are pickles that run
            code when loaded: pass only files you trust (the shipped ones are checked against their sha256).
        train_steps: steps of a fresh PPO run [steps], 0: none (default 500000).
        seeds: perturbed starts [episodes].
        steps: steps per episode [steps].
        seed: seed of the fresh training run [-].
        hyperparams: YAML of the fresh PPO run [file] (default: agents/hyperparams/ppo.yml).
        plots: draw the figures; --no-plots: skip the figures.
        benchmark: run the quick benchmark subset (step 3); --no-benchmark: skip the quick benchmark table (step 3).
        progress: show the progress bars (training, benchmark; phase lines go to stderr in any case);
            --no-progress: no progress bar (default: shown on a terminal).
    """

    out: str = "results"
    models: str = str(pretrained_dir())
    train_steps: int = 500_000
    seeds: int = 10
    steps: int = 400
    seed: int = 0
    hyperparams: str | None = None
    plots: bool = field(default=True, metadata=cli("--no-plots"))
    benchmark: bool = field(default=True, metadata=cli("--no-benchmark"))
    progress: bool = field(default=True, metadata=cli("--no-progress"))

    def validate(self) -> None:
        for name, low in (("train_steps", 0), ("seed", 0), ("seeds", 1)):
            if getattr(self, name) < low:
                raise ValueError(f"--{name.replace('_', '-')} must be an integer >= {low}, got {getattr(self, name)}")


def run_compare(s: CompareSettings) -> dict[str, Any]:
    """Run the main job; the JSON document."""
    out, models = Path(s.out), Path(s.models) if s.models else None
    with runs.RunLock(out):
        runs.clean_temporaries(out)
        hyperparams = Path(s.hyperparams) if s.hyperparams else None
        if models is not None:
            say(f"loading pretrained agents from {models}")
        proto, agents, specs, training = ev.protocol_agents(s.steps, s.seeds, models)
        if s.train_steps > 0:
            from amigo_gym.tools.training.train import Settings, train

            run_dir = out / "train_ppo"
            stale = reuse_mismatch(run_dir, fresh_run_request(s.train_steps, s.seed, hyperparams))
            if stale is not None and run_dir.exists():
                say(f"retraining: the run in {run_dir} does not match the request ({stale})")
                shutil.rmtree(run_dir)
            argv = ["--algo", "ppo", "--seed", str(s.seed), "--timesteps", str(s.train_steps), "--out", str(run_dir)]
            fresh = Settings(
                algo="ppo",
                seed=s.seed,
                out=str(run_dir),
                timesteps=s.train_steps,
                hyperparams=None if hyperparams is None else str(hyperparams),
                resume=stale is None,
                eval_freq=0,
                checkpoint_freq=max(s.train_steps // 4, 1),
                progress=s.progress,
                argv=argv + ([] if hyperparams is None else ["--hyperparams", str(hyperparams)]),
            )
            if stale is None:
                say(f"reusing the PPO run in {run_dir}: its recorded configuration equals the request")
            else:
                say(f"training a fresh PPO agent for {s.train_steps} steps in {run_dir}")
            t0 = time.perf_counter()
            rec = training["ppo_fresh"] = train(fresh)
            took = f"{time.perf_counter() - t0:.0f} s here" if stale is not None else "reused"
            print(f"ppo_fresh: {rec['timesteps']} steps, trained in {rec['wall_time_s']:.0f} s ({took})")
            trained = ev.find_models(run_dir)[0]
            agents["ppo_fresh"] = trained.load()  # checked against run.json, as every model
            specs.append(replace(trained, name="ppo_fresh", seed=s.seed, _model=agents["ppo_fresh"]))
        say(f"evaluating {len(agents)} agents: {', '.join(agents)} ({len(proto.scenarios)} scenarios)")
        results, trajs = ev.evaluate_agents(agents, proto)
        extra: dict[str, Any] = {"training": training, "targets": TARGETS, "best_learned": best_learned(results)}
        bench: dict[str, Any] | None = None
        if s.benchmark:
            generalists = models / "v1" if models is not None and (models / "v1").is_dir() else None
            also = f" and {generalists}" if generalists else ""
            say(f"quick benchmark (amigo-gym benchmark --quick) on these agents{also}")
            v1 = [] if generalists is None else bm.generalists(generalists)  # named <folder>_v1
            bench = bm.run_benchmark([*specs, *v1], bm.quick_suite(), progress=s.progress, quick=True)
            bench["command"] = "amigo-gym compare (the quick subset of amigo-gym benchmark)"
            extra["benchmark"] = json_safe(bench)
            extra["benchmark_plots"] = s.plots and bool(bench["results"])
        with tempfile.TemporaryDirectory(dir=out, prefix=".staging-", ignore_cleanup_errors=True) as tmp:
            staging = Path(tmp)
            doc = ev.write_outputs(results, trajs, proto, staging, staging / "results.json", extra=extra, plots=s.plots)
            if bench is not None and extra["benchmark_plots"]:
                bm.plot_all(bench, staging)
            atomic_write(staging / "report.md", report_markdown(doc).encode())
            # every file of staging moved into out as one set, the manifest last
            runs.publish({out / p.name: p for p in sorted(staging.iterdir()) if p.is_file()}, out, MANIFEST)
        return doc


def main(argv: Sequence[str] | None = None) -> int:
    s = parse_settings(CompareSettings, argv, PROG, "Pretrained agents vs the analytic inverse solution.")

    def run() -> int:
        ev.one_torch_thread()
        doc = run_compare(replace(s, progress=s.progress and sys.stderr.isatty()))
        print(summary_text(doc, Path(s.out)))
        return 0

    return run_guarded(run, PROG)
