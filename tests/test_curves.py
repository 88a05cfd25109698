"""``amigo-gym curves`` on hand-written run folders: means, bootstrap bands and threshold times against numpy."""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from amigo_gym.tools.cli import main as cli_main
from amigo_gym.tools.training.curves import find_runs, learning_curves, write_outputs

STEPS = [1000, 2000, 3000, 4000]
#: h_rms_m per seed of "ppo" at STEPS (settled values are 0.8 of these)
PPO_H = {0: [0.08, 0.02, 0.006, 0.004], 1: [0.1, 0.03, 0.004, 0.003], 2: [0.05, 0.009, 0.008, 0.007]}
PPO_R = {0: [10.0, 50.0, 80.0, 90.0], 1: [5.0, 40.0, 85.0, 95.0], 2: [20.0, 60.0, 70.0, 75.0]}
PPO_WALL = {0: [10.0, 20.0, 30.0, 40.0], 1: [12.0, 25.0, 37.0, 49.0], 2: [9.0, 17.0, 26.0, 33.0]}


def write_run(folder: Path, evals: list[dict[str, Any]], config: dict[str, Any] | None = None) -> None:
    folder.mkdir(parents=True)
    (folder / "eval.json").write_text(json.dumps(evals))
    if config is not None:
        (folder / "config.json").write_text(json.dumps(config))


def entry(t: int, h: float, r: float, wall: float, settled: float | None = None) -> dict[str, Any]:
    return {
        "timesteps": t,
        "mean_reward": r,
        "best_mean_reward": r,
        "wall_time_s": wall,
        "h_rms_m": h,
        "h_rms_settled_m": 0.8 * h if settled is None else settled,
        "speed_err_rms": 0.01,
        "failure_rate": 0.0,
    }


@pytest.fixture
def runs_dir(tmp_path: Path) -> Path:
    root = tmp_path / "runs"
    for s in PPO_H:
        evals = [entry(t, h, r, w) for t, h, r, w in zip(STEPS, PPO_H[s], PPO_R[s], PPO_WALL[s], strict=True)]
        write_run(root / f"ppo_s{s}", evals)
    # sac: named by config.json only; seed 7 evaluates at other steps; seed 8 was resumed (step 2000 twice)
    cfg = {"settings": {"algo": "sac", "seed": 7}, "env_id": "AmigoBot-v1"}
    write_run(root / "first", [entry(500, 0.2, 1.0, 5.0), entry(1500, 0.01, 2.0, 15.0)], cfg)
    cfg8 = {"settings": {"algo": "sac", "seed": 8}, "env_id": "AmigoBot-v1"}
    evals8 = [entry(1000, 0.3, 0.5, 8.0), entry(2000, 0.9, 0.1, 16.0), entry(2000, 0.02, 3.0, 18.0)]
    write_run(root / "second", evals8, cfg8)
    (root / "notes").mkdir()  # no eval.json: skipped
    write_run(root / "junk", [entry(1000, 0.1, 1.0, 1.0)])  # neither config.json nor <algo>_s<seed>: skipped
    return root


def hold(xs: list[float], ys: list[float], x: float) -> float:
    """The latest ``y`` at or before ``x`` (independent of the module's searchsorted)."""
    best = None
    for xi, yi in sorted(zip(xs, ys, strict=True)):
        if xi <= x:
            best = yi
    assert best is not None
    return best


def test_runs_found_named_and_skipped(runs_dir: Path) -> None:
    runs, skipped = find_runs([runs_dir])
    assert [(r.group, r.seed) for r in runs] == [("ppo", 0), ("ppo", 1), ("ppo", 2), ("sac", 7), ("sac", 8)]
    assert {Path(s["path"]).name: s["reason"] for s in skipped}.keys() == {"notes", "junk"}
    sac8 = next(r for r in runs if r.seed == 8)
    assert [e["timesteps"] for e in sac8.evals] == [1000, 2000]
    assert sac8.evals[1]["h_rms_m"] == 0.02  # the later evaluation of a repeated step


