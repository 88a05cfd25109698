"""The golden tests' tolerance (tests/golden_compare.py: 1e-9 of each quantity's scale) is portable and still
catches changes of behaviour.

- With numpy's run-time SIMD dispatch restricted to its baseline (``NPY_DISABLE_CPU_FEATURES`` naming
  every dispatched feature this CPU has: another machine's ``exp``/``sin``/``cos``), the golden tests pass.
- A relative change of 1e-7 of a physical constant of the robot (wheel radius, half track, offset of H) or of a
  reward constant moves the episodes beyond the tolerance.
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


def test_unchanged_code_is_within_tolerance() -> None:
    assert _problems({}) == [[] for _ in EPISODES]


@pytest.mark.parametrize(
    ("field", "nominal"),
    [("r1", 0.05), ("l1", 0.12), ("l3", 0.08)],
    ids=["wheel radius r1", "half track l1", "offset of H l3"],
)
def test_a_small_change_of_a_physical_constant_fails(field: str, nominal: float) -> None:
    problems = _problems({"robot": {field: nominal * (1.0 + 1e-7)}})
    assert sum(map(bool, problems)) >= len(EPISODES) // 3, problems


def test_a_small_change_of_a_reward_constant_fails() -> None:
    assert sum(map(bool, _problems({"sigma_track": 0.02 * (1 + 1e-7)}))) >= len(EPISODES) // 3


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
