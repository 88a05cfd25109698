"""``amigo-gym train`` with tiny budgets: outputs, resume, interruption, bad input.

The interrupted run (SIGTERM) and the bad-argument checks run the command by subprocess; the other runs call
``amigo_gym.tools.cli.main`` in this process (the same dispatcher, without paying torch's import per run)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from cli_here import Ran

ROOT = Path(__file__).resolve().parent.parent

TINY = {
    "sac": """AmigoBot-v0:
  policy: MlpPolicy
  learning_rate: 0.001
  buffer_size: 5000
  learning_starts: 100
  batch_size: 32
  train_freq: 8
  gradient_steps: 2
  policy_kwargs: {net_arch: [16, 16]}
""",
    "td3": """AmigoBot-v0:
  policy: MlpPolicy
  learning_rate: lin_0.001
  buffer_size: 5000
  learning_starts: 100
  batch_size: 32
  train_freq: 8
  gradient_steps: 2
  noise_type: normal
  noise_std: 0.1
  policy_kwargs: {net_arch: [16, 16], activation_fn: ReLU}
""",
    "ppo": """AmigoBot-v0:
  policy: MlpPolicy
  n_envs: 4
  n_steps: 32
  batch_size: 64
  n_epochs: 1
  policy_kwargs: {net_arch: [16, 16]}
