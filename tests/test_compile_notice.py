"""The first compiled step says, in one line, that numba is compiling; a warm cache and the numpy kernel say nothing.

The notice is for a person at a terminal (here a pseudo-terminal); a script's captured stderr stays empty."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from amigo_gym.sim.fast_v1 import COMPILE_NOTICE

STEP = (
    "import gymnasium as gym, amigo_gym\n"
    "env = gym.make('AmigoBot-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
    "print(type(env.unwrapped._kernel).__name__ if env.unwrapped._kernel else 'numpy')\n"
)


def _run(cache: Path, kernel: str) -> subprocess.CompletedProcess[str]:
    """The step in a fresh process whose stderr is a terminal (a pseudo-terminal), as a person runs it."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "AMIGO_GYM_KERNEL": kernel}
    env.pop("AMIGO_GYM_COMPILE_NOTICE", None)
    master, slave = os.openpty()
    try:
        proc = subprocess.Popen([sys.executable, "-c", STEP], stdout=subprocess.PIPE, stderr=slave, text=True, env=env)
        os.close(slave)
        chunks = []
        while True:
            try:
                data = os.read(master, 4096)
            except OSError:  # EIO: the child closed the terminal
                break
            if not data:
                break
            chunks.append(data)
        out = proc.stdout.read() if proc.stdout else ""
        proc.wait(timeout=300)
    finally:
        os.close(master)
    err = b"".join(chunks).decode().replace("\r\n", "\n")
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


@pytest.mark.slow
def test_notice_once_when_compiling_and_never_from_a_warm_cache(tmp_path: Path) -> None:
    cold = _run(tmp_path / "numba", "auto")  # an empty cache: numba compiles the step's kernels
    assert cold.returncode == 0, cold.stderr
    assert cold.stdout.strip() == "StepKernel"  # the compiled step ran
    assert cold.stderr.splitlines().count(COMPILE_NOTICE) == 1, cold.stderr  # many kernels, one line
    assert "once" in COMPILE_NOTICE and "numba" in COMPILE_NOTICE
    warm = _run(tmp_path / "numba", "auto")  # the same cache: loaded, not compiled
    assert warm.returncode == 0, warm.stderr
    assert COMPILE_NOTICE not in warm.stderr
    reference = _run(tmp_path / "other", "numpy")  # the numpy reference compiles nothing
    assert reference.returncode == 0, reference.stderr
    assert reference.stdout.strip() == "numpy"
    assert COMPILE_NOTICE not in reference.stderr


@pytest.mark.slow
def test_captured_stderr_stays_empty_without_a_terminal(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "AMIGO_GYM_KERNEL": "auto"}
    env.pop("AMIGO_GYM_COMPILE_NOTICE", None)
    r = subprocess.run([sys.executable, "-c", STEP], capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 0 and r.stdout.strip() == "StepKernel", r.stderr
    assert COMPILE_NOTICE not in r.stderr
