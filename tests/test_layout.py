"""The package's layout (docs/architecture.md): imports point down the layers, no circles, the core never imports
the tools layer, nothing imports the CLI, a small root.

The structure is read from the source by :mod:`tests.layout` (``ast``; imports inside functions count). A test
that the checker itself sees what it should: made-up packages with a circle, an upward import and core modules
importing the tools.
"""

from __future__ import annotations

from pathlib import Path

import layout


def test_every_import_points_down_the_layers() -> None:
    mods = layout.modules()
    assert all(layout.layer_of(m) >= 0 for m in mods), [m for m in mods if layout.layer_of(m) < 0]
    assert layout.upward(layout.imports(mods)) == []


def test_no_import_circles() -> None:
    assert layout.circles(layout.imports(layout.modules())) == []


def test_the_root_holds_at_most_eight_modules() -> None:
    assert len(layout.root_modules()) <= layout.MAX_ROOT_MODULES, layout.root_modules()


def test_nothing_imports_the_cli() -> None:
    assert layout.imports_of_the_cli(layout.imports(layout.modules())) == []


def test_the_core_never_imports_the_tools_layer() -> None:
    mods = layout.modules()
    assert any(layout.within(m, layout.TOOLS) for m in mods) and any(not layout.within(m, layout.TOOLS) for m in mods)
    assert layout.core_imports_of_tools(layout.imports(mods)) == []


def _package(root: Path, files: dict[str, str]) -> dict[str, set[str]]:
    """The import graph of a made-up ``amigo_gym`` under ``root`` of ``{relative path: source}`` (empty
    ``__init__.py`` files added where missing)."""
    pkg = root / "amigo_gym"
    for rel, src in files.items():
        f = pkg / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(src)
    for d in [pkg, *(p for p in pkg.rglob("*") if p.is_dir())]:
        if not (d / "__init__.py").exists():
            (d / "__init__.py").write_text("")
    return layout.imports(layout.modules(pkg))


def test_the_checker_finds_a_circle_and_an_upward_import(tmp_path: Path) -> None:
    graph = _package(
        tmp_path,
        {
            "model/a.py": "from amigo_gym.model import b\n",
            "model/b.py": "def f():\n    from amigo_gym.model.a import x\n    from amigo_gym.envs import e\n",
            "envs/e.py": "import amigo_gym.envs\n",
        },
    )
    assert layout.circles(graph) == [["amigo_gym.model.a", "amigo_gym.model.b"]]
    assert layout.upward(graph) == [("amigo_gym.model.b", "amigo_gym.envs.e")]


def test_the_checker_finds_a_core_module_that_imports_the_tools(tmp_path: Path) -> None:
    """Each way a core module can reach the tools (import, from-import of a module or a name, inside a function,
    importlib with a literal name) is found; the tools importing the core and each other are not reported."""
    graph = _package(
        tmp_path,
        {
            "envs/a.py": "import amigo_gym.tools.training.train\n",
            "envs/b.py": "from amigo_gym.tools import runs\n",
            "policies/c.py": "def f():\n    from amigo_gym.tools.runs import RunLock\n",
            "logs.py": "import importlib\nm = importlib.import_module('amigo_gym.tools.cli')\n",
            "model/ok.py": "import amigo_gym.envs.a\n",
            "tools/runs.py": "import amigo_gym.model.ok\n",
            "tools/training/train.py": "from amigo_gym.tools import runs\n",
            "tools/cli/__init__.py": "import amigo_gym.tools.training.train\n",
        },
    )
    assert layout.core_imports_of_tools(graph) == [
        ("amigo_gym.envs.a", "amigo_gym.tools.training.train"),
        ("amigo_gym.envs.b", "amigo_gym.tools.runs"),
        ("amigo_gym.logs", "amigo_gym.tools.cli"),
        ("amigo_gym.policies.c", "amigo_gym.tools.runs"),
    ]
    assert layout.imports_of_the_cli(graph) == [("amigo_gym.logs", "amigo_gym.tools.cli")]
