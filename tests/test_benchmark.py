"""The benchmark: rliable statistics against closed forms, task metrics, the suite, the CLI on v0 and a fake v1."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

import amigo_gym  # noqa: F401
from amigo_gym.tools.training import benchmark as bm
from amigo_gym.tools.training.intervals import (
    iqm,
    optimality_gap,
    score_distribution,
    stratified_bootstrap,
)
from amigo_gym.tools.training.task_metrics import InfoAdapter, episode_metrics

ROOT = Path(__file__).resolve().parents[1]


# --------------------------------------------------------------------------- statistics (rliable definitions)
@pytest.mark.parametrize("shape", [(1, 1), (3, 1), (5, 7), (10, 3), (4, 4)])
def test_iqm_is_scipy_trim_mean(shape: tuple[int, int]) -> None:
    x = np.random.default_rng(1).normal(size=shape)
    assert iqm(x) == pytest.approx(stats.trim_mean(x, proportiontocut=0.25, axis=None), abs=1e-15)


def test_iqm_closed_form_and_batched() -> None:
    x = np.arange(1.0, 9.0).reshape(2, 4)  # 8 scores: drop 2 at each end -> mean(3..6) = 4.5
    assert float(iqm(x)) == 4.5
    batch = np.stack([x, 2 * x])
    np.testing.assert_allclose(iqm(batch), [4.5, 9.0])


def test_optimality_gap_closed_form() -> None:
    x = np.array([[0.5, 1.2], [0.9, 1.0]])
    assert float(optimality_gap(x)) == pytest.approx(1 - (0.5 + 1.0 + 0.9 + 1.0) / 4)
    # lower-is-better metric h with target g: gap of -h at -g is mean(max(h - g, 0))
    h = np.array([[0.004, 0.02], [0.03, 0.0]])
    assert float(optimality_gap(-h, -0.01)) == pytest.approx(np.mean(np.maximum(h - 0.01, 0)))


def test_score_distribution_definition() -> None:
    x = np.array([[0.1, 0.5], [0.9, 0.3]])
    np.testing.assert_allclose(score_distribution(x, [0.0, 0.2, 0.4, 1.0]), [1.0, 0.75, 0.5, 0.0])


def test_bootstrap_is_stratified_and_reproducible() -> None:
    # one run per task, or identical runs within every task: every resample is the data -> zero width
    single = np.array([[1.0, 2.0, 5.0]])
    pt, ci = stratified_bootstrap(single, iqm, reps=200)
    assert ci[0] == ci[1] == pt
    same_per_task = np.tile([[1.0, 4.0, 9.0]], (5, 1))
    pt, ci = stratified_bootstrap(same_per_task, iqm, reps=200)
    assert ci[0] == ci[1] == pt
    x = np.random.default_rng(0).normal(size=(5, 8))
    a = stratified_bootstrap(x, iqm, reps=500, seed=3)
    b = stratified_bootstrap(x, iqm, reps=500, seed=3)
    np.testing.assert_array_equal(a[1], b[1])


def test_bootstrap_of_the_mean_matches_the_normal_approximation() -> None:
    # rliable's documented example: StratifiedBootstrap(x).conf_int(np.mean), x standard normal (5, 50).
    # Stratified resampling of runs within tasks: Var(mean*) = sum_m s_m^2 / (N M^2), s_m^2 the plug-in
    # variance of task m's N runs. The percentile interval is then mean +- 1.96 sd (CLT over 50 tasks).
    x = np.random.default_rng(1234).standard_normal((5, 50))
    pt, ci = stratified_bootstrap(x, lambda s: np.mean(s, axis=(-2, -1)), reps=20_000, seed=0)
    sd = math.sqrt(np.sum(np.var(x, axis=0)) / (5 * 50**2))
    assert float(pt) == pytest.approx(x.mean())
    assert ci[0] == pytest.approx(x.mean() - 1.96 * sd, abs=0.05 * sd + 1e-3)
    assert ci[1] == pytest.approx(x.mean() + 1.96 * sd, abs=0.05 * sd + 1e-3)


def test_performance_profile_shapes_and_band() -> None:
    x = np.random.default_rng(2).uniform(size=(4, 6))
    taus = np.linspace(0, 1, 11)
    prof, band = stratified_bootstrap(x, lambda s: score_distribution(s, taus), reps=300, seed=0)
    assert prof.shape == (11,) and band.shape == (2, 11)
    assert np.all(band[0] <= prof + 1e-12) and np.all(prof <= band[1] + 1e-12)
    assert prof[0] == 1.0 and prof[-1] == 0.0


def test_statistics_refuse_bad_input() -> None:
    with pytest.raises(ValueError, match="finite"):
        stratified_bootstrap(np.array([[np.nan]]), iqm)
    with pytest.raises(ValueError, match="matrix"):
        stratified_bootstrap(np.zeros(3), iqm)
    with pytest.raises(ValueError, match="reps"):
        stratified_bootstrap(np.zeros((2, 2)), iqm, reps=0)


# --------------------------------------------------------------------------- task metrics
def test_episode_metrics_closed_form() -> None:
    e = np.array([0.3, -0.2, 0.05, 0.0])
    cmd = np.array([[1.0, 1.0], [2.0, 1.0], [2.0, 1.0], [2.0, 3.0]])
    m = episode_metrics(
        e, np.array([0.1, 0.0, 0.0, 0.0]), cmd, cmd, np.ones(4), dt=0.5, terminated=False, settle_time_s=1.5
    )
    assert m["h_rms_m"] == pytest.approx(math.sqrt((0.09 + 0.04 + 0.0025) / 4))
    assert m["h_rms_settled_m"] == pytest.approx(math.sqrt(0.0025 / 2))  # t = 1.5, 2.0
    assert m["h_max_m"] == 0.3 and m["return"] == 4.0 and m["failure"] == 0.0
    assert m["chatter_rms"] == pytest.approx(math.sqrt((1 + 0 + 0 + 0 + 0 + 4) / 6))
    assert m["chatter_settled_rms"] == pytest.approx(math.sqrt((0 + 0 + 0 + 4) / 4))
    assert m["speed_err_rms"] == pytest.approx(0.05)
    bad = episode_metrics(e * 10, e, cmd, cmd, np.ones(4), dt=0.5, terminated=False, settle_time_s=1.5)
    assert bad["failure"] == 1.0  # settled |e| = 0.5 m > 0.1 m
    term = episode_metrics(e, e, cmd, cmd, np.ones(4), dt=0.5, terminated=True)
    assert term["failure"] == 1.0 and math.isnan(term["h_rms_settled_m"])


def test_info_adapter_v0_and_v1() -> None:
    env = gym.make("AmigoBot-v0", speed=0.3)
    ad = InfoAdapter.for_env(env)
    r = env.unwrapped.params.robot  # type: ignore[attr-defined]
    s = ad.read({"cross_track_error": 0.01, "wheel_rates": np.array([6.0, 5.0])})
    assert s.speed_error == pytest.approx(0.5 * (r.r1 * 6 + r.r2 * 5) - 0.3)
    assert s.command == (6.0, 5.0)
    v1 = ad.read({"cross_track_error": 0.0, "wheel_rates": [1, 2], "command": [3, 4], "speed_error": -0.02})
    assert v1.speed_error == -0.02 and v1.command == (3.0, 4.0) and v1.wheel_rates == (1.0, 2.0)
    env.close()


# --------------------------------------------------------------------------- the suite
def test_suite_is_versioned_data_with_required_coverage() -> None:
    names = [sc.name for sc in bm.SUITE]
    assert len(set(names)) == len(names)
    assert all(sc.version == bm.SUITE_VERSION for sc in bm.SUITE)
    assert bm.SUITES[bm.SUITE_VERSION] is bm.SUITE
    v1 = [sc for sc in bm.SUITE if sc.env_id == "AmigoBot-v1"]
    kw = [dict(sc.env_kwargs) for sc in v1]
    assert {k.get("path") for k in kw} >= {"circle", "manoeuvre", "figure8", "lane_change", "random", "mixed"}
    assert {k.get("dt") for k in kw} >= {0.05, 0.2}
    assert {k.get("direction") for k in kw if k.get("path") == "circle"} >= {1, -1}
    assert {k.get("speed") for k in kw} >= {0.1, 0.4}
    assert any(k.get("speed_profile") == "trapezoid" for k in kw)
    assert any("true_robot" in k for k in kw)
    rand = [k["randomize"] for k in kw if isinstance(k.get("randomize"), dict)]
    for field in ("slip", "delay", "position_noise"):
        assert any(field in r for r in rand), field
    assert any(sc.held_out for sc in bm.SUITE) and not all(sc.held_out for sc in bm.SUITE)
    assert any(sc.env_id == "AmigoBot-v0" and not sc.env_kwargs for sc in bm.SUITE)  # the paper's circle on v0
    for sc in bm.SUITE:  # the mapping kwargs are valid Randomization ranges
        r = sc.env_kwargs.get("randomize")
        if isinstance(r, dict):
            from amigo_gym.model.randomization import make_randomization

            make_randomization(r)
    json.dumps([sc.to_json() for sc in bm.SUITE])


def test_scenario_validation() -> None:
    with pytest.raises(ValueError, match="seeds"):
        bm.Scenario("x", "AmigoBot-v0", seeds=())
    with pytest.raises(ValueError, match="distinct"):
        bm.Scenario("x", "AmigoBot-v0", seeds=(1, 1))
    with pytest.raises(ValueError, match="max_steps"):
        bm.Scenario("x", "AmigoBot-v0", max_steps=0)


# --------------------------------------------------------------------------- runs
class _FakeV1(gym.Wrapper[Any, Any, Any, Any]):
    """AmigoBot-v0 reporting v1-style info (command, actual rates lagging, speed error) and a stateful agent."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(gym.make("AmigoBot-v0", **kwargs).env)  # type: ignore[attr-defined]

    def step(self, action: Any) -> Any:
        obs, r, term, trunc, info = self.env.step(action)
        info = dict(info)
        info["command"] = info["wheel_rates"]
        info["wheel_rates"] = 0.9 * info["wheel_rates"]
        info["speed_error"] = 0.01
        return obs, r, term, trunc, info


