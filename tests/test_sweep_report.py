"""experiments/sweep_report.py: the report of a sweep study, checked against a study whose answer is known.

The study is made here with a known objective (no training): ``f = (x - 0.3)^2 + 1e-6 y``, where ``x`` decides the
value and ``y`` barely moves it, so the importance must rank ``x`` first; pruned trials appear at their last
report; the best trial, the CSV and the files must agree with the study.
"""

from __future__ import annotations

import csv
import importlib.util
import json
from pathlib import Path
from types import ModuleType

import pytest

optuna = pytest.importorskip("optuna")


def _script() -> ModuleType:
    path = Path(__file__).resolve().parents[1] / "experiments" / "sweep_report.py"
    spec = importlib.util.spec_from_file_location("sweep_report", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _study(url: str) -> None:
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(study_name="s", storage=url, sampler=optuna.samplers.RandomSampler(seed=3))
    for i in range(24):
        t = study.ask()
        x, y = t.suggest_float("x", 0.0, 1.0), t.suggest_float("y", 0.0, 1.0)
        value = (x - 0.3) ** 2 + 1e-6 * y
        if i % 6 == 5:  # a pruned trial: reported once at step 100, never finished
            t.report(value + 1.0, 100)
            study.tell(t, state=optuna.trial.TrialState.PRUNED)
        else:
            if i == 0:
                t.set_user_attr("baseline", True)
            study.tell(t, value)


def test_report_matches_the_study_and_ranks_the_deciding_parameter_first(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 's.db'}"
    _study(url)
    out = tmp_path / "rep"
    assert _script().main(["--storage", url, "--study", "s", "--out", str(out), "--bootstrap", "20"]) == 0
    study = optuna.load_study(study_name="s", storage=url)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["best"]["number"] == study.best_trial.number
    assert summary["states"]["COMPLETE"] == 20 and summary["states"]["PRUNED"] == 4
    rows = list(csv.DictReader((out / "trials.csv").open()))
    assert len(rows) == 24
    for r, t in zip(rows, sorted(study.trials, key=lambda t: t.number), strict=True):
        assert int(r["number"]) == t.number and r["state"] == t.state.name
        if t.state.name == "COMPLETE":
            assert float(r["objective_mm"]) == pytest.approx(1e3 * t.value, abs=1e-4)
        else:  # the last report, and the step it was pruned at
            assert float(r["objective_mm"]) == pytest.approx(1e3 * t.intermediate_values[100], abs=1e-4)
            assert r["pruned_at_step"] == "100"
    assert [r["baseline"] for r in rows].count("1") == 1
    imp = json.loads((out / "importance.json").read_text())
    assert list(imp["importance"]) == ["x", "y"] and imp["complete_trials"] == 20
    x = imp["importance"]["x"]
    assert x["all_trials"] > imp["importance"]["y"]["all_trials"] and x["lo"] <= x["hi"]
    for name in ("importance.png", "history.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    report = (out / "report.md").read_text()
    assert f"| {study.best_trial.number} | {1e3 * study.best_value:.3f} |" in report


def test_bad_options_are_refused_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    url = f"sqlite:///{tmp_path / 's.db'}"
    _study(url)
    main = _script().main
    for argv, field in ((["--target-quantile", "1.5"], "--target-quantile"), (["--bootstrap", "-1"], "--bootstrap")):
        assert main(["--storage", url, "--study", "s", "--out", str(tmp_path / "o"), *argv]) == 2
        err = capsys.readouterr().err.strip()
        assert field in err and len(err.splitlines()) == 1
    assert not (tmp_path / "o").exists()
