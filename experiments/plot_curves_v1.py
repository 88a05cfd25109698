"""Learning curves and time to quality of the shipped fast-PPO generalist (five seeds) against the analytic controller.

    python experiments/plot_curves_v1.py      # docs/figures/fastppo/{learning_curves,time_to_quality}.png
    python experiments/plot_curves_v1.py --stem compensator_residual --label "compensator residual" --seeds 0 1 2 \
        --curves docs/figures/compensator_residual --out docs/figures/compensator_residual \
        --manifests agents/pretrained/v1/compensator_residual

Inputs: the training curves ``docs/figures/fastppo/ppo_fast_s{0..4}.curve.csv`` (copies of the runs'
``curve.csv``, written by ``amigo-gym train-fast`` every ``--eval-every`` env-steps: columns ``env_steps``,
``wall_s`` [s], ``eval_h_rms_m`` [m], ``eval_chatter_settled_rms`` [rad/s], ...) and the shipped manifests
``agents/pretrained/v1/ppo_fast/ppo_fast_s{i}.json`` (their ``settings``: the training distribution, the validation
seeds ``eval_seed + j`` for ``j < eval_envs`` and the episode length). Each curve's last row must equal its
manifest's ``last_eval`` (the curves are those of the shipped models), else the script stops.

Validation metric: the mean over ``eval_envs`` (32) deterministic episodes on the validation seeds
1 000 000 + j of the training distribution (never the benchmark's cells), as ``amigo-gym train-fast`` evaluates.
The analytic reference (:class:`amigo_gym.policies.AnalyticTrackingPolicy` on the nominal robot) is evaluated here
with the same function, :func:`amigo_gym.tools.training.fastppo.evaluate_policy`, on the same settings.

Aggregation over the five seeds at each evaluation (all seeds evaluate at the same env-steps): the IQM
(:func:`amigo_gym.tools.training.intervals.iqm`: with five seeds the mean of the middle three) and the min-max band.
Against wall-clock, each seed's value at ``t`` is its latest evaluation at or before ``t`` (what stopping the run at
``t`` gives; a finished seed keeps its last value), on a grid of 1 s from the latest first evaluation to the latest
last one.

Time to quality: the first evaluation at which a seed's validation H RMS is within 1.5x (``--factor``) the analytic
value (env-steps and wall seconds), and the same for the IQM curves.

Outputs (written atomically): ``<out>/learning_curves.png`` (H RMS and settled chatter against env-steps, the
analytic line, the 1 rad/s chatter target), ``<out>/time_to_quality.png`` (H RMS against wall-clock, 1.5x analytic
and the 30-minute line), ``<out>/curves_summary.json``, and a Markdown summary on stdout.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.io import atomic_save, atomic_write_json
from amigo_gym.tools.training.intervals import iqm

ROOT = Path(__file__).resolve().parents[1]
FACTOR = 1.5  # "quality": within 1.5x the analytic controller's validation H RMS
WALL_LINE_S = 1800.0  # the 30-minute line
CHATTER_TARGET = 1.0  # rad/s, issue 18's settled-chatter target


def read_curve(path: Path) -> dict[str, np.ndarray]:
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise ValueError(f"{path}: no rows")
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def first_within(x: np.ndarray, y: np.ndarray, level: float) -> float | None:
    hit = np.flatnonzero(y <= level)
    return float(x[hit[0]]) if hit.size else None


def step_on_grid(x: np.ndarray, y: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """The latest ``y`` at or before each grid point (``x`` increasing; the grid starts at or after ``x[0]``)."""
    return y[np.searchsorted(x, grid, side="right") - 1]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--curves", default=str(ROOT / "docs/figures/fastppo"), help="folder of ppo_fast_s<i>.curve.csv")
    p.add_argument("--manifests", default=str(ROOT / "agents/pretrained/v1/ppo_fast"), help="shipped manifests")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    p.add_argument("--stem", default="ppo_fast", help="the files' stem before _s<seed>")
    p.add_argument("--label", default="fast PPO", help="the agent's name in the figures")
    p.add_argument("--out", default=str(ROOT / "docs/figures/fastppo"), help="output folder")
    p.add_argument("--factor", type=float, default=FACTOR, help="quality: within this factor of the analytic's")
    a = p.parse_args()

    from amigo_gym.policies import AnalyticTrackingPolicy
    from amigo_gym.tools.training.fastppo import FastPPOSettings, evaluate_policy

    curves, settings = [], []
    for seed in a.seeds:
        c = read_curve(Path(a.curves) / f"{a.stem}_s{seed}.curve.csv")
        m = json.loads((Path(a.manifests) / f"{a.stem}_s{seed}.json").read_text())
        last = m["last_eval"]
        for key in ("env_steps", "eval_h_rms_m", "eval_chatter_settled_rms"):
            if not np.isclose(c[key][-1], float(last[key]), rtol=1e-12, atol=0.0):
                raise SystemExit(f"seed {seed}: curve's last {key} {c[key][-1]!r} != manifest's {last[key]!r}")
        curves.append(c)
        settings.append(FastPPOSettings.from_json(m["settings"]))
    s = settings[0]
    same = ("env_kwargs", "eval_seed", "eval_envs", "max_episode_steps")
    if any(tuple(getattr(x, k) for k in same) != tuple(getattr(s, k) for k in same) for x in settings):
        raise SystemExit("the seeds were evaluated on different validation settings")
    steps = curves[0]["env_steps"]
    if any(not np.array_equal(c["env_steps"], steps) for c in curves):
        raise SystemExit("the seeds were evaluated at different env-steps")

    ref = evaluate_policy(AnalyticTrackingPolicy(s.spec().params()), dataclasses.replace(s))
    h_ref, quality = ref["h_rms_m"], a.factor * ref["h_rms_m"]

    h = np.stack([c["eval_h_rms_m"] for c in curves])  # (seeds, evals) [m]
    ch = np.stack([c["eval_chatter_settled_rms"] for c in curves])  # [rad/s]
    h_iqm = iqm(h.T[:, None, :])  # IQM over seeds at each evaluation
    ch_iqm = iqm(ch.T[:, None, :])
    t0 = max(float(c["wall_s"][0]) for c in curves)
    t1 = max(float(c["wall_s"][-1]) for c in curves)  # a finished seed keeps its final model (its last value)
    grid = np.arange(np.ceil(t0), np.floor(t1) + 1.0)
    h_wall = np.stack([step_on_grid(c["wall_s"], c["eval_h_rms_m"], grid) for c in curves])
    h_wall_iqm = iqm(h_wall.T[:, None, :])

    per_seed = [
        {
            "seed": seed,
            "steps_to_quality": first_within(c["env_steps"], c["eval_h_rms_m"], quality),
            "wall_s_to_quality": first_within(c["wall_s"], c["eval_h_rms_m"], quality),
            "final_env_steps": float(c["env_steps"][-1]),
            "final_wall_s": float(c["wall_s"][-1]),
            "final_h_rms_m": float(c["eval_h_rms_m"][-1]),
            "final_chatter_settled_rms": float(c["eval_chatter_settled_rms"][-1]),
        }
        for seed, c in zip(a.seeds, curves, strict=True)
    ]
    summary: dict[str, Any] = {
        "command": "python experiments/plot_curves_v1.py",
        "validation": {
            "env_kwargs": dict(s.env_kwargs),
            "seeds": f"{s.eval_seed} + j, j < {s.eval_envs}",
            "max_episode_steps": s.max_episode_steps,
        },
        "analytic": {k: float(v) for k, v in ref.items()},
        "quality_factor": a.factor,
        "quality_h_rms_m": quality,
        "iqm": {
            "steps_to_quality": first_within(steps, h_iqm, quality),
            "wall_s_to_quality": first_within(grid, h_wall_iqm, quality),
            "h_rms_m_at_wall_line": float(h_wall_iqm[np.searchsorted(grid, WALL_LINE_S, side="right") - 1])
            if grid[0] <= WALL_LINE_S
            else None,
            "final_h_rms_m": float(h_iqm[-1]),
            "final_chatter_settled_rms": float(ch_iqm[-1]),
            # from the first evaluation after step 0 (the untrained policy's near-constant commands do not chatter)
            "steps_to_chatter_target": first_within(steps[1:], ch_iqm[1:], CHATTER_TARGET),
        },
        "seeds": per_seed,
        "wall_clock_note": "measured on a loaded, shared 2-core machine (other training runs beside): indicative only",
    }
    out = Path(a.out)
    atomic_write_json(out / "curves_summary.json", summary)
    plot(
        out, steps, h, h_iqm, ch, ch_iqm, curves, grid, h_wall_iqm, h_ref, quality, ref["chatter_settled_rms"], a.label
    )

    mm = 1e3
    print(f"analytic on the validation episodes: H RMS {mm * h_ref:.3f} mm, {a.factor:g}x = {mm * quality:.3f} mm, "
          f"settled chatter {ref['chatter_settled_rms']:.3f} rad/s")  # fmt: skip
    head = f"env-steps to {a.factor:g}x analytic | wall [s] | final H RMS [mm] | final settled chatter [rad/s]"
    print(f"| seed | {head} |")
    print("|---|---:|---:|---:|---:|")
    fmt = lambda x, f: "never" if x is None else f"{x:{f}}"  # noqa: E731
    for r in per_seed:
        print(
            f"| {r['seed']} | {fmt(r['steps_to_quality'], ',.0f')} | {fmt(r['wall_s_to_quality'], '.0f')} | "
            f"{mm * r['final_h_rms_m']:.2f} | {r['final_chatter_settled_rms']:.2f} |"
        )
    q = summary["iqm"]
    print(
        f"| IQM | {fmt(q['steps_to_quality'], ',.0f')} | {fmt(q['wall_s_to_quality'], '.0f')} | "
        f"{mm * q['final_h_rms_m']:.2f} | {q['final_chatter_settled_rms']:.2f} |"
    )
    at30 = q["h_rms_m_at_wall_line"]
    print(f"IQM at 30 min of wall-clock: {'-' if at30 is None else f'{mm * at30:.2f} mm'}; IQM settled chatter first "
          f"<= 1 rad/s at {fmt(q['steps_to_chatter_target'], ',.0f')} env-steps")  # fmt: skip
    return 0


def mm_ticks(ax: Any) -> None:
    """Plain millimetre labels on a log axis (1, 2, 3, 5, 10, 20, 50)."""
    from matplotlib.ticker import FixedLocator, NullFormatter, NullLocator, ScalarFormatter

    ax.yaxis.set_major_locator(FixedLocator([1, 1.5, 2, 3, 5, 10, 20, 50]))
    ax.yaxis.set_major_formatter(ScalarFormatter())
    ax.yaxis.set_minor_locator(NullLocator())
    ax.yaxis.set_minor_formatter(NullFormatter())


def plot(
    out: Path,
    steps: np.ndarray,
    h: np.ndarray,
    h_iqm: np.ndarray,
    ch: np.ndarray,
    ch_iqm: np.ndarray,
    curves: list[dict[str, np.ndarray]],
    grid: np.ndarray,
    h_wall_iqm: np.ndarray,
    h_ref: float,
    quality: float,
    ch_ref: float,
    label: str,
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(curves)
    x = steps / 1e6
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    ax1.fill_between(x, 1e3 * h.min(0), 1e3 * h.max(0), alpha=0.25, label=f"min-max over {n} seeds")
    ax1.plot(x, 1e3 * h_iqm, lw=2, label=f"{label}, IQM over seeds")
    ax1.axhline(1e3 * h_ref, color="k", ls="-", lw=1, label=f"analytic ({1e3 * h_ref:.2f} mm)")
    ax1.axhline(1e3 * quality, color="k", ls="--", lw=1, label=f"{quality / h_ref:g}x analytic")
    ax1.set_yscale("log")
    mm_ticks(ax1)
    ax1.set_xlabel("env-steps of training [millions]")
    ax1.set_ylabel("validation H cross-track RMS [mm]")
    ax1.set_title("H error (32 validation episodes of the training distribution)", fontsize=9)
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3, which="both")
    ax2.fill_between(x[1:], ch.min(0)[1:], ch.max(0)[1:], alpha=0.25, label=f"min-max over {n} seeds")
    ax2.plot(x[1:], ch_iqm[1:], lw=2, label=f"{label}, IQM over seeds")  # step 0: an untrained policy, ~0 commands
    ax2.axhline(CHATTER_TARGET, color="r", ls="--", lw=1, label="target 1 rad/s")
    ax2.axhline(ch_ref, color="k", lw=1, label=f"analytic ({ch_ref:.2f} rad/s)")
    ax2.set_xlabel("env-steps of training [millions]")
    ax2.set_ylabel("settled command chatter, RMS [rad/s]")
    ax2.set_title("step-to-step change of the wheel-rate command, t >= 5 s", fontsize=9)
    ax2.set_ylim(bottom=0)
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    atomic_save(lambda tmp: fig.savefig(tmp, dpi=110, format="png"), out / "learning_curves.png", parents=True)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7.5, 4.5), constrained_layout=True)
    for i, c in enumerate(curves):
        ax.step(c["wall_s"] / 60, 1e3 * c["eval_h_rms_m"], where="post", lw=0.8, alpha=0.6, label=f"seed {i}")
    ax.plot(grid / 60, 1e3 * h_wall_iqm, lw=2, color="C0", label="IQM over seeds")
    ax.axhline(1e3 * h_ref, color="k", lw=1, label="analytic")
    ax.axhline(1e3 * quality, color="k", ls="--", lw=1, label=f"{quality / h_ref:g}x analytic")
    ax.axvline(WALL_LINE_S / 60, color="r", ls=":", lw=1.2, label="30 min")
    ax.set_yscale("log")
    mm_ticks(ax)
    ax.set_xlabel("wall-clock of training [min] (loaded, shared 2-core machine)")
    ax.set_ylabel("validation H cross-track RMS [mm]")
    ax.set_title(f"Time to quality: {label}, {steps[-1] / 1e6:.0f}M env-steps per seed", fontsize=10)
    ax.legend(fontsize=8, ncol=2)
    ax.grid(alpha=0.3, which="both")
    atomic_save(lambda tmp: fig.savefig(tmp, dpi=110, format="png"), out / "time_to_quality.png", parents=True)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
