"""The extras of pyproject.toml provide what the commands' messages say, and `all` is what the README measured.

Parsed from pyproject.toml (the file pip reads), with the extras that include other extras
(``amigo_gym[train]``) resolved, so that a message naming an extra that lacks a module fails here rather than
on a newcomer's machine.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # CPython 3.10: pytest's own dependency, the same parser
    import tomli as tomllib

from amigo_gym.tools.cli import COMMANDS, EXTRA_OF_MODULE, install_hint

ROOT = Path(__file__).resolve().parents[1]

#: import name -> the distribution on PyPI that installs it
DISTRIBUTION = {
    "torch": "torch",
    "stable_baselines3": "stable-baselines3",
    "sb3_contrib": "sb3-contrib",
    "filelock": "filelock",
    "yaml": "pyyaml",
    "tqdm": "tqdm",
    "rich": "rich",
    "tensorboard": "tensorboard",
    "matplotlib": "matplotlib",
    "sympy": "sympy",
    "pygame": "pygame",
    "moviepy": "moviepy",
    "nbclient": "nbclient",
    "nbformat": "nbformat",
    "optuna": "optuna",
    "psycopg2": "psycopg2-binary",
    "numba": "numba",
    "rosbags": "rosbags",
}


def _extras() -> dict[str, list[str]]:
    data = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    extras: dict[str, list[str]] = data["project"]["optional-dependencies"]
    return extras


def provided(extra: str) -> set[str]:
    """Distribution names (lower case) that ``pip install ".[extra]"`` installs, nested extras resolved."""
    extras = _extras()
    out: set[str] = set()
    todo, seen = [extra], set()
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        for req in extras[name]:
            m = re.match(r"amigo_gym\[([^\]]+)\]", req)
            if m:
                todo += [x.strip() for x in m.group(1).split(",")]
            else:
                out.add(re.split(r"[<>=\[; ]", req, maxsplit=1)[0].lower())
    return out


@pytest.mark.parametrize("name", [n for n, c in COMMANDS.items() if c.extra])
def test_each_commands_extra_provides_the_modules_it_checks(name: str) -> None:
    cmd = COMMANDS[name]
    assert cmd.extra is not None
    missing = {m for m in cmd.modules if DISTRIBUTION[m] not in provided(cmd.extra)}
    assert not missing, f"amigo-gym {name} says it needs [{cmd.extra}], which lacks {missing}"


def test_each_module_missing_at_run_time_names_an_extra_that_has_it() -> None:
    for module, extra in EXTRA_OF_MODULE.items():
        assert DISTRIBUTION[module] in provided(extra), (module, extra)


def test_all_is_the_measured_configuration_with_the_compiled_step() -> None:
    everything = provided("all")
    assert "numba" in everything  # the README's performance figures are the compiled step's
    for extra in _extras():
        if extra not in ("dev", "docs"):
            assert provided(extra) <= everything, (extra, provided(extra) - everything)


def test_dev_includes_the_docs_site() -> None:
    assert provided("docs") <= provided("dev")
    assert {"mkdocs", "mkdocs-material", "mkdocstrings"} <= provided("docs")


def test_messages_give_the_command_for_a_clone_too() -> None:
    hint = install_hint("train")
    assert 'pip install "amigo-gym[train]"' in hint and 'pip install -e ".[train]"' in hint
    for path in ("amigo_gym/envs/rendering.py", "amigo_gym/sim/fast_v1.py"):
        text = (ROOT / path).read_text(encoding="utf-8")
        extra = "render" if "rendering" in path else "fast"
        assert f'pip install -e ".[{extra}]"' in text, path
