"""The golden tests' tolerance is portable and still catches changes of behaviour (issue 17).

- With numpy's run-time SIMD dispatch restricted to its baseline (``NPY_DISABLE_CPU_FEATURES`` naming
  every dispatched feature this CPU has: another machine's ``exp``/``sin``/``cos``), the golden tests pass.
- A one-ulp change of a physical constant of the robot (wheel radius, half track, offset of H) moves the
  episode beyond the tolerance, and so does a relative change of 1e-12 of a reward constant.
- A change below the machines' own spread, such as re-associating the product of the reward terms
  (one ulp of the reward, like a change of CPU: ``python tests/golden_compare.py`` style figures are in
  docs/development.md), passes the portable test; it is caught on the machine where it is made when one
  code path has it and the other does not (the numpy reference against the compiled step, bit for bit).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import test_golden as tg
from golden_compare import mismatches

import amigo_gym.task.v1 as tracking

ROOT = Path(__file__).resolve().parent.parent
EPISODES = [(c, s, k) for c in tg.CONFIGS for s in tg.SEEDS for k in tg.KINDS]  # the whole golden file


def _dispatched_features() -> list[str]:
    """The SIMD features numpy dispatches to on this CPU beyond its compiled baseline."""
    try:
        from numpy._core import _multiarray_umath as um  # numpy >= 2
    except ImportError:  # pragma: no cover - numpy 1.x
        from numpy.core import _multiarray_umath as um  # type: ignore[no-redef]
    return [f for f in um.__cpu_dispatch__ if um.__cpu_features__.get(f)]


def _problems(overrides: dict[str, Any]) -> list[list[str]]:
    """The golden mismatches of :data:`EPISODES` replayed with ``gym.make`` settings ``overrides``."""
    golden = dict(np.load(tg.GOLDEN))
    out = []
    for config, seed, kind in EPISODES:
        key = f"{config}/{seed}/{kind}"
        saved = tg.CONFIGS[config]
        tg.CONFIGS[config] = {**saved, **overrides}
        try:
            got, _ = tg.single_episode(config, seed, golden[f"{key}/action"])
        finally:
            tg.CONFIGS[config] = saved
        out.append(mismatches(got, tg._recorded(golden, key)))
    return out


def _next(x: float) -> float:
    return float(np.nextafter(x, np.inf))


def test_unchanged_code_is_within_tolerance() -> None:
    assert _problems({}) == [[] for _ in EPISODES]


@pytest.mark.parametrize(
    ("field", "nominal"),
    [("r1", 0.05), ("l1", 0.12), ("l3", 0.08)],
    ids=["wheel radius r1", "half track l1", "offset of H l3"],
)
def test_one_ulp_of_a_physical_constant_fails(field: str, nominal: float) -> None:
    problems = _problems({"robot": {field: _next(nominal)}})
    assert sum(map(bool, problems)) >= len(EPISODES) // 3, problems  # rewards move by 50-400 ulp of their scale


def test_a_small_change_of_a_reward_constant_fails() -> None:
    assert sum(map(bool, _problems({"sigma_track": 0.02 * (1 + 1e-12)}))) >= len(EPISODES) // 3


def test_a_reordered_reward_product_is_caught_by_the_same_machine_comparison(monkeypatch: pytest.MonkeyPatch) -> None:
    """Re-associating the reward product in one code path: one ulp, seen bit for bit against the other path."""
    import gymnasium as gym

    golden = dict(np.load(tg.GOLDEN))
    actions = golden["manoeuvre_right_fine/1/noisy/action"]
    single, _ = tg.single_episode("manoeuvre_right_fine", 1, actions)  # the single env's step (unchanged)
    # the numpy reference of AmigoBot-v0 (its configuration of task.v1) takes the product by this name
    monkeypatch.setattr(tracking, "reward_product", lambda a, b, c, d: ((d * c) * b) * a)
    envs = gym.make_vec("AmigoBot-v0", num_envs=1, kernel="numpy", **tg.CONFIGS["manoeuvre_right_fine"])
    envs.reset(seed=1)
    rewards = [envs.step(a[None, :])[1][0] for a in actions]
    envs.close()
    assert not np.array_equal(np.array(rewards), single["reward"])  # bit for bit: caught
    np.testing.assert_allclose(rewards, single["reward"], rtol=4e-16, atol=0)  # though it is one ulp


def test_golden_tests_pass_with_numpy_dispatch_restricted() -> None:
    """Another machine's SIMD functions, simulated: the golden tests run again with numpy's dispatch off."""
    features = _dispatched_features()
    already = os.environ.get("NPY_DISABLE_CPU_FEATURES", "").split()  # a run restricted already keeps its own
    env = {**os.environ, "NPY_DISABLE_CPU_FEATURES": " ".join([*already, *features])}
    probe = (
        "import numpy; from numpy._core import _multiarray_umath as u; "
        "print(' '.join(f for f in u.__cpu_dispatch__ if u.__cpu_features__.get(f)) or 'none')"
    )
    if features:
        left = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
        assert left.stdout.strip() == "none", left.stdout  # the restriction took effect
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "tests/test_golden.py",
            "tests/test_golden_v1.py",
        ],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, f"NPY_DISABLE_CPU_FEATURES={features}:\n{run.stdout[-3000:]}\n{run.stderr[-2000:]}"
    assert " passed" in run.stdout and "failed" not in run.stdout
