"""Shared test settings: headless rendering, a non-interactive matplotlib backend, and the order in which the two
xdist workers take the test files (the longest first).

The README's test command runs ``pytest -n 2 --dist loadfile``: each file goes whole to one worker, and a worker
takes the next file of the queue when it runs low. xdist's default queue puts the files with the most tests first,
so files with a few long tests (mypy, the kill-and-resume runs) came last, and one worker ran them alone while the
other idled. Here the queue starts with the files that take longest (longest-processing-time-first scheduling);
the other files follow in their collection order. Only the order changes: every test runs, unchanged.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable

import pytest
from cli_here import Ran, runner

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
os.environ.setdefault("MPLBACKEND", "Agg")
# the sha256 of the pickles the tests' runs write (amigo_gym.io.vouch): not into the user's own record
os.environ.setdefault("AMIGO_GYM_STATE_DIR", tempfile.mkdtemp(prefix="amigo_gym_state_"))

# The files that take longest, longest first: the sum of each file's test times (setup + call + teardown) over
# `python -m pytest -q -n 2 --dist loadfile --durations=0 --junitxml=t.xml` (2 cores, load average 3; summed per
# file from t.xml), rounded. A file missing from this list is not an error: it runs after these in collection order.
LONGEST_FILES = (
    "test_vector_v1_kernel.py",  # 632 s
    "test_sweep.py",  # 246 s
    "test_runs.py",  # 183 s
    "test_lint.py",  # 149 s (mypy --strict from an empty cache)
    "test_train.py",  # 128 s
    "test_compare.py",  # 118 s
    "test_sweep_fastppo.py",  # 112 s
    "test_kernel_v1.py",  # 90 s
    "test_fastppo.py",  # 76 s
    "test_train_evaluate.py",  # 75 s
    "test_newcomer.py",  # 72 s
    "test_benchmark.py",  # 61 s
    "test_notebook.py",  # 60 s
    "test_env_v1.py",  # 46 s
    "test_bad_inputs.py",  # 43 s
    "test_evaluate.py",  # 42 s
    "test_bad_inputs_v1.py",  # 40 s
    "test_compile_notice.py",  # 39 s
    "test_agents_pretrained.py",  # 35 s
    "test_v0_as_v1.py",  # 34 s
)


def pytest_configure(config: pytest.Config) -> None:
    """Keep the collection order (below) as xdist's file queue instead of xdist's tests-per-file order."""
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The files of :data:`LONGEST_FILES` first, in that order; the tests inside a file keep their order."""
    rank = {name: k for k, name in enumerate(LONGEST_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: the rest keep collection order


@pytest.fixture
def in_process(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Callable[..., Ran]:
    """``amigo-gym ARGS`` in the test's process (tests/cli_here.py)."""
    return runner(capsys, monkeypatch)
