"""Quality per second of training: an off-policy algorithm or the fast PPO, trained for a CPU budget, with a curve.

    nice -n 10 python experiments/offpolicy_quality.py --algo td3 --config ht --cpu-budget 150 \\
        --out docs/figures/offpolicy/td3_ht_s0.curve.csv
    nice -n 10 python experiments/offpolicy_quality.py --algo fastppo --cpu-budget 150 \\
        --out docs/figures/offpolicy/fastppo_s0.curve.csv

Trains on ``AmigoBot-v1`` with the training distribution (``TRAINING_DISTRIBUTION``), one torch thread, seed 0:

* ``sac``, ``td3``, ``crossq``, ``tqc``: the configuration ``--config`` of :mod:`amigo_gym.tools.bench.train`
  (``shipped`` or ``ht``) over the SB3 adapter of the native vector env, in chunks of ``--eval-every`` env-steps;
* ``fastppo``: :func:`amigo_gym.tools.training.fastppo.train` with its defaults, ``--filter-alpha 0.5`` and
  ``--total-steps 15000000`` (the learning-rate schedule of the published fast-PPO curve,
  ``docs/figures/fastppo/ppo_fast_s0.curve.csv``), resumed chunk after chunk; its times are those of the training
  iterations (rollouts and updates, ``cpu_s_this_call``), without the evaluations and the chunking's
  checkpoint save/load.

After each chunk the policy (deterministic) is evaluated with :func:`amigo_gym.tools.training.fastppo.evaluate_policy`
on the fast PPO's validation episodes (32 robots, seeds 1,000,000 + i: the seeds of the published fast-PPO curve, not
the benchmark's test seeds). Training stops at the first chunk end past ``--cpu-budget`` CPU seconds of training
(process time, all threads; the evaluations excluded) or ``--wall-budget`` wall seconds. Each row: ``env_steps``,
``grad_steps``, ``wall_s`` and ``cpu_s`` of training so far, then the validation metrics (``eval_h_rms_m`` ...).
The CSV is rewritten atomically after every row; a JSON summary (settings, versions, load) is written beside it.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from amigo_gym.io import atomic_write_json
from amigo_gym.tools.bench import load_values
from amigo_gym.tools.bench.train import _venv, cpu_model, make_model, offpolicy_config
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
from amigo_gym.tools.training.fastppo import FastPPOSettings, evaluate_policy

EVAL = {"eval_envs": 32, "eval_seed": 1_000_000, "max_episode_steps": 600}


def write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        f.write(buf.getvalue())
    os.replace(tmp, path)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--algo", required=True, choices=["sac", "td3", "crossq", "tqc", "fastppo"])
    p.add_argument("--config", default="ht", choices=["shipped", "ht"])
    p.add_argument("--cpu-budget", type=float, default=150.0, help="CPU seconds of training [s]")
    p.add_argument("--wall-budget", type=float, default=3600.0, help="wall seconds of training [s]")
    p.add_argument("--eval-every", type=int, default=0, help="env-steps per chunk (0: 8192 off-policy, 262144 PPO)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", required=True, help="curve CSV")
    a = p.parse_args()
    import torch

    torch.set_num_threads(1)
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    kw = dict(TRAINING_DISTRIBUTION["env_kwargs"])
    es = FastPPOSettings(env_kwargs=kw, **EVAL)  # type: ignore[arg-type]
    rows: list[dict[str, Any]] = []
    wall = cpu = 0.0
    summary: dict[str, Any] = {
        "algo": a.algo,
        "seed": a.seed,
        "command": "python experiments/offpolicy_quality.py " + " ".join(sys.argv[1:]),
        "cpu_model": cpu_model(),
        "torch": torch.__version__,
        "torch_threads": 1,
        "load_average_start": load_values(),
        "validation": EVAL | {"env_kwargs": kw},
    }

    def record(n: int, g: int, policy: Any) -> None:
        m = evaluate_policy(policy, es)
        rows.append(
            {"env_steps": n, "grad_steps": g, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2)}
            | {f"eval_{k}": v for k, v in m.items()}
        )
        write_csv(out, rows)
        print(f"{n:>10} env-steps {g:>8} grad  {wall:7.1f} s wall {cpu:7.1f} s CPU  H RMS "
              f"{1e3 * m['h_rms_m']:.2f} mm (settled {1e3 * m['h_rms_settled_m']:.2f}) "
              f"chatter {m['chatter_settled_rms']:.2f} failure {m['failure']:.2f}", flush=True)  # fmt: skip

    if a.algo == "fastppo":
        from amigo_gym.tools.training.fastppo import train

        chunk = a.eval_every or 262_144
        s = FastPPOSettings(
            env_kwargs=kw, total_steps=15_000_000, seed=a.seed, threads=1, filter_alpha=0.5,
            eval_every=chunk, checkpoint_every=10**10, **EVAL,  # type: ignore[arg-type]
        )  # fmt: skip
        summary["settings"] = s.to_json()
        per_iter = s.epochs * (s.num_envs * s.rollout_steps // s.minibatch_size)  # gradient steps per iteration
        with tempfile.TemporaryDirectory() as tmp:
            run = Path(tmp) / "run"
            k = 1
            while True:
                # train's own evaluation (the same evaluate_policy and validation seeds) at every chunk end
                rec = train(s, run, resume=k > 1, until_steps=k * chunk, log=None)
                curve = json.loads((run / "curve.json").read_text())
                curve = curve if isinstance(curve, list) else curve["rows"]
                last = curve[-1]
                # training iterations only (rollouts and updates): no evaluation, no checkpoint save/load of chunking
                split = rec["cpu_s_this_call"]
                wall += float(split["loop_wall"])
                cpu += float(split["rollout"]) + float(split["update"])
                if k == 1:  # the evaluation before the first update (train evaluates at step 0)
                    first = {kk: v for kk, v in curve[0].items() if kk.startswith("eval_") and kk != "eval_s"}
                    rows.append({"env_steps": 0, "grad_steps": 0, "wall_s": 0.0, "cpu_s": 0.0} | first)
                n = int(last["env_steps"])
                rows.append(
                    {"env_steps": n, "grad_steps": n // (s.num_envs * s.rollout_steps) * per_iter,
                     "wall_s": round(wall, 2), "cpu_s": round(cpu, 2)}
                    | {kk: v for kk, v in last.items() if kk.startswith("eval_") and kk != "eval_s"}
                )  # fmt: skip
                write_csv(out, rows)
                print(f"{n:>10} env-steps {wall:7.1f} s wall {cpu:7.1f} s CPU  H RMS "
                      f"{1e3 * last['eval_h_rms_m']:.2f} mm chatter {last['eval_chatter_settled_rms']:.2f}",
                      flush=True)  # fmt: skip
                if cpu >= a.cpu_budget or wall >= a.wall_budget:
                    break
                k += 1
    else:
        hp = offpolicy_config(a.algo, a.config)
        summary["config"] = {k: (list(v) if isinstance(v, tuple) else v) for k, v in hp.items()} | {"name": a.config}
        chunk = a.eval_every or 8192
        t0, c0 = time.perf_counter(), time.process_time()
        venv = _venv(int(hp.get("n_envs", 1)), a.seed)
        model = make_model(a.algo, hp, venv, a.seed)
        wall += time.perf_counter() - t0
        cpu += time.process_time() - c0
        record(0, 0, model)  # evaluate_policy predicts deterministically
        first = True
        while cpu < a.cpu_budget and wall < a.wall_budget:
            t0, c0 = time.perf_counter(), time.process_time()
            model.learn(total_timesteps=chunk, reset_num_timesteps=first)
            first = False
            wall += time.perf_counter() - t0
            cpu += time.process_time() - c0
            record(int(model.num_timesteps), int(model._n_updates), model)
        venv.close()
    summary |= {"rows": len(rows), "last": rows[-1], "load_average_end": load_values()}
    atomic_write_json(out.with_suffix("").with_suffix(".json"), summary, parents=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
