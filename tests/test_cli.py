"""The ``amigo-gym`` dispatcher: missing extras, one-line errors, units and defaults in every ``--help``."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from amigo_gym.tools.cli import COMMANDS, main

ROOT = Path(__file__).resolve().parents[1]

#: run the CLI with the given top-level modules made unimportable (a sys.meta_path finder), no uninstall
BLOCKED_CLI = """
import sys
BLOCKED = set(sys.argv[1].split(","))
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, Block())
from amigo_gym.tools.cli import main
sys.exit(main(sys.argv[2:]))
"""


def run_blocked(blocked: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", BLOCKED_CLI, blocked, *args], cwd=ROOT, capture_output=True, text=True, timeout=120
    )


@pytest.mark.parametrize(
    ("blocked", "args", "extra", "module"),
    [
        ("stable_baselines3,torch", ["train", "--algo", "ppo", "--out", "x"], "train", "torch"),
        ("stable_baselines3", ["evaluate", "--no-plots"], "train", "stable_baselines3"),
        ("torch", ["compare", "--train-steps", "0"], "train", "torch"),
        ("sympy", ["derive"], "symbolic", "sympy"),
        ("sympy", ["verify"], "symbolic", "sympy"),
        ("matplotlib", ["paper", "--out", "x"], "plot", "matplotlib"),
    ],
)
def test_missing_extra_is_one_line_and_exit_2(blocked: str, args: list[str], extra: str, module: str) -> None:
    r = run_blocked(blocked, *args)
    assert r.returncode == 2, r.stderr
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    prog = f"amigo-gym {args[0]}"
    assert lines[0].startswith(f'{prog}: error: needs the {extra!r} extra: pip install "amigo-gym[{extra}]"')
    assert f'(from a clone: pip install -e ".[{extra}]")' in lines[0]
    assert module in lines[0]
    assert "Traceback" not in r.stderr


def test_a_module_missing_at_run_time_names_its_extra() -> None:
    """``convergence --plot`` needs matplotlib only for the plot: found missing on import, still one line."""
    r = run_blocked("matplotlib", "convergence", "--gains", "3", "--seeds", "1", "--steps", "20",
                    "--t-from", "0.5", "--t-to", "1.5", "--plot", "x.png")  # fmt: skip
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip() == (
        "amigo-gym convergence: error: needs the 'plot' extra: pip install \"amigo-gym[plot]\" "
        '(from a clone: pip install -e ".[plot]") (missing: matplotlib)'
    )


def test_verify_quick_needs_no_sympy() -> None:
    r = run_blocked("sympy", "verify", "--quick")
    assert r.returncode == 0, r.stderr
    assert "PASS" in r.stdout


def test_unexpected_error_is_one_line(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    import amigo_gym.tools.bench.core as bench

    def boom(argv: object) -> int:
        raise RuntimeError("something\nbroke")

    monkeypatch.setattr(bench, "main", boom)
    monkeypatch.delenv("AMIGO_GYM_TRACEBACK", raising=False)
    assert main(["bench-core"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("amigo-gym bench-core: error: RuntimeError: something broke")


def _option_blocks(help_text: str) -> dict[str, str]:
    """``{--option: its help text}`` parsed from argparse's ``--help`` output (wrapped lines joined)."""
    blocks: dict[str, str] = {}
    current = None
    section = ""
    for line in help_text.splitlines():
        if line and not line.startswith(" "):
            section = line
            current = None
            continue
        if "option" not in section:
            continue
        m = re.match(r"^  (-\S+.*?)(?:\s{2,}(.*))?$", line)
        if m and line.startswith("  -"):
            flags = m.group(1)
            current = max(re.findall(r"--[\w-]+", flags) or [flags.split()[0]], key=len)
            blocks[current] = f"{flags} :: {m.group(2) or ''}"
        elif current is not None:
            blocks[current] += " " + line.strip()
    return blocks


@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_option_help_gives_unit_and_default(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main([name, "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert "`" not in text, f"{name} --help shows reST markup"
    blocks = _option_blocks(text)
    blocks.pop("--help")
    assert blocks, f"{name}: no options parsed"
    for flag, text in blocks.items():
        flags, _, help_ = text.partition(" :: ")
        assert "default" in help_.lower() or "required" in help_.lower(), f"{name} {flag}: no default in {help_!r}"
        takes_value = len(flags.split(",")[-1].split()) > 1
        choices = "{" in flags
        if takes_value and not choices:
            assert re.search(r"\[[^\]]+\]", help_), f"{name} {flag}: no [unit] in {help_!r}"


@pytest.mark.parametrize(
    "args",
    [
        ["train", "--algo", "nope", "--out", "x"],
        ["evaluate", "--steps", "zero"],
        ["compare", "--seeds", "0", "--train-steps", "0"],
        ["inverse", "--radius", "-1"],
        ["verify", "--bogus"],
    ],
)
def test_bad_options_one_line_nonzero(args: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    try:
        rc = main(args)
    except SystemExit as exc:
        rc = int(exc.code or 0)
    assert rc != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"amigo-gym {args[0]}: error: "), err
