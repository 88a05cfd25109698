"""Training at machine scale, measured in one run: throughput of ``amigo-gym train-fast`` at large N, then a
generalist trained for a fixed wall budget, evaluated against the analytic controller on the ideal-robot cells.

    python experiments/gpu_train_bench.py                                   # GPU node: N = 16,384, 180 s
    python experiments/gpu_train_bench.py --budget-s 20 --n-envs 256        # any CPU machine, a smoke run

Settings: ``agents/hyperparams/fastppo_gpu.yml`` with ``num_envs = --n-envs``, ``minibatch_size = N T / 8`` (the
file's 8 minibatches per epoch), ``env_threads = --env-threads`` (default: every thread numba may use) and
``device = --device``. Steps, each printed and written to ``$OUT/gpu_train_bench.json`` (``--json`` otherwise):

1. the machine: CPU name, CPUs, torch device (and GPU name), torch and numba thread counts, load average;
2. env only: the vector env (the training distribution, numba-parallel) stepped with random actions;
3. training throughput: ``--measure-iters`` iterations after one warm-up iteration (compilation, CUDA start), timed
   over their second half (by then episodes end and restart, as in a long run; right after reset none does), the
   env's and the learner's shares of their wall time (the learner: policy, transfers, GAE, updates); without the
   curriculum; the same at each of ``--sizes`` (N) besides ``--n-envs``;
4. training for ``--budget-s`` seconds of iterations: ``total_steps`` = the measured rate times the budget (whole
   rollouts; the learning rate anneals over it), then ``model.zip`` (copied beside the JSON as ``gpu_model.zip``, with
   ``gpu_run.json`` and ``gpu_settings.json``);
   (shrunk if the steps before it took so long that the run would pass ``--deadline-s``, default 7 minutes);
5. the validation curve of that training (``--curve-points`` evaluations of ``eval_envs`` validation episodes,
   against training time without the evaluations' time, beside the analytic controller's H RMS on them);
6. the generalist and the analytic controller on the 11 ideal-robot cells of ``experiments/targets_v1.py``
   (:data:`targets_v1.IDEAL`, the benchmark suite's scenarios and test seeds, ``amigo-gym benchmark``'s
   evaluation): IQM of H RMS over (seed, cell) as ``targets_v1`` computes it, its ratio to the analytic's, the
   median over the cells of the settled chatter (issue 35's targets: ratio <= 1.2, chatter <= 0.1 rad/s, in <= 3
   minutes of training; >= 1M env-steps/s of training);
7. ``--overlap``: step 3's throughput again at each N with ``overlap`` (two halves, one's env step on a second thread
   while the main thread computes the other's policy), and its ratio to step 3's; last, so that it does not cut the
   budget of step 4.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

# this checkout's amigo_gym (whatever is installed) and targets_v1, beside this file
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from targets_v1 import IDEAL, _matrix

from amigo_gym.io import atomic_write_json, sha256_file
from amigo_gym.tools.machine import cpu_model
from amigo_gym.tools.training import benchmark as bm
from amigo_gym.tools.training.fastppo import (
    FastPPOSettings,
    _numba_threads_limit,
    load_settings_yaml,
    resolve_device,
    train,
)
from amigo_gym.tools.training.intervals import iqm

ROOT = Path(__file__).resolve().parent.parent
CONFIG = ROOT / "agents" / "hyperparams" / "fastppo_gpu.yml"


def say(msg: str) -> None:
    print(msg, flush=True)


def settings(
    args: argparse.Namespace, total_steps: int, seed: int, curriculum: bool = True, overlap: bool = False
) -> FastPPOSettings:
    """The file's settings at ``--n-envs``; ``curriculum`` False: without the curvature curriculum (whose raises,
    eight in a run, each rebuild the pool of random paths: one per iteration in the few iterations of a timing)."""
    hp: dict[str, Any] = load_settings_yaml(CONFIG)
    if not curriculum:
        hp["curriculum_max_curvature"] = 0.0
    hp["hidden"] = tuple(hp["hidden"])
    batch = args.n_envs * hp["rollout_steps"]
    hp |= {"num_envs": args.n_envs, "minibatch_size": max(1, batch // 8), "env_threads": args.env_threads}
    hp |= {"device": args.device, "threads": args.threads or hp["threads"], "total_steps": total_steps, "seed": seed}
    hp |= {"eval_every": 10**10, "checkpoint_every": 10**10, "overlap": overlap}
    return FastPPOSettings(**hp)


def env_only(s: FastPPOSettings, steps: int) -> float:
    """Env-steps/s of the training env alone (random actions), after one warm-up step."""
    from amigo_gym.tools.training.fastppo import _training_env

    env = _training_env(s)
    env.reset(seed=list(range(s.num_envs)))
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (steps + 1, s.num_envs, 2))
    env.step(acts[0])
    t0 = time.perf_counter()
    for a in acts[1:]:
        env.step(a)
    wall = time.perf_counter() - t0
    env.close()
    return s.num_envs * steps / wall


def timed_train(s: FastPPOSettings, out: Path, **kw: Any) -> dict[str, Any]:
    t0 = time.perf_counter()
    rec = train(s, out, log=None, **{"evaluate_runs": False, **kw})
    rec["call_s"] = time.perf_counter() - t0
    return rec


def throughput(args: argparse.Namespace, out: Path, overlap: bool = False) -> dict[str, Any]:
    """Training env-steps/s over the second half of ``--measure-iters`` iterations at ``args.n_envs``."""
    s = settings(args, 1, args.seed, False)
    batch = s.num_envs * s.rollout_steps
    s = settings(args, batch * args.measure_iters, args.seed, False, overlap)
    half = args.measure_iters // 2
    if half:
        timed_train(s, out, until_steps=batch * half)
    m = timed_train(s, out, resume=half > 0)
    w = m["wall_s_this_call"]
    sps = (m["timesteps"] - batch * half) / w["loop"]
    return {
        "n_envs": s.num_envs,
        "overlap": overlap,
        "env_steps": m["timesteps"] - batch * half,
        "loop_s": w["loop"],
        "train_sps": round(sps),
        "env_share": round(w["env"] / w["loop"], 3),
        "learner_share": round(1 - w["env"] / w["loop"], 3),
        "rollout_share": round(w["rollout"] / w["loop"], 3),
        "update_share": round(w["update"] / w["loop"], 3),
    }


def curve(s: FastPPOSettings, run: Path) -> list[dict[str, float]]:
    """The run's validation curve against training time (its evaluations' time taken out) and the analytic
    controller's H RMS on the same validation episodes: the time to quality."""
    import gymnasium as gym

    from amigo_gym.policies.tracking import AnalyticTrackingPolicy
    from amigo_gym.tools.training.fastppo import evaluate_policy

    ref = evaluate_policy(AnalyticTrackingPolicy(gym.make("AmigoBot-v1", **s.env_kwargs).unwrapped.params), s)
    rows, spent = [], 0.0
    for row in json.loads((run / "curve.json").read_text()):
        spent += row["eval_s"]
        h = row["eval_h_rms_m"]
        rows.append({"env_steps": row["env_steps"], "train_s": round(row["wall_s"] - spent, 1), "h_rms_mm": 1e3 * h,
                     "ratio_to_analytic": h / ref["h_rms_m"],
                     "chatter_settled": row["eval_chatter_settled_rms"]})  # fmt: skip
        say(
            f"  curve: {row['env_steps']:>13,.0f} env-steps, {rows[-1]['train_s']:6.1f} s of training: H RMS "
            f"{1e3 * h:.2f} mm, {rows[-1]['ratio_to_analytic']:.2f}x the analytic controller's (validation)"
        )
    return rows


