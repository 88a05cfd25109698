"""Train the fast-PPO agents of AmigoBot-v1 (PPO generalist, residual policy; seeds 0-4) and write manifests.

One readable file: the agents as data (:data:`AGENTS`: the ``amigo-gym train-fast`` options of each), explicit
seeds, ``--workers`` runs at a time as ``nice -n 5`` subprocesses with one torch thread each (so that a core
stays free). Every run checkpoints (``--checkpoint-every``); a killed script is simply started again: finished
runs are skipped, unfinished ones resumed from their checkpoint (``--resume``), bit for bit.

    python experiments/train_v1_fast.py --runs runs/fast_v1 --workers 1                  # everything
    python experiments/train_v1_fast.py --agents residual --seeds 0 1 --workers 2       # a subset
    python experiments/train_v1_fast.py --runs runs/fast_v1 --export                     # + copy to agents/

Each finished run ``<runs>/<agent>_s<seed>/`` holds ``model.zip``, ``best.zip``, ``curve.csv``/``curve.json``
and ``run.json``; the script writes ``<runs>/<agent>_s<seed>.manifest.json`` beside it (training command, seed,
steps, wall time, versions, sha256 of ``model.zip``, the training distribution). ``--export`` copies model and
manifest to ``agents/pretrained/v1/<agent>/<agent>_s<seed>.{zip,json}``: do that only for agents the benchmark
measures better than what is shipped (``amigo-gym benchmark --agents analytic <agent>=<runs>/<agent>_s*/model.zip``).

Distributions (never the benchmark's cells; the evaluations during training use validation seeds 1,000,000+):

* ``ppo_fast``: :data:`amigo_gym.tools.training.benchmark.TRAINING_DISTRIBUTION` (mixed paths, 0.1-0.4 m/s, ``mild``),
  with the settings the sweep found (``agents/hyperparams/fastppo.yml``: its best trial, including the low-pass
  action filter and the CAPS smoothness weight) and the curvature curriculum to 4.25 1/m, 10M env-steps; run from
  the repository's root (the relative path). The shipped seeds ran under the name ``ppo_fast_curv`` (the same
  command) and were exported as ``ppo_fast``;
* ``ppo_fast_nocurv``: the same without the curriculum (the first tuned seeds; they failed half the paths above
  2 1/m at 0.4 m/s);
* ``ppo_fast_hand``: the previous release's ``ppo_fast``, before the sweep: the module's defaults with the low-pass
  action parameterisation ``--filter-alpha 0.5`` (of the smoothness variants measured on the validation seeds,
  docs/experiments.md, 1.5M steps each, it had both the lowest settled chatter and H error), 15M env-steps;
* ``ppo_fast_curv``: ``ppo_fast`` with the curvature curriculum up to 4.25 1/m (K(0.4), the most the env accepts
  at the top speed; docs/experiments.md, "Failure rate per curvature bin");
* ``ppo_fast_30m``: ``ppo_fast_hand`` for 30M env-steps (the learning rate anneals over the longer run): the
  settled chatter keeps falling; seeds 1-4 not continued, superseded by the tuned ``ppo_fast`` (docs/experiments.md,
  "Time to quality"; ``experiments/time_to_quality.py``);
* ``residual``: the same paths and speeds with a wider randomisation: wheel radii and track +-7 %, slip <= 2 %,
  actuation delay 0-0.3 s, ``mild``'s noise; the correction is bounded to +-0.3 of the action range and the
  policy observes the last 4 steps' commands and measurements (``--history 4``: 0.4 s, longer than the delays).
* ``residual2``: the same robots, delays and paths without measurement noise and with a 4x sharper tracking
  reward (``sigma_track`` 5 mm); correction bound 0.15, an L2 penalty on the correction (``--residual-penalty 3``),
  30 % of the training robots nominal (``--nominal-fraction 0.3``), 3M steps; the kept model is ``best.zip``
  (:data:`KEEP_BEST`), chosen on validation versions of the benchmark's cells (docs/experiments.md, "Residual
  policy, second round"; ``experiments/residual_val_cells.py``).
"""

