"""``amigo-gym compare`` reuses its fresh PPO run only when the recorded configuration equals the request."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
from cli_here import Ran

TINY_PPO = """AmigoBot-v0:
  n_envs: 2
  policy: MlpPolicy
  n_steps: 32
  batch_size: 64
  n_epochs: 1
  policy_kwargs: {net_arch: [8, 8]}
"""


@pytest.fixture
def cli(in_process: Any) -> Any:
    """``amigo-gym ARGS`` in this process (tests/cli_here.py): the test is about what compare does."""
    return in_process


def compare(cli: Any, out: Path, hp: Path, *args: str, bench: bool = False) -> Ran:
    cmd = ["compare", "--out", str(out), "--models", "", "--no-plots"]
    cmd += ["--seeds", "1", "--steps", "10", "--no-progress", "--hyperparams", str(hp), *args]
    cmd += [] if bench else ["--no-benchmark"]
    r = cli(*cmd)
    assert r.returncode == 0, r.stderr
    return r


def test_reuse_only_the_same_configuration(tmp_path: Path, cli: Any) -> None:
    hp = tmp_path / "ppo.yml"
    hp.write_text(TINY_PPO)
    out = tmp_path / "out"
    model = out / "train_ppo" / "model.zip"

    r = compare(cli, out, hp, "--train-steps", "128", "--seed", "0", bench=True)
    assert "training a fresh PPO agent" in r.stderr
    first = model.stat().st_mtime_ns
    # the quick benchmark ran on the fresh agent too (a v0 model: unavailable on the v1 scenario, said so)
    bench = json.loads((out / "results.json").read_text())["benchmark"]
    assert bench["quick"] and {r["agent"] for r in bench["results"]} == {"analytic", "analytic_ff", "ppo_fresh"}
    assert {u["scenario"] for u in bench["unavailable"] if u["agent"] == "ppo_fresh"} == {"circle_r1_ccw"}
    fresh = next(a for a in bench["agents"] if a["agent"] == "ppo_fresh")
    assert fresh["sha256"] == json.loads((out / "train_ppo" / "run.json").read_text())["sha256"]

    r = compare(cli, out, hp, "--train-steps", "128", "--seed", "0")
    assert "reusing the PPO run" in r.stderr and "retraining" not in r.stderr
    cfg = json.loads((out / "train_ppo" / "config.json").read_text())
    assert (cfg["settings"]["seed"], cfg["settings"]["timesteps"]) == (0, 128)
    assert "resumes" not in cfg or all(r["from_step"] >= 128 for r in cfg["resumes"])

    r = compare(cli, out, hp, "--train-steps", "192", "--seed", "0")
    assert "retraining" in r.stderr and "timesteps 128 != 192" in r.stderr
    cfg = json.loads((out / "train_ppo" / "config.json").read_text())
    assert cfg["settings"]["timesteps"] == 192 and "resumes" not in cfg
    assert model.stat().st_mtime_ns != first

    r = compare(cli, out, hp, "--train-steps", "192", "--seed", "1")
    assert "retraining" in r.stderr and "seed 0 != 1" in r.stderr
    doc = json.loads((out / "results.json").read_text())
    assert doc["training"]["ppo_fresh"]["seed"] == 1
    assert json.loads((out / "train_ppo" / "config.json").read_text())["settings"]["seed"] == 1


@pytest.mark.parametrize("key", ["versions", "env_kwargs", "hyperparams"])
def test_any_recorded_difference_is_a_mismatch(tmp_path: Path, key: str) -> None:
    from amigo_gym.tools.training.compare import fresh_run_request, reuse_mismatch

    request = fresh_run_request(100, 0)
    run = tmp_path / "train_ppo"
    run.mkdir()
    (run / "checkpoint.json").write_text("{}")
    cfg = {
        "settings": {"algo": "ppo", "timesteps": 100, "seed": 0},
        "env_kwargs": request["env_kwargs"],
        "hyperparams": request["hyperparams"],
        "versions": request["versions"],
    }
    (run / "config.json").write_text(json.dumps(cfg))
    assert reuse_mismatch(run, request) is None
    changed = {**cfg, key: {**cfg[key], "extra": 1}}
    (run / "config.json").write_text(json.dumps(changed))
    assert reuse_mismatch(run, request) == f"{key} differ"


def test_quick_benchmark_table_in_the_published_set(tmp_path: Path, cli: Any) -> None:
    """Without ``--no-benchmark`` the report and results.json carry the quick benchmark; the set verifies."""
    from amigo_gym.tools.training.benchmark import QUICK_SCENARIOS
    from amigo_gym.tools.training.compare import verify_outputs

    out = tmp_path / "out"
    cmd = ["compare", "--out", str(out), "--models", "", "--train-steps", "0"]
    cmd += ["--seeds", "1", "--steps", "20", "--no-progress"]
    r = cli(*cmd)
    assert r.returncode == 0, r.stderr
    report = (out / "report.md").read_text()
    assert "## AmigoBot benchmark, suite 1.0 (quick subset)" in report
    assert "| analytic | 1 | 3 | 0 of 6 |" in report and "### H cross-track RMS per scenario" in report
    doc = json.loads((out / "results.json").read_text())
    assert [s["name"] for s in doc["benchmark"]["scenarios"]] == list(QUICK_SCENARIOS)
    assert doc["benchmark"]["aggregates"]["analytic"]["n_runs"] == 1
    files = verify_outputs(out)
    assert {"benchmark_scenarios.png", "benchmark_profiles.png", "report.md", "results.json"} <= set(files)


def test_compare_runs_the_fast_ppo_generalist_beside_sb3s_and_labels_them(tmp_path: Path, cli: Any) -> None:
    """``--models`` in the pretrained layout with a v1 SB3 seed (the low-pass TD3, an SB3 TD3 zip) and a fast-PPO seed:
    the quick benchmark runs both (``td3lp_v1``, ``ppo_fast_v1``) on its v1 scenarios, and the report and the summary
    tell "SB3 TD3 low-pass" from "fast PPO"."""
    import shutil

    from amigo_gym.data import pretrained_dir

    src, models = pretrained_dir(), tmp_path / "models"
    for rel in ("ppo.zip", "ppo.json", "v1/td3lp/td3lp_s0.zip", "v1/td3lp/td3lp_s0.json"):
        (models / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(src / rel, models / rel)
    for rel in ("v1/ppo_fast/ppo_fast_s0.zip", "v1/ppo_fast/ppo_fast_s0.json"):
        (models / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(src / rel, models / rel)
    out = tmp_path / "out"
    cmd = ["compare", "--out", str(out), "--models", str(models)]
    cmd += ["--train-steps", "0", "--seeds", "1", "--steps", "20", "--no-progress", "--no-plots"]
    r = cli(*cmd)
    assert r.returncode == 0, r.stderr
    doc = json.loads((out / "results.json").read_text())
    bench = doc["benchmark"]
    v1 = [s["name"] for s in bench["scenarios"] if s["env_id"] == "AmigoBot-v1"]
    assert v1
    runs = {(x["agent"], x["scenario"]) for x in bench["results"]}
    for agent in ("td3lp_v1", "ppo_fast_v1"):
        assert {(agent, sc) for sc in v1} <= runs, agent  # every v1 scenario ran, none unavailable
        assert bench["aggregates"][agent]["n_runs"] == 1
    kinds = {a["agent"]: (a["kind"], a.get("algo")) for a in bench["agents"]}
    assert kinds["ppo_fast_v1"] == ("fastppo", "fastppo") and kinds["td3lp_v1"] == ("sb3", "td3")
    report = (out / "report.md").read_text()
    assert "`ppo_fast_v1`: pretrained fast PPO AmigoBot-v1 generalists" in report
    assert "`td3lp_v1`: pretrained SB3 TD3 low-pass AmigoBot-v1 generalists" in report
    assert "`td3lp_v1`: SB3 TD3 low-pass generalist" in report
    assert "`ppo_fast_v1`: fast PPO generalist" in report  # the benchmark table's own legend
    assert "ppo_fast_v1 " in r.stdout and "fast PPO" in r.stdout
    assert re.search(r"ppo_fast_v1 [\d.]+ \(\d+ of \d+ failed\)", r.stdout), r.stdout  # failures beside the error
