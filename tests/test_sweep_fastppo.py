"""``amigo-gym sweep --algo fastppo`` (issue 18, item 2) and ``amigo-gym train-fast --hyperparams``.

Tiny budgets: 64 robots, 8- or 16-step rollouts, a 16-unit network, 100-step training episodes, one validation
episode of 20 steps per held-in cell. The sweep runs as the console command would (a subprocess) where it is
stopped by a signal; the other commands run through ``amigo_gym.tools.cli.main`` in this process, and the pruned trial
calls the objective directly (it needs a pruner of its own).
"""

from __future__ import annotations

import json
import signal
from pathlib import Path

import numpy as np
import pytest
import yaml

optuna = pytest.importorskip("optuna")
torch = pytest.importorskip("torch")
import test_sweep as ts  # noqa: E402  (the subprocess helpers of the SB3 sweep's tests)
from optuna.trial import TrialState  # noqa: E402

TINY = {"num_envs": 64, "rollout_steps": 16, "minibatch_size": 256, "hidden": [16], "max_episode_steps": 100}


def _tiny_file(tmp: Path, **extra: object) -> Path:
    f = tmp / "tiny_fastppo.yml"
    f.write_text(yaml.safe_dump({"AmigoBot-v1": {**TINY, **extra}}))
    return f


def _args(tmp: Path, *extra: str) -> list[str]:
    return [
        "--algo", "fastppo", "--env", "AmigoBot-v1", "--hyperparams", str(_tiny_file(tmp)),
        "--timesteps", "4096", "--eval-freq", "1024", "--eval-episodes", "2",
        "--out", str(tmp / "out"), "--n-startup-trials", "1", "--val-episodes", "1", "--val-max-steps", "20",
        *extra,
    ]  # fmt: skip


def _weights(model: Path) -> list[np.ndarray]:
    from amigo_gym.policies.learned import FastPolicy

    return [w for layer in FastPolicy.load(model).layers for w in layer]


