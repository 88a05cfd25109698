"""`import amigo_gym` needs only numpy and gymnasium: heavy libraries load only where used."""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("scipy", "sympy", "pygame", "matplotlib", "torch", "stable_baselines3")


def test_import_is_light() -> None:
    code = (
        "import sys, gymnasium as gym, amigo_gym\n"
        "env = gym.make('AmigoBot-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
        f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"heavy modules imported by `import amigo_gym` and stepping: {out}"


def test_cli_help_lists_commands() -> None:
    r = subprocess.run([sys.executable, "-m", "amigo_gym.cli", "--help"], capture_output=True, text=True)
    assert r.returncode == 0
    for cmd in ("inverse", "paper", "train", "evaluate", "compare"):
        assert cmd in r.stdout


def test_cli_unknown_command_is_one_line_error() -> None:
    r = subprocess.run([sys.executable, "-m", "amigo_gym.cli", "nonsense"], capture_output=True, text=True)
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1
    assert "unknown command" in r.stderr