class _CountingAgent:
    """A stateful policy: counts steps since the episode start (integral action would keep its integral)."""

    def __init__(self) -> None:
        from amigo_gym.policies.analytic import AnalyticPolicy
        from amigo_gym.task.v1 import TrackingParams

        self.inner = AnalyticPolicy(TrackingParams.v0())
        self.starts = 0

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> Any:
        """SB3's batched interface: ``observation (N, d)``, ``episode_start (N,)``, ``state (N,)`` step counts."""
        obs = np.atleast_2d(observation)
        starts = np.ones(len(obs), dtype=bool) if episode_start is None else np.asarray(episode_start, dtype=bool)
        self.starts += int(starts.sum())
        count = np.zeros(len(obs), dtype=np.int64) if state is None else np.asarray(state).copy()
        count[starts] = 0
        action, _ = self.inner.predict(obs)
        return action, count + 1


@pytest.fixture(scope="module")
def fake_v1() -> str:
    env_id = "AmigoBotFakeBench-v1"
    if env_id not in gym.registry:
        gym.register(env_id, entry_point=_FakeV1, max_episode_steps=400)
    return env_id


def test_run_benchmark_on_v0_and_fake_v1(fake_v1: str, tmp_path: Path) -> None:
    scenarios = (
        bm.Scenario("v0_circle", "AmigoBot-v0", seeds=(100, 101), max_steps=80),
        bm.Scenario("fake_v1", fake_v1, {"speed": 0.3}, seeds=(5,), max_steps=60, held_out=True),
        bm.Scenario("missing", "AmigoBot-v77", {"path": "circle"}, seeds=(1,), max_steps=10),
        bm.Scenario("bad_kwargs", "AmigoBot-v0", {"no_such_setting": 1}, seeds=(1,), max_steps=10),
    )
    counting = _CountingAgent()
    bm.CLASSICAL["counting"] = lambda env: counting
    try:
        agents = [bm.AgentSpec("analytic"), bm.AgentSpec("counting"), bm.AgentSpec("pure_pursuit")]
        doc = bm.run_benchmark(agents, scenarios, progress=False, reps=200, profile_reps=50)
    finally:
        del bm.CLASSICAL["counting"]
    assert counting.starts == 3  # episode_start passed through: 2 + 1 episodes
    recs = {(r["agent"], r["scenario"]): r for r in doc["results"]}
    assert set(recs) == {(a, s) for a in ("analytic", "counting") for s in ("v0_circle", "fake_v1")}
    for r in doc["results"]:
        for key in ("agent", "seed", "scenario", "h_rms_m", "speed_err_rms", "failure_rate", "return"):
            assert key in r
    assert recs[("analytic", "fake_v1")]["speed_err_rms"] == pytest.approx(0.01)  # v1 info used as is
    assert recs[("analytic", "v0_circle")]["speed_err_rms"] < 1e-6  # v0: from the wheel rates
    assert recs[("analytic", "v0_circle")]["episodes"] == 2
    status = {s["name"]: s["status"] for s in doc["scenarios"]}
    assert status["missing"] == "unavailable: environment AmigoBot-v77 is not registered"
    assert status["bad_kwargs"].startswith("unavailable: gym.make")
    reasons = {(u["agent"], u["scenario"]) for u in doc["unavailable"]}
    assert {(None, "missing"), (None, "bad_kwargs"), ("pure_pursuit", "v0_circle")} <= reasons
    agg = doc["aggregates"]["analytic"]
    assert agg["metric"] == "h_rms_m" and agg["ci95"][0] <= agg["iqm"] <= agg["ci95"][1]
    assert agg["held_out"]["scenarios"] == ["fake_v1"] and agg["in_distribution"]["scenarios"] == ["v0_circle"]
    assert set(doc["performance_profiles"]["agents"]) == {"analytic", "counting"}
    paired = doc["paired"]  # the agent against the analytic controller on the cells where both ran
    assert (paired["baseline"], paired["reps"], set(paired["agents"])) == ("analytic", 200, {"counting"})
    cells = {c["scenario"]: c for c in paired["agents"]["counting"]["cells"]}
    assert set(cells) == {"v0_circle", "fake_v1"} and cells["v0_circle"]["episodes"] == 2
    base = [1e3 * h for h in recs[("analytic", "v0_circle")]["per_episode"]["h_rms_m"]]
    agent = [1e3 * h for h in recs[("counting", "v0_circle")]["per_episode"]["h_rms_m"]]
    assert cells["v0_circle"]["diff_mm"] == pytest.approx(np.mean(agent) - np.mean(base), rel=1e-12, abs=1e-12)
    md = bm.markdown_report(doc)
    assert "Unavailable" in md and "AmigoBot-v77" in md
    assert "## Paired difference to the analytic controller" in md and "| counting | fake_v1 | yes |" in md
    written = bm.write_outputs(doc, tmp_path, tmp_path / "b.json", tmp_path / "b.md")
    assert all(p.is_file() and p.stat().st_size > 0 for p in written)
    json.loads((tmp_path / "b.json").read_text())


