"""The report of an ``amigo-gym sweep`` study: trials, best parameters, importances, and two plots.

Read-only on the study (it never adds, changes or resumes a trial). Writes into ``--out``:

* ``summary.json``: the sweep's own summary (:func:`amigo_gym.tools.training.sweep.summarize`: states, best trial, every
  trial with its parameters and attributes);
* ``trials.csv``: one row per trial (number, state, objective in mm, the env-step it was pruned at, parameters);
* ``importance.json`` / ``importance.png``: Optuna's PED-ANOVA importance of each parameter (how far its
  distribution in the best ``--target-quantile`` of the COMPLETE trials differs from that over all of them; built
  into Optuna, where fANOVA needs scikit-learn), with a 95 % interval over ``--bootstrap`` resamples of the
  trials: with a few tens of trials the ranking moves with which trials are in the top quarter;
* ``history.png``: the objective of each trial against its number (pruned trials at the value of their last
  report), the best so far, and the baseline trial (user attribute ``baseline``) marked;
* ``report.md``: the tables behind both, for docs/experiments.md.

    python experiments/sweep_report.py --storage sqlite:////work/runs/sweep_fastppo/sweep.db --study fastppo-hp \\
        --out docs/figures/sweep_fastppo

The objective is the sweep's: IQM of H's cross-track RMS over the held-in validation cells (never the benchmark's
test cells), in metres in the study, in mm here.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path
from typing import Any

import numpy as np


def _is_baseline(t: Any) -> bool:
    """The trial that ran the base settings: user attribute ``baseline`` (``amigo-gym sweep --enqueue-base``; the
    first TD3 study, started at commit 738908a, named it ``base``)."""
    return bool(t.user_attrs.get("baseline") or t.user_attrs.get("base"))


def _last_report(t: Any) -> tuple[int | None, float | None]:
    """(env-step, value) of a trial's last intermediate report, or (None, None)."""
    if not t.intermediate_values:
        return None, None
    step = max(t.intermediate_values)
    return int(step), float(t.intermediate_values[step])


