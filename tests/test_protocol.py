"""The benchmark protocol 2.0 (amigo_gym/tools/training/protocol.py): validation and test cells split in their
definitions, test cells on seeds no decision uses, and tuning code that cannot name a test cell."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from amigo_gym.tools.training import benchmark
from amigo_gym.tools.training.protocol import TEST, TEST_SEEDS, VALIDATION, VALIDATION_SEEDS, validation_cells
from amigo_gym.tools.training.task_metrics import Scenario, make_env

ROOT = Path(__file__).resolve().parents[1]
#: the names that reach test cells or test seeds, and those that reach validation cells
TEST_NAMES = {"TEST", "TEST_SEEDS", "SUITE", "SUITES", "SUITE_1_0", "quick_suite", "curvature_scenarios"}
VALIDATION_NAMES = {"VALIDATION", "VALIDATION_SEEDS", "validation_cells"}


def _names(path: Path) -> set[str]:
    # the names, attributes and imported names of a module
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    names |= {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    return names | {a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}


#: every module that takes a decision while building an agent: the sweep's objective, training (evaluation during
#: training, early stopping), and every experiment that reads validation cells (the choice between agents, gains,
#: rules), found rather than listed
TUNING = (
    "amigo_gym/tools/training/sweep.py",
    "amigo_gym/tools/training/fastppo.py",
    "amigo_gym/tools/training/train.py",
    *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "experiments").glob("*.py") if _names(p) & VALIDATION_NAMES),
)


def test_the_experiments_that_decide_on_validation_cells_are_found() -> None:
    found = set(TUNING)
    for name in ("sweep_objective", "residual_val_cells", "smith_delay", "compensator_val", "oracle_delay"):
        assert f"experiments/{name}.py" in found, name


def _key(sc: Scenario) -> tuple[str, str]:
    return sc.env_id, json.dumps(dict(sc.env_kwargs), sort_keys=True)


def test_test_cells_are_other_cells_on_other_seeds() -> None:
    val = {_key(sc) for sc in VALIDATION}
    assert not [sc.name for sc in TEST if _key(sc) in val]
    names = [sc.name for sc in VALIDATION + TEST]
    assert len(set(names)) == len(names)
    assert all(sc.seeds == TEST_SEEDS and sc.episodes >= 30 and sc.version == "2.0" for sc in TEST)
    old_test_seeds = {s for sc in benchmark.SUITES["1.0"] for s in sc.seeds}
    assert not set(VALIDATION_SEEDS) & (set(TEST_SEEDS) | old_test_seeds)
    assert benchmark.SUITES["2.0"] == TEST
    # the conditions the issue names are among the test cells: other delays, radii only, track only
    kinds = {json.dumps(dict(sc.env_kwargs).get("randomize")) for sc in TEST} | {
        json.dumps(dict(sc.env_kwargs).get("true_robot"), sort_keys=True) for sc in TEST
    }
    assert '{"delay": [0.15, 0.15]}' in kinds and '{"delay": [0.3, 0.3]}' in kinds
    assert any(s.startswith('{"r1"') and '"l1"' not in s for s in kinds) and '{"l1": 0.1116}' in kinds


@pytest.mark.parametrize("env_id", ["AmigoBot-v0", "AmigoBot-v1"])
def test_validation_cells_hold_no_test_cell_or_seed(env_id: str) -> None:
    cells = validation_cells(env_id, episodes=3, max_steps=50)
    test = {_key(sc) for sc in TEST}
    assert cells and all(c.env_id == env_id and _key(c) not in test for c in cells)
    assert all(c.seeds == VALIDATION_SEEDS[:3] and c.max_steps <= 50 for c in cells)
    with pytest.raises(ValueError, match=r"episodes must be an integer in \[1, 100\], got 0"):
        validation_cells(env_id, episodes=0)
    with pytest.raises(ValueError, match="env_id must be one of"):
        validation_cells("CartPole-v1")


@pytest.mark.parametrize("path", TUNING)
def test_tuning_code_names_no_test_cell(path: str) -> None:
    """Decisions see validation cells only: no tuning module names the test suites (the sweep once took its cells
    from the benchmark's ``SUITE``; this fails on that code)."""
    names = _names(ROOT / path)
    assert not names & TEST_NAMES, f"{path} names {sorted(names & TEST_NAMES)}"


def test_every_cell_makes_resets_and_steps() -> None:
    for sc in VALIDATION + TEST:
        env = make_env(sc)
        env.reset(seed=sc.seeds[0])
        env.step(env.action_space.sample() * 0)
        env.close()


def test_the_suite_2_results_in_the_docs_are_generated_from_the_committed_run() -> None:
    doc = json.loads((ROOT / "docs/benchmark/suite_2.0/benchmark.json").read_text())
    assert doc["suite_version"] == "2.0" and [s["name"] for s in doc["scenarios"]] == [sc.name for sc in TEST]
    text = (ROOT / "docs/benchmark.md").read_text(encoding="utf-8")
    assert benchmark.readme_table(doc) in text
    assert "amigo-gym benchmark --table-from docs/benchmark/suite_2.0/benchmark.json" in text
