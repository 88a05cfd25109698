"""Run folders survive every fault: kills at each stage of a save, two processes, corrupt files (issue 11).

Kills are real: a training process is started with ``AMIGO_GYM_FAULT=<stage>[@n]`` and SIGKILLs itself
there (:func:`amigo_gym.io.fault_point`). After every fault the folder must hold a complete checkpoint
(or none yet), and the resumed run must reach the same final step count with no lost or half-written
file and no duplicate evaluation. The runs that are not killed (the final resumes, the refused second
process) call ``amigo_gym.tools.cli.main`` in the test's process: another process than the killed or running one,
without paying torch's import again.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path
from typing import Any

import pytest

from amigo_gym.io import STATE_ENV, TRUST_ENV, UntrustedFileError
from amigo_gym.tools import runs
from amigo_gym.tools.training.compare import verify_outputs

ROOT = Path(__file__).resolve().parent.parent  # the checkout under test (also in CI's editable install)

SAC = """AmigoBot-v0:
  policy: MlpPolicy
  learning_rate: 0.001
  buffer_size: 5000
  learning_starts: 50
  batch_size: 32
  train_freq: 8
  gradient_steps: 1
  policy_kwargs: {net_arch: [8]}
"""
PPO = """AmigoBot-v0:
  policy: MlpPolicy
  n_envs: 4
  n_steps: 16
  batch_size: 64
  n_epochs: 1
  policy_kwargs: {net_arch: [8]}
