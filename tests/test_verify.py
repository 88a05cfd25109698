"""`amigo-gym verify` by subprocess: the table prints, and its exact rows meet the bounds it states."""

from __future__ import annotations

import subprocess
import sys


def test_verify_quick_prints_the_bounds_it_claims() -> None:
    r = subprocess.run(
        [sys.executable, "-m", "amigo_gym.cli", "verify", "--quick"], capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    rows = [ln.split("|")[1:4] for ln in r.stdout.splitlines() if ln.startswith("| ") and "---" not in ln][1:]
    values = {what.strip(): float(val) for what, val, _ in rows}
    exact = [v for k, v in values.items() if k.startswith(("exact step", "AmigoBot-v0"))]
    euler = [v for k, v in values.items() if k.startswith("Euler step")]
    steady = [v for k, v in values.items() if k.startswith("steady")]
    assert len(exact) == 4 and max(exact) <= 1e-9
    assert len(euler) == 3 and min(euler) > 1e-4
    assert len(steady) == 4 and max(map(abs, steady)) < 5e-7
