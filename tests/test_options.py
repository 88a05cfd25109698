"""Options derived from a settings dataclass (amigo_gym.tools.options): one source for each default and help."""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import pytest

from amigo_gym.tools.options import (
    OneLineParser,
    add_dataclass_options,
    attribute_help,
    cli,
    json_object,
    parse_settings,
    settings_from_args,
)


@dataclass
class Demo:
    """A command's settings.

    Attributes:
        algos: algorithms (required).
        count: how many [items].
        rate: step size [1/s], ``> 0``
            (continued on a second line).
        name: a name [name] (default: derived from --count).
        mode: how.
        size: width and height [m].
        widths: layer widths [units].
        fast: go fast.
        progress: show a bar; --no-progress: none.
        norm: normalise.
        kwargs: keywords as JSON [json].
        path: a file [file].
        secret: internal.
        argv: not an option.
    """

    algos: list[Literal["ppo", "sac"]] = field(metadata=cli("--algo"))
    count: int = 3
    rate: float = 0.5
    name: str | None = None
    mode: Literal["a", "b", "c"] = "b"
    size: tuple[float, float] = (1.0, 2.0)
    widths: tuple[int, ...] = (64, 64)
    fast: bool = False
    progress: bool = field(default=True, metadata=cli("--no-progress"))
    norm: bool = True
    kwargs: dict[str, Any] = field(default_factory=dict, metadata=cli(parse=json_object))
    path: Path = Path("out")
    secret: int = field(default=0, metadata=cli(hidden=True))
    argv: list[str] = field(default_factory=list, metadata=cli(skip=True))

    def validate(self) -> None:
        if self.count < 1:
            raise ValueError(f"--count must be >= 1, got {self.count}")


def _parser() -> argparse.ArgumentParser:
    p = OneLineParser(prog="demo")
    add_dataclass_options(p, Demo)
    return p


def test_defaults_and_types_come_from_the_fields() -> None:
    s = settings_from_args(Demo, _parser().parse_args(["--algo", "ppo"]), argv=["x"])
    assert s == Demo(algos=["ppo"], argv=["x"])
    s = settings_from_args(
        Demo,
        _parser().parse_args(
            [
                "--algo",
                "sac",
                "ppo",
                "--count",
                "7",
                "--rate",
                "0.25",
                "--name",
                "n",
                "--mode",
                "c",
                "--size",
                "3",
                "4",
                "--widths",
                "8",
                "--fast",
                "--no-progress",
                "--norm",
                "false",
                "--kwargs",
                '{"a":1}',
                "--path",
                "p",
                "--secret",
                "2",
            ]
        ),
    )
    assert s == Demo(["sac", "ppo"], 7, 0.25, "n", "c", (3.0, 4.0), (8,), True, False, False, {"a": 1}, Path("p"), 2)
    assert isinstance(s.size, tuple) and isinstance(s.widths, tuple) and isinstance(s.algos, list)


