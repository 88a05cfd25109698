"""What a newcomer reads in the first hour (issue 17, section 3): each surprise they met, fixed and pinned.

evaluate's default folder is not compare's; ``train --timesteps`` says what it rounds to; ``--seeds`` counts the
starts in every command; compare and benchmark name the agents alike; reports explain every name they print, show
no machine's temporary paths and stay short; the unavailable runs are one line per agent.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from cli_here import Ran

ROOT = Path(__file__).resolve().parents[1]

TINY_PPO = """AmigoBot-v0:
  policy: MlpPolicy
  n_envs: 4
  n_steps: 32
  batch_size: 64
  n_epochs: 1
  policy_kwargs: {net_arch: [16, 16]}
"""


def cli(*args: str, cwd: Path = ROOT, timeout: float = 240) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.fixture
def here(in_process: Callable[..., Ran]) -> Callable[..., Ran]:
    """``amigo-gym ARGS`` in this process (tests/cli_here.py), from ``cwd`` as :func:`cli` runs it: for the commands
    whose output is the point, not the process. ``--help`` (its wrapping follows the terminal) and the torch-thread
    check (a process's state) stay with :func:`cli`."""
    return in_process


# --------------------------------------------------------------------------- evaluate does not overwrite compare
def test_evaluate_has_its_own_default_folder_and_refuses_a_compare_output_set(
    tmp_path: Path, here: Callable[..., Ran]
) -> None:
    results = tmp_path / "results"  # what `amigo-gym compare --out results` left
    results.mkdir()
    (results / "manifest.json").write_text("{}")
    (results / "results.json").write_text('{"from": "compare"}')
    args = ("evaluate", "--no-models", "--no-plots", "--steps", "20", "--seeds", "1")
    r = here(*args, "--out", str(results))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "--force" in r.stderr and "manifest.json" in r.stderr
    assert (results / "results.json").read_text() == '{"from": "compare"}'  # untouched
    r = here(*args, cwd=tmp_path)  # the default folder
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "results" / "evaluate" / "results.json").is_file()
    assert (results / "results.json").read_text() == '{"from": "compare"}'
    r = here(*args, "--out", str(results), "--force")
    assert r.returncode == 0, r.stderr
    assert "protocol" in json.loads((results / "results.json").read_text())


# --------------------------------------------------------------------------- train says what it rounds to
def test_planned_timesteps_is_the_next_whole_rollout() -> None:
    from types import SimpleNamespace as Model

    from amigo_gym.tools.training.train import planned_timesteps

    ppo = Model(num_timesteps=0, n_envs=16, n_steps=256)
    assert planned_timesteps(ppo, 1) == (4096, "n_steps 256 x 16 envs")
    assert planned_timesteps(ppo, 4096)[0] == 4096
    assert planned_timesteps(ppo, 4097)[0] == 8192
    steps = Model(unit=Model(value="step"), frequency=8)
    resumed = Model(num_timesteps=400, n_envs=1, train_freq=steps)  # a resume continues from its step
    assert planned_timesteps(resumed, 601) == (608, "train_freq 8 x 1 envs")
    assert planned_timesteps(Model(num_timesteps=0, n_envs=1, train_freq=None), 10)[0] == 10


def test_train_timesteps_1_says_it_trains_a_whole_rollout(tmp_path: Path, here: Callable[..., Ran]) -> None:
    hp = tmp_path / "ppo.yml"
    hp.write_text(TINY_PPO)
    out = tmp_path / "run"
    r = here("train", "--algo", "ppo", "--out", str(out), "--hyperparams", str(hp), "--timesteps", "1",
            "--eval-freq", "0", "--no-progress")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "--timesteps 1 becomes 128 steps" in r.stderr and "n_steps 32 x 4 envs" in r.stderr
    assert json.loads((out / "run.json").read_text())["timesteps"] == 128  # what the message announced
    assert "rounded up to whole rollouts" in cli("train", "--help").stdout


# --------------------------------------------------------------------------- --seeds: how many, everywhere
def test_seeds_counts_the_starts_in_convergence_as_in_evaluate_and_compare() -> None:
    quick = ("--gains", "3", "--steps", "45", "--t-from", "1", "--t-to", "4")
    r = cli("convergence", *quick, "--seeds", "3")
    assert r.returncode == 0, r.stderr
    assert ", 3 seeds" in r.stdout and r.stderr == ""
    for command in ("evaluate", "compare", "convergence"):
        help_text = " ".join(cli(command, "--help").stdout.split())
        assert re.search(r"--seeds SEEDS [^-]*(number|how many|perturbed starts)", help_text), (command, help_text)


