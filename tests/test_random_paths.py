"""The published random-path protocol as benchmark scenarios (tools/training/random_paths.py, ``amigo-gym benchmark
--random-paths``); tiny budgets.

Reference: the per-path records of the former experiment's 1000-path run (docs/benchmark/random_paths/
random_paths_paper100_1000.json: the authors' stream, each path's length and peak curvature, each episode's peak
|e|), against which the generator and the textbook pure pursuit are checked."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from amigo_gym.tools.training import random_paths as rp
from amigo_gym.tools.training.benchmark import main
from amigo_gym.tools.training.evaluate import AgentSpec

REFERENCE = Path(__file__).parents[1] / "docs/benchmark/random_paths/random_paths_paper100_1000.json"


def _reference() -> dict[tuple[int, str, str], dict[str, Any]]:
    doc = json.loads(REFERENCE.read_text())
    return {(e["path"], e["condition"], e["agent"]): e for e in doc["episodes"]}


def test_the_generator_is_deterministic_and_draws_the_published_paths() -> None:
    a, b = np.random.RandomState(100), np.random.RandomState(100)
    for _ in range(3):
        pa, ka = rp.draw_path(a)
        pb, kb = rp.draw_path(b)
        assert np.array_equal(pa, pb) and ka == kb
    ref = _reference()
    ps = rp.path_set(6, "firmware")
    assert len(ps.scenarios) == 6 and not ps.skipped
    for sc in ps.scenarios:
        tag = ps.tags[sc.name]
        r = ref[(int(tag["path"]), "paper", "analytic")]
        assert (tag["length"], tag["max_curvature"], tag["fit_step"]) == (
            r["length"],
            r["max_curvature"],
            r["fit_step"],
        )
    offset = json.loads(REFERENCE.read_text())["start_pose_offset"]
    assert rp.start_offset() == pytest.approx(offset, abs=1e-15)


def test_the_textbook_pure_pursuit_fails_the_published_paths_as_the_experiment() -> None:
    ps = rp.path_set(2, "paper")  # path 0 fails at 0.1 m (peak 0.101 m), path 1 does not (0.049 m)
    doc = rp.run_random_paths([AgentSpec("pure_pursuit_textbook")], ps, progress=False)
    ref = _reference()
    for ep in doc["episodes"]:
        r = ref[(ep["path"], "paper", "pure_pursuit_cao2024")]
        assert ep["peak_m"] == pytest.approx(r["peak"], abs=2e-5) and ep["steps"] == r["steps"]
    fails = {(r["tolerance"], r["failures"]) for r in doc["table"] if r["group"] == "all"}
    assert fails == {(0.1, 1), (0.2, 0), (0.3, 0)}


def test_the_failure_table_pools_seeds_bins_curvature_and_keeps_each_seed() -> None:
    eps = [
        {"agent": "a", "seed": s, "peak_m": p, "feasible": f, "max_curvature": k}
        for s, p, f, k in ((0, 0.15, True, 1.0), (0, 0.05, False, 30.0), (1, 0.25, True, 1.0), (1, 0.0, True, 30.0))
    ]
    rows = rp.failure_table(eps, (0.1, 0.2))
    get = {(r["group"], r.get("seed"), str(r.get("kappa")), r["tolerance"]): r for r in rows}
    assert get[("all", None, "None", 0.1)]["failures"] == 2 and get[("all", None, "None", 0.2)]["failures"] == 1
    assert get[("accepted", None, "None", 0.1)]["n"] == 3
    assert get[("seed", 1, "None", 0.2)]["rate"] == 0.5 and get[("seed", 0, "None", 0.2)]["rate"] == 0.0
    assert get[("curvature", None, "[0.0, 2.0]", 0.1)]["failures"] == 2
    assert get[("curvature", None, "[20.0, 60.0]", 0.1)]["failures"] == 0
    assert get[("curvature", None, "[5.0, 10.0]", 0.1)]["rate"] is None


def _spread_episodes() -> list[dict[str, Any]]:
    """Agent ``a``: 3 seeds on 4 paths (0 and 1 within the wheel limits), seed 2 fails twice as often as the median
    on all paths at 0.1 m and alone on the accepted ones; ``b``: 3 seeds on 10 paths failing 2, 3 and 2 times (worst
    exactly 1.5x the median); ``c``: one seed; ``d``: 2 seeds that never fail."""
    peaks = {0: [0.0, 0.0, 0.15, 0.0], 1: [0.0, 0.0, 0.15, 0.0], 2: [0.0, 0.25, 0.15, 0.0]}
    eps = [
        {"agent": "a", "seed": s, "peak_m": p, "feasible": i < 2} for s, ps in peaks.items() for i, p in enumerate(ps)
    ]
    eps += [{"agent": "b", "seed": s, "peak_m": 0.15 * (i < k), "feasible": True}
            for s, k in ((0, 2), (1, 3), (2, 2)) for i in range(10)]  # fmt: skip
    eps += [{"agent": "c", "seed": 0, "peak_m": 0.5, "feasible": True}]
    return eps + [{"agent": "d", "seed": s, "peak_m": 0.0, "feasible": True} for s in (0, 1) for _ in range(3)]


def test_no_failed_seed_is_every_seed_within_1_5x_of_the_median_seed() -> None:
    rows = rp.seed_spread(_spread_episodes(), (0.1, 0.2))
    get = {(r["agent"], r["paths"], r["tolerance"]): r for r in rows}
    assert {a for a, _, _ in get} == {"a", "b", "d"}  # one seed: no verdict
    a = get[("a", "all", 0.1)]  # rates 1/4, 1/4, 1/2: the worst seed is 2x the median
    assert [r["rate"] for r in a["seed_rates"]] == [0.25, 0.25, 0.5]
    assert (a["median_rate"], a["worst_rate"], a["worst_seed"], a["ratio"], a["within"]) == (0.25, 0.5, 2, 2.0, False)
    acc = get[("a", "accepted", 0.1)]  # rates 0, 0, 1/2: a median of 0 asks every seed to be 0
    assert (acc["median_rate"], acc["worst_rate"], acc["ratio"], acc["within"]) == (0.0, 0.5, None, False)
    b = get[("b", "all", 0.1)]  # 0.2, 0.3, 0.2: worst = 1.5 x median, within
    assert (b["median_rate"], b["worst_rate"], b["worst_seed"], b["within"]) == (0.2, 0.3, 1, True)
    assert b["ratio"] == pytest.approx(1.5)
    assert get[("b", "all", 0.2)]["within"] and get[("b", "all", 0.2)]["median_rate"] == 0.0  # all 0: within
    assert all(get[("d", paths, t)]["within"] for paths in ("accepted", "all") for t in (0.1, 0.2))
    two = [e for e in _spread_episodes() if e["agent"] == "a" and e["seed"] in (0, 2)]  # an even count: the mean
    assert rp.seed_spread(two, (0.1,))[1]["median_rate"] == pytest.approx(0.375)  # of the two middle seeds
    protocol = {"paths": 4, "seed": 100, "condition": "firmware", "speed": 0.2, "duration_s": 20.0}
    protocol |= {"failure": "peak >= tolerance", "tolerances": [0.1, 0.2]}
    table = rp.failure_table([e | {"max_curvature": 1.0} for e in _spread_episodes()], (0.1, 0.2))
    doc = {"protocol": protocol, "skipped": [], "accepted": 2, "table": table, "seed_spread": rows, "unavailable": []}
    md = rp.markdown_random_paths(doc)
    assert "every training seed's failure rate within 1.5x of the median seed's" in md
    assert "| a | all | 0.1 m | 3 | 25.0 | 50.0 (seed 2) | **no** |" in md
    assert "| b | all | 0.1 m | 3 | 20.0 | 30.0 (seed 1) | yes |" in md


def test_the_cli_writes_its_table_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["--random-paths", "2", "--condition", "firmware", "--tolerance", "0.05", "0.1", "--quick"]
    args += ["--agents", "analytic", "pure_pursuit_textbook", "--out", str(tmp_path), "--no-progress"]
    assert main(args) == 0
    doc = json.loads((tmp_path / "random_paths.json").read_text())
    assert doc["protocol"]["condition"] == "firmware" and doc["protocol"]["tolerances"] == [0.05, 0.1]
    assert doc["seed_spread"] == [] and doc["protocol"]["seed_factor"] == 1.5  # no agent with two seeds here
    assert len(doc["episodes"]) == 4 and {e["agent"] for e in doc["episodes"]} == {"analytic", "pure_pursuit_textbook"}
    md = (tmp_path / "random_paths.md").read_text()
    assert "| pure_pursuit_textbook | " in md and "| agent | 0.05 m | 0.1 m |" in md
    assert md in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--random-paths", "-3"], "--random-paths must be an integer >= 0, got -3"),
        (["--random-paths", "2", "--condition", "lab"], "--condition: invalid choice: 'lab'"),
        (["--random-paths", "2", "--tolerance", "0.1", "0"], "--tolerance must be in (0, 10] m each, got [0.1, 0.0]"),
        (["--random-paths", "2", "--curvature"], "--curvature, --random-paths and --path/--scenarios exclude"),
    ],
)
def test_bad_input_is_one_line(args: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc: Any
    try:
        rc = main([*args, "--out", str(tmp_path)])
    except SystemExit as exc:  # the parser's own errors (choices)
        rc = exc.code
    err = capsys.readouterr().err.strip()
    assert rc == 2 and says in err and len(err.splitlines()) == 1


def test_the_committed_run_s_table_is_generated_from_its_json() -> None:
    run = REFERENCE.parent / "firmware_200"
    doc = json.loads((run / "random_paths.json").read_text())
    assert rp.markdown_random_paths(doc) == (run / "random_paths.md").read_text()
    assert doc["command"].startswith("amigo-gym benchmark --random-paths 200 --condition firmware")
