"""``amigo_gym/tools/training/evaluate.py``: protocol, metrics against independent computations, outputs."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym.policies.analytic import AnalyticPolicy
from amigo_gym.task.v1 import TrackingParams
from amigo_gym.tools.training.evaluate import (
    EvalProtocol,
    default_agents,
    evaluate_agents,
    find_models,
    markdown_table,
    steady_start_pose,
)

ROOT = Path(__file__).resolve().parent.parent
Eval = tuple[list[dict[str, Any]], dict[str, dict[str, list[Any]]]]


def test_steady_start_pose_is_the_closed_form_steady_state() -> None:
    p = TrackingParams.v0()
    pose = steady_start_pose(p)
    l3, radius = p.robot.l3, p.radius
    h = pose[:2] + l3 * np.array([math.cos(pose[2]), math.sin(pose[2])])
    np.testing.assert_allclose(h, [0.0, 0.0], atol=1e-15)  # H at the paper's start point
    # A on the concentric circle of radius R_A = sqrt(R^2 - l3^2) about the centre (0, R)
    assert math.isclose(math.hypot(pose[0], pose[1] - radius), math.sqrt(radius**2 - l3**2), rel_tol=1e-12)
    assert math.isclose(pose[2], -math.atan(l3 / math.sqrt(radius**2 - l3**2)), rel_tol=1e-12)


@pytest.fixture(scope="module")
def analytic_eval() -> Eval:
    proto = EvalProtocol(steps=320, perturbed_seeds=(100, 101))
    results, trajs = evaluate_agents(default_agents(TrackingParams.v0()), proto)
    return results, trajs


def row(results: list[dict[str, Any]], agent: str, scenario: str) -> dict[str, Any]:
    (r,) = [r for r in results if r["agent"] == agent and r["scenario"] == scenario]
    return r


def test_analytic_nominal_is_exact(analytic_eval: Eval) -> None:
    results, _ = analytic_eval
    p = TrackingParams.v0()
    for agent in ("analytic", "analytic_ff"):
        r = row(results, agent, "nominal")
        assert float(r["h_max_m"]) <= 1e-6
        assert float(r["wheel_rate_dev_steady_rms"]) <= 1e-5
        assert r["terminated"] == 0 and r["settling_time_s"] == 0.0
        # H travels at v R / R_A: laps = T v / (2 pi R_A)
        laps = 320 * p.dt * p.speed / (2 * math.pi * math.sqrt(p.radius**2 - p.robot.l3**2))
        assert math.isclose(float(r["laps"]), laps, rel_tol=1e-6)
    # the analytic agent is its own reference (to the float32 rounding of its action)
    assert row(results, "analytic", "perturbed")["wheel_rate_dev_rms"] < 1e-6


def test_metrics_match_an_independent_rollout(analytic_eval: Eval) -> None:
    """Recompute the perturbed metrics of analytic_ff with a plain env loop."""
    results, _ = analytic_eval
    env = gym.make("AmigoBot-v0", max_episode_steps=320)
    p = TrackingParams.v0()
    ff, ref = AnalyticPolicy(p, feedforward_only=True), AnalyticPolicy(p, gain=3.0)
    es, devs, rets = [], [], []
    for seed in (100, 101):
        obs, _ = env.reset(seed=seed)
        ret = 0.0
        for _ in range(320):
            a, _ = ff.predict(obs)
            w_ref = ref.wheel_rates(obs)
            obs, rew, term, trunc, info = env.step(a)
            ret += float(rew)
            es.append(info["cross_track_error"])
            devs.append(info["wheel_rates"] - w_ref)
            if term or trunc:
                break
        rets.append(ret)
    r = row(results, "analytic_ff", "perturbed")
    assert math.isclose(float(r["h_rms_m"]), math.sqrt(np.mean(np.square(es))), rel_tol=1e-12)
    assert math.isclose(float(r["h_max_m"]), np.abs(es).max(), rel_tol=1e-12)
    dev = float(np.sqrt(np.mean(np.square(devs))))
    assert math.isclose(float(r["wheel_rate_dev_rms"]), dev, rel_tol=1e-9)
    assert math.isclose(float(r["mean_return"]), float(np.mean(rets)), rel_tol=1e-12)
    # without feedback the start offset stays: never within 1 mm for these seeds' offsets
    assert float(r["h_rms_settled_m"]) > 1e-3
    assert r["settling_time_s"] is None


def test_feedback_beats_feedforward(analytic_eval: Eval) -> None:
    results, _ = analytic_eval
    fb, ff = row(results, "analytic", "perturbed"), row(results, "analytic_ff", "perturbed")
    assert float(fb["h_rms_settled_m"]) < 1e-6 < float(ff["h_rms_settled_m"])
    assert float(fb["settling_time_s"]) < 2.0


def test_markdown_table_has_a_row_per_result(analytic_eval: Eval) -> None:
    results, _ = analytic_eval
    lines = markdown_table(results).strip().splitlines()
    assert len(lines) == 2 + len(results) == 2 + 2 * 3
    assert all(line.count("|") == lines[0].count("|") for line in lines)


def test_protocol_refuses_bad_values() -> None:
    with pytest.raises(ValueError, match=r"EvalProtocol\.steps"):
        EvalProtocol(steps=0)
    with pytest.raises(ValueError, match=r"EvalProtocol\.settle_time_s"):
        EvalProtocol(settle_time_s=math.nan)
    with pytest.raises(ValueError, match=r"EvalProtocol\.scenarios"):
        EvalProtocol(scenarios=("bogus",))


def test_cli_writes_json_table_and_plots(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "amigo_gym.tools.cli", "evaluate", "--no-models", "--steps", "60", "--seeds", "2"]
    r = subprocess.run([*cmd, "--out", str(tmp_path)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "results.json").read_text())
    assert doc["protocol"]["steps"] == 60 and doc["protocol"]["scenarios"]["perturbed"]["seeds"] == [100, 101]
    keys = {"agent", "scenario", "h_rms_m", "h_max_m", "wheel_rate_dev_rms", "mean_return", "h_rms_settled_m"}
    assert {(d["agent"], d["scenario"]) for d in doc["results"]} == {
        (a, s) for a in ("analytic", "analytic_ff") for s in ("nominal", "paper_start", "perturbed")
    }
    assert all(keys <= set(d) for d in doc["results"])
    assert (tmp_path / "eval.md").read_text().count("\n") == 8
    for name in ("eval_trajectories.png", "eval_wheels.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".*"))
    r = subprocess.run([*cmd[:4], "--steps", "0"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "steps" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = subprocess.run(
        [*cmd[:4], "--models", str(tmp_path / "nope")], cwd=ROOT, env=env, capture_output=True, text=True
    )
    assert r.returncode == 2 and "no file or directory" in r.stderr


def test_evaluate_names_the_pretrained_agents_as_compare_and_benchmark_do(tmp_path: Path, in_process: Any) -> None:
    r = in_process("evaluate", "--steps", "20", "--seeds", "1", "--no-plots", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "results.json").read_text())
    assert {d["agent"] for d in doc["results"]} == {"analytic", "analytic_ff", "ppo_v0", "sac_v0", "td3_v0"}
    assert set(doc["training"]) == {"ppo_v0", "sac_v0", "td3_v0"}


def test_compare_main_job_smoke(tmp_path: Path) -> None:
    """``amigo-gym compare`` with a tiny fresh PPO run and short episodes: report, JSON, plots."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "amigo_gym.tools.cli", "compare", "--out", str(tmp_path), "--models", ""]
    cmd += ["--train-steps", "1000", "--seeds", "1", "--steps", "40"]
    r = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=240)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "results.json").read_text())
    agents = {d["agent"] for d in doc["results"]}
    assert agents == {"analytic", "analytic_ff", "ppo_fresh"}
    assert doc["best_learned"]["agent"] == "ppo_fresh" and doc["best_learned"]["scenario"] == "perturbed"
    assert doc["training"]["ppo_fresh"]["timesteps"] >= 1000
    report = (tmp_path / "report.md").read_text()
    assert "## Targets" in report and "ppo_fresh" in report and "eval_wheels.png" in report
    assert (tmp_path / "eval_trajectories.png").is_file() and (tmp_path / "train_ppo" / "model.zip").is_file()
    r = subprocess.run([*cmd[:4], "--seeds", "0"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "--seeds" in r.stderr


def _schedule_that_must_not_run(progress: float) -> float:
    raise RuntimeError("the model's pickled learning rate ran")


def test_a_model_is_loaded_for_acting_without_running_its_pickled_learning_rate(tmp_path: Path) -> None:
    """The shipped ppo.zip holds its learning-rate schedule as code pickled by Python 3.11, which crashed 3.13 (a
    segmentation fault in `compare`) when SB3 called it on loading; the loaders give it a learning rate of 0."""
    import base64
    import zipfile

    import cloudpickle

    from amigo_gym.data import pretrained_dir

    src = pretrained_dir() / "ppo.zip"
    with zipfile.ZipFile(src) as z:
        members = {name: z.read(name) for name in z.namelist()}
    data = json.loads(members["data"])
    assert ":serialized:" in data["learning_rate"]  # code, not a number
    pickled = base64.b64encode(cloudpickle.dumps(_schedule_that_must_not_run)).decode()
    data["learning_rate"] = {":type:": "<class 'function'>", ":serialized:": pickled}
    crafted = tmp_path / "ppo.zip"
    with zipfile.ZipFile(crafted, "w") as z:
        for name, blob in members.items():
            z.writestr(name, json.dumps(data) if name == "data" else blob)
    from amigo_gym.io import sha256_file
    from amigo_gym.policies import load_pretrained

    model = find_models(crafted)[0].load(trust=True)
    crafted.with_suffix(".json").write_text(json.dumps({"algo": "ppo", "sha256": sha256_file(crafted)}))
    for m in (model, load_pretrained(crafted, trust=True)):  # the evaluation's loader and the package's
        assert m.learning_rate == 0.0
        action, _ = m.predict(np.zeros(m.observation_space.shape, dtype=np.float32))
        assert action.shape == (2,)
    # a learning rate stored as a number is the file's for load_pretrained (a user may train on)
    assert load_pretrained(pretrained_dir() / "v1" / "td3lp" / "td3lp_s0.zip").learning_rate == 0.001
