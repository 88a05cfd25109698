"""The shipped AmigoBot-v1 generalists: manifests complete, sha256 right, and the benchmark reproduces their
claimed numbers exactly on re-run scenarios (experiments/claim_v1.py wrote them from a full benchmark run)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from amigo_gym.data import pretrained_dir
from amigo_gym.training import benchmark as bm

MANIFESTS = sorted((pretrained_dir() / "v1").glob("*/*.json"))
#: the scenarios re-run here (the full benchmark holds the others)
RERUN = ("lane_change",)  # short episodes (the path ends after about 5 m): a cheap exact re-run
KEYS = ("h_rms_m", "h_rms_settled_m", "speed_err_rms", "failure_rate", "return")


def test_models_are_shipped() -> None:
    assert MANIFESTS, "no AmigoBot-v1 generalists under agents/pretrained/v1"


@pytest.mark.parametrize("manifest", MANIFESTS, ids=[m.stem for m in MANIFESTS])
def test_manifest_is_complete_and_matches_the_model(manifest: Path) -> None:
    m = json.loads(manifest.read_text())
    for key in ("algo", "seed", "timesteps", "wall_time_s", "versions", "sha256", "training_command", "env_id"):
        assert key in m, key
    assert m["env_id"] == "AmigoBot-v1" and m["algo"] in manifest.parent.name
    assert hashlib.sha256(manifest.with_suffix(".zip").read_bytes()).hexdigest() == m["sha256"]
    assert "--env AmigoBot-v1" in m["training_command"] and f"--seed {m['seed']}" in m["training_command"]


CLAIMED = [m for m in MANIFESTS if "claimed" in json.loads(m.read_text())]


@pytest.mark.parametrize("manifest", CLAIMED, ids=[m.stem for m in CLAIMED])
def test_benchmark_reproduces_claimed_numbers(manifest: Path) -> None:
    m = json.loads(manifest.read_text())
    claimed = m["claimed"]
    assert claimed["suite_version"] == bm.SUITE_VERSION
    scenarios = [sc for sc in bm.SUITE if sc.name in RERUN and sc.name in claimed["scenarios"]]
    assert scenarios
    spec = bm.parse_agents([str(manifest.with_suffix(".zip"))])[0]
    import torch

    threads = torch.get_num_threads()  # other tests may have changed it: the last bits depend on it
    torch.set_num_threads(int(claimed["torch_threads"]))
    try:
        doc = bm.run_benchmark([spec], scenarios, progress=False, reps=100, profile_reps=10)
    finally:
        torch.set_num_threads(threads)
    for r in doc["results"]:
        want = claimed["scenarios"][r["scenario"]]
        for key in KEYS:
            assert r[key] == want[key], (r["scenario"], key, r[key], want[key])  # exactly
