"""``amigo-gym verify``: PASS/FAIL per check, exit status 1 when one fails, and the bounds it claims."""

from __future__ import annotations

import subprocess
import sys

import pytest

from amigo_gym.tools.analysis import verify


def test_verify_quick_passes_and_prints_the_bounds_it_claims() -> None:
    r = subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "verify", "--quick"], capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    rows = [ln.split("|")[1:5] for ln in r.stdout.splitlines() if ln.startswith("| ") and "---" not in ln][1:]
    assert rows and all(verdict.strip() == "PASS" for *_, verdict in rows)
    values = {what.strip(): float(val) for what, val, _, _ in rows}
    exact = [v for k, v in values.items() if k.startswith(("exact step", "AmigoBot-v0"))]
    euler = [v for k, v in values.items() if k.startswith("Euler step")]
    steady = [v for k, v in values.items() if k.startswith("steady")]
    assert len(exact) == 4 and max(exact) <= 1e-9
    assert len(euler) == 3 and min(euler) > 1e-4
    assert len(steady) == 4 and max(map(abs, steady)) < 5e-7
    assert r.stdout.strip().splitlines()[-1] == f"{len(rows)} of {len(rows)} checks passed"


def test_a_failing_check_prints_fail_and_exits_1(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    good = verify.Check("a check that holds", 0.0, "<= 1", True)
    bad = verify._check("a check that does not", 2.0, "<= 1", lambda v: v <= 1.0)
    nan = verify._check("a NaN never passes", float("nan"), "<= 1", lambda v: True)
    monkeypatch.setattr(verify, "rows", lambda quick=False: [good, bad, nan])
    assert verify.main(["--quick"]) == 1
    out = capsys.readouterr().out
    assert "| a check that holds | 0 | <= 1 | PASS |" in out
    assert "| a check that does not | 2 | <= 1 | FAIL |" in out
    assert "| a NaN never passes | nan | <= 1 | FAIL |" in out
    assert out.strip().splitlines()[-1] == "1 of 3 checks passed: FAIL"