""",
}


def run_train(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "train", "--no-progress", *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


@pytest.fixture
def train_here(in_process: Callable[..., Ran]) -> Callable[..., Ran]:
    """``amigo-gym train --no-progress ARGS`` in this process (tests/cli_here.py), from the checkout's root as
    :func:`run_train` runs it."""
    return lambda *args: in_process("train", "--no-progress", *args)


def hp_file(tmp_path: Path, algo: str) -> str:
    f = tmp_path / f"{algo}.yml"
    f.write_text(TINY[algo])
    return str(f)


def no_temp_files(d: Path) -> bool:
    return not [p for p in d.rglob(".*") if p.is_file() or p.is_dir()]


def test_sac_train_then_resume(tmp_path: Path, train_here: Callable[..., Ran]) -> None:
    from stable_baselines3 import SAC

    out = tmp_path / "run"
    hp = hp_file(tmp_path, "sac")
    common = ["--algo", "sac", "--seed", "3", "--out", str(out), "--hyperparams", hp, "--eval-freq", "200"]
    r = train_here(*common, "--timesteps", "400", "--eval-episodes", "1", "--checkpoint-freq", "200")
    assert r.returncode == 0, r.stderr
    rec = json.loads((out / "run.json").read_text())
    assert rec["timesteps"] == 400 and rec["seed"] == 3 and rec["resumed_from"] is None
    assert rec["cpu"] and rec["device"] == "cpu" and rec["torch_threads"] >= 1 and rec["numba_threads"] >= 1
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["settings"]["algo"] == "sac" and cfg["hyperparams"]["batch_size"] == 32
    assert len(cfg["git_revision"]) >= 40 and cfg["versions"]["torch"]
    assert cfg["command"].startswith("amigo-gym train --no-progress --algo sac")
    assert (out / "checkpoints" / "step_400" / "replay_buffer.pkl").is_file()
    assert any((out / "tb").rglob("events.out.tfevents.*"))
    model = SAC.load(out / "model.zip", device="cpu")
    action, _ = model.predict(np.zeros(10, dtype=np.float32), deterministic=True)
    assert action.shape == (2,)

    # resume to 600: the remaining 200 steps, the step counter and the evaluation history continue
    r = train_here(*common, "--timesteps", "600", "--eval-episodes", "1", "--resume", "--export", str(tmp_path / "exp"))
    assert r.returncode == 0, r.stderr
    rec = json.loads((out / "run.json").read_text())
    assert rec["timesteps"] == 600 and rec["resumed_from"] == 400
    assert rec["command"] == cfg["command"] and rec["resumes"][0]["from_step"] == 400
    assert "--resume" in rec["resumes"][0]["command"]
    assert [e["timesteps"] for e in json.loads((out / "eval.json").read_text())] == [200, 400, 600]
    assert SAC.load(out / "model.zip", device="cpu").num_timesteps == 600
    assert json.loads((tmp_path / "exp" / "sac.json").read_text())["timesteps"] == 600
    assert (tmp_path / "exp" / "sac.zip").read_bytes() == (out / "model.zip").read_bytes()
    assert no_temp_files(out)


def test_sigterm_leaves_checkpoint_and_resume_finishes(tmp_path: Path, train_here: Callable[..., Ran]) -> None:
    from stable_baselines3 import PPO

    out = tmp_path / "ppo"
    hp = hp_file(tmp_path, "ppo")
    common = ["--algo", "ppo", "--seed", "0", "--out", str(out), "--hyperparams", hp, "--eval-freq", "0"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "amigo_gym.tools.cli", "train", "--no-progress", *common, "--timesteps", "10000000"],
        cwd=ROOT,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 60
        while not any((out / "tb").rglob("events.out.tfevents.*")) and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(2.0)  # some rollouts (a rollout of 128 steps takes milliseconds; 2 s leaves room on a loaded CI)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "interrupted" in err
    ckpt = json.loads((out / "checkpoint.json").read_text())
    done = ckpt["num_timesteps"]
    assert done > 0 and done % 128 == 0  # whole rollouts of 4 envs x 32 steps
    assert PPO.load(out / ckpt["path"] / "model.zip", device="cpu").num_timesteps == done
    assert not (out / "model.zip").exists()  # the final model is written only at the end
    assert no_temp_files(out)

    r = train_here(*common, "--timesteps", str(done + 256), "--resume")  # not stopped: in this process
    assert r.returncode == 0, r.stderr
    rec = json.loads((out / "run.json").read_text())
    assert rec["timesteps"] == done + 256 and rec["resumed_from"] == done and rec["n_envs"] == 4


def test_td3_runs_with_noise_and_schedule(tmp_path: Path, train_here: Callable[..., Ran]) -> None:
    out = tmp_path / "td3"
    exp = tmp_path / "exp"
    r = train_here(
        "--algo", "td3", "--out", str(out), "--hyperparams", hp_file(tmp_path, "td3"), "--timesteps", "200",
        "--eval-freq", "100", "--eval-episodes", "1", "--export", str(exp), "--export-model", "best",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "run.json").read_text())["timesteps"] == 200
    rec = json.loads((exp / "td3.json").read_text())
    evals = json.loads((out / "eval.json").read_text())
    assert rec["exported_model"] == "best" and rec["exported_timesteps"] in (100, 200) and len(evals) == 2
    assert rec["best_eval"] == max(evals, key=lambda e: e["mean_reward"])
    assert (exp / "td3.zip").read_bytes() == (out / "best_model.zip").read_bytes()
    from stable_baselines3 import TD3
    from stable_baselines3.common.noise import NormalActionNoise

    model = TD3.load(out / "model.zip", device="cpu")  # the file's noise and schedule reached the model
    assert model.lr_schedule(1.0) == pytest.approx(1e-3) and model.lr_schedule(0.5) == pytest.approx(5e-4)
    noise = model.action_noise
    assert isinstance(noise, NormalActionNoise) and np.allclose(noise._sigma, 0.1), noise


def test_the_same_command_twice_gives_the_same_weights(tmp_path: Path, train_here: Callable[..., Ran]) -> None:
    """Issue 36, item 5: the training command re-run on the same machine gives the same weights (SB3's TD3, the
    shipped low-pass agent's algorithm, past its first gradient steps); another seed does not."""
    import torch
    from stable_baselines3 import TD3

    hp = hp_file(tmp_path, "td3")
    weights = []
    for name, seed in (("a", "5"), ("b", "5"), ("c", "6")):
        r = train_here("--algo", "td3", "--seed", seed, "--out", str(tmp_path / name), "--hyperparams", hp,
                       "--timesteps", "300", "--eval-freq", "1000", "--eval-episodes", "1")  # fmt: skip
        assert r.returncode == 0, r.stderr
        weights.append(TD3.load(tmp_path / name / "model.zip", device="cpu").policy.state_dict())
    assert weights[0].keys() == weights[1].keys()
    assert all(torch.equal(weights[0][k], weights[1][k]) for k in weights[0])
    assert not all(torch.equal(weights[0][k], weights[2][k]) for k in weights[0])


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--algo", "a2c", "--out", "x"], "invalid choice"),
        (["--algo", "sac", "--out", "x", "--timesteps", "0"], "timesteps must be an integer >= 1"),
        (["--algo", "sac", "--out", "x", "--seed", "-1"], "seed must be an integer >= 0"),
    ],
)
def test_bad_arguments(args: list[str], message: str) -> None:
    r = run_train(*args)
    assert r.returncode == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_refuses_non_empty_out_and_missing_checkpoint(tmp_path: Path, train_here: Callable[..., Ran]) -> None:
    (tmp_path / "junk").write_text("x")
    r = train_here("--algo", "sac", "--out", str(tmp_path), "--timesteps", "10")
    assert r.returncode == 2 and "not empty" in r.stderr
    r = train_here("--algo", "sac", "--out", str(tmp_path / "none"), "--timesteps", "10", "--resume")
    assert r.returncode == 2 and "no checkpoint" in r.stderr


def test_a_refused_env_kwargs_writes_nothing_and_the_corrected_rerun_runs(
    tmp_path: Path, train_here: Callable[..., Ran]
) -> None:
    out = tmp_path / "run"
    args = ["--algo", "ppo", "--out", str(out), "--hyperparams", hp_file(tmp_path, "ppo"), "--eval-freq", "0"]
    r = train_here(*args, "--timesteps", "128", "--env-kwargs", '{"speed": -1}')
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "speed" in r.stderr, r.stderr
    assert not out.exists()
    r = train_here(*args, "--timesteps", "128", "--env-kwargs", '{"speed": 0.2}')
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "run.json").read_text())["timesteps"] == 128