from __future__ import annotations

import argparse
import json
import shlex
import shutil
import subprocess
import sys
import time
import zipfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from amigo_gym.data import pretrained_dir
from amigo_gym.io import sha256_file
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

RESIDUAL_ENV_KWARGS: dict[str, object] = {
    "path": "mixed",
    "speed": [0.1, 0.4],
    "randomize": {
        "wheel_radius": [0.93, 1.07],
        "track": [0.93, 1.07],
        "slip": [0.0, 0.02],
        "delay": [0.0, 0.3],
        "position_noise": 0.002,
        "heading_noise": 0.005,
        "wheel_rate_noise": 0.05,
    },
}

#: the second residual (docs/experiments.md, "Residual policy, second round"): no measurement noise, a tracking reward
#: 4x sharper (sigma_track 5 mm), the same robots, delays and paths as RESIDUAL_ENV_KWARGS
RESIDUAL2_ENV_KWARGS: dict[str, object] = {
    "path": "mixed",
    "sigma_track": 0.005,
    "speed": [0.1, 0.4],
    "randomize": {"wheel_radius": [0.93, 1.07], "track": [0.93, 1.07], "slip": [0.0, 0.02], "delay": [0.0, 0.3]},
}


def steps(n: int) -> list[str]:
    """The ``--total-steps`` option: ``n`` env-steps."""
    return ["--total-steps", str(n)]


def curriculum(max_curvature: str) -> list[str]:
    """The curvature curriculum up to ``max_curvature`` [1/m] (``"0"``: none; docs/baselines.md)."""
    return ["--curriculum-max-curvature", max_curvature]


def mixed() -> dict[str, object]:
    """A copy of the training distribution's env keywords (mixed paths, 0.1-0.4 m/s, ``mild``)."""
    return dict(TRAINING_DISTRIBUTION["env_kwargs"])


#: the settings the sweep found (its best trial, agents/hyperparams/fastppo.yml, a path from the repository's root)
#: for 10M env-steps
TUNED = ["--hyperparams", "agents/hyperparams/fastppo.yml", *steps(10_000_000)]
#: the hand-set options before the sweep: the low-pass action parameterisation
HAND = ["--filter-alpha", "0.5"]
#: the residual's correction bound and history (RESIDUAL_ENV_KWARGS)
RESIDUAL = ["--residual-bound", "0.3", "--history", "4"]
#: the second residual's (RESIDUAL2_ENV_KWARGS)
RESIDUAL2 = ["--residual-bound", "0.15", "--residual-penalty", "3.0", "--history", "4", "--nominal-fraction", "0.3"]

#: agent -> (env keywords, extra ``amigo-gym train-fast`` options): one line an agent
AGENTS: dict[str, tuple[dict[str, object], list[str]]] = {
    "ppo_fast": (mixed(), [*TUNED, *curriculum("4.25")]),
    "ppo_fast_nocurv": (mixed(), [*TUNED, *curriculum("0")]),
    "ppo_fast_hand": (mixed(), [*steps(15_000_000), *HAND]),
    "ppo_fast_curv": (mixed(), [*TUNED, *curriculum("4.25")]),
    "ppo_fast_30m": (mixed(), [*steps(30_000_000), *HAND]),
    "residual": (RESIDUAL_ENV_KWARGS, [*steps(10_000_000), *RESIDUAL]),
    "residual2": (RESIDUAL2_ENV_KWARGS, [*steps(3_000_000), *RESIDUAL2]),
}
#: agents whose kept model is ``best.zip`` (the lowest H RMS of the evaluations on the validation seeds)
KEEP_BEST = {"residual2"}


@dataclass(frozen=True)
class Settings:
    """What to train and where."""

    agents: tuple[str, ...] = tuple(AGENTS)
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)
    runs: Path = Path("runs/fast_v1")
    workers: int = 1
    export: bool = False
    nice: int = 5