def test_help_is_the_docstring_with_units_and_the_default() -> None:
    text = " ".join(_parser().format_help().split())
    assert "--count COUNT how many [items] (default: 3)" in text
    assert "step size [1/s], > 0 (continued on a second line) (default: 0.5)" in text
    assert "a name [name] (default: derived from --count)" in text  # names its default itself: not twice
    assert "--size SIZE SIZE width and height [m] (default: 1.0 2.0)" in text
    assert "--fast go fast (default: off)" in text
    assert "--no-progress none (default: off)" in text  # the field's help after "--no-progress: "
    assert "normalise [true/false] (default: True)" in text
    assert "--secret" not in text and "--argv" not in text
    assert attribute_help(Demo)["rate"] == "step size [1/s], > 0 (continued on a second line)"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([], "the following arguments are required: --algo"),
        (["--algo", "td3"], "argument --algo: invalid choice: 'td3' (choose from 'ppo', 'sac')"),
        (["--algo", "ppo", "--mode", "d"], "argument --mode: invalid choice: 'd' (choose from 'a', 'b', 'c')"),
        (["--algo", "ppo", "--count", "x"], "argument --count: invalid int value: 'x'"),
        (["--algo", "ppo", "--size", "1"], "argument --size: expected 2 arguments"),
        (["--algo", "ppo", "--kwargs", "[1]"], "--kwargs must be a JSON object, got '[1]'"),
        (["--algo", "ppo", "--kwargs", "{"], "--kwargs must be a JSON object, got '{'"),
        (["--algo", "ppo", "--count", "0"], "--count must be >= 1, got 0"),
        (["--algo", "ppo", "--norm", "maybe"], "argument --norm: expected true or false, got 'maybe'"),
    ],
)
def test_bad_values_are_one_line_errors(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        parse_settings(Demo, argv, "demo")
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err == f"demo: error: {message}\n"


def test_a_field_of_no_command_line_type_is_refused() -> None:
    @dataclass
    class Bad:
        """Attributes:
        table: a mapping.
        """

        table: dict[str, int] = field(default_factory=dict)

    with pytest.raises(TypeError, match="no command-line type"):
        add_dataclass_options(argparse.ArgumentParser(), Bad)


@dataclass(frozen=True)
class Base:
    """Options shared by two commands.

    Attributes:
        log: the log [file].
        only: families to draw [names] (default: all).
    """

    log: str = field(metadata=cli(positional=True))
    only: list[str] | None = field(default=None, metadata=cli(nargs="*"))


@dataclass(frozen=True)
class Child(Base):
    """A command with a positional argument, a group of exclusive options, a metavar and named choices.

    Attributes:
        only: families, as the child says [names] (default: all).
        at: brake at [s].
        laps: laps [laps].
        suite: suite version.
        csv: a CSV file [file], written whole (they are
            files: a continuation line).
    """

    at: float | None = field(default=None, metadata=cli(group="brake"))
    laps: float | None = field(default=None, metadata=cli(group="brake"))
    suite: str = field(default="v2", metadata=cli(choices=("v1", "v2")))
    csv: str | None = field(default=None, metadata=cli(metavar="FILE"))


def test_positional_group_metavar_choices_nargs_and_inherited_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert parse_settings(Child, ["x.csv"], "child") == Child("x.csv")
    s = parse_settings(Child, ["x.csv", "--only", "--at", "2", "--suite", "v1", "--csv", "o.csv"], "child")
    assert s == Child("x.csv", [], 2.0, None, "v1", "o.csv")
    p = OneLineParser(prog="child")
    add_dataclass_options(p, Child)
    text = " ".join(p.format_help().split())
    assert "[--at AT | --laps LAPS]" in text
    assert "--csv FILE a CSV file [file], written whole (they are files: a continuation line)" in text
    assert "log the log [file]" in text  # the base class's docstring
    assert "families, as the child says [names] (default: all)" in text  # the child's entry replaces the base's
    assert "--suite {v1,v2} suite version (default: v2)" in text
    for argv, message in (
        (["x", "--at", "1", "--laps", "2"], "argument --laps: not allowed with argument --at"),
        (["x", "--suite", "v3"], "argument --suite: invalid choice: 'v3' (choose from 'v1', 'v2')"),
        ([], "the following arguments are required: log"),
    ):
        with pytest.raises(SystemExit):
            parse_settings(Child, argv, "child")
        assert capsys.readouterr().err == f"child: error: {message}\n"


def test_a_parsed_default_set_on_the_parser_is_kept() -> None:
    """``set_defaults`` of an already parsed value (train-fast's ``--hyperparams`` file) reaches the field as is."""
    p = _parser()
    p.set_defaults(kwargs={"a": 1})
    assert settings_from_args(Demo, p.parse_args(["--algo", "ppo"])).kwargs == {"a": 1}
    assert settings_from_args(Demo, p.parse_args(["--algo", "ppo", "--kwargs", '{"b":2}'])).kwargs == {"b": 2}


def test_no_command_builds_its_options_by_hand() -> None:
    """Every sub-command derives its parser from a settings dataclass (issue 19: one source for each setting)."""
    root = Path(__file__).resolve().parents[1] / "amigo_gym"
    hand_made = [
        str(f.relative_to(root))
        for f in sorted(root.rglob("*.py"))
        if f.name != "options.py" and ".add_argument(" in f.read_text()
    ]
    assert hand_made == []


@dataclass(frozen=True)
class _Files:
    """Settings with files.

    Attributes:
        log: the log [file].
        out: output [file] (default: none).
        table: a table [file], named by cli.
        rows: rows [rows].
    """

    log: str
    out: str | None = None
    table: str | None = field(default=None, metadata=cli(metavar="CSV"))
    rows: int = 3


def test_an_option_whose_unit_is_a_file_shows_file() -> None:
    """``--out FILE`` (unit ``[file]``), not ``--out OUT``; a metavar named by ``cli``, a positional and other units
    keep theirs."""
    p = OneLineParser(prog="files")
    add_dataclass_options(p, _Files)
    usage = " ".join(p.format_usage().split())
    assert usage == "usage: files [-h] --log FILE [--out FILE] [--table CSV] [--rows ROWS]"
