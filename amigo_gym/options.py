"""Command-line helpers shared by every ``amigo-gym`` sub-command: one-line errors, option help with defaults,
options derived from a settings dataclass, and the extra-module probe.

Sits at the bottom of the package (standard library only), so that the sub-commands in ``training``,
``analysis``, ``bench`` and ``model`` import it downwards; the dispatcher :mod:`amigo_gym.cli` imports it too
and is imported by nothing.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

__all__ = [
    "HelpFormatter",
    "OneLineParser",
    "add_dataclass_options",
    "attribute_help",
    "install_hint",
    "missing_modules",
    "run_guarded",
]


class HelpFormatter(argparse.HelpFormatter):
    """Appends ``(default: X)`` to an option's help unless the help already names its default.

    Flags (``store_true``) say ``(default: off)``. Units stay the help text's job: every option taking a
    value names its unit in brackets, e.g. ``[m]``, ``[s]``, ``[steps]``, ``[file]``.
    """

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if "default" in text.lower() or not action.option_strings or action.default is argparse.SUPPRESS:
            return text
        if isinstance(action, argparse._StoreTrueAction):
            return f"{text} (default: off)"
        if action.default is None:
            return text
        default = action.default
        shown = " ".join(map(str, default)) if isinstance(default, list | tuple) else str(default)
        return f"{text} (default: {shown!r})" if shown == "" else f"{text} (default: {shown})"


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line on stderr and exit status 2 (no usage dump).

    Uses :class:`HelpFormatter` (every option's help ends with its default) unless told otherwise.
    """

    def __init__(self, *args: object, **kwargs: object) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def attribute_help(cls: type) -> dict[str, str]:
    """The ``Attributes:`` section of a dataclass's docstring as ``{field: text}`` (continuation lines joined)."""
    doc = cls.__doc__ or ""
    out: dict[str, str] = {}
    inside, current = False, ""
    for line in doc.splitlines():
        stripped = line.strip()
        if stripped == "Attributes:":
            inside = True
            continue
        if not inside:
            continue
        if not stripped:
            break
        name, colon, text = stripped.partition(": ")
        if colon and name.isidentifier():
            current = name
            out[name] = text.rstrip(".")
        elif current:
            out[current] += " " + stripped
    return out


def add_dataclass_options(parser: argparse.ArgumentParser, cls: type) -> None:
    """One option ``--field-name`` per field of the dataclass ``cls``, typed and defaulted as the field.

    The help of each option is the field's line in the class docstring's ``Attributes:`` section (which
    therefore names the unit in brackets); the default is appended by :class:`HelpFormatter`.
    """
    from dataclasses import fields

    helps = attribute_help(cls)
    defaults = cls()
    for f in fields(cls):
        default = getattr(defaults, f.name)
        flag = "--" + f.name.replace("_", "-")
        parser.add_argument(flag, type=type(default), default=default, help=helps.get(f.name, ""))


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def run_guarded(fn: Callable[[], int | None], prog: str) -> int:
    """Run ``fn``; a bad input (``ValueError``, ``FileNotFoundError``, ``FileExistsError``) gives one line, status 2."""
    try:
        rc = fn()
    except (ValueError, FileNotFoundError, FileExistsError) as exc:
        print(f"{prog}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    return 0 if rc is None else int(rc)


def missing_modules(modules: Sequence[str]) -> list[str]:
    """The modules of ``modules`` that cannot be found (``importlib.util.find_spec``; nothing is imported)."""
    out = []
    for m in modules:
        try:
            found = importlib.util.find_spec(m) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            out.append(m)
    return out


def install_hint(extra: str) -> str:
    """The two commands that install ``extra``: from an index, and from a clone of the repository."""
    return f'pip install "amigo-gym[{extra}]" (from a clone: pip install -e ".[{extra}]")'