def ideal_cells(model: Path, episodes: int) -> dict[str, Any]:
    """The generalist against the analytic controller on the ideal cells (targets_v1's figures), the first
    ``episodes`` test seeds of each."""
    (model.with_suffix(".json")).write_text(json.dumps({"algo": "fastppo", "seed": 0, "sha256": sha256_file(model)}))
    agents = [bm.AgentSpec("analytic"), bm.parse_agents([f"fastppo={model}"])[0]]
    cells = [dataclasses.replace(sc, seeds=sc.seeds[:episodes]) for sc in bm.SUITE if sc.name in IDEAL]
    doc = bm.run_benchmark(agents, cells, progress=False, reps=100, profile_reps=10)
    rows = [r for r in doc["results"] if r.get("h_rms_m") is not None]
    out: dict[str, Any] = {"cells": list(IDEAL), "episodes_per_cell": cells[0].episodes}
    for agent in ("analytic", "fastppo"):
        h = _matrix(rows, agent, IDEAL, "h_rms_m") * 1e3
        ch = _matrix(rows, agent, IDEAL, "chatter_settled_rms").mean(axis=0)
        out[agent] = {"h_rms_iqm_mm": float(iqm(h)), "chatter_settled_median_rad_s": float(np.median(ch)),
                      "chatter_settled_max_rad_s": float(ch.max())}  # fmt: skip
    out["ratio"] = out["fastppo"]["h_rms_iqm_mm"] / out["analytic"]["h_rms_iqm_mm"]
    return out


