"""Failure rate per curvature bin (tools/training/curvature.py, ``amigo-gym benchmark --curvature``); tiny budgets.

References: the Wilson interval's closed forms, hand-made episodes for the binning, and the cells' paths rebuilt
independently from their seeds with :func:`amigo_gym.paths.random_path` (curvature read from the segments)."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from amigo_gym.paths import random_path
from amigo_gym.task.v1 import feasible_random_curvature
from amigo_gym.tools.training.curvature import (
    BIN_EDGES,
    bin_table,
    cell_specs,
    evaluate_tagged,
    markdown_curvature,
)
from amigo_gym.tools.training.intervals import Z95, wilson_interval


def _seg_max(path: object) -> float:
    return max(max(abs(g.curvature), abs(g.curvature + g.curvature_rate * g.length)) for g in path.segments)  # type: ignore[attr-defined]


def _seg_kappa(path: object, s: float) -> float:
    """kappa at arc length s from the segments (kappa0 + rate (s - s0) on the segment holding s)."""
    s0 = 0.0
    segs = path.segments  # type: ignore[attr-defined]
    for g in segs:
        if s <= s0 + g.length:
            return float(g.curvature + g.curvature_rate * (s - s0))
        s0 += g.length
    g = segs[-1]
    return float(g.curvature + g.curvature_rate * g.length)


# --------------------------------------------------------------------------- Wilson
def test_wilson_interval_closed_forms() -> None:
    zz = Z95 * Z95
    assert wilson_interval(0, 10) == pytest.approx((0.0, zz / (10 + zz)), abs=1e-15)
    assert wilson_interval(10, 10) == pytest.approx((10 / (10 + zz), 1.0), abs=1e-15)
    lo, hi = wilson_interval(5, 10)
    assert (lo + hi) / 2 == pytest.approx(0.5, abs=1e-15)
    assert (lo, hi) == pytest.approx((0.2366, 0.7634), abs=1e-4)  # the textbook value of 5/10
    assert all(math.isnan(x) for x in wilson_interval(0, 0))
    with pytest.raises(ValueError, match="failures"):
        wilson_interval(11, 10)


# --------------------------------------------------------------------------- binning
def test_bin_table_on_hand_made_episodes() -> None:
    def ep(agent: str, v: float, k: float, fail: bool, k_end: float = 0.0) -> dict[str, object]:
        return {"agent": agent, "speed": v, "k_limit": 4.0, "path_max_kappa": k, "failure": fail, "kappa_end": k_end}

    eps = [
        ep("a", 0.4, 0.5, False),
        ep("a", 0.4, 0.99, True, 0.9),  # x = 0.2475: bin 0
        ep("a", 0.4, 1.0, False),  # x = 0.25 exactly: bin 1 (left-closed)
        ep("a", 0.4, 3.0, True, 2.0),  # x = 0.75: bin 3
        ep("a", 0.4, 3.9, True, 3.5),
        ep("a", 0.4, 4.0, False),  # x = 1: the last bin is closed
        ep("b", 0.4, 2.5, True, 1.0),
    ]
    rows = bin_table(eps)
    a = [r for r in rows if r["agent"] == "a"]
    assert [r["n"] for r in a] == [2, 1, 0, 3]
    assert [r["failures"] for r in a] == [1, 0, 0, 2]
    assert a[0]["rate"] == 0.5 and a[2]["rate"] is None and a[3]["rate"] == pytest.approx(2 / 3)
    assert a[3]["ci95"] == pytest.approx(list(wilson_interval(2, 3)))
    assert a[3]["kappa_end_failed"] == pytest.approx(2.75)  # median of 2.0 and 3.5
    assert (a[1]["kappa_lo"], a[1]["kappa_hi"]) == (1.0, 2.0)
    b = [r for r in rows if r["agent"] == "b"]
    assert [r["n"] for r in b] == [0, 0, 1, 0]
    with pytest.raises(ValueError, match="outside"):
        bin_table([ep("a", 0.4, 4.1, False)])
    md = markdown_curvature({"table": rows, "protocol": {"failure": "f"}})
    assert "0.667 [" in md and "(2/3)" in md and "[3.00, 4.00]" in md


# --------------------------------------------------------------------------- the cells
def test_cells_follow_the_feasible_limit_and_the_env_accepts_them() -> None:
    cells = cell_specs(episodes=3)
    assert [c.name for c in cells] == [f"curv_v{v:g}_k{j}" for v in (0.1, 0.4) for j in (1, 2, 3, 4)]
    for c in cells:
        v = c.env_kwargs["speed"]
        j = int(c.name[-1])
        k = c.env_kwargs["path_params"]["max_curvature"]
        assert k == pytest.approx(feasible_random_curvature(v) * j / 4, rel=1e-15)
        assert c.env_kwargs["path_params"]["max_curvature_rate"] == k
        assert c.seeds == (100, 101, 102) and c.max_steps == 600
        gym.make("AmigoBot-v1", **c.env_kwargs).close()  # feasibility="error": refused if infeasible
    with pytest.raises(ValueError, match="episodes"):
        cell_specs(episodes=0)


@pytest.mark.parametrize("cell", [3, 7])  # the sharpest level at 0.1 and at 0.4 m/s
def test_cells_paths_have_the_claimed_curvature(cell: int) -> None:
    sc = cell_specs(episodes=12)[cell]
    pp = sc.env_kwargs["path_params"]
    venv = gym.make_vec("AmigoBot-v1", num_envs=12, **sc.env_kwargs)
    venv.reset(seed=list(sc.seeds))
    u = venv.unwrapped
    for i, info in enumerate(u.path_infos):  # type: ignore[attr-defined]
        ref = random_path(np.random.default_rng(info["id"]), **pp)
        assert u.paths[i].segments == ref.segments  # type: ignore[attr-defined]
        assert _seg_max(ref) <= pp["max_curvature"] * (1 + 1e-12)
        assert ref.length == pytest.approx(pp["length"])
    assert max(_seg_max(p) for p in u.paths.paths) > 0.5 * pp["max_curvature"]  # type: ignore[attr-defined]
    assert any(info["id"] >= 1024 for info in u.path_infos)  # type: ignore[attr-defined]
    venv.close()


def test_tags_of_a_run_match_the_paths_rebuilt_independently() -> None:
    from amigo_gym.tools.training.benchmark import make_env, parse_agents

    sc = replace(cell_specs(episodes=3)[7], max_steps=80)
    env = make_env(sc)
    agent = parse_agents(["analytic"])[0].instantiate(env)
    eps = evaluate_tagged(agent, sc)
    pp = sc.env_kwargs["path_params"]
    assert len(eps) == 3
    for e in eps:
        ref = random_path(np.random.default_rng(e["path_id"]), **pp)
        assert e["path_max_kappa"] == pytest.approx(_seg_max(ref), rel=1e-12)
        assert e["kappa_end"] == pytest.approx(abs(_seg_kappa(ref, e["progress_end"])), rel=1e-9, abs=1e-12)
        assert 0.0 < e["progress_end"] < 0.4 * 8.0 + 0.2  # H covered at most about v t in 8 s
        assert e["failure"] in (0.0, 1.0)


def test_cli_curvature_quick(tmp_path: Path) -> None:
    from amigo_gym.tools.training.benchmark import main

    assert main(["--curvature", "--quick", "--agents", "analytic", "--out", str(tmp_path), "--no-progress"]) == 0
    doc = json.loads((tmp_path / "curvature.json").read_text())
    assert len(doc["episodes"]) == 16 and len(doc["table"]) == 2 * (len(BIN_EDGES) - 1)
    assert sum(r["n"] for r in doc["table"]) == 16
    assert "Failure rate per curvature bin" in (tmp_path / "curvature.md").read_text()
    assert main(["--curvature", "--scenarios", "figure8", "--out", str(tmp_path)]) == 2
