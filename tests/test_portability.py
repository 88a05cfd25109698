"""The compiled step agrees with the reference on another CPU's code, simulated on this machine.

A CI or user machine may be an AVX-512 Intel, an AVX2 AMD or an ARM: numpy dispatches its SIMD loops at run time and
numba compiles for the host's CPU, so the code that runs there is not the code that runs here. This test runs the
tests that compare the compiled step with the reference (within the stated tolerance) and the golden episodes in a
new process where numpy's run-time dispatch is restricted to its baseline (``NPY_DISABLE_CPU_FEATURES`` naming every
dispatched feature this CPU has) and numba compiles for a generic CPU of this architecture (``NUMBA_CPU_NAME=generic``
with ``NUMBA_CPU_FEATURES=""``: no AVX, no FMA; the name alone keeps the host's features), into a numba cache of its
own.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from test_golden_tolerance import _dispatched_features

ROOT = Path(__file__).resolve().parent.parent
#: the tests of the compiled step against the reference (to tolerance) and of its determinism
FILES = (
    "tests/test_kernel_v1.py",
    "tests/test_v0_as_v1.py",
    "tests/test_golden.py",
    "tests/test_direct_call.py",
)


def test_compiled_steps_match_their_references_on_baseline_code(tmp_path: Path) -> None:
    already = os.environ.get("NPY_DISABLE_CPU_FEATURES", "").split()
    env = {
        **os.environ,
        "NPY_DISABLE_CPU_FEATURES": " ".join([*already, *_dispatched_features()]),
        "NUMBA_CPU_NAME": "generic",
        "NUMBA_CPU_FEATURES": "",
        "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
    }
    probe = (
        "import numba, numpy; from numpy._core import _multiarray_umath as u; "
        "print(' '.join(f for f in u.__cpu_dispatch__ if u.__cpu_features__.get(f)) or 'none', numba.config.CPU_NAME, "
        "repr(numba.config.CPU_FEATURES))"
    )
    left = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    assert left.stdout.split() == ["none", "generic", "''"], left.stdout  # the restriction took effect
    run = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist", *FILES],
        env=env,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=1200,
    )
    where = f"NPY_DISABLE_CPU_FEATURES={env['NPY_DISABLE_CPU_FEATURES']!r}, numba generic (no features)"
    assert run.returncode == 0, f"{where}:\n{run.stdout[-4000:]}\n{run.stderr[-2000:]}"
    assert " passed" in run.stdout and "failed" not in run.stdout and "skipped" not in run.stdout
