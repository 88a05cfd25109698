"""`import amigo_gym` needs only numpy and gymnasium: heavy libraries load only where used."""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("scipy", "sympy", "pygame", "matplotlib", "torch", "stable_baselines3")


def _heavy_after(kernel: str) -> list[str]:
    code = (
        "import sys, gymnasium as gym, amigo_gym\n"
        f"env = gym.make('AmigoBot-v0', kernel={kernel!r}); env.reset(seed=0); env.step(env.action_space.sample())\n"
        f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    return [m for m in out.split(",") if m]


def test_import_is_light() -> None:
    """Importing and stepping with numpy loads none of the heavy modules. The compiled step (the default when
    numba is installed) loads numba, whose start-up probes ``scipy.linalg`` for BLAS when scipy is installed;
    nothing else."""
    assert _heavy_after("numpy") == [], "heavy modules imported by `import amigo_gym` and a numpy step"
    assert set(_heavy_after("auto")) <= {"scipy"}, "heavy modules imported by the compiled step"


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