# --------------------------------------------------------------------------- paired difference to the analytic
def _paired_doc(base_mm: list[float], seeds_mm: dict[int, list[float]], agent: str = "a") -> dict[str, Any]:
    """A benchmark document of one cell ``c``: the analytic controller's and ``agent``'s episodes [mm]."""

    def rec(name: str, seed: int, mm: list[float]) -> dict[str, Any]:
        per = {"h_rms_m": [x / 1e3 for x in mm], "failure": [float(x > 9.0) for x in mm]}
        return {"agent": name, "seed": seed, "scenario": "c", "chatter_settled_rms": 0.5 + seed, "per_episode": per}

    results = [rec("analytic", 0, base_mm)] + [rec(agent, s, mm) for s, mm in seeds_mm.items()]
    results.append(rec(agent, 0, [1.0]) | {"scenario": "only_agent"})  # no analytic run there: not paired
    scenarios = [{"name": n, "held_out": n == "c"} for n in ("only_agent", "c")]
    return {"scenarios": scenarios, "results": results}


def test_paired_difference_closed_form() -> None:
    """Agent minus analytic per episode, averaged over the training seeds: with offsets +0.1 and +0.3 mm on every
    episode of a very spread analytic controller, Δ = +0.2 mm exactly and its paired interval has zero width (an
    unpaired or seed-pooled bootstrap would be wide); the ratio, failures and trimmed means are the closed forms."""
    base = [1.0, 5.0, 2.0, 9.5, 3.0]
    doc = _paired_doc(base, {1: [x + 0.1 for x in base], 0: [x + 0.3 for x in base]})
    p = bm.paired_differences(doc, reps=500, seed=3)
    assert (p["baseline"], p["unit"], p["reps"], p["seed"], list(p["agents"])) == ("analytic", "mm", 500, 3, ["a"])
    (c,) = p["agents"]["a"]["cells"]  # the cell without an analytic run is left out
    assert (c["scenario"], c["held_out"], c["seeds"], c["episodes"]) == ("c", True, [0, 1], 5)
    assert c["diff_mm"] == pytest.approx(0.2, abs=1e-12)
    assert c["diff_ci95_mm"] == pytest.approx([0.2, 0.2], abs=1e-12)
    assert c["baseline_mm"] == pytest.approx(4.1) and c["agent_mm"] == pytest.approx(4.3)
    assert c["agent_seeds_mm"] == pytest.approx([4.4, 4.2])  # sorted by training seed
    assert c["ratio"] == pytest.approx(4.3 / 4.1) and c["chatter_settled_rms"] == pytest.approx(1.0)
    assert (c["failed"], c["agent_episodes"], c["baseline_failed"]) == (2, 10, 1)  # 9.5 + 0.1, 9.5 + 0.3 > 9
    assert c["baseline_ci95_mm"][1] - c["baseline_ci95_mm"][0] > 1.0 and c["overlap"]  # the marginal is wide
    assert p["agents"]["a"]["trimmed_mean_mm"] == pytest.approx({"baseline": 4.1, "agent": 4.3})
    md = "\n".join(bm.paired_lines(p))
    assert "| a | c | yes | 4.10 | 4.30 | 1.05 | +0.20 [+0.20, +0.20] | 2 of 10 | 1 of 5 |" in md
    assert "- `a`: interval below 0 on 0, above 0 on 1 of 1 cells" in md
    assert bm.paired_lines(bm.paired_differences(_paired_doc(base, {}))) == []  # the analytic controller alone


