"""The README: short, self-contained, its set-up commands agree with CI, its commands and code run."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from amigo_gym.tools.cli import COMMANDS

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


def test_readme_images_exist() -> None:
    text = (ROOT / "README.md").read_text()
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert images
    for img in images:
        assert (ROOT / img).is_file(), img


def test_readme_is_short_and_names_nothing_outside_the_repository() -> None:
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    assert not re.search(r"(\.\./|\bshared/|MODEL\.md|/work/|~/)", text)
    for link in re.findall(r"\]\(([^)#]+)", text):  # every relative link points into the repository
        if not link.startswith(("http://", "https://")):
            assert (ROOT / link).exists(), link


def test_docs_and_docstrings_name_nothing_outside_the_repository() -> None:
    files = [*(ROOT / "docs").glob("*.md"), *(ROOT / "amigo_gym").rglob("*.py")]
    for f in files:
        text = f.read_text(encoding="utf-8")
        assert not re.search(r"(\.\./shared|\bshared/|MODEL\.md)", text), f


def test_readme_quick_start_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The quick start's code, with a shorter training run."""
    text = (ROOT / "README.md").read_text()
    code = text.split("## Quick start", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    assert len(code.strip().splitlines()) < 15
    namespace: dict[str, object] = {}
    small = code.replace(
        "AmigoBotSB3VecEnv(16), n_steps=256).learn(20_000)",
        "AmigoBotSB3VecEnv(2), n_steps=16, batch_size=32, n_epochs=1).learn(32)",
    )
    assert small != code
    exec(compile(small, "README.md", "exec"), namespace)
    assert namespace["reference"].predict(namespace["obs"])[0].shape == (2,)  # type: ignore[attr-defined]


#: shorter budgets for the README's code (the code is otherwise run as written)
SMALL_BUDGETS = {
    "AmigoBotSB3VecEnv(16), n_steps=256).learn(20_000)": (
        "AmigoBotSB3VecEnv(2), n_steps=16, batch_size=32, n_epochs=1).learn(32)"
    ),
}


def _python_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text()
    return re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)


def test_every_python_block_of_the_readme_runs_when_pasted_alone() -> None:
    """Each ```python block, alone in a fresh interpreter (no import from another block), as a newcomer pastes it."""
    blocks = _python_blocks()
    assert len(blocks) >= 3
    for block in blocks:
        code = block
        for long, short in SMALL_BUDGETS.items():
            code = code.replace(long, short)
        r = subprocess.run(
            [sys.executable, "-c", code],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=300,
            env={**os.environ, "AMIGO_GYM_KERNEL": "numpy"},
        )
        assert r.returncode == 0, f"README block fails:\n{block}\n{r.stderr[-2000:]}"


def test_architecture_page_is_short_with_its_picture_and_table() -> None:
    """docs/architecture.md is read by a newcomer in minutes: at most 300 lines, with the layer picture, the "which
    file to edit" table and the tolerance decision; history lives in git and CHANGELOG.md."""
    page = (ROOT / "docs" / "architecture.md").read_text()
    assert len(page.splitlines()) <= 300
    assert "figures/layers.png" in page and "## Which file to edit" in page and "1e-9" in page
    assert (ROOT / "CHANGELOG.md").is_file()
