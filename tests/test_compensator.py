"""The delay compensator (amigo_gym.policies.compensator): against a scalar reference written apart from it
(experiments/smith_delay.py's ``SmithEstimated``, one robot, Python lists), against the robot itself (the delay it
estimates, the error it predicts), its quiet rule, its numba-free route, its residual in ``FastPolicy``, bad input."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from amigo_gym.policies import AnalyticTrackingPolicy, DelayCompensatedPolicy
from amigo_gym.policies import compensator as comp
from amigo_gym.policies.learned import FastPolicy, FeatureBuilder, FeatureSpec, RunningMeanStd, env_action

ROOT = Path(__file__).resolve().parents[1]
CIRCLE = {"path": "circle", "speed": 0.2, "dt": 0.1}


def _reference() -> type:
    spec = importlib.util.spec_from_file_location("smith_delay", ROOT / "experiments" / "smith_delay.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.SmithEstimated  # type: ignore[no-any-return]


def _episode(kw: dict[str, object], steps: int, seed: int = 3) -> tuple[list[np.ndarray], list[np.ndarray], list]:
    """Actions of the reference and of the policy, each stepping its own env, and the policy's (delay, quiet)."""
    ref_cls = _reference()
    ea, eb = gym.make("AmigoBot-v1", **kw), gym.make("AmigoBot-v1", **kw)
    ref, pol = ref_cls(ea.unwrapped.params, 2.0, 1e-6), DelayCompensatedPolicy(eb.unwrapped.params)  # type: ignore[attr-defined]
    oa, _ = ea.reset(seed=seed)
    ob, _ = eb.reset(seed=seed)
    acts_a, acts_b, est, state = [], [], [], None
    for t in range(steps):
        a = ref.act(oa, t == 0)
        b, state = pol.predict(ob, state=state, episode_start=np.array([t == 0]))
        est.append((ref.delay, ref.pol is ref.fast))
        acts_a.append(a)
        acts_b.append(b)
        oa = ea.step(a)[0]
        ob = eb.step(b)[0]
    return acts_a, acts_b, est


@pytest.mark.parametrize(
    "kw",
    [
        {**CIRCLE, "randomize": {"delay": (0.25, 0.25)}},
        {"path": "figure8", "speed": 0.3, "randomize": {"wheel_radius": (0.95, 1.05), "delay": (0.1, 0.1)}},
        {**CIRCLE, "randomize": {"wheel_rate_noise": 0.05, "position_noise": 0.002}},
    ],
    ids=["delay", "mismatch", "noise"],
)
def test_matches_the_scalar_reference_step_by_step(kw: dict[str, object]) -> None:
    """The vectorised compiled compensator and the one-robot reference act alike to float32's rounding (6e-8 on
    actions in [-1, 1]) over 120 steps; the gain 2.05 instead of 2 moves them by 1.1e-3, the candidates 10 ms off
    by 1.9e-2 (tried by hand)."""
    a, b, _ = _episode(kw, 120)
    assert np.max(np.abs(np.array(a) - np.array(b))) <= 1e-6