def main(argv: list[str] | None = None) -> int:
    import optuna
    from optuna.trial import TrialState

    from amigo_gym.io import atomic_write_json
    from amigo_gym.tools.training.sweep import summarize

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--storage", required=True, help="the study's storage URL (e.g. sqlite:////path/sweep.db)")
    ap.add_argument("--study", required=True, help="the study's name")
    ap.add_argument("--out", type=Path, required=True, help="folder for the report [folder]")
    ap.add_argument("--target-quantile", type=float, default=0.25, help="PED-ANOVA's top quantile (default 0.25)")
    ap.add_argument("--bootstrap", type=int, default=200, help="bootstrap resamples of the trials (default 200)")
    a = ap.parse_args(argv)
    if not 0.0 < a.target_quantile < 1.0 or not np.isfinite(a.target_quantile):
        print(f"sweep_report: error: --target-quantile {a.target_quantile}: must be in (0, 1)", file=sys.stderr)
        return 2
    if not 0 <= a.bootstrap <= 100_000:
        print(f"sweep_report: error: --bootstrap {a.bootstrap}: must be in [0, 100000]", file=sys.stderr)
        return 2
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.load_study(study_name=a.study, storage=a.storage)
    trials = sorted(study.get_trials(deepcopy=False), key=lambda t: t.number)
    complete = [t for t in trials if t.state == TrialState.COMPLETE]
    if len(complete) < 2:
        print(f"sweep_report: error: study {a.study}: {len(complete)} complete trials, need >= 2", file=sys.stderr)
        return 2
    a.out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(a.out / "summary.json", summarize(study))

    names = sorted({k for t in trials for k in t.params})
    with open(a.out / "trials.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["number", "state", "objective_mm", "pruned_at_step", "baseline", *names])
        for t in trials:
            step, last = _last_report(t)
            value = t.value if t.state == TrialState.COMPLETE else (last if t.state == TrialState.PRUNED else None)
            w.writerow(
                [
                    t.number,
                    t.state.name,
                    "" if value is None else f"{1e3 * value:.4f}",
                    step if t.state == TrialState.PRUNED else "",
                    int(bool(_is_baseline(t))),
                    *[t.params.get(k, "") for k in names],
                ]
            )

    # PED-ANOVA (Optuna's, no scikit-learn): how much each parameter's distribution differs between the best
    # quarter of the complete trials and all of them; over bootstrap resamples of the complete trials, since with
    # a few tens of trials the estimate moves with which trials happen to be in the top quarter
    evaluator = optuna.importance.PedAnovaImportanceEvaluator(target_quantile=a.target_quantile)
    rng = np.random.default_rng(0)
    runs = []
    for b in range(a.bootstrap + 1):
        picked = complete if b == 0 else [complete[i] for i in rng.integers(0, len(complete), len(complete))]
        sub = optuna.create_study(direction="minimize")
        sub.add_trials(picked)
        runs.append(optuna.importance.get_param_importances(sub, evaluator=evaluator, normalize=True))
    imp = {k: np.array([r.get(k, 0.0) for r in runs]) for k in names}
    order = sorted(names, key=lambda k: -imp[k][0])
    importance = {
        "evaluator": f"optuna PedAnovaImportanceEvaluator(target_quantile={a.target_quantile}), normalised, "
        "over the COMPLETE trials; interval: 2.5-97.5 % over bootstrap resamples of those trials (seed 0)",
        "complete_trials": len(complete),
        "bootstrap": a.bootstrap,
        "importance": {
            k: {
                "all_trials": float(imp[k][0]),
                "lo": float(np.quantile(imp[k][1:], 0.025)) if a.bootstrap else None,
                "hi": float(np.quantile(imp[k][1:], 0.975)) if a.bootstrap else None,
            }
            for k in order
        },
    }
    atomic_write_json(a.out / "importance.json", importance)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    means = [imp[k][0] for k in order]
    if a.bootstrap:
        lo = [max(imp[k][0] - np.quantile(imp[k][1:], 0.025), 0.0) for k in order]
        hi = [max(np.quantile(imp[k][1:], 0.975) - imp[k][0], 0.0) for k in order]
        ax.barh(order[::-1], means[::-1], xerr=[lo[::-1], hi[::-1]], color="tab:blue", capsize=3)
    else:
        ax.barh(order[::-1], means[::-1], color="tab:blue")
    ax.set_xlabel(f"PED-ANOVA importance (top {a.target_quantile:g}; bars: 95 % over {a.bootstrap} bootstraps)")
    ax.set_title(f"{a.study}: {len(complete)} complete trials, objective H RMS IQM (validation cells)", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out / "importance.png", dpi=120)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    best = np.inf
    xs, bests = [], []
    for t in trials:
        if t.state == TrialState.COMPLETE:
            ax.plot(t.number, 1e3 * t.value, "o", color="tab:blue", ms=5)
            best = min(best, 1e3 * t.value)
        elif t.state == TrialState.PRUNED and _last_report(t)[1] is not None:
            ax.plot(t.number, 1e3 * float(_last_report(t)[1] or 0.0), "x", color="tab:gray", ms=5)
        if _is_baseline(t) and t.value is not None:
            ax.plot(
                t.number, 1e3 * t.value, "s", mfc="none", mec="tab:red", ms=10, label="baseline (hand-set settings)"
            )
        if np.isfinite(best):
            xs.append(t.number)
            bests.append(best)
    ax.step(xs, bests, where="post", color="tab:orange", label="best so far")
    ax.plot([], [], "o", color="tab:blue", label="complete")
    ax.plot([], [], "x", color="tab:gray", label="pruned (last report)")
    ax.set_xlabel("trial")
    ax.set_ylabel("H RMS IQM, validation cells [mm]")
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    ax.set_title(f"{a.study}: objective per trial", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.out / "history.png", dpi=120)
    plt.close(fig)

    states = {s.name: sum(t.state == s for t in trials) for s in TrialState if any(t.state == s for t in trials)}
    top = sorted(complete, key=lambda t: float(t.value or np.inf))[:8]
    lines = [
        f"Study `{a.study}`: {len(trials)} trials ({', '.join(f'{v} {k}' for k, v in states.items())}).",
        "",
        "Best complete trials (objective: IQM of H RMS over the validation cells, mm):",
        "",
        "| trial | objective [mm] | " + " | ".join(names) + " |",
        "|---:|---:|" + "---|" * len(names),
    ]
    for t in top:
        cells = [f"{v:.3g}" if isinstance(v, float) else str(v) for v in (t.params.get(k, "") for k in names)]
        mark = " (baseline)" if _is_baseline(t) else ""
        lines.append(f"| {t.number}{mark} | {1e3 * float(t.value or 0.0):.3f} | " + " | ".join(cells) + " |")
    base = [t for t in trials if _is_baseline(t) and t.value is not None]
    if base:
        lines += ["", f"Baseline (hand-set settings, trial {base[0].number}): {1e3 * float(base[0].value):.3f} mm."]
    lines += [
        "",
        f"PED-ANOVA importance (top quantile {a.target_quantile:g}; all complete trials [95 % bootstrap]):",
        "",
    ]
    for k in order:
        band = f" [{np.quantile(imp[k][1:], 0.025):.2f}, {np.quantile(imp[k][1:], 0.975):.2f}]" if a.bootstrap else ""
        lines.append(f"- {k}: {imp[k][0]:.2f}{band}")
    (a.out / "report.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