def test_paired_difference_bootstrap_percentiles_and_determinism() -> None:
    """Differences (0, 1) mm: resampled means 0, 0.5, 1 with probabilities 1/4, 1/2, 1/4, so the 2.5 and 97.5
    percentiles are 0 and 1; the agent's sign is kept; the same seed gives the same document."""
    doc = _paired_doc([2.0, 4.0], {7: [1.0, 4.0]})  # agent - analytic = (-1, 0)
    p = bm.paired_differences(doc, reps=2_000, seed=0)
    (c,) = p["agents"]["a"]["cells"]
    assert c["diff_mm"] == pytest.approx(-0.5) and c["diff_ci95_mm"] == pytest.approx([-1.0, 0.0])
    assert p == bm.paired_differences(doc, reps=2_000, seed=0)
    short = _paired_doc([2.0, 4.0], {7: [1.0]})  # other episode counts: not paired
    assert bm.paired_differences(short)["agents"] == {}


def test_paired_difference_reproduces_paired_cells_on_the_committed_suite() -> None:
    """The numbers experiments/paired_cells.py printed before it read them from the package (12 decimals)."""
    doc = json.loads((ROOT / "docs/benchmark/suite_2.0/benchmark.json").read_text())
    entry = bm.paired_differences(doc)["agents"]["compensator_residual_v1"]
    cells = {c["scenario"]: c for c in entry["cells"]}
    assert len(cells) == 12
    c = cells["wheels_unequal7"]
    assert c["baseline_mm"] == pytest.approx(3.393459670349, abs=1e-11)
    assert c["agent_seeds_mm"] == pytest.approx([1.189551607061, 1.261602464769, 1.213295548962], abs=1e-11)
    assert c["diff_mm"] == pytest.approx(-2.171976463418, abs=1e-11)
    assert c["diff_ci95_mm"] == pytest.approx([-2.300529993050, -2.036903576109], abs=1e-11)
    assert c["baseline_ci95_mm"] == pytest.approx([3.254268561476, 3.550364810797], abs=1e-11)
    assert c["agent_ci95_mm"] == pytest.approx([1.107907673231, 1.332828842991], abs=1e-11)
    assert cells["noise_2x"]["diff_ci95_mm"] == pytest.approx([-0.015749125832, -0.001594231658], abs=1e-11)
    assert entry["trimmed_mean_mm"] == pytest.approx({"baseline": 1.399899117127, "agent": 1.017417962981}, abs=1e-11)