# --------------------------------------------------------------------------- one naming of the agents
def test_benchmark_and_compare_name_the_pretrained_agents_alike() -> None:
    from amigo_gym.tools.training.benchmark import ALGOS, RETIRED_V1_AGENTS, V1_AGENTS, default_agents
    from amigo_gym.tools.training.evaluate import v0_name

    names = {a.name for a in default_agents()}
    assert {"analytic", "analytic_ff"} <= names
    from amigo_gym.tools.training.evaluate import CLASSICAL

    learned = names - set(CLASSICAL)
    # v0 specialists <algo>_v0, v1 generalists <folder>_v1 (one per shipped folder of agents/pretrained/v1)
    allowed = {f"{a}_v0" for a in ALGOS} | {f"{folder}_v1" for folder in V1_AGENTS}
    assert learned and learned <= allowed, learned - allowed
    assert {"ppo_v0", "td3lp_v1", "ppo_fast_v1", "residual_v1"} <= learned
    assert not learned & {f"{folder}_v1" for folder in RETIRED_V1_AGENTS}  # retired references: not shipped
    assert {v0_name(a) for a in ALGOS} == {f"{a}_v0" for a in ALGOS}  # compare's names of agents/pretrained/*.zip
    assert v0_name("ppo_s0") == "ppo_s0"  # a run of one's own keeps its name


# --------------------------------------------------------------------------- reports
def test_unavailable_runs_are_one_line_per_agent_and_reason() -> None:
    from amigo_gym.tools.training.benchmark import unavailable_lines

    reason = "observation shape (10,) of the scenario differs from the model's (20,)"
    rows = [
        {"agent": f"{algo}_v1", "seed": seed, "scenario": sc, "reason": reason}
        for algo in ("ppo", "sac", "td3")
        for seed in range(5)
        for sc in ("v0_paper_circle", "v0_speed_0.4")
    ]
    rows.append({"agent": None, "seed": None, "scenario": "x", "reason": "not registered"})
    lines = unavailable_lines(rows)
    assert len(rows) == 31 and len(lines) == 4
    assert lines[0] == f"ppo_v1 (5 training seeds) on v0_paper_circle, v0_speed_0.4: {reason}"
    assert lines[-1] == "all agents on x: not registered"


def test_printed_commands_show_no_temporary_paths(tmp_path: Path) -> None:
    from amigo_gym.tools.training.compare import display_command

    cmd = "amigo-gym train --algo ppo --out /tmp/retrain/runs/ppo --export /tmp/retrain/export --export-model best"
    shown = display_command(cmd, root=tmp_path)
    assert shown == "amigo-gym train --algo ppo --out runs/ppo --export retrain/export --export-model best"
    inside = display_command(f"amigo-gym train --out '{tmp_path / 'runs' / 'a b'}'", root=tmp_path)
    assert inside == "amigo-gym train --out 'runs/a b'"


@pytest.mark.slow
def test_compare_prints_a_short_report_that_explains_its_names_and_ends_with_the_files(
    tmp_path: Path, here: Callable[..., Ran]
) -> None:
    out = tmp_path / "results"
    r = here("compare", "--out", str(out), "--train-steps", "0", "--steps", "20", "--seeds", "1", "--no-plots",
            "--no-benchmark", "--no-progress")  # fmt: skip
    assert r.returncode == 0, r.stderr
    lines = r.stdout.strip().splitlines()
    assert len(lines) <= 30, r.stdout  # the full tables are in report.md
    assert lines[-1].startswith(f"Files in {out}/") and "report.md" in lines[-1]
    doc = json.loads((out / "results.json").read_text())
    names = {row["agent"] for row in doc["results"]}
    assert {"analytic", "analytic_ff", "ppo_v0", "sac_v0", "td3_v0"} <= names  # the benchmark's names
    for name in names:
        assert f"`{name}`: " in r.stdout, name  # every name printed is explained
    report = (out / "report.md").read_text()
    for text in (r.stdout, report):
        assert "analytic_gain" not in text and "/tmp/retrain" not in text  # the shipped records have it
    assert "feedback gain k = 3/s" in report
    for name in names:
        assert f"`{name}`: " in report, name


# --------------------------------------------------------------------------- benchmark --quick is quick
def test_the_benchmark_runs_the_policies_on_one_torch_thread(tmp_path: Path) -> None:
    """Torch's default threads spun against the environment and other processes: ``benchmark --quick`` took 52 s
    of CPU instead of 16 s (docs/benchmark.md). The evaluating commands now use one thread, recorded in the JSON."""
    out = tmp_path / "bench"
    model = ROOT / "agents" / "pretrained" / "ppo.zip"
    r = cli("benchmark", "--agents", "analytic", f"ppo_v0={model}", "--scenarios", "v0_paper_circle", "--reps", "20",
            "--profile-reps", "20", "--no-plots", "--no-progress", "--out", str(out))  # fmt: skip
    assert r.returncode == 0, r.stderr
    doc = json.loads((out / "benchmark.json").read_text())
    assert doc["torch_threads"] == 1
    assert {a["agent"] for a in doc["agents"]} == {"analytic", "ppo_v0"}