# --------------------------------------------------------------------------- hyperparameter study
def test_fastppo_study_completes_reports_each_evaluation_and_saves_the_best(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
    from amigo_gym.tools.training.fastppo import FastPPOSettings, load_settings_yaml
    from amigo_gym.tools.training.protocol import VALIDATION_SEEDS, validation_cells

    target = tmp_path / "hp.yml"  # a file with another block, whose comment and values must survive
    other = "# kept as written\nAmigoBot-v0:\n  n_steps: 32  # a comment\n\n"
    target.write_text(other + "# replaced\nAmigoBot-v1:\n  num_envs: 1\n")
    # two startup trials: the median pruner prunes nothing before two trials have completed (it would otherwise
    # compare the second trial with the first; a pruned trial is test_a_pruned_fastppo_trial_...'s subject)
    args = _args(
        tmp_path, "--n-trials", "2", "--n-startup-trials", "2", "--study-name", "fp", "--save-best", str(target)
    )
    out = ts._sweep_here(capsys, args)  # one job: the command's trials run in this process
    study = optuna.load_study(study_name="fp", storage=f"sqlite:///{tmp_path / 'out' / 'sweep.db'}")
    trials = study.get_trials()
    assert [t.state for t in trials] == [TrialState.COMPLETE] * 2, [(t.state, t.user_attrs) for t in trials]
    held_in = [sc.name for sc in validation_cells("AmigoBot-v1")]
    for t in trials:
        # every evaluation (steps 0, 1024, ..., 4096) reached the pruner
        assert sorted(t.intermediate_values) == [0, 1024, 2048, 3072, 4096]
        curve = json.loads((Path(t.user_attrs["run_dir"]) / "run" / "curve.json").read_text())
        assert [t.intermediate_values[int(r["env_steps"])] for r in curve] == [r["eval_h_rms_m"] for r in curve]
        # the run trained the base file's settings with the sampled ones, on the training distribution
        s = json.loads((Path(t.user_attrs["run_dir"]) / "run" / "settings.json").read_text())
        hp = t.user_attrs["hyperparams"]
        assert {k: s[k] for k in hp} == hp and s["hidden"] == [16] and s["max_episode_steps"] == 100
        assert s["env_kwargs"] == TRAINING_DISTRIBUTION["env_kwargs"] and s["total_steps"] == 4096
        assert s["num_envs"] * s["rollout_steps"] % s["minibatch_size"] == 0
        assert 3e-5 <= s["learning_rate"] <= 3e-3 and 0.9 <= s["gamma"] <= 0.999 and 0.2 <= s["filter_alpha"] <= 1
        assert s["gamma"] == pytest.approx(1 - t.params["one_minus_gamma"], abs=1e-15)
        # the objective: IQM over the protocol's v1 validation cells (never a test cell or seed)
        val = t.user_attrs["validation"]
        assert list(val["cells"]) == held_in and val["seeds"] == [VALIDATION_SEEDS[0]]
        cells = np.sort(np.array(list(val["cells"].values())))
        k = int(0.25 * cells.size)
        assert t.value == pytest.approx(float(cells[k : cells.size - k].mean()), rel=1e-12)
    # --save-best: the best trial's settings under AmigoBot-v1, the other block as it was, the command named
    best = min(trials, key=lambda t: t.value)
    text = target.read_text()
    assert text.startswith(other) and "# replaced" not in text
    assert f"trial {best.number}" in text and "# Found by: amigo-gym sweep --algo fastppo" in text
    assert load_settings_yaml(target) == best.user_attrs["hyperparams"]
    assert yaml.safe_load(text)["AmigoBot-v0"] == {"n_steps": 32}
    FastPPOSettings.from_json(load_settings_yaml(target))  # a valid train-fast settings file
    assert f"wrote the best trial's hyperparameters under AmigoBot-v1 in {target}" in out


def test_a_pruned_fastppo_trial_stops_training_at_the_pruned_evaluation(tmp_path: Path) -> None:
    """The pruner's verdict stops the training itself: a threshold pruner that prunes any value above 0 from step
    2048 on leaves three reports and three evaluations, and no model."""
    from amigo_gym.tools.training.sweep import SweepConfig, _objective

    cfg = SweepConfig(
        algos=["fastppo"], env_id="AmigoBot-v1", hyperparams=str(_tiny_file(tmp_path)), timesteps=8192,
        eval_freq=1024, eval_episodes=2, val_episodes=1, val_max_steps=20, out=str(tmp_path / "out"), n_trials=1,
    )  # fmt: skip
    cfg.validate()
    study = optuna.create_study(pruner=optuna.pruners.ThresholdPruner(upper=0.0, n_warmup_steps=2048))
    study.optimize(_objective(cfg, study, 0), n_trials=1)
    (t,) = study.get_trials()
    assert t.state == TrialState.PRUNED
    assert sorted(t.intermediate_values) == [0, 1024, 2048]
    run = Path(t.user_attrs["run_dir"]) / "run"
    curve = json.loads((run / "curve.json").read_text())
    assert [int(r["env_steps"]) for r in curve] == [0, 1024, 2048]  # no training after the verdict
    assert not (run / "model.zip").exists() and t.user_attrs["last_eval_timesteps"] == 2048


# --------------------------------------------------------------------------- seeds grid, interruption
def test_sigterm_requeues_a_fastppo_cell_and_the_rerun_resumes_it_and_runs_the_grid(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A SIGTERM'd fastppo trial stops after a checkpoint and is queued again; the rerun continues it from that
    checkpoint (curve rows from before the stop kept) to the model an uninterrupted run gives, bit for bit, and
    trains the rest of the grid with the file's settings."""
    from amigo_gym.tools.training.fastppo import FastPPOSettings, train

    base = _args(tmp_path, "--mode", "seeds", "--seeds", "0", "1", "--study-name", "grid")
    base[base.index("--timesteps") + 1] = "40960"  # 40 iterations: long enough to be stopped part-way
    storage = f"sqlite:///{tmp_path / 'out' / 'sweep.db'}"
    victim = ts._sweep(base)
    (trial,) = ts._wait_running(storage, "grid", 1, [victim], tmp_path / "out" / "grid")
    victim.send_signal(signal.SIGTERM)
    out, _ = victim.communicate(timeout=300)
    assert victim.returncode == 130, out[-3000:]
    trials = optuna.load_study(study_name="grid", storage=storage).get_trials()
    stopped = next(t for t in trials if t.number == trial.number)
    assert stopped.state == TrialState.FAIL and "SIGTERM" in stopped.user_attrs["interrupted"]
    old_run = Path(stopped.user_attrs["run_dir"]) / "run"
    ck = torch.load(old_run / "checkpoint.pt", weights_only=False)
    assert 0 < ck["global_step"] < 40960  # stopped part-way, after a checkpoint at an iteration's end
    assert (Path(stopped.user_attrs["run_dir"]) / "ABANDONED.json").is_file()

    ts._sweep_here(capsys, base)  # the rerun, not killed: in this process
    trials = optuna.load_study(study_name="grid", storage=storage).get_trials()
    done = {t.params["seed"]: t for t in trials if t.state == TrialState.COMPLETE}
    assert sorted(done) == [0, 1], [(t.number, t.state, t.params) for t in trials]
    retry = next(t for t in trials if t.user_attrs.get("retry_of") == stopped.number)
    assert retry.state == TrialState.COMPLETE and retry.user_attrs["resumed_from"]["trial"] == stopped.number
    new_run = Path(retry.user_attrs["run_dir"]) / "run"
    curve = json.loads((new_run / "curve.json").read_text())
    assert curve[: len(ck["curve"])] == ck["curve"] and curve[-1]["env_steps"] == 40960
    # the resumed model is the uninterrupted run's, bit for bit
    s = FastPPOSettings.from_json(json.loads((new_run / "settings.json").read_text()))
    train(s, tmp_path / "straight", log=None)
    for a, b in zip(_weights(new_run / "model.zip"), _weights(tmp_path / "straight" / "model.zip"), strict=True):
        np.testing.assert_array_equal(a, b)
    # every cell trained the file's settings with its own seed
    for seed, t in done.items():
        st = json.loads((Path(t.user_attrs["run_dir"]) / "run" / "settings.json").read_text())
        assert st["seed"] == seed and {k: st[k] for k in TINY} == TINY and "n_minibatches" not in t.params


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("extra", "yml", "message"),
    [
        (["--env", "AmigoBot-v0"], None, "--algo fastppo trains the native AmigoBot-v1 vector env: add --env"),
        (["--mode", "seeds", "--algo", "fastppo", "ppo"], None, "one file cannot hold the settings of fastppo and"),
        ([], {"n_steps": 32}, "unknown key(s) for fastppo: n_steps"),
        ([], {"seed": 3}, "seed belong to a run's command line"),
        ([], {"gamma": 1.5}, "gamma"),
        (["--mode", "seeds", "--save-best", "x.yml"], None, "--save-best applies to --mode hyperparams, not seeds"),
    ],
)
def test_bad_fastppo_sweeps_are_refused_in_one_line(
    tmp_path: Path, extra: list[str], yml: dict[str, object] | None, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from amigo_gym.tools.training.sweep import main

    args = _args(tmp_path)
    if yml is not None:
        _tiny_file(tmp_path, **yml)
    if "--algo" in extra:  # the seeds grid of two algorithms
        args = [a for a in args if a != "fastppo"]
        args.remove("--algo")
    with pytest.raises(SystemExit) as exc:
        main([*args, *extra])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- train-fast --hyperparams
def test_train_fast_takes_a_settings_file_and_the_command_line_overrides_it(tmp_path: Path) -> None:
    from amigo_gym.tools.training.fastppo import main

    f = _tiny_file(tmp_path, epochs=3)
    rc = main(["--out", str(tmp_path / "run"), "--hyperparams", str(f), "--epochs", "2", "--total-steps", "1024",
               "--eval-envs", "2", "--quiet"])  # fmt: skip
    assert rc == 0
    s = json.loads((tmp_path / "run" / "settings.json").read_text())
    assert s["epochs"] == 2 and s["total_steps"] == 1024  # the command line
    assert {k: s[k] for k in ("num_envs", "rollout_steps", "hidden", "max_episode_steps")} == {
        k: TINY[k] for k in ("num_envs", "rollout_steps", "hidden", "max_episode_steps")
    }  # the file
    assert s["learning_rate"] == 3e-4  # neither: the default


def test_train_fast_refuses_a_bad_settings_file_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from amigo_gym.tools.training.fastppo import main

    for content, message in (
        ({"AmigoBot-v1": {"n_steps": 8}}, "unknown key(s) for fastppo: n_steps"),
        ({"AmigoBot-v1": {"minibatch_size": 3}}, "minibatch_size must divide"),
        ({"AmigoBot-v0": {"epochs": 2}}, "expected a mapping with the key 'AmigoBot-v1'"),
        ({"AmigoBot-v1": {"env_kwargs": {}}}, "env_kwargs belong to a run's command line"),
    ):
        f = tmp_path / "bad.yml"
        f.write_text(yaml.safe_dump(content))
        assert main(["--out", str(tmp_path / "run"), "--hyperparams", str(f)]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
    assert main(["--out", str(tmp_path / "run"), "--hyperparams", str(tmp_path / "missing.yml")]) == 2
    assert not (tmp_path / "run").exists()


def test_shipped_fastppo_file_gives_the_shipped_generalists_settings() -> None:
    """agents/hyperparams/fastppo.yml holds the settings the shipped ppo_fast seeds were trained with."""
    from amigo_gym.data import hyperparams_dir, pretrained_dir
    from amigo_gym.tools.training.fastppo import FastPPOSettings, load_settings_yaml

    file = load_settings_yaml(hyperparams_dir() / "fastppo.yml")
    for manifest in sorted((pretrained_dir() / "v1" / "ppo_fast").glob("*.json")):
        shipped = json.loads(manifest.read_text())["settings"]
        mine = FastPPOSettings.from_json({**file, "seed": shipped["seed"], "env_kwargs": shipped["env_kwargs"]})
        # fields added after the seeds were trained hold their defaults (from_json fills them in)
        assert mine.to_json() == FastPPOSettings.from_json(shipped).to_json(), manifest
        assert {k: v for k, v in mine.to_json().items() if k in shipped} == shipped, manifest


def test_replace_yaml_block_keeps_the_other_blocks_as_written() -> None:
    from amigo_gym.tools.training.sweep import replace_yaml_block

    text = "# head of v0\nAmigoBot-v0:\n  a: 1\n\n# v1 says\n# more\nAmigoBot-v1:\n  b: 2\n\n# tail key\nX:\n  c: 3\n"
    new = replace_yaml_block(text, "AmigoBot-v1", "# new\nAmigoBot-v1:\n  b: 5\n")
    assert new == "# head of v0\nAmigoBot-v0:\n  a: 1\n\n# new\nAmigoBot-v1:\n  b: 5\n\n# tail key\nX:\n  c: 3\n"
    assert replace_yaml_block("A:\n  a: 1\n", "B", "B:\n  b: 2\n") == "A:\n  a: 1\n\nB:\n  b: 2\n"
    assert replace_yaml_block("", "B", "B:\n  b: 2") == "B:\n  b: 2\n"
    assert yaml.safe_load(replace_yaml_block(text, "AmigoBot-v0", "AmigoBot-v0: {a: 9}\n")) == {
        "AmigoBot-v0": {"a": 9},
        "AmigoBot-v1": {"b": 2},
        "X": {"c": 3},
    }


def test_a_retry_resumes_the_newest_abandoned_checkpoint_of_the_same_settings(tmp_path: Path) -> None:
    """What a retry continues from, whichever way its original ended (SIGTERM, or killed and found stale by the
    heartbeat: FAIL without a reason of its own): the newest checkpoint of an abandoned trial with the same
    parameters and settings; never that of a trial that failed by its own error or trained other settings."""
    from optuna.distributions import CategoricalDistribution

    from amigo_gym.tools.training.fastppo import FastPPOSettings, train
    from amigo_gym.tools.training.sweep import _resume_fastppo

    kw = {**TINY, "hidden": (16,), "rollout_steps": 8, "total_steps": 2048, "eval_envs": 2}
    s, other = FastPPOSettings(**kw), FastPPOSettings(**kw, seed=1)  # type: ignore[arg-type]
    study = optuna.create_study()
    dist = {"seed": CategoricalDistribution([0, 1])}

    def abandoned(name: str, settings: FastPPOSettings, steps: int, **attrs: object) -> Path:
        run = tmp_path / name / "run"
        train(settings, run, until_steps=steps, log=None)
        study.add_trial(
            optuna.trial.create_trial(
                state=TrialState.FAIL, params={"seed": 0}, distributions=dist,
                user_attrs={"run_dir": str(run.parent), **attrs},
            )
        )  # fmt: skip
        return run

    abandoned("old", s, 512, interrupted="stopped by SIGTERM or Ctrl-C")
    newest = abandoned("killed", s, 1024)  # stale heartbeat: no attribute of its own
    abandoned("error", s, 1536, fail_reason="ValueError: ...")
    abandoned("other_settings", other, 1536)
    study.enqueue_trial({"seed": 0})  # the retry of seed 0 (ask alone would sample the seed: 0 or 1 at random)
    trial = study.ask({"seed": CategoricalDistribution([0, 1])})
    assert trial.params == {"seed": 0}
    out = tmp_path / "retry" / "run"
    assert _resume_fastppo(study, trial, s, out) == {"trial": 1, "run_dir": str(newest)}
    assert (out / "checkpoint.pt").read_bytes() == (newest / "checkpoint.pt").read_bytes()
    assert (newest / "checkpoint.pt").is_file()  # the abandoned folder keeps its files
    rec = train(s, out, resume=True, log=None)
    assert rec["finished"] and rec["timesteps"] == 2048
    assert _resume_fastppo(study, trial, FastPPOSettings(**{**kw, "epochs": 2}), tmp_path / "x") is None  # type: ignore[arg-type]
