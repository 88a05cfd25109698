"""Train the SB3 AmigoBot-v1 generalists (PPO, SAC, TD3, the low-pass TD3 x 5 seeds) and export them with manifests.

One readable file, cleanrl style: a settings dataclass, explicit seeds, and the library's training
function (``amigo_gym.tools.training.train``) run as ``amigo-gym train`` subprocesses, ``--workers`` at a time.
Each run trains on the training distribution of ``amigo_gym.tools.training.benchmark.TRAINING_DISTRIBUTION``
with the ``AmigoBot-v1`` hyperparameters of ``agents/hyperparams/<algo>.yml``, checkpoints as it goes
(a killed script is simply started again: finished runs are skipped, unfinished ones resumed) and is
exported to ``agents/pretrained/v1/<algo>/<algo>_s<seed>.zip`` with a manifest ``<algo>_s<seed>.json``
(training command, seed, steps, wall time, package versions, sha256 of the zip).

    python experiments/train_v1_generalists.py --runs runs_v1 --workers 2
    python experiments/train_v1_generalists.py --algos sac --seeds 0 1 --workers 1   # a subset
    python experiments/train_v1_generalists.py --algos td3lp --runs runs/td3lp --workers 2   # the low-pass TD3

Agents (:data:`AGENTS`): ``ppo``, ``sac``, ``td3`` (the SB3 generalists, ``agents/hyperparams/<algo>.yml``, the
v0 settings on small budgets: untuned references, **not shipped**: retired from ``agents/pretrained/v1`` because
the kept agents supersede them and they miss the smoothness targets, docs/experiments.md "Retired references"; the
commands above still train them, and their export lands in ``agents/pretrained/v1/<algo>/`` (or ``--export``),
which ``amigo-gym benchmark`` does not pick up by default: name them,
``--agents 'ppo_v1=agents/pretrained/v1/ppo/*.zip'``;
the retired zips themselves are in git history: ``git checkout 8f0a874 -- agents/pretrained/v1/ppo
agents/pretrained/v1/sac agents/pretrained/v1/td3``); ``td3lp``: shipped, the off-policy choice of issue 18, SB3's
TD3 in the high-throughput configuration with the low-pass actor (``agents/hyperparams/td3_lowpass.yml``, 500k
env-steps, evaluated every 100k; docs/experiments.md, "TD3 with a low-pass actor: the full record").

The claimed benchmark numbers are added to the manifests by ``amigo-gym benchmark --claim`` afterwards.
"""

from __future__ import annotations

import argparse
import json
import shlex
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from amigo_gym.data import pretrained_dir
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

#: agent -> (SB3 algorithm, hyperparameter file or None for ``agents/hyperparams/<algo>.yml``, extra options);
#: ``ppo``, ``sac``, ``td3``: the retired untuned references (not shipped; module docstring), ``td3lp``: shipped
AGENTS: dict[str, tuple[str, str | None, list[str]]] = {
    "ppo": ("ppo", None, []),
    "sac": ("sac", None, []),
    "td3": ("td3", None, []),
    "td3lp": (
        "td3",
        "agents/hyperparams/td3_lowpass.yml",
        ["--eval-freq", "100000", "--eval-episodes", "16", "--checkpoint-freq", "250000"],
    ),
}


@dataclass(frozen=True)
class Settings:
    """What to train and where."""

    algos: tuple[str, ...] = ("ppo", "sac", "td3")
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)
    runs: Path = Path("runs_v1")
    export: Path = field(default_factory=lambda: pretrained_dir() / "v1")
    workers: int = 2
    env_kwargs: dict[str, object] = field(default_factory=lambda: dict(TRAINING_DISTRIBUTION["env_kwargs"]))


def command(s: Settings, algo: str, seed: int) -> list[str]:
    """The ``amigo-gym train`` command of one run of agent ``algo`` (:data:`AGENTS`; resumed if its folder exists)."""
    out = s.runs / f"{algo}_s{seed}"
    sb3_algo, hyperparams, extra = AGENTS[algo]
    cmd = ["amigo-gym", "train", "--algo", sb3_algo, "--seed", str(seed), "--env", "AmigoBot-v1"]
    cmd += ["--env-kwargs", json.dumps(s.env_kwargs)]
    cmd += ["--hyperparams", hyperparams] if hyperparams else []
    cmd += ["--out", str(out), *extra, "--no-progress"]
    if (out / "config.json").is_file():
        cmd.append("--resume")
    return cmd


def export(s: Settings, algo: str, seed: int, cmd: list[str], wall_s: float) -> Path:
    """Copy the run's final model to the pretrained folder with its manifest (the run record plus the command)."""
    out = s.runs / f"{algo}_s{seed}"
    record = json.loads((out / "run.json").read_text())
    dest = s.export / algo
    dest.mkdir(parents=True, exist_ok=True)
    zip_path = dest / f"{algo}_s{seed}.zip"
    shutil.copyfile(out / "model.zip", zip_path)
    manifest = record | {
        "agent": algo,  # the folder's name (the SB3 algorithm is the record's "algo")
        "env_id": "AmigoBot-v1",
        "env_kwargs": s.env_kwargs,
        # as typed from the repository root (the run folder named relative to --runs)
        "training_command": " ".join(shlex.quote(c) for c in cmd if c != "--resume").replace(str(s.runs), s.runs.name),
        "training_distribution": TRAINING_DISTRIBUTION,
        "wall_time_this_call_s": round(wall_s, 1),
    }
    (dest / f"{algo}_s{seed}.json").write_text(json.dumps(manifest, indent=2) + "\n")
    return zip_path


def run_one(s: Settings, algo: str, seed: int) -> str:
    out = s.runs / f"{algo}_s{seed}"
    if (out / "run.json").is_file() and (s.export / algo / f"{algo}_s{seed}.zip").is_file():
        return f"{algo} seed {seed}: done before, skipped"
    cmd = command(s, algo, seed)
    t0 = time.perf_counter()
    if (out / "run.json").is_file():  # trained (perhaps by an earlier call), not yet exported
        cmd = [c for c in cmd if c != "--resume"]
        return f"{algo} seed {seed}: trained before -> {export(s, algo, seed, cmd, 0.0)}"
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return f"{algo} seed {seed}: FAILED ({r.returncode}): {r.stderr.strip().splitlines()[-1:]}"
    path = export(s, algo, seed, cmd, time.perf_counter() - t0)
    return f"{algo} seed {seed}: {time.perf_counter() - t0:.0f} s -> {path}"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--algos", nargs="+", default=list(Settings.algos), choices=list(AGENTS), help="agents (default ppo sac td3)"
    )
    p.add_argument("--seeds", nargs="+", type=int, default=list(Settings.seeds), help="seeds (default 0-4)")
    p.add_argument("--runs", default="runs_v1", help="folder of the run folders (default runs_v1)")
    p.add_argument("--workers", type=int, default=2, help="runs at a time (default 2)")
    p.add_argument(
        "--export",
        type=Path,
        default=Settings().export,
        help="folder of the exported <agent>/ (default agents/pretrained/v1)",
    )
    a = p.parse_args()
    s = Settings(tuple(a.algos), tuple(a.seeds), Path(a.runs), a.export, workers=a.workers)
    jobs = [(algo, seed) for seed in s.seeds for algo in s.algos]
    with ThreadPoolExecutor(max_workers=s.workers) as pool:
        for line in pool.map(lambda j: run_one(s, *j), jobs):
            print(line, file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