def test_parse_agents(tmp_path: Path) -> None:
    assert [a.name for a in bm.parse_agents(["analytic", "analytic_ff"])] == ["analytic", "analytic_ff"]
    with pytest.raises(ValueError, match="unknown classical"):
        bm.parse_agents(["nonsense"])
    with pytest.raises(FileNotFoundError):
        bm.parse_agents([f"sac={tmp_path}/*.zip"])
    d = tmp_path / "v1" / "ppo"
    d.mkdir(parents=True)
    for s in (3, 7):
        (d / f"seed_{s}.zip").write_bytes(b"x")
    specs = bm.parse_agents([str(tmp_path / "v1")])
    assert [(a.name, a.seed, a.algo) for a in specs] == [("ppo", 3, "ppo"), ("ppo", 7, "ppo")]
    (d / "seed_7.json").write_text(json.dumps({"algo": "ppo", "seed": 11}))
    specs = bm.parse_agents([f"gen={d}/*.zip"])
    assert [(a.name, a.seed) for a in specs] == [("gen", 3), ("gen", 11)]


def test_default_agents_include_the_fast_ppo_generalist_labelled_apart_from_sb3s() -> None:
    """The shipped fast-PPO seeds are default agents (``ppo_fast_v1``, algorithm ``fastppo`` from the manifest, five
    training seeds, sha256 in the manifest), beside the SB3 generalist (``td3lp_v1``) and the residual, the retired
    SB3 references (``ppo_v1``, ``sac_v1``, ``td3_v1``) are not, and every label tells them apart."""
    specs = bm.default_agents()
    fast = [a for a in specs if a.name == "ppo_fast_v1"]
    assert sorted(a.seed for a in fast) == [0, 1, 2, 3, 4]
    assert all(a.algo == "fastppo" and (a.manifest or {}).get("agent") == "ppo_fast" for a in fast)
    assert all(a.path is not None and a.path.endswith(f"ppo_fast/ppo_fast_s{a.seed}.zip") for a in fast)
    assert {a.name for a in specs} >= {"td3lp_v1", "ppo_fast_v1", "residual_v1"}
    assert not {a.name for a in specs} & {"ppo_v1", "sac_v1", "td3_v1"}  # retired: not shipped, not benchmarked
    assert set(bm.RETIRED_V1_AGENTS) == {"ppo", "sac", "td3"} and not set(bm.RETIRED_V1_AGENTS) & set(bm.V1_AGENTS)
    assert bm.agent_label("ppo_fast_v1") == "fast PPO generalist"
    # a retired generalist (restored from git history, or in an older benchmark document) keeps its label
    assert bm.agent_label("ppo_v1") == "SB3 PPO generalist" and bm.agent_label("sac_v1", "sac") == "SB3 SAC generalist"
    assert bm.agent_label("mine", "fastppo") == "fast PPO" and bm.agent_label("mine", "ppo") == "SB3 PPO"
    assert bm.agent_label("mine", "fastppo_residual") == "fast PPO residual" and bm.agent_label("x") == "model"
    assert bm.agent_label("ppo_v0") == "SB3 PPO v0 specialist" and bm.agent_label("analytic") == "classical"
    assert bm.agent_label("ppo_v1", "fastppo") == "fast PPO generalist"  # the manifest's algorithm decides
    assert bm.agent_label("robust_residual_v1", "fastppo_residual") == "fast PPO robust residual generalist"
    # a variant of the manifest's algorithm keeps its folder's label; another algorithm's zip under it does not
    assert bm.agent_label("td3lp_v1", "td3") == "SB3 TD3 low-pass generalist"
    assert bm.agent_label("td3lp_v1", "sac") == "SB3 SAC generalist"
    assert ("ppo_fast_v1", "fast PPO") in bm.README_ROWS and ("td3lp_v1", "SB3 TD3 low-pass") in bm.README_ROWS
    assert not {name for name, _ in bm.README_ROWS} & {"ppo_v1", "sac_v1", "td3_v1"}  # the README shows what ships
    # it runs, and the report's legend names it: one short episode
    sc = bm.Scenario("tiny_circle", "AmigoBot-v1", {"path": "circle", "radius": 1.0, "speed": 0.2}, (3,), 30)
    doc = bm.run_benchmark([bm.AgentSpec("analytic"), fast[0]], [sc], progress=False, reps=50, profile_reps=10)
    assert not doc["unavailable"] and {r["agent"] for r in doc["results"]} == {"analytic", "ppo_fast_v1"}
    assert "`ppo_fast_v1`: fast PPO generalist" in bm.markdown_report(doc)