def test_groups_name_the_env_when_runs_differ_in_it(tmp_path: Path) -> None:
    for env, seed in (("AmigoBot-v0", 0), ("AmigoBot-v1", 0), ("AmigoBot-v1", 1)):
        cfg = {"settings": {"algo": "ppo", "seed": seed}, "env_id": env}
        write_run(tmp_path / f"{env}_{seed}", [entry(1000, 0.1, 1.0, 1.0)], cfg)
    runs, _ = find_runs([tmp_path])
    assert sorted((r.group, r.seed) for r in runs) == [
        ("ppo AmigoBot-v0", 0),
        ("ppo AmigoBot-v1", 0),
        ("ppo AmigoBot-v1", 1),
    ]


def test_step_curves_mean_and_band_against_numpy(runs_dir: Path) -> None:
    doc = learning_curves([runs_dir], reps=10_000)
    h = doc["curves"]["ppo"]["timesteps"]["h_rms_m"]
    assert h["x"] == STEPS and h["seeds"] == [0, 1, 2]
    values = np.array([PPO_H[s] for s in (0, 1, 2)])
    np.testing.assert_allclose(h["mean"], values.mean(axis=0), rtol=1e-12)
    # 3 seeds: every bootstrap resample is one of 27 equally likely ones; "all three the same seed" has
    # probability 1/27 = 3.7 % > 2.5 %, so the 95 % percentile bounds are exactly the smallest and largest seed
    np.testing.assert_allclose(h["ci95_low"], values.min(axis=0), rtol=1e-12)
    np.testing.assert_allclose(h["ci95_high"], values.max(axis=0), rtol=1e-12)
    r = doc["curves"]["ppo"]["timesteps"]["mean_reward"]
    np.testing.assert_allclose(r["mean"], np.array([PPO_R[s] for s in (0, 1, 2)]).mean(axis=0), rtol=1e-12)


def test_wall_time_curve_is_the_mean_of_step_functions(runs_dir: Path) -> None:
    doc = learning_curves([runs_dir], reps=2_000)
    c = doc["curves"]["ppo"]["wall_time_s"]["mean_reward"]
    lo = max(w[0] for w in PPO_WALL.values())
    hi = min(w[-1] for w in PPO_WALL.values())
    grid = sorted({w for ws in PPO_WALL.values() for w in ws if lo <= w <= hi})
    assert c["x"] == grid and grid[0] == 12.0 and grid[-1] == 33.0
    want = [np.mean([hold(PPO_WALL[s], PPO_R[s], x) for s in PPO_WALL]) for x in grid]
    np.testing.assert_allclose(c["mean"], want, rtol=1e-12)
    assert all(lo_ <= m <= hi_ for lo_, m, hi_ in zip(c["ci95_low"], c["mean"], c["ci95_high"], strict=True))


def test_uneven_steps_use_the_common_range(runs_dir: Path) -> None:
    doc = learning_curves([runs_dir], reps=10_000)
    c = doc["curves"]["sac"]["timesteps"]["h_rms_m"]
    # seed 7 at 500, 1500; seed 8 at 1000, 2000: common range [1000, 1500]
    assert c["x"] == [1000, 1500]
    np.testing.assert_allclose(c["mean"], [(0.2 + 0.3) / 2, (0.01 + 0.3) / 2], rtol=1e-12)
    # 2 seeds: the bounds are the two seeds exactly (each "both the same seed" has probability 1/4)
    np.testing.assert_allclose(c["ci95_low"], [0.2, 0.01], rtol=1e-12)
    np.testing.assert_allclose(c["ci95_high"], [0.3, 0.3], rtol=1e-12)


