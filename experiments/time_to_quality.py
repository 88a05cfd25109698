"""Time to quality of one ``amigo-gym train-fast`` run: when its validation H error came within 1.5x the analytic
controller's with a settled chatter of at most 1 rad/s (issue 18's target: <= 30 minutes on a 2-core machine).

    amigo-gym train-fast --out runs/ttq --total-steps 30000000 --filter-alpha 0.5     # the documented command
    python experiments/time_to_quality.py runs/ttq [--out docs/figures/fastppo --name ttq_30m]

Reads the run's ``curve.csv`` (one row per ``--eval-every`` env-steps: ``env_steps``, ``wall_s`` [s] since the
start of training, ``eval_h_rms_m`` [m], ``eval_chatter_settled_rms`` [rad/s], ``eval_speed_err_settled_rms``
[m/s] over the validation episodes) and its ``settings.json``; evaluates the analytic controller
(:class:`amigo_gym.policies.AnalyticTrackingPolicy`, nominal robot) with the same function,
:func:`amigo_gym.tools.training.fastppo.evaluate_policy`, on the same validation episodes (seeds ``eval_seed + j``,
``j < eval_envs``, of the training distribution: never the benchmark's cells). "Quality" is both at once: H RMS
<= 1.5x the analytic value and settled chatter <= 1 rad/s, at one evaluation.

Writes (atomically) ``<out>/<name>.png`` (H RMS and settled chatter against wall-clock, with the 1.5x line, the
chatter target and the 30-minute line), ``<out>/<name>.json`` and ``<out>/<name>.curve.csv`` (a copy), and prints a
Markdown summary. Wall-clock depends on the machine and its load: the JSON records the CPU and the load average
the run's manifest or this script saw; read the figure with it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.io import atomic_save, atomic_write_json

sys.path.insert(0, str(Path(__file__).resolve().parent))
from plot_curves_v1 import CHATTER_TARGET, FACTOR, WALL_LINE_S, read_curve


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", help="run folder of amigo-gym train-fast (curve.csv, settings.json)")
    p.add_argument("--out", default="docs/figures/fastppo", help="output folder")
    p.add_argument("--name", default="time_to_quality_run", help="stem of the output files")
    a = p.parse_args()

    from amigo_gym.policies import AnalyticTrackingPolicy
    from amigo_gym.tools.machine import machine_line
    from amigo_gym.tools.training.fastppo import FastPPOSettings, evaluate_policy

    run = Path(a.run)
    c = read_curve(run / "curve.csv")
    s = FastPPOSettings.from_json(json.loads((run / "settings.json").read_text()))
    ref = evaluate_policy(AnalyticTrackingPolicy(s.spec().params()), dataclasses.replace(s))
    level = FACTOR * ref["h_rms_m"]
    ok = (c["eval_h_rms_m"] <= level) & (c["eval_chatter_settled_rms"] <= CHATTER_TARGET)
    hit = np.flatnonzero(ok)
    first = int(hit[0]) if hit.size else None
    summary: dict[str, Any] = {
        "command": f"python experiments/time_to_quality.py {a.run} --out {a.out} --name {a.name}",
        "machine": machine_line(),
        "load_average_now": list(os.getloadavg()),
        "settings": s.to_json(),
        "analytic": {k: float(v) for k, v in ref.items()},
        "quality": {"h_rms_m_at_most": level, "chatter_settled_rms_at_most": CHATTER_TARGET},
        "first_quality_eval": None
        if first is None
        else {k: float(c[k][first]) for k in ("env_steps", "wall_s", "eval_h_rms_m", "eval_chatter_settled_rms")},
        "final": {k: float(c[k][-1]) for k in c},
        "within_30_minutes": first is not None and float(c["wall_s"][first]) <= WALL_LINE_S,
    }
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / f"{a.name}.json", summary)
    shutil.copyfile(run / "curve.csv", out / f"{a.name}.curve.csv")

    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    minutes = c["wall_s"] / 60.0
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.2))
    ax1.plot(minutes, 1e3 * c["eval_h_rms_m"], "o-", ms=3, label="fast PPO (validation)")
    ax1.axhline(1e3 * ref["h_rms_m"], color="k", lw=1, label=f"analytic ({1e3 * ref['h_rms_m']:.2f} mm)")
    ax1.axhline(1e3 * level, color="k", ls="--", lw=1, label="1.5x analytic")
    ax1.set_yscale("log")
    ax1.set_yticks([t for t in (1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0) if t <= 1.2e3 * c["eval_h_rms_m"].max()])
    ax1.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax1.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax1.set_ylabel("validation H cross-track RMS [mm]")
    ax2.plot(minutes, c["eval_chatter_settled_rms"], "o-", ms=3, label="fast PPO (validation)")
    ax2.axhline(CHATTER_TARGET, color="r", ls="--", lw=1, label="target 1 rad/s")
    ax2.set_ylabel("settled command chatter RMS [rad/s]")
    for ax in (ax1, ax2):
        ax.axvline(WALL_LINE_S / 60.0, color="r", ls=":", lw=1.2, label="30 min")
        if first is not None:
            ax.axvline(minutes[first], color="g", lw=1.2, label=f"quality at {minutes[first]:.1f} min")
        ax.set_xlabel("wall-clock of training [min]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Time to quality of one train-fast run ({summary['machine']})", fontsize=9)
    fig.tight_layout()
    atomic_save(lambda tmp: fig.savefig(tmp, dpi=100, format="png"), out / f"{a.name}.png")
    plt.close(fig)

    f = summary["first_quality_eval"]
    print(f"analytic H RMS {1e3 * ref['h_rms_m']:.2f} mm; quality: H <= {1e3 * level:.2f} mm and chatter <= 1 rad/s")
    if f is None:
        print("quality not reached")
    else:
        print(
            f"quality at {f['env_steps']:,.0f} env-steps, {f['wall_s']:.0f} s ({f['wall_s'] / 60:.1f} min): "
            f"H {1e3 * f['eval_h_rms_m']:.2f} mm, chatter {f['eval_chatter_settled_rms']:.2f} rad/s"
        )
    fin = summary["final"]
    print(
        f"final: {fin['env_steps']:,.0f} env-steps, {fin['wall_s']:.0f} s: H {1e3 * fin['eval_h_rms_m']:.2f} mm, "
        f"chatter {fin['eval_chatter_settled_rms']:.2f} rad/s, settled speed error "
        f"{1e3 * fin['eval_speed_err_settled_rms']:.1f} mm/s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