def test_cli_quick(tmp_path: Path) -> None:
    sac = ROOT / "agents" / "pretrained" / "sac.zip"
    cmd = [sys.executable, "-m", "amigo_gym.tools.cli", "benchmark", "--quick", "--out", str(tmp_path), "--reps", "500"]
    cmd += ["--agents", "analytic", f"sac_v0={sac}"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    doc = json.loads((tmp_path / "benchmark.json").read_text())
    assert doc["quick"] and doc["suite_version"] == bm.SUITE_VERSION
    assert {r["agent"] for r in doc["results"]} == {"analytic", "sac_v0"}
    assert {(r["agent"], r["scenario"]) for r in doc["results"]} == {
        ("analytic", "v0_paper_circle"),
        ("analytic", "v0_speed_0.4"),
        ("analytic", "circle_r1_ccw"),  # AmigoBot-v1's analytic tracking policy
        ("sac_v0", "v0_paper_circle"),
        ("sac_v0", "v0_speed_0.4"),
    }
    # the v0 specialist cannot read v1's observation: reported, not dropped
    assert any(u["scenario"] == "circle_r1_ccw" and u.get("agent") == "sac_v0" for u in doc["unavailable"])
    assert "circle_r1_ccw" in r.stdout
    sac_rec = next(a for a in doc["agents"] if a["agent"] == "sac_v0")
    assert sac_rec["seed"] == 0 and len(sac_rec["sha256"]) == 64
    for f in ("benchmark.md", "benchmark_scenarios.png", "benchmark_profiles.png"):
        assert (tmp_path / f).is_file()
    assert "benchmark" in r.stderr  # the progress bar


def test_cli_list_and_errors(tmp_path: Path) -> None:
    r = subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "benchmark", "--list"], capture_output=True, text=True
    )
    assert r.returncode == 0 and "v0_paper_circle" in r.stdout and "held out" in r.stdout
    r = subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "benchmark", "--scenarios", "nope", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1 and "unknown" in r.stderr