"""


def env_for(fault: str | None) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("AMIGO_GYM_FAULT", None)
    if fault:
        env["AMIGO_GYM_FAULT"] = fault
    return env


def train_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "amigo_gym.tools.cli", "train", "--no-progress", *args]


def run(args: list[str], fault: str | None = None, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        train_cmd(*args), cwd=ROOT, env=env_for(fault), capture_output=True, text=True, timeout=timeout
    )


@pytest.fixture
def here(in_process: Any) -> Any:
    """``amigo-gym ARGS`` in this process (tests/cli_here.py), as :func:`run` and :func:`compare` start it but
    without a fault."""
    return in_process


def hp(tmp_path: Path, text: str, name: str) -> str:
    f = tmp_path / name
    f.write_text(text)
    return str(f)


def dot_files(d: Path) -> list[Path]:
    return [p for p in d.rglob(".*")]


def check_consistent(out: Path, algo: str) -> int | None:
    """What must hold after any fault: the pointer names a complete checkpoint; the record is valid JSON."""
    ptr_file = out / "checkpoint.json"
    step = None
    if ptr_file.is_file():
        ptr = json.loads(ptr_file.read_text())
        ck = runs.verify_checkpoint(out / ptr["path"], algo)  # complete, every sha256 matches
        assert ck.step == ptr["num_timesteps"]
        if ptr["previous"]:
            runs.verify_checkpoint(out / ptr["previous"], algo)
        step = ck.step
    # every checkpoint folder is complete (only a complete folder is renamed into place); folders the
    # pointer does not name yet are deleted by the next successful save
    for folder in (out / "checkpoints").glob("step_*") if (out / "checkpoints").is_dir() else []:
        runs.verify_checkpoint(folder, algo)
    if (out / "eval.json").is_file():
        steps = [e["timesteps"] for e in json.loads((out / "eval.json").read_text())]
        assert steps == sorted(set(steps)), steps
    return step


def check_finished(out: Path, algo: str, total: int, evals: list[int]) -> None:
    rec = json.loads((out / "run.json").read_text())
    assert rec["timesteps"] == total
    assert rec["sha256"] == runs.sha256_file(out / "model.zip")
    assert [e["timesteps"] for e in json.loads((out / "eval.json").read_text())] == evals
    assert check_consistent(out, algo) == total
    assert len(list((out / "checkpoints").iterdir())) == 2
    assert not dot_files(out), dot_files(out)


# --------------------------------------------------------------------------- kills at every stage
# Each process resumes from the previous one's fault and is killed at the next stage. The stages of
# runs.save_checkpoint after the model files (files, meta, rename, pointer, trash) are each killed in
# test_every_stage_of_a_checkpoint_save (fast, no SB3); here the SB3 writes and the other run files.
SAC_CHAIN: list[tuple[bool, str | None]] = [
    (False, "write:config.json"),  # killed before anything else: the folder holds only the lock and a temporary
    (False, "rename:best_model.zip"),  # a fresh start is allowed there; killed at the first evaluation (step 100)
    (True, "checkpoint:model"),  # killed inside a checkpoint save: model written, buffer not
    (True, "checkpoint:replay"),  # buffer written, meta.json not
    (True, "rename:checkpoint.json"),  # pointer switched, oldest not deleted, folder not fsynced
    (True, "write:model.zip"),  # the final model (the run's record is then rewritten too)
    (True, None),
]


def test_sac_survives_a_kill_at_every_stage(tmp_path: Path, here: Any) -> None:
    out = tmp_path / "sac"
    common = ["--algo", "sac", "--seed", "1", "--out", str(out), "--hyperparams", hp(tmp_path, SAC, "sac.yml")]
    common += ["--timesteps", "600", "--checkpoint-freq", "50", "--eval-freq", "100", "--eval-episodes", "1"]
    resumes = 0
    for resume, fault in SAC_CHAIN:
        args = [*common, *(["--resume"] if resume else [])]
        resumes += resume
        if fault is None:  # the last resume, not killed: in this process
            r = here("train", "--no-progress", *args)
            assert r.returncode == 0, r.stderr
        else:
            r = run(args, fault)
            assert r.returncode == -signal.SIGKILL, (fault, r.returncode, r.stderr)
            check_consistent(out, "sac")
    check_finished(out, "sac", 600, [100, 200, 300, 400, 500, 600])
    assert len(json.loads((out / "config.json").read_text())["resumes"]) == resumes


def test_ppo_survives_kills_and_counts_only_trained_steps(tmp_path: Path, here: Any) -> None:
    out = tmp_path / "ppo"
    common = ["--algo", "ppo", "--seed", "0", "--out", str(out), "--hyperparams", hp(tmp_path, PPO, "ppo.yml")]
    common += ["--timesteps", "512", "--checkpoint-freq", "100", "--eval-freq", "128", "--eval-episodes", "1"]
    for resume, fault in [(False, "checkpoint:model@2"), (True, "rename:checkpoint.json"), (True, None)]:
        args = [*common, *(["--resume"] if resume else [])]
        # the last resume, not killed: in this process
        r = run(args, fault) if fault else here("train", "--no-progress", *args)
        if fault is None:
            assert r.returncode == 0, r.stderr
        else:
            assert r.returncode == -signal.SIGKILL, r.stderr
            step = check_consistent(out, "ppo")
            assert step is not None and step % 64 == 0  # rollout boundaries: 4 envs x 16 steps
    check_finished(out, "ppo", 512, [128, 256, 384, 512])


def test_every_stage_of_a_checkpoint_save(tmp_path: Path) -> None:
    """Without SB3 (fast): a kill at each stage of ``runs.save_checkpoint`` leaves a loadable pointer."""
    stages = [
        "checkpoint:files",
        "checkpoint:meta",
        "checkpoint:rename",
        "write:checkpoint.json",
        "rename:checkpoint.json",
        "checkpoint:trash",
    ]
    script = """
import sys
from pathlib import Path
from amigo_gym.tools import runs
out = Path(sys.argv[1])
def writer(step):
    def write(folder):
        (folder / "model.zip").write_bytes(b"m%d" % step)
        return ["model.zip"]
    return write
with runs.RunLock(out):
    (out / "eval.json").write_text("[]")
    for step in (10, 20, 30):
        runs.save_checkpoint(out, "sac", step, writer(step), 1.0)