def test_band_of_five_seeds_matches_the_exact_bootstrap(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    values = rng.lognormal(-5, 1, size=5)
    for s, v in enumerate(values):
        write_run(tmp_path / f"td3_s{s}", [entry(1000, float(v), 1.0, 1.0)])
    c = learning_curves([tmp_path], reps=20_000, bootstrap_seed=11)["curves"]["td3"]["timesteps"]["h_rms_m"]
    # the exact bootstrap distribution of the mean: all 5^5 equally likely resamples
    means = np.array([values[list(i)].mean() for i in itertools.product(range(5), repeat=5)])
    assert c["mean"] == pytest.approx([values.mean()], rel=1e-12)
    lo, hi = c["ci95_low"][0], c["ci95_high"][0]
    assert np.quantile(means, 0.02) <= lo <= np.quantile(means, 0.03)
    assert np.quantile(means, 0.97) <= hi <= np.quantile(means, 0.98)


def test_threshold_times_and_medians(runs_dir: Path) -> None:
    doc = learning_curves([runs_dir], reps=100)
    assert doc["protocol"]["threshold_metric"] == "h_rms_settled_m" and doc["protocol"]["threshold_m"] == 0.005
    t = doc["threshold"]["ppo"]
    # settled = 0.8 h <= 5 mm, i.e. h <= 6.25 mm: seed 0 at 3000 (6 mm), seed 1 at 3000 (4 mm), seed 2 never
    per = {q["seed"]: q for q in t["per_seed"]}
    assert (per[0]["timesteps"], per[0]["wall_time_s"]) == (3000, 30.0)
    assert (per[1]["timesteps"], per[1]["wall_time_s"]) == (3000, 37.0)
    assert not per[2]["reached"] and per[2]["last_timesteps"] == 4000
    assert (t["n_seeds"], t["n_reached"]) == (3, 2)
    assert t["median_timesteps"] == 3000.0
    assert t["median_wall_time_s"] == 37.0  # median of 30, 37 and "never"
    sac = doc["threshold"]["sac"]
    assert sac["n_reached"] == 0 and sac["median_timesteps"] is None  # 1.5 * 0.8 * 0.01 = 8 mm > 5 mm
    looser = learning_curves([runs_dir], threshold=0.007, metric="h_rms_m", reps=100)["threshold"]["ppo"]
    assert [q["timesteps"] for q in looser["per_seed"]] == [3000, 3000, 4000]
    assert looser["median_timesteps"] == 3000.0 and looser["n_reached"] == 3


def test_median_is_not_reached_when_fewer_than_half_did(tmp_path: Path) -> None:
    write_run(tmp_path / "ppo_s0", [entry(100, 0.001, 1.0, 1.0)])
    write_run(tmp_path / "ppo_s1", [entry(100, 0.1, 1.0, 1.0)])
    t = learning_curves([tmp_path], reps=100)["threshold"]["ppo"]
    assert t["n_reached"] == 1 and t["median_timesteps"] is None and t["median_wall_time_s"] is None


def test_command_writes_outputs(runs_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert cli_main(["curves", "--runs", str(runs_dir), "--out", str(out), "--reps", "200", "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "| ppo | 2/3 | 3000 | 37 |" in captured.out
    assert "skipping" in captured.err and "junk" in captured.err
    for name in ("curves.json", "curves.md", "curves_steps.png", "curves_wall.png"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "curves_steps.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    doc = json.loads((out / "curves.json").read_text())
    assert doc["command"].startswith("amigo-gym curves --runs")
    assert {r["group"] for r in doc["runs"]} == {"ppo", "sac"}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--runs", "/nonexistent/runs"], "no directory /nonexistent/runs"),
        (["--runs", "{empty}"], "no run folder with an eval.json"),
        (["--runs", "{runs}", "{runs}/ppo_s0"], "ppo seed 0 twice"),
        (["--runs", "{runs}", "--threshold", "0"], "--threshold must be"),
        (["--runs", "{runs}", "--reps", "0"], "--reps must be"),
    ],
)
def test_errors_are_one_line(
    runs_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    (tmp_path / "empty").mkdir()
    argv = [a.format(runs=runs_dir, empty=tmp_path / "empty") for a in args]
    assert cli_main(["curves", *argv, "--out", str(tmp_path / "o"), "--no-plots"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("amigo-gym curves: error: ") and message in err[-1], err


def test_write_outputs_without_plots(runs_dir: Path, tmp_path: Path) -> None:
    doc = learning_curves([runs_dir], reps=100)
    written = write_outputs(doc, tmp_path / "o", plots=False)
    assert [p.name for p in written] == ["curves.json", "curves.md"]
    assert "| sac | 0/2 | not reached | not reached |" in (tmp_path / "o" / "curves.md").read_text()