def command(s: Settings, agent: str, seed: int) -> list[str]:
    """The ``amigo-gym train-fast`` command of one run (``--resume`` added when its checkpoint exists)."""
    env_kwargs, extra = AGENTS[agent]
    out = s.runs / f"{agent}_s{seed}"
    cmd = ["amigo-gym", "train-fast", "--out", str(out), "--seed", str(seed), "--threads", "1"]
    cmd += ["--eval-every", "1000000", "--checkpoint-every", "1000000", "--env-kwargs", json.dumps(env_kwargs), *extra]
    if (out / "checkpoint.pt").is_file():
        cmd.append("--resume")
    return cmd


def manifest(s: Settings, agent: str, seed: int, cmd: list[str]) -> Path:
    """Write ``<runs>/<agent>_s<seed>.manifest.json`` from the run record (and export it with ``--export``)."""
    out = s.runs / f"{agent}_s{seed}"
    record = json.loads((out / "run.json").read_text())
    env_kwargs, _ = AGENTS[agent]
    model = out / ("best.zip" if agent in KEEP_BEST else "model.zip")
    if agent in KEEP_BEST:
        info = json.loads(zipfile.ZipFile(model).read("model.json"))["info"]
        record |= {"sha256": sha256_file(model), "kept": "best.zip", "kept_env_steps": info.get("env_steps")}
    doc = record | {
        "agent": agent,
        "env_id": "AmigoBot-v1",
        "env_kwargs": env_kwargs,
        "training_command": " ".join(shlex.quote(c) for c in cmd if c != "--resume"),
        "training_distribution": TRAINING_DISTRIBUTION if agent.startswith("ppo_fast") else env_kwargs,
        "loader": "amigo_gym.policies.load_pretrained",
    }
    path = s.runs / f"{agent}_s{seed}.manifest.json"
    path.write_text(json.dumps(doc, indent=2) + "\n")
    if s.export:
        dest = pretrained_dir() / "v1" / agent
        dest.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(model, dest / f"{agent}_s{seed}.zip")
        (dest / f"{agent}_s{seed}.json").write_text(json.dumps(doc, indent=2) + "\n")
    return path


def run_one(s: Settings, agent: str, seed: int) -> str:
    out = s.runs / f"{agent}_s{seed}"
    cmd = command(s, agent, seed)
    if not (out / "run.json").is_file():
        t0 = time.perf_counter()
        r = subprocess.run(["nice", "-n", str(s.nice), *cmd], capture_output=True, text=True)
        (s.runs / f"{agent}_s{seed}.log").write_text(r.stdout + r.stderr)
        if r.returncode != 0:
            return f"{agent} seed {seed}: FAILED ({r.returncode}): {r.stderr.strip().splitlines()[-1:]}"
        took = f"{time.perf_counter() - t0:.0f} s"
    else:
        took = "done before"
    return f"{agent} seed {seed}: {took} -> {manifest(s, agent, seed, cmd)}"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--agents", nargs="+", default=list(AGENTS), choices=list(AGENTS), help="agents (default all)")
    p.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3, 4], help="seeds (default 0-4)")
    p.add_argument("--runs", default="runs/fast_v1", help="folder of the run folders (default runs/fast_v1)")
    p.add_argument("--workers", type=int, default=1, help="runs at a time (default 1)")
    p.add_argument("--export", action="store_true", help="copy models + manifests to agents/pretrained/v1/<agent>/")
    p.add_argument("--nice", type=int, default=5, help="niceness of the runs (default 5)")
    a = p.parse_args()
    s = Settings(tuple(a.agents), tuple(a.seeds), Path(a.runs), a.workers, a.export, a.nice)
    s.runs.mkdir(parents=True, exist_ok=True)
    jobs = [(agent, seed) for seed in s.seeds for agent in s.agents]
    with ThreadPoolExecutor(max_workers=s.workers) as pool:
        for line in pool.map(lambda j: run_one(s, *j), jobs):
            print(line, file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