"""
    for stage in stages:
        out = tmp_path / stage.replace(":", "_")
        out.mkdir()
        r = subprocess.run(
            [sys.executable, "-c", script, str(out)],
            env=env_for(stage + ("@1" if stage == "checkpoint:trash" else "@2")),
            capture_output=True,
            text=True,
        )
        assert r.returncode == -signal.SIGKILL, (stage, r.stderr)
        step = check_consistent(out, "sac")
        assert step in (10, 20, 30), (stage, step)
        loaded = runs.load_checkpoint(out, "sac", lambda ck: (ck.folder / "model.zip").read_bytes())
        assert loaded is not None and loaded[1] == b"m%d" % loaded[0].step
        # the next process under the lock removes what the killed one left
        with runs.RunLock(out):
            runs.clean_temporaries(out)
        assert not dot_files(out), (stage, dot_files(out))


@pytest.mark.parametrize("stage", ["write:eval.json", "rename:eval.json"])
def test_a_killed_atomic_write_leaves_the_old_or_the_new_file(tmp_path: Path, stage: str) -> None:
    """Every record file (eval.json, run.json, config.json, ...) is written by io.atomic_write_json."""
    script = """
import sys
from pathlib import Path
from amigo_gym.io import atomic_write_json
for n in range(3):
    atomic_write_json(Path(sys.argv[1]) / "eval.json", [{"timesteps": 100 * (k + 1)} for k in range(n + 1)])
"""
    r = subprocess.run([sys.executable, "-c", script, str(tmp_path)], env=env_for(stage + "@2"), capture_output=True)
    assert r.returncode == -signal.SIGKILL
    steps = [e["timesteps"] for e in json.loads((tmp_path / "eval.json").read_text())]
    assert steps == ([100] if stage.startswith("write") else [100, 200])
    with runs.RunLock(tmp_path):
        runs.clean_temporaries(tmp_path)
    assert not dot_files(tmp_path)


# --------------------------------------------------------------------------- two processes on one folder
def test_second_train_and_resume_while_running_are_refused(tmp_path: Path, here: Any) -> None:
    out = tmp_path / "run"
    common = ["--algo", "ppo", "--seed", "0", "--out", str(out), "--hyperparams", hp(tmp_path, PPO, "ppo.yml")]
    common += ["--eval-freq", "0"]
    proc = subprocess.Popen(
        train_cmd(*common, "--timesteps", "10000000"),
        cwd=ROOT,
        env=env_for(None),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 60
        while not (out / "config.json").is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert (out / "config.json").is_file()
        for extra in ([], ["--resume"]):  # a second process (this one) on the folder
            r = here("train", "--no-progress", *common, "--timesteps", "1000", *extra)
            assert r.returncode == 2, r.stderr
            lines = r.stderr.strip().splitlines()
            assert len(lines) == 1 and "in use by another amigo-gym process" in lines[0], r.stderr
            assert f"pid {proc.pid}" in lines[0]
        assert proc.poll() is None  # the running one goes on
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130 and "interrupted" in err, err
    done = json.loads((out / "checkpoint.json").read_text())["num_timesteps"]
    assert done % 64 == 0  # stopped at a rollout start
    r = here("train", "--no-progress", *common, "--timesteps", str(done + 128), "--resume")
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "run.json").read_text())["timesteps"] == done + 128


# --------------------------------------------------------------------------- corrupt files
HP_FILE: list[str] = []


@pytest.fixture(scope="module")
def finished_sac(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished tiny SAC run (in process) with two checkpoints, 96 and 160."""
    from amigo_gym.tools.training.train import Settings, train

    d = tmp_path_factory.mktemp("sac")
    hp_file = hp(d, SAC, "sac.yml")
    HP_FILE[:] = [hp_file]
    out = d / "run"
    s = Settings(
        algo="sac", seed=2, out=str(out), timesteps=160, hyperparams=hp_file, eval_freq=80, eval_episodes=1,
        checkpoint_freq=40, progress=False,
    )  # fmt: skip
    train(s)
    ptr = json.loads((out / "checkpoint.json").read_text())
    assert ptr["num_timesteps"] == 160 and ptr["previous"] is not None
    return out


