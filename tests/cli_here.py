"""``amigo-gym ARGS`` in the test's own process: for the tests whose point is what a command does and prints, not
starting Python (each ``amigo-gym`` process pays torch's import, about 5 s). The fixture ``in_process``
(tests/conftest.py) hands out :func:`runner`'s function.

Kills, signals, concurrent workers, ``--help`` (its wrapping follows the terminal) and per-process state (torch's
threads) stay real subprocesses in the tests that need them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Ran:
    """What one ``amigo-gym`` command returned and printed."""

    returncode: int
    stdout: str
    stderr: str


def runner(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Callable[..., Ran]:
    """``run(*args, cwd=ROOT)``: ``amigo_gym.tools.cli.main(args)`` from ``cwd`` (the checkout's root by default, where
    the subprocesses run), without an injected fault (``AMIGO_GYM_FAULT`` unset), its output captured; argparse's
    refusals (``SystemExit``) give their exit status as the return code."""
    from amigo_gym.tools.cli import main

    monkeypatch.delenv("AMIGO_GYM_FAULT", raising=False)

    def run(*args: str, cwd: Path = ROOT) -> Ran:
        monkeypatch.chdir(cwd)
        capsys.readouterr()
        try:
            rc = main(list(args))
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else 1
        out, err = capsys.readouterr()
        return Ran(rc, out, err)

    return run
