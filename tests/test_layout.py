"""The package's layout (issue 19, docs/architecture.md): imports point down the layers, no circles, a small root.

The structure is read from the source by :mod:`tests.layout` (``ast``; imports inside functions count). A test
that the checker itself sees what it should: a made-up package with a circle and an upward import.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import layout
import pytest


def test_every_import_points_down_the_layers() -> None:
    mods = layout.modules()
    assert all(layout.layer_of(m) >= 0 for m in mods), [m for m in mods if layout.layer_of(m) < 0]
    assert layout.upward(layout.imports(mods)) == []


def test_no_import_circles() -> None:
    assert layout.circles(layout.imports(layout.modules())) == []


def test_the_root_holds_at_most_eight_modules() -> None:
    assert len(layout.root_modules()) <= layout.MAX_ROOT_MODULES, layout.root_modules()


def test_nothing_imports_the_cli() -> None:
    graph = layout.imports(layout.modules())
    cli = "amigo_gym.tools.cli"
    users = sorted(a for a, bs in graph.items() for b in bs if b.startswith(cli) and not a.startswith(cli))
    assert users == []


def test_the_checker_finds_a_circle_and_an_upward_import(tmp_path: Path) -> None:
    pkg = tmp_path / "amigo_gym"
    (pkg / "model").mkdir(parents=True)
    (pkg / "envs").mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "model" / "__init__.py").write_text("")
    (pkg / "envs" / "__init__.py").write_text("")
    (pkg / "model" / "a.py").write_text("from amigo_gym.model import b\n")
    (pkg / "model" / "b.py").write_text(
        "def f():\n    from amigo_gym.model.a import x\n    from amigo_gym.envs import e\n"
    )
    (pkg / "envs" / "e.py").write_text("import amigo_gym.envs\n")
    graph = layout.imports(layout.modules(pkg))
    assert layout.circles(graph) == [["amigo_gym.model.a", "amigo_gym.model.b"]]
    assert layout.upward(graph) == [("amigo_gym.model.b", "amigo_gym.envs.e")]


def test_old_task_names_are_found_with_a_warning() -> None:
    from amigo_gym import task
    from amigo_gym.task import v0

    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        assert task.reward_term_columns is v0.reward_term_columns
    assert any("moved to amigo_gym.task.v0.reward_term_columns" in str(x.message) for x in w)
    with pytest.raises(AttributeError):
        task.no_such_name  # noqa: B018


@pytest.mark.parametrize("name", ["step_columns", "transition", "State", "evaluate", "start_pose", "bound_heading"])
def test_removed_task_names_name_their_replacement(name: str) -> None:
    """AmigoBot-v0's second column step (removed in 0.2): a clear one-line error from both old homes, no warning."""
    from amigo_gym import task
    from amigo_gym.task import v0

    assert name in v0.REMOVED and name not in v0.__all__
    for home in (v0, task):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(AttributeError, match=rf"task\.v0\.{name} was removed .* use amigo_gym\.task\.v[01]\."):
                getattr(home, name)
    with pytest.raises(ImportError):
        exec(f"from amigo_gym.task.v0 import {name}")
    assert not hasattr(v0, name)