def resume(out: Path, total: int = 160) -> dict[str, Any]:
    from amigo_gym.tools.training.train import Settings, train

    s = Settings(
        algo="sac", seed=2, out=str(out), timesteps=total, hyperparams=HP_FILE[0], eval_freq=80,
        eval_episodes=1, checkpoint_freq=40, progress=False, resume=True,
    )  # fmt: skip
    return train(s)


def latest(out: Path) -> Path:
    return out / json.loads((out / "checkpoint.json").read_text())["path"]


def truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def garble(p: Path) -> None:
    data = bytearray(p.read_bytes())
    for i in range(100, len(data), 997):
        data[i] ^= 0xFF
    p.write_bytes(bytes(data))


def foreign_model(p: Path) -> None:
    """A well-formed zip that is not a SAC model, recorded with a matching sha256 (a hash proves nothing)."""
    with zipfile.ZipFile(p, "w") as z:
        z.writestr("data", json.dumps({"policy_class": "not a class"}))
    rehash(p)


def foreign_pickle(p: Path) -> None:
    import pickle

    p.write_bytes(pickle.dumps({"not": "a replay buffer"}))
    rehash(p)


def rehash(p: Path) -> None:
    """Record ``p``'s sha256 in its checkpoint's meta.json and as written by this installation (``io.vouch``): a file
    the run itself wrote, with the wrong content (trust and integrity pass; loading must still fail cleanly)."""
    from amigo_gym import io

    io.vouch(runs.sha256_file(p))
    meta_file = p.parent / "meta.json"
    meta = json.loads(meta_file.read_text())
    meta["files"][p.name] = runs.sha256_file(p)
    meta_file.write_text(json.dumps(meta))


CORRUPTIONS = {
    "model_truncated": (lambda out: truncate(latest(out) / "model.zip"), "model.zip: sha256"),
    "model_garbled": (lambda out: garble(latest(out) / "model.zip"), "model.zip: sha256"),
    "model_foreign": (lambda out: foreign_model(latest(out) / "model.zip"), "not a loadable SAC model"),
    "buffer_garbled": (lambda out: garble(latest(out) / "replay_buffer.pkl"), "replay_buffer.pkl: sha256"),
    "buffer_foreign": (lambda out: foreign_pickle(latest(out) / "replay_buffer.pkl"), "not a loadable replay buffer"),
    "meta_garbled": (lambda out: (latest(out) / "meta.json").write_text("{nope"), "meta.json: not valid JSON"),
    "meta_missing": (lambda out: (latest(out) / "meta.json").unlink(), "meta.json: missing"),
}


