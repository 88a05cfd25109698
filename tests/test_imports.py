"""`import amigo_gym` needs only numpy and gymnasium: heavy libraries load only where used.

numba is a core dependency on the platforms with its wheels (pyproject.toml), and the compiled step, the default
where it is installed, loads it when an env is built; `import amigo_gym` itself and the reference step
(`kernel="numpy"`, what runs without numba) do not.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys

HEAVY = ("sympy", "pygame", "matplotlib", "torch", "stable_baselines3", "scipy.optimize")


def _loaded(code: str, names: tuple[str, ...]) -> list[str]:
    """Which of ``names`` are in ``sys.modules`` after ``code`` ran in a fresh interpreter."""
    code = f"import sys\n{code}\nprint(','.join(m for m in {names!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    return [m for m in out.split(",") if m]


def _after_step(kernel: str) -> list[str]:
    code = (
        "import gymnasium as gym, amigo_gym\n"
        f"env = gym.make('AmigoBot-v0', kernel={kernel!r}); env.reset(seed=0); env.step(env.action_space.sample())"
    )
    return _loaded(code, (*HEAVY, "scipy", "numba"))


def test_import_is_light() -> None:
    """``import amigo_gym`` loads none of the heavy modules, nor numba nor scipy."""
    assert _loaded("import amigo_gym", (*HEAVY, "scipy", "numba")) == []


def test_steps_load_only_what_they_use() -> None:
    """Stepping with numpy (the reference) loads none of the heavy modules nor numba. The compiled step (the
    default when numba is installed) loads numba, whose start-up probes ``scipy.linalg`` for BLAS when scipy is
    installed; nothing else (no ``scipy.optimize``, torch, SB3, matplotlib)."""
    assert _after_step("numpy") == [], "modules imported by `import amigo_gym` and a numpy step"
    compiled = set(_after_step("auto"))
    assert compiled <= {"scipy", "numba"}, "heavy modules imported by the compiled step"
    assert ("numba" in compiled) == (importlib.util.find_spec("numba") is not None), "the compiled step ran"


def test_cli_help_lists_commands() -> None:
    r = subprocess.run([sys.executable, "-m", "amigo_gym.tools.cli", "--help"], capture_output=True, text=True)
    assert r.returncode == 0
    for cmd in ("inverse", "paper", "train", "evaluate", "compare"):
        assert cmd in r.stdout


def test_cli_unknown_command_is_one_line_error() -> None:
    r = subprocess.run([sys.executable, "-m", "amigo_gym.tools.cli", "nonsense"], capture_output=True, text=True)
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1
    assert "unknown command" in r.stderr