@pytest.mark.parametrize("delay", [0.1, 0.25])
def test_estimates_the_true_delay_and_predicts_the_error_it_brings(delay: float) -> None:
    """On the nominal robot with a fixed delay the estimate is the true delay once the robot has moved (the
    candidates' simulated speeds differ only after the first commands act), and the error it predicts ``d`` ahead is
    the robot's: ``e`` predicted at step ``t`` against H's error observed at ``t + d / dt`` (``d = 0.2`` s, two steps)
    within 10 um (seen: 0.6 um, from the Euler steps of 5 ms and the curvature held over ``d``), where the error
    observed now differs from that by more (56 um: a predictor that did nothing would fail)."""
    env = gym.make("AmigoBot-v1", **CIRCLE, randomize={"delay": (delay, delay)})
    pol = DelayCompensatedPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
    obs, _ = env.reset(seed=5)
    st = np.zeros((1, pol.state_dim))
    delays = []
    for t in range(60):
        o = np.asarray(obs, dtype=np.float64)[None]
        a, d, quiet, st = pol.compensate(o, st, np.array([t == 0]))
        delays.append(float(d[0]))
        obs = env.step(a[0])[0]
    assert delays[-1] == pytest.approx(delay) and all(x == pytest.approx(delay) for x in delays[20:])
    assert quiet[0] == 1.0

    env = gym.make("AmigoBot-v1", **CIRCLE, randomize={"delay": (0.2, 0.2)})
    params = env.unwrapped.params  # type: ignore[attr-defined]
    pol = DelayCompensatedPolicy(params)
    obs, _ = env.reset(seed=5)
    st, col = np.zeros((1, pol.state_dim)), pol._col
    predicted, seen = [], []
    for t in range(80):
        o = np.asarray(obs, dtype=np.float64)[None]
        _, _, _, st_next = pol.compensate(o, st, np.array([t == 0]))
        _, _, pred = comp.predict_rows(o, np.array([t == 0]), np.array(st[:, 1:]), col, np.array(comp.CANDIDATES),
                                       pol._rob, params.dt, params.error_scale)  # fmt: skip
        predicted.append(pred[0, 0])
        seen.append(o[0, col[0]] * params.error_scale)
        a = AnalyticTrackingPolicy(params).predict(o, state=np.zeros((1, 1)))[0]  # any commands that move the robot
        st = st_next
        obs = env.step(a[0])[0]
    gap = np.abs(np.array(predicted[30:-2]) - np.array(seen[32:]))
    assert gap.max() <= 1e-5 < np.abs(np.array(seen[30:-2]) - np.array(seen[32:])).max()


def test_quiet_rule_keeps_the_analytic_gain_where_the_model_does_not_explain_the_measurements() -> None:
    """Noisy wheel rates: the quiet flag goes off within a few steps (the gain ``k = 1``); without noise it stays on."""
    for noise, want in ((0.05, 0.0), (0.0, 1.0)):
        env = gym.make("AmigoBot-v1", **CIRCLE, randomize={"wheel_rate_noise": noise})
        pol = DelayCompensatedPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
        obs, _ = env.reset(seed=1)
        st = np.zeros((1, pol.state_dim))
        flags = []
        for t in range(40):
            a, _, quiet, st = pol.compensate(np.asarray(obs, dtype=np.float64)[None], st, np.array([t == 0]))
            flags.append(quiet[0])
            obs = env.step(a[0])[0]
        assert all(f == want for f in flags[10:])


def test_the_numba_free_route_gives_the_compiled_result() -> None:
    """``predict_rows`` as plain Python (``AMIGO_GYM_KERNEL=numpy``, or no numba) against its compilation, on a
    batch of 16 robots over 30 steps: within 1e-12 (the C library's ``sin``/``cos``/``atan2`` against Python's)."""
    env = gym.make_vec("AmigoBot-v1", num_envs=16, vectorization_mode="vector_entry_point", path="mixed",
                       randomize={"delay": (0.0, 0.3)})  # fmt: skip
    p = env.params  # type: ignore[attr-defined]
    pol = DelayCompensatedPolicy(p)
    obs, _ = env.reset(seed=2)
    st = np.zeros((16, pol.state_dim))
    compiled = comp._predictor()
    assert compiled is not comp.predict_rows
    for t in range(30):
        o, starts = np.asarray(obs, dtype=np.float64), np.full(16, t == 0)
        rest = (pol._col, np.array(comp.CANDIDATES), pol._rob, p.dt, p.error_scale)
        st_py, st_nb = np.array(st[:, 1:]), np.array(st[:, 1:])  # each route updates its own copy
        out_py, out_nb = comp.predict_rows(o, starts, st_py, *rest), compiled(o, starts, st_nb, *rest)
        for x, y in zip((*out_py, st_py), (*out_nb, st_nb), strict=True):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)
        a, _, _, st = pol.compensate(o, st, starts)
        obs = env.step(a.astype(np.float32))[0]
    env.close()


def _zero_residual(spec: FeatureSpec, out: np.ndarray | None = None) -> FastPolicy:
    dim = FeatureBuilder(spec).dim
    last = np.zeros(2) if out is None else out
    return FastPolicy(spec, [(np.zeros((dim, 2)), last)], np.zeros(2), RunningMeanStd.zeros(dim))