@pytest.mark.parametrize("case", sorted(CORRUPTIONS))
def test_corrupt_checkpoint_falls_back_to_the_previous(
    case: str, finished_sac: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    shutil.copytree(finished_sac, out)
    damage, needle = CORRUPTIONS[case]
    damage(out)
    (out / "run.json").unlink()
    rec = resume(out)
    err = capsys.readouterr().err
    warning = [ln for ln in err.splitlines() if "unusable" in ln]
    assert len(warning) == 1 and needle in warning[0] and "falling back to step_120" in warning[0], err
    assert rec["timesteps"] == 160 and rec["resumed_from"] == 120  # the same final step count
    check_finished(out, "sac", 160, [80, 160])


def test_corrupt_pointer_is_reported_and_the_folders_still_found(
    finished_sac: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    shutil.copytree(finished_sac, out)
    (out / "checkpoint.json").write_text('{"path": ')
    rec = resume(out)
    assert "checkpoint.json: not valid JSON" in capsys.readouterr().err
    assert rec["timesteps"] == 160 and rec["resumed_from"] == 160
    check_finished(out, "sac", 160, [80, 160])


def test_damaged_record_files_are_repaired_by_resume(finished_sac: Path, tmp_path: Path) -> None:
    out = tmp_path / "run"
    shutil.copytree(finished_sac, out)
    before = (out / "eval.json").read_bytes()
    truncate(out / "model.zip")
    (out / "run.json").write_text("{")
    (out / "eval.json").write_text("[{")
    garble(out / "best_model.zip")
    rec = resume(out)
    assert rec["timesteps"] == 160
    assert (out / "eval.json").read_bytes() == before
    assert (out / "best_model.zip").read_bytes() == (latest(out) / "best_model.zip").read_bytes()
    check_finished(out, "sac", 160, [80, 160])


def test_no_usable_checkpoint_and_bad_config_are_one_line_errors(finished_sac: Path, tmp_path: Path) -> None:
    out = tmp_path / "run"
    shutil.copytree(finished_sac, out)
    for folder in (out / "checkpoints").iterdir():
        truncate(folder / "model.zip")
    with pytest.raises(runs.CorruptFileError, match="no usable checkpoint") as exc:
        resume(out)
    assert "\n" not in str(exc.value)
    (out / "config.json").write_text("garbage")
    with pytest.raises(runs.CorruptFileError, match=r"config\.json: not valid JSON") as exc:
        resume(out)
    assert "\n" not in str(exc.value)


def test_a_lost_config_json_does_not_make_a_run_unresumable(
    finished_sac: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run"
    shutil.copytree(finished_sac, out)
    (out / "config.json").unlink()
    rec = resume(out, total=200)  # 40 more steps from the intact checkpoint of step 160
    assert rec["resumed_from"] == 160 and rec["timesteps"] == 200
    assert "config.json is missing; resuming from the checkpoints" in capsys.readouterr().err
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["recovered"] is True and cfg["settings"]["algo"] == "sac" and cfg["resumes"][-1]["from_step"] == 160
    check_finished(out, "sac", 200, [80, 160])  # evaluations every 80 steps
    # without checkpoints there is nothing to resume: the one-line error as before
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(FileNotFoundError, match="no checkpoint in"):
        resume(empty)


class _Crafted:
    """Unpickling this creates the file ``path`` (stands for any code a crafted pickle runs)."""

    def __init__(self, path: Path) -> None:
        self.path = str(path)

    def __reduce__(self) -> tuple[Any, tuple[str, str]]:
        return (open, (self.path, "w"))


def test_a_crafted_pickle_beside_a_verified_model_is_refused_before_it_is_loaded(
    finished_sac: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import pickle

    from amigo_gym.tools.training.benchmark import AgentSpec
    from amigo_gym.tools.training.evaluate import find_models, load_model

    out = tmp_path / "run"
    shutil.copytree(finished_sac, out)
    record = json.loads((out / "run.json").read_text())
    assert set(record["files"]) == {"model.zip", "best_model.zip"}  # every pickle a loader reads beside it
    ran = tmp_path / "code_ran"
    (out / "vecnormalize.pkl").write_bytes(pickle.dumps(_Crafted(ran)))
    (ref,) = find_models(out)
    assert ref.vecnormalize == out / "vecnormalize.pkl"
    with pytest.raises(UntrustedFileError, match=r"vecnormalize\.pkl: refused: .* --trust-unverified"):
        load_model(ref)
    assert not ran.exists()
    record["files"]["vecnormalize.pkl"] = "0" * 64  # listed, then replaced: the hash does not match
    (out / "run.json").write_text(json.dumps(record))
    with pytest.raises(runs.CorruptFileError, match=r"vecnormalize\.pkl: sha256 .* does not match"):
        load_model(ref)
    assert not ran.exists()
    # the same for a benchmark agent whose manifest names another sha256
    (out / "sac_s2.zip").write_bytes(pickle.dumps(_Crafted(ran)))
    spec = AgentSpec("sac", 2, str(out / "sac_s2.zip"), "sac", {"sha256": "0" * 64})
    with pytest.raises(runs.CorruptFileError, match=r"sac_s2\.zip: sha256 .* does not match"):
        spec.instantiate(None)
    assert not ran.exists()
    # nothing recorded beside it: a model a run here wrote still loads (its sha256 was recorded when written)
    (out / "vecnormalize.pkl").unlink()
    (out / "run.json").unlink()
    (ref,) = find_models(out)
    assert ref.record is None
    load_model(ref)
    # one from elsewhere is refused, and loads with the user's flag
    monkeypatch.setenv(STATE_ENV, str(tmp_path / "elsewhere"))
    with pytest.raises(UntrustedFileError, match=r"model\.zip: refused"):
        load_model(ref)
    monkeypatch.setenv(TRUST_ENV, "1")
    load_model(ref)
    assert not ran.exists()


# --------------------------------------------------------------------------- result files
def test_evaluate_writes_null_not_nan(tmp_path: Path) -> None:
    from amigo_gym.tools.training.evaluate import EvalProtocol, markdown_table, write_outputs

    row = {"agent": "a", "scenario": "nominal", "h_rms_m": 1e-3, "h_rms_settled_m": float("nan")}
    row |= {"h_max_m": 1e-3, "settling_time_s": None, "wheel_rate_dev_rms": 0.0, "wheel_rate_dev_steady_rms": 0.0}
    row |= {"mean_return": float("inf"), "terminated": 0}
    write_outputs([row], {}, EvalProtocol(), tmp_path, tmp_path / "r.json", plots=False)

    def refuse(constant: str) -> None:
        raise AssertionError(f"bare {constant} in JSON")

    doc = json.loads((tmp_path / "r.json").read_text(), parse_constant=refuse)
    assert doc["results"][0]["h_rms_settled_m"] is None and doc["results"][0]["mean_return"] is None
    assert "n/a" in markdown_table(doc["results"])


def compare(out: Path, fault: str | None = None) -> subprocess.CompletedProcess[str]:
    args = ["--out", str(out), "--models", "", "--train-steps", "0", "--seeds", "1", "--steps", "20", "--no-plots"]
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "compare", *args],
        cwd=ROOT,
        env=env_for(fault),
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_compare_publishes_its_outputs_as_one_set(tmp_path: Path, here: Any) -> None:
    out = tmp_path / "results"
    args = ["compare", "--out", str(out), "--models", "", "--train-steps", "0", "--seeds", "1", "--steps", "20"]
    args += ["--no-plots"]  # compare()'s command, run in this process when it is not killed
    assert here(*args).returncode == 0
    first = verify_outputs(out)
    assert set(first) == {"results.json", "report.md", "eval.md"}
    r = compare(out, "publish:report.md")  # killed halfway through publishing a new set
    assert r.returncode == -signal.SIGKILL, r.stderr
    with pytest.raises(FileNotFoundError, match="not a complete set"):
        verify_outputs(out)
    r = here(*args)
    assert r.returncode == 0, r.stderr
    verify_outputs(out)
    assert not dot_files(out), dot_files(out)


# --------------------------------------------------------------------------- trust
def test_shipped_models_match_their_manifests() -> None:
    from amigo_gym.data import pretrained_dir

    for algo in ("ppo", "sac", "td3"):
        manifest = json.loads((pretrained_dir() / f"{algo}.json").read_text())
        assert manifest["sha256"] == runs.sha256_file(pretrained_dir() / f"{algo}.zip")


def test_models_are_checked_before_loading(tmp_path: Path) -> None:
    from amigo_gym.data import pretrained_dir
    from amigo_gym.io import UntrustedFileError
    from amigo_gym.tools.training.evaluate import load_agents

    shutil.copy(pretrained_dir() / "td3.zip", tmp_path / "td3.zip")
    shutil.copy(pretrained_dir() / "td3.json", tmp_path / "td3.json")
    assert set(load_agents(tmp_path)) == {"td3"}
    garble(tmp_path / "td3.zip")  # e.g. a crafted zip put in place of the recorded one
    with pytest.raises(runs.CorruptFileError, match=r"td3\.zip: sha256 .* recorded in") as exc:
        load_agents(tmp_path)
    assert "\n" not in str(exc.value)
    (tmp_path / "td3.json").unlink()  # without a record: refused as untrusted, one line naming the flag
    with pytest.raises(UntrustedFileError, match=r"td3\.zip: refused.*--trust-unverified") as refused:
        load_agents(tmp_path)
    assert "\n" not in str(refused.value)
    with pytest.raises(runs.CorruptFileError, match=r"td3\.zip: not a loadable TD3 model"):  # trusted: not a traceback
        load_agents(tmp_path, trust=True)


# --------------------------------------------------------------------------- the lock file goes with a clean exit
def test_a_clean_exit_removes_the_lock_file_and_a_kill_leaves_a_harmless_one(tmp_path: Path) -> None:
    with runs.RunLock(tmp_path):
        assert (tmp_path / runs.LOCK_NAME).read_text().strip() == str(os.getpid())
    assert not (tmp_path / runs.LOCK_NAME).exists()
    script = "import os, sys\nfrom amigo_gym.tools import runs\nruns.RunLock(sys.argv[1]).acquire()\nos._exit(0)\n"
    r = subprocess.run([sys.executable, "-c", script, str(tmp_path)], env=env_for(None), capture_output=True)
    assert r.returncode == 0 and (tmp_path / runs.LOCK_NAME).exists()  # died holding it (no release)
    with runs.RunLock(tmp_path):  # the next process takes the stale file over
        pass
    assert not (tmp_path / runs.LOCK_NAME).exists()


def test_a_lock_taken_on_a_removed_file_is_not_trusted(tmp_path: Path) -> None:
    """The race a removed lock file opens: B opened run.lock just before A removed it, then locks the removed file;
    is_current_lock tells B that the path now names another file (or none), so B starts again on the new one."""
    path = tmp_path / runs.LOCK_NAME
    a = runs.RunLock(tmp_path).acquire()
    fd_b = os.open(path, os.O_RDWR)  # B opens the file A holds
    try:
        assert runs.is_current_lock(fd_b, path)
        a.release()  # A removes it and unlocks
        assert not runs.is_current_lock(fd_b, path)  # B would lock a file no one else can see
        c = runs.RunLock(tmp_path).acquire()  # C creates and locks a new one
        assert not runs.is_current_lock(fd_b, path)  # B's file is still not the current one
        with pytest.raises(runs.RunLockedError):  # and B, starting again on the path, meets C's lock
            runs.RunLock(tmp_path).acquire()
        c.release()
    finally:
        os.close(fd_b)


def test_clean_temporaries_removes_only_the_package_temporaries(tmp_path: Path) -> None:
    """A user's dot-files in an --out folder (.git, .env, .gitignore) survive; what killed writers left goes."""
    import tempfile

    from amigo_gym.tools.runs import clean_temporaries

    keep = [".git", ".env", ".gitignore", ".venv", ".DS_Store", "notes.txt"]
    for name in keep:
        (tmp_path / name).mkdir() if name in (".git", ".venv") else (tmp_path / name).write_text("x")
    (tmp_path / ".git" / "HEAD").write_text("ref: refs/heads/main\n")
    made = [
        tempfile.mkstemp(dir=tmp_path, prefix=".model.", suffix=".zip")[1],
        tempfile.mkstemp(dir=tmp_path, prefix=".benchmark.results.", suffix=".json")[1],
        tempfile.mkdtemp(dir=tmp_path, prefix=".tmp-"),
        tempfile.mkdtemp(dir=tmp_path, prefix=".staging-"),
    ]
    clean_temporaries(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(keep)
    assert (tmp_path / ".git" / "HEAD").read_text() == "ref: refs/heads/main\n"
    assert not any(Path(m).exists() for m in made)
