"""The pretrained agents still reach the figures claimed in ``agents/pretrained/claimed.json``.

``claimed.json`` is the JSON that ``amigo-gym evaluate --json agents/pretrained/claimed.json`` wrote when
the models were committed. The test re-runs the same protocol (same steps and seeds; every rollout is
deterministic) and accepts a metric within its relative tolerance of the claim (:data:`REL`, as
tests/test_agents_v1_pretrained.py's): torch's CPU kernels may round differently on other machines, and the closed
loop damps such differences (``python -m pytest tests/test_agents_pretrained.py -k reach -s -q`` prints the largest
deviation: within 2e-4 on an AMD EPYC, also under the AVX2 recipe of docs/development.md).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from amigo_gym.tools.training.evaluate import ALGOS, PRETRAINED_DIR, EvalProtocol, evaluate_agents, load_agents, v0_name

CLAIMED = PRETRAINED_DIR / "claimed.json"
#: relative tolerance per metric (the settled ones are small differences of the closed loop)
REL = {
    "h_rms_m": 0.02,
    "h_rms_settled_m": 0.06,
    "h_max_m": 0.02,
    "wheel_rate_dev_rms": 0.02,
    "wheel_rate_dev_steady_rms": 0.06,
    "mean_return": 0.01,
}


def claimed() -> dict[str, Any]:
    doc: dict[str, Any] = json.loads(CLAIMED.read_text())
    return doc


def test_pretrained_files_and_records() -> None:
    for algo in ALGOS:
        z = PRETRAINED_DIR / f"{algo}.zip"
        assert z.is_file() and z.stat().st_size < 1_000_000, z
        rec = json.loads((PRETRAINED_DIR / f"{algo}.json").read_text())
        assert rec["algo"] == algo and rec["timesteps"] > 0 and rec["wall_time_s"] > 0
        assert rec["command"].startswith(f"amigo-gym train --algo {algo}")
        assert f"--seed {rec['seed']}" in rec["command"]
        assert rec["git_revision"] and rec["versions"]["torch"]
        # where it was trained: CPU and threads ("unknown: ..." where the trainer did not record them yet), device
        assert all(rec.get(k) not in (None, "") for k in ("cpu", "torch_threads", "numba_threads")), algo
        assert rec.get("device") in ("cpu", "cuda"), algo


@pytest.fixture(scope="module")
def rerun() -> list[dict[str, Any]]:
    proto_doc = claimed()["protocol"]
    proto = EvalProtocol(
        steps=proto_doc["steps"],
        perturbed_seeds=tuple(proto_doc["scenarios"]["perturbed"]["seeds"]),
        settle_time_s=proto_doc["settle_time_s"],
        analytic_gain=proto_doc["analytic_gain"],
        scenarios=tuple(proto_doc["run_scenarios"]),
    )
    results, _ = evaluate_agents(dict(load_agents(PRETRAINED_DIR)), proto)
    return results


@pytest.mark.parametrize("algo", ALGOS)
def test_pretrained_reach_claimed_figures(algo: str, rerun: list[dict[str, Any]]) -> None:
    claims = [r for r in claimed()["results"] if r["agent"] == v0_name(algo)]  # the command's name of <algo>.zip
    assert {r["scenario"] for r in claims} == {"nominal", "paper_start", "perturbed"}
    worst = 0.0  # the largest relative deviation, printed with -s
    for c in claims:
        (new,) = [r for r in rerun if r["agent"] == algo and r["scenario"] == c["scenario"]]
        assert new["terminated"] == c["terminated"] == 0
        for key, rel in REL.items():
            assert abs(new[key] - c[key]) <= rel * abs(c[key]), (algo, c["scenario"], key, new[key], c[key])
            worst = max(worst, abs(new[key] - c[key]) / abs(c[key]))
    print(f"\n{algo}: largest relative deviation from the claims {worst:.1e}")


def test_claimed_best_agent_meets_targets() -> None:
    """The committed claim itself: the best learned agent on the perturbed starts meets the targets."""
    rows = [r for r in claimed()["results"] if r["scenario"] == "perturbed" and r["agent"] in map(v0_name, ALGOS)]
    best = min(rows, key=lambda r: r["h_rms_m"])
    assert best["h_rms_m"] <= 2e-3 and best["wheel_rate_dev_rms"] <= 0.1


def test_claims_are_for_these_models() -> None:
    """``claimed.json`` names the pretrained models' training records it was made with."""
    doc = claimed()
    for algo in ALGOS:
        rec = json.loads((PRETRAINED_DIR / f"{algo}.json").read_text())
        assert doc["training"][v0_name(algo)] == rec
    assert Path(CLAIMED).is_file()