def main(argv: list[str] | None = None) -> int:
    import numba
    import torch

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else "")
    ap.add_argument("--budget-s", type=float, default=180.0, help="wall seconds of training iterations [s]")
    ap.add_argument("--n-envs", type=int, default=16384, help="robots N")
    ap.add_argument("--env-threads", type=int, default=_numba_threads_limit(), help="numba threads of the env")
    ap.add_argument("--threads", type=int, help="torch threads (default: the file's)")
    ap.add_argument("--deadline-s", type=float, default=420.0, help="shrink the budget to end by then [s]")
    ap.add_argument("--device", default="auto", choices=("auto", "cpu", "cuda"))
    ap.add_argument("--measure-iters", type=int, default=48, help="iterations of the throughput (half timed)")
    ap.add_argument("--curve-points", type=int, default=6, help="validation evaluations during the training")
    ap.add_argument("--sizes", type=int, nargs="*", default=[], help="other N whose throughput is measured too")
    ap.add_argument("--env-steps", type=int, default=50, help="steps of the env-only timing")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--episodes", type=int, default=10, help="test seeds per ideal cell (the suite's: 10)")
    ap.add_argument("--json", type=Path, help="write the results here (default: $OUT/gpu_train_bench.json)")
    ap.add_argument("--overlap", action="store_true", help="last, the throughput again with train-fast --overlap")
    args = ap.parse_args(argv)
    t_all = time.perf_counter()
    device = resolve_device(args.device)
    doc: dict[str, Any] = {
        "command": " ".join([sys.executable.rsplit("/", 1)[-1], *sys.argv]),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "device": device,
        "device_name": torch.cuda.get_device_name() if device == "cuda" else cpu_model(),
        "torch": torch.__version__,
        "load_average_start": list(os.getloadavg()),
        "config": str(CONFIG.relative_to(ROOT)),
    }
    say(f"CPU: {doc['cpu']} ({doc['cpu_count']} CPUs); torch {torch.__version__} on {device} ({doc['device_name']}); "
        f"load {doc['load_average_start']}")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        s = settings(args, 1, args.seed)
        batch = s.num_envs * s.rollout_steps
        warm = timed_train(settings(args, batch, args.seed, False), Path(tmp) / "warm")  # compiles, starts CUDA
        doc |= {k: warm[k] for k in ("torch_threads", "numba_threads", "git_revision")}
        doc["warmup_call_s"] = round(warm["call_s"], 1)
        say(f"threads: torch {warm['torch_threads']}, numba (env) {warm['numba_threads']}; N = {s.num_envs}, "
            f"T = {s.rollout_steps}, minibatch {s.minibatch_size}, epochs {s.epochs}; "
            f"warm-up {warm['call_s']:.1f} s")  # fmt: skip
        doc["env_only_sps"] = round(env_only(s, args.env_steps))
        say(f"env only: {doc['env_only_sps']:,} env-steps/s (numba threads {numba.get_num_threads()})")
        doc["throughput_sizes"] = []
        for n in [*args.sizes, args.n_envs]:
            t = throughput(argparse.Namespace(**{**vars(args), "n_envs": n}), Path(tmp) / f"measure{n}")
            doc["throughput_sizes"].append(t)
            shares = f"rollout {100 * t['rollout_share']:.0f} % incl. env, update {100 * t['update_share']:.0f} %"
            say(f"training, N = {n:,}: {t['train_sps']:,} env-steps/s over the iterations after the first "
                f"{args.measure_iters // 2}; env {100 * t['env_share']:.0f} %, learner {100 * t['learner_share']:.0f} "
                f"% ({shares})")  # fmt: skip
        doc["throughput"] = t
        sps = t["train_sps"]
        # 90 s for the evaluation (it compiles the env's one-thread kernel on a fresh machine), 10 s per curve point
        budget = min(args.budget_s, args.deadline_s - (time.perf_counter() - t_all) - 90.0 - 10.0 * args.curve_points)
        if budget < args.budget_s:
            say(f"budget cut to {budget:.0f} s to end within --deadline-s {args.deadline_s:g} s")
        doc["budget_s"] = budget = max(budget, 1.0)
        total = max(1, round(sps * budget / batch)) * batch
        say(f"training {total:,} env-steps (budget {budget:g} s at the measured rate) ...")
        run = Path(tmp) / "run"
        every = -(-total // (args.curve_points * batch)) * batch  # whole rollouts
        final = dataclasses.replace(settings(args, total, args.seed), eval_every=every)
        rec = timed_train(final, run, evaluate_runs=args.curve_points > 0)
        w = rec["wall_s_this_call"]
        doc["training"] = {
            "total_steps": total,
            "loop_s": w["loop"],
            "call_s": round(rec["call_s"], 1),
            "train_sps": round(total / w["loop"]),
            "env_share": round(w["env"] / w["loop"], 3),
            "sha256": rec.get("sha256"),
        }
        say(f"trained {total:,} env-steps in {w['loop']:.1f} s of iterations ({total / w['loop']:,.0f} env-steps/s; "
            f"call {rec['call_s']:.1f} s); evaluating on the ideal cells ...")  # fmt: skip
        t0 = time.perf_counter()
        doc["ideal_cells"] = q = ideal_cells(run / "model.zip", args.episodes)
        if args.curve_points > 0:
            doc["curve"] = curve(final, run)
        path = args.json or (Path(os.environ["OUT"]) / "gpu_train_bench.json" if os.environ.get("OUT") else None)
        for name in ("model.zip", "run.json", "settings.json", "curve.csv") if path is not None else ():
            path.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(run / name, path.parent / f"gpu_{name}")  # the trained generalist, kept
        q["eval_s"] = round(time.perf_counter() - t0, 1)
        doc["throughput_overlap"] = []
        for plain in doc["throughput_sizes"] if args.overlap else ():
            n = plain["n_envs"]
            try:  # a failure here leaves the figures above their JSON
                t = throughput(argparse.Namespace(**{**vars(args), "n_envs": n}), Path(tmp) / f"overlap{n}", True)
            except Exception as exc:
                doc["throughput_overlap"].append({"n_envs": n, "overlap": True, "error": repr(exc)})
                say(f"training, N = {n:,}, --overlap: failed: {exc!r}")
                continue
            t["ratio_to_plain"] = round(t["train_sps"] / plain["train_sps"], 3)
            doc["throughput_overlap"].append(t)
            say(f"training, N = {n:,}, --overlap: {t['train_sps']:,} env-steps/s ({t['ratio_to_plain']:.2f}x without; "
                f"env {100 * t['env_share']:.0f} % of the wall on its thread, rollout {100 * t['rollout_share']:.0f} "
                f"%, update {100 * t['update_share']:.0f} %)")  # fmt: skip
    a, f = q["analytic"], q["fastppo"]
    say(f"ideal cells ({len(IDEAL)} x {q['episodes_per_cell']} episodes): H RMS IQM analytic {a['h_rms_iqm_mm']:.2f} "
        f"mm, generalist {f['h_rms_iqm_mm']:.2f} mm, ratio {q['ratio']:.2f} (target <= 1.2); settled chatter median "
        f"{f['chatter_settled_median_rad_s']:.3f} rad/s (max {f['chatter_settled_max_rad_s']:.3f}; "
        "target <= 0.1)")  # fmt: skip
    doc["load_average_end"] = list(os.getloadavg())
    doc["total_s"] = round(time.perf_counter() - t_all, 1)
    if path is not None:
        atomic_write_json(path, doc, parents=True)
        say(f"wrote {path}")
    say(f"total {doc['total_s']:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
