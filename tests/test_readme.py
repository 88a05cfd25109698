"""The README's set-up commands and CI agree, and the CLI commands the README shows exist."""

from __future__ import annotations

import re
from pathlib import Path

from amigo_gym.cli import COMMANDS

ROOT = Path(__file__).resolve().parents[1]


def _setup_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    block = text.split("## Set-up: the two commands", 1)[1].split("```bash", 1)[1].split("```", 1)[0]
    return [ln.strip() for ln in block.splitlines() if ln.strip() and not ln.strip().startswith("#")]


def test_readme_has_exactly_two_setup_commands() -> None:
    cmds = _setup_commands()
    assert len(cmds) == 2, cmds
    assert "amigo-gym compare" in cmds[0]
    assert "pytest" in cmds[1]


def test_ci_runs_the_readme_test_command() -> None:
    ci = (ROOT / ".ci" / "run").read_text()
    test_cmd = _setup_commands()[1]
    assert test_cmd.replace("pip install", "pip install -q") in ci or test_cmd in ci, (test_cmd, ci)


def test_readme_cli_commands_exist() -> None:
    text = (ROOT / "README.md").read_text()
    used = set(re.findall(r"amigo-gym ([a-z][a-z-]+)", text))
    assert used, "README shows no amigo-gym command"
    assert used <= set(COMMANDS), used - set(COMMANDS)


def _plain(text: str) -> str:
    """Text without markup that differs between a docstring and Markdown: backticks, role prefixes, spacing."""
    text = re.sub(r":(?:func|class|data|mod|attr):", "", text)
    return " ".join(text.replace("`", "").split())


def test_readme_mirrors_the_env_card() -> None:
    """Every section of AmigoBotEnv's docstring (the env card) appears in the README."""
    import inspect

    from amigo_gym.envs import AmigoBotEnv

    doc = inspect.getdoc(AmigoBotEnv)
    assert doc is not None
    readme = _plain((ROOT / "README.md").read_text())
    sections = [s for s in doc.partition("\n\n")[2].split("## ") if s.strip()]
    assert len(sections) >= 9
    for sec in sections:
        assert _plain(sec) in readme, sec.splitlines()[0]


def test_readme_images_exist() -> None:
    text = (ROOT / "README.md").read_text()
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert len(images) >= 5
    for img in images:
        assert (ROOT / img).is_file(), img
