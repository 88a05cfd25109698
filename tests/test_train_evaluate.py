"""``train`` then ``evaluate --models <what train wrote>``, with rl-zoo idioms in the hyperparameter file."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]

PPO_NORMALIZED = """AmigoBot-v0:
  n_envs: 2
  policy: MlpPolicy
  normalize: true
  n_steps: 64
  batch_size: 64
  n_epochs: 1
  gamma: 0.98
  learning_rate: lin_0.001
  clip_range: lin_0.2
  policy_kwargs: "dict(net_arch=[16, 16], activation_fn=nn.Tanh)"
"""

TD3_OU = """AmigoBot-v0:
  policy: MlpPolicy
  learning_starts: 50
  buffer_size: 1000
  batch_size: 16
  train_freq: 8
  gradient_steps: 1
  noise_type: ornstein-uhlenbeck
  noise_std: 0.2
  policy_kwargs: "dict(net_arch=[8, 8])"
"""


def cli(*args: str, timeout: float = 180) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two tiny runs side by side: PPO with normalize and schedules, TD3 with Ornstein-Uhlenbeck noise."""
    root = tmp_path_factory.mktemp("runs")
    for algo, text, steps in (("ppo", PPO_NORMALIZED, "256"), ("td3", TD3_OU, "200")):
        hp = root.parent / f"{algo}.yml"
        hp.write_text(text)
        r = cli("train", "--no-progress", "--algo", algo, "--out", str(root / f"{algo}_run"), "--hyperparams",
                str(hp), "--timesteps", steps, "--eval-freq", "0")  # fmt: skip
        assert r.returncode == 0, r.stderr
    return root


def _evaluate(tmp_path: Path, models: Path) -> dict[str, object]:
    out = tmp_path / "eval"
    r = cli("evaluate", "--models", str(models), "--out", str(out), "--steps", "20", "--seeds", "1", "--no-plots")
    assert r.returncode == 0, r.stderr
    doc: dict[str, object] = json.loads((out / "results.json").read_text())
    return doc


def test_run_folder_is_evaluated(runs: Path, tmp_path: Path) -> None:
    run = runs / "ppo_run"
    assert (run / "vecnormalize.pkl").is_file()  # normalize: the statistics beside the model
    doc = _evaluate(tmp_path, run)
    agents = {r["agent"] for r in doc["results"]}  # type: ignore[attr-defined]
    assert agents == {"analytic", "analytic_ff", "ppo_run"}
    assert doc["training"]["ppo_run"]["algo"] == "ppo"  # type: ignore[index]


def test_folder_of_runs_model_zip_and_pretrained_layout(runs: Path, tmp_path: Path) -> None:
    from amigo_gym.data import pretrained_dir
    from amigo_gym.tools.training.evaluate import find_models

    def found(p: Path) -> set[tuple[str, str, str]]:
        return {(r.name, r.algo, r.model.name) for r in find_models(p)}

    assert found(runs) == {("ppo_run", "ppo", "model.zip"), ("td3_run", "td3", "model.zip")}
    assert found(runs / "td3_run" / "model.zip") == {("td3_run", "td3", "model.zip")}
    assert found(pretrained_dir()) == {(a, a, f"{a}.zip") for a in ("ppo", "sac", "td3")}
    assert [r.vecnormalize is not None for r in find_models(runs)] == [True, False]


def test_normalized_model_sees_normalized_observations(runs: Path) -> None:
    """The loaded agent feeds the model ``clip((o - mean) / sqrt(var + eps))`` with the saved statistics."""
    import pickle

    from stable_baselines3 import PPO

    from amigo_gym.tools.training.evaluate import load_agents

    agent = load_agents(runs / "ppo_run")["ppo_run"]
    with open(runs / "ppo_run" / "vecnormalize.pkl", "rb") as f:
        stats = pickle.load(f)
    model = PPO.load(runs / "ppo_run" / "model.zip", device="cpu")
    obs = np.random.default_rng(0).uniform(-1, 1, (5, 10)).astype(np.float32)
    mean, var = stats.obs_rms.mean, stats.obs_rms.var
    assert np.any(mean != 0) and np.any(var != 1)  # statistics were collected
    by_hand = np.clip((obs - mean) / np.sqrt(var + stats.epsilon), -stats.clip_obs, stats.clip_obs)
    want, _ = model.predict(by_hand.astype(np.float32), deterministic=True)
    got, _ = agent.predict(obs, deterministic=True)
    np.testing.assert_array_equal(got, want)
    raw, _ = model.predict(obs, deterministic=True)
    assert not np.array_equal(got, raw)


def test_folder_without_models_is_refused(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    r = cli("evaluate", "--models", str(tmp_path / "empty"), "--no-plots", "--out", str(tmp_path / "o"))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "no models in" in r.stderr


def test_unknown_keys_refused_before_anything_is_written(tmp_path: Path) -> None:
    hp = tmp_path / "bad.yml"
    hp.write_text("AmigoBot-v0:\n  n_steps: 64\n  frame_stack: 4\n  env_wrapper: x\n")
    out = tmp_path / "run"
    r = cli("train", "--no-progress", "--algo", "ppo", "--out", str(out), "--hyperparams", str(hp))
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1
    assert "unknown key(s) for ppo: env_wrapper, frame_stack" in r.stderr
    assert not out.exists()