# --------------------------------------------------------------------------- learning curves: task metrics in training
def test_training_logs_task_metrics_and_after_eval_can_stop(tmp_path: Path) -> None:
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    from amigo_gym.tools.training.train import Settings, train

    hp = tmp_path / "tiny.yml"
    hp.write_text("AmigoBot-v0:\n  n_steps: 32\n  batch_size: 32\n  n_epochs: 1\n  policy_kwargs:\n    net_arch: [8]\n")
    seen: list[dict[str, Any]] = []

    def stop_after_first(entry: dict[str, Any]) -> bool:
        seen.append(entry)
        return False

    s = Settings(
        algo="ppo",
        out=str(tmp_path / "run"),
        timesteps=256,
        eval_freq=32,
        eval_episodes=2,
        checkpoint_freq=0,
        progress=False,
        hyperparams=str(hp),
    )
    record = train(s, after_eval=stop_after_first)
    assert len(seen) == 1 and record["timesteps"] < 256  # the hook stopped training after one evaluation
    entry = json.loads((tmp_path / "run" / "eval.json").read_text())[0]
    for key in ("h_rms_m", "h_rms_settled_m", "speed_err_rms", "failure_rate", "wall_time_s"):
        assert key in entry and math.isfinite(entry[key]), key
    assert 0.0 <= entry["failure_rate"] <= 1.0
    events = list((tmp_path / "run" / "tb").rglob("events.out.tfevents.*"))
    ea = EventAccumulator(str(events[0]))
    ea.Reload()
    for tag in ("eval/h_rms_m", "eval/speed_err_rms", "eval/failure_rate", "eval/mean_reward"):
        assert tag in ea.Tags()["scalars"], tag