def test_a_residual_on_the_compensator_adds_its_delay_and_quiet_flag_and_gates_its_correction(tmp_path: Path) -> None:
    """``FeatureSpec(base="compensator")``: the network sees the compensator's action, delay and quiet flag (4 more
    inputs); a zero network acts as the compensator; with ``gate`` a constant correction counts only where the flag
    is on; the spec survives save and load."""
    kw = {**CIRCLE, "randomize": {"wheel_rate_noise": 0.05}}
    spec = FeatureSpec(kw, history=2, residual_bound=0.3, residual_gain=2.0, base="compensator")
    b = FeatureBuilder(spec)
    assert b.dim == b.obs_dim + 2 * 7 + 4 and b.state_dim == DelayCompensatedPolicy(spec.params()).state_dim + 14
    env = gym.make("AmigoBot-v1", **kw)
    pol, ref = _zero_residual(spec), DelayCompensatedPolicy(env.unwrapped.params)  # type: ignore[attr-defined]
    gated = _zero_residual(FeatureSpec(kw, 2, 0.3, residual_gain=2.0, base="compensator", gate=True), np.ones(2))
    obs, _ = env.reset(seed=4)
    st, flags = np.zeros((1, ref.state_dim)), []
    for t in range(25):
        start = np.array([t == 0])
        a, _ = pol.predict(obs, episode_start=start)
        g, _ = gated.predict(obs, episode_start=start)
        r, _, quiet, st = ref.compensate(np.asarray(obs, dtype=np.float64)[None], st, start)
        np.testing.assert_allclose(a, r[0], rtol=0, atol=1e-7)
        np.testing.assert_allclose(g, np.clip(r[0] + 0.3 * quiet[0], -1.0, 1.0), rtol=0, atol=1e-7)
        flags.append(quiet[0])
        obs = env.step(a)[0]
    assert flags[0] == 1.0 and flags[-1] == 0.0  # the gate was open, then shut by the noise
    gated.save(tmp_path / "g.zip")
    back = FastPolicy.load(tmp_path / "g.zip")
    assert back.spec.base == "compensator" and back.spec.gate and back.name == "fastppo_compensator_residual"


def test_env_action_mask_zeroes_the_correction_on_masked_rows() -> None:
    u, base, prev = np.ones((3, 2)), np.zeros((3, 2)), np.zeros((3, 2))
    a = env_action(u, base, prev, 0.3, 1.0, np.array([True, False, True]))
    np.testing.assert_array_equal(a, [[0.3, 0.3], [0.0, 0.0], [0.3, 0.3]])


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda p: DelayCompensatedPolicy(p, quiet=2.0),
            r"DelayCompensatedPolicy\.quiet must be a finite number in \[0, 1\], got 2",
        ),
        (
            lambda p: DelayCompensatedPolicy(p, gain=0.0),
            r"DelayCompensatedPolicy\.gain must be a finite number in \(0, 10\], got 0",
        ),
        (lambda p: FeatureSpec(CIRCLE, residual_bound=0.3, base="smith"), r"FeatureSpec\.base must be 'analytic' or"),
        (lambda p: FeatureSpec(CIRCLE, residual_bound=0.3, gate=True), r"FeatureSpec\.gate must be a bool, True only"),
        (lambda p: FeatureSpec(CIRCLE, base="compensator", gate=True), r"True only for a residual on the compensator"),
    ],
    ids=["quiet", "gain", "base", "gate", "gate_without_residual"],
)
def test_bad_settings_are_one_line_errors(call: object, match: str) -> None:
    params = gym.make("AmigoBot-v1", **CIRCLE).unwrapped.params  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match=match):
        call(params)  # type: ignore[operator]


def test_too_short_a_step_for_the_delays_is_refused() -> None:
    params = gym.make("AmigoBot-v1", path="circle", dt=0.04).unwrapped.params  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match=r"params\.dt = 0\.04 s is too short for the 0\.3 s delays"):
        DelayCompensatedPolicy(params)
