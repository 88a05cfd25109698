"""Learning curves of the low-pass TD3 (five seeds) and its final models on the fast PPO's validation episodes.

    python experiments/plot_curves_td3lp.py      # docs/figures/td3lp/{learning_curves.png,curves_summary.json}

Inputs: ``docs/figures/td3lp/td3lp_s{i}.eval.json`` (copies of the runs' ``eval.json``: ``amigo-gym train`` writes
one entry per evaluation, every 100k env-steps, with ``timesteps``, ``wall_time_s`` and ``h_rms_m``, the mean over 16
deterministic episodes of the training distribution) and the shipped models ``agents/pretrained/v1/td3lp/``. The
training evaluations run on one evaluation env seeded once (``seed + 10 000``), so each evaluation sees other
episodes: the curve carries that sampling noise.

Final models: every seed's zip (loaded with :func:`amigo_gym.policies.load_pretrained`) and the analytic controller
(:class:`amigo_gym.policies.AnalyticTrackingPolicy`, nominal robot) on the same 32 validation episodes of the
training distribution (seeds 1 000 000 + j, never the benchmark's), with the function the fast PPO's curves use,
:func:`amigo_gym.tools.training.fastppo.evaluate_policy`: H RMS, settled H RMS, settled chatter and settled speed error.

Aggregation over the seeds at each evaluation (all seeds evaluate at the same env-steps): the IQM
(:func:`amigo_gym.tools.training.intervals.iqm`, with five seeds the mean of the middle three) and the min-max band;
against wall-clock, each seed's latest evaluation at or before ``t``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.io import atomic_save, atomic_write_json
from amigo_gym.tools.training.intervals import iqm

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--curves", default=str(ROOT / "docs/figures/td3lp"), help="folder of td3lp_s<i>.eval.json")
    p.add_argument("--models", default=str(ROOT / "agents/pretrained/v1/td3lp"), help="shipped zips and manifests")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    p.add_argument("--out", default=str(ROOT / "docs/figures/td3lp"), help="output folder")
    a = p.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from amigo_gym.policies import AnalyticTrackingPolicy, load_pretrained
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
    from amigo_gym.tools.training.fastppo import FastPPOSettings, evaluate_policy

    evals = [json.loads((Path(a.curves) / f"td3lp_s{s}.eval.json").read_text()) for s in a.seeds]
    steps = np.array([e["timesteps"] for e in evals[0]], dtype=float)
    if any([e["timesteps"] for e in ev] != list(steps) for ev in evals):
        raise SystemExit("the seeds were evaluated at different env-steps")
    h = np.array([[e["h_rms_m"] for e in ev] for ev in evals])  # (seeds, evals) [m]
    wall = np.array([[e["wall_time_s"] for e in ev] for ev in evals])
    h_iqm = iqm(h.T[:, None, :])

    settings = FastPPOSettings(env_kwargs=dict(TRAINING_DISTRIBUTION["env_kwargs"]))
    ref = evaluate_policy(AnalyticTrackingPolicy(settings.spec().params()), settings)
    finals: list[dict[str, Any]] = []
    for s in a.seeds:
        zip_path = Path(a.models) / f"td3lp_s{s}.zip"
        m = evaluate_policy(load_pretrained(zip_path), settings)
        finals.append({"seed": s} | m)
    keys = ("h_rms_m", "h_rms_settled_m", "chatter_settled_rms", "speed_err_settled_rms")
    summary = {
        "command": "python experiments/plot_curves_td3lp.py",
        "validation": {
            "env_kwargs": settings.env_kwargs,
            "eval_seed": settings.eval_seed,
            "episodes": settings.eval_envs,
        },
        "analytic": {k: ref[k] for k in keys},
        "final": [{k: f[k] for k in ("seed", *keys)} for f in finals],
        "curve": {"env_steps": steps.tolist(), "h_rms_iqm_m": h_iqm.tolist(), "h_rms_m": h.tolist()},
    }
    atomic_write_json(Path(a.out) / "curves_summary.json", summary, parents=True)

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    ax1.fill_between(steps / 1e6, h.min(0) * 1e3, h.max(0) * 1e3, alpha=0.25, label="min-max over seeds")
    ax1.plot(steps / 1e6, h_iqm * 1e3, "o-", label=f"IQM over {len(a.seeds)} seeds")
    ax1.axhline(ref["h_rms_m"] * 1e3, color="k", ls="--", label="analytic (32 validation episodes)")
    ax1.set(xlabel="env-steps [millions]", ylabel="H RMS [mm] (16 episodes per evaluation)", yscale="log")
    ax1.set_title("low-pass TD3: learning curve")
    ax1.legend(fontsize=8)
    for i, s in enumerate(a.seeds):
        ax2.plot(wall[i] / 60.0, h[i] * 1e3, ".-", label=f"seed {s}")
    ax2.axhline(ref["h_rms_m"] * 1e3, color="k", ls="--")
    ax2.set(xlabel="wall-clock [min] (shared 2-core machine)", ylabel="H RMS [mm]", yscale="log")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    atomic_save(lambda tmp: fig.savefig(tmp, format="png", dpi=110), Path(a.out) / "learning_curves.png", parents=True)

    print("| model | H RMS [mm] | settled H RMS [mm] | settled chatter [rad/s] | settled speed error [mm/s] |")
    print("|---|---:|---:|---:|---:|")
    rows = [("analytic", ref)] + [(f"td3lp seed {f['seed']}", f) for f in finals]
    for name, r in rows:
        print(
            f"| {name} | {r['h_rms_m'] * 1e3:.2f} | {r['h_rms_settled_m'] * 1e3:.2f} | "
            f"{r['chatter_settled_rms']:.2f} | {r['speed_err_settled_rms'] * 1e3:.1f} |"
        )
    curve = ", ".join(f"{int(x)}: {y * 1e3:.2f}" for x, y in zip(steps, h_iqm, strict=True))
    print(f"\ncurve (IQM over seeds, H RMS [mm]): {curve}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