def _bench(out: Path, fault: str | None = None) -> subprocess.CompletedProcess[str]:
    import os

    env = dict(os.environ, PYTHONWARNINGS="ignore")
    env.pop("AMIGO_GYM_FAULT", None)
    if fault is not None:
        env["AMIGO_GYM_FAULT"] = fault
    args = ["--agents", "analytic", "--scenarios", "v0_paper_circle", "--quick", "--reps", "20"]
    args += ["--profile-reps", "20", "--no-progress", "--out", str(out)]
    return subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "benchmark", *args],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_outputs_are_published_as_one_set_temporaries_cleaned_and_out_locked(tmp_path: Path) -> None:
    from amigo_gym.tools import runs

    out = tmp_path / "bench"
    killed = _bench(out, "publish:benchmark.md")  # the JSON and the Markdown moved, the plots not, no manifest
    assert killed.returncode == -9, killed.stderr[-2000:]
    assert (out / "benchmark.json").is_file() and not (out / bm.MANIFEST).exists()
    with pytest.raises(FileNotFoundError, match="not a complete set"):
        bm.verify_outputs(out)
    assert [p for p in out.iterdir() if p.name.startswith(".staging-benchmark-")]
    (out / ".benchmark.k2j4.json").write_text("{")  # what a kill inside an atomic write leaves
    (out / ".mine").write_text("a user's file")
    with runs.RunLock(out):  # a second benchmark on the same --out is refused while one runs
        second = _bench(out)
    assert second.returncode == 2 and "in use by another amigo-gym process" in second.stderr, second.stderr
    ok = _bench(out)
    assert ok.returncode == 0, ok.stderr[-2000:]
    files = bm.verify_outputs(out)
    assert set(files) == {"benchmark.json", "benchmark.md", "benchmark_scenarios.png", "benchmark_profiles.png"}
    assert not [p.name for p in out.iterdir() if p.name.startswith((".staging", ".benchmark"))]
    assert (out / ".mine").read_text() == "a user's file"  # only the benchmark's own temporaries are removed
    manifest = json.loads((out / bm.MANIFEST).read_text())
    assert manifest["command"].startswith("amigo-gym benchmark --agents analytic")
    (out / "benchmark.md").write_text("a table of another run")
    with pytest.raises(runs.CorruptFileError, match="does not match"):
        bm.verify_outputs(out)
