"""Command-line helpers of every ``amigo-gym`` sub-command: options derived from a settings dataclass, one-line
errors, range checks, the extra-module probe."""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import itertools
import json
import re
import sys
import types
from collections.abc import Callable, Iterator, Sequence
from dataclasses import MISSING, Field, fields
from typing import Any, Literal, NoReturn, TypeVar, Union, get_args, get_origin, get_type_hints

T = TypeVar("T")


class HelpFormatter(argparse.HelpFormatter):
    """Appends ``(default: X)`` (a flag: ``(default: off)``) to an option's help unless it names its default."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text, default = action.help or "", action.default
        if "default" in text.lower() or not action.option_strings or default in (None, argparse.SUPPRESS):
            return text
        if isinstance(action, argparse._StoreTrueAction | argparse._StoreFalseAction):
            return f"{text} (default: off)"
        shown = " ".join(map(str, default)) if isinstance(default, list | tuple) else str(default)
        return f"{text} (default: {shown or repr(shown)})"


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line on stderr and exit status 2; :class:`HelpFormatter` by default,
    description and epilog without reST markup."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        kwargs |= {k: _plain(v) for k, v in kwargs.items() if k in ("description", "epilog") and isinstance(v, str)}
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def attribute_help(cls: type) -> dict[str, str]:
    """The ``Attributes:`` sections of a dataclass's docstring and its bases' as ``{field: text}`` (continuation
    lines joined, reST markup and the final full stop removed; a class's entry replaces its bases')."""
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        lines = (klass.__dict__.get("__doc__") or "").partition("Attributes:\n")[2].splitlines()
        indent, current = len(lines[0]) - len(lines[0].lstrip()) if lines else 0, ""
        for line in itertools.takewhile(str.strip, lines):  # an entry starts at the first entry's indent
            name, colon, text = line.strip().partition(": ")
            if colon and name.isidentifier() and len(line) - len(line.lstrip()) == indent:
                current, out[name] = name, text
            elif current:
                out[current] += " " + line.strip()
    return {name: _plain(text).rstrip(".") for name, text in out.items()}


def _plain(text: str) -> str:
    return re.sub(r":\w+:`~?([^`]*)`", r"\1", text).replace("``", "")


def cli(
    flag: str | None = None,
    *,
    required: bool = False,
    hidden: bool = False,
    parse: Callable[[str], Any] | None = None,
    skip: bool = False,
    positional: bool = False,
    metavar: str | None = None,
    choices: Sequence[Any] | None = None,
    nargs: str | int | None = None,
    group: str | None = None,
) -> dict[str, Any]:
    """Command-line metadata of a settings field, for ``field(..., metadata=cli(...))``: ``flag``, the option's name
    when not ``--field-name`` (a ``--no-x`` flag of a ``bool`` field stores ``False``); ``required``: the option must
    be given although the field has a default; ``hidden``: left out of ``--help``; ``parse`` turns the option's text
    into the value (e.g. :func:`json_object`; a ``ValueError`` becomes ``<flag> <message>``); ``skip``: no option (the
    command sets the field); ``positional``: a positional argument; ``metavar``, ``choices``, ``nargs``: argparse's,
    in place of the type's; ``group``: a mutually exclusive group's name."""
    return {"cli": dict(locals())}  # the arguments above, by name


def json_object(text: str) -> dict[str, Any]:
    """``text`` as a JSON object; ``ValueError`` otherwise."""
    with contextlib.suppress(ValueError):
        if isinstance(value := json.loads(text), dict):
            return value
    raise ValueError(f"must be a JSON object, got {text!r}")


def parse_bool(text: str) -> bool:
    """``true/yes/on/1`` or ``false/no/off/0`` (any case) as a ``bool``."""
    words = {"1": True, "true": True, "yes": True, "on": True, "0": False, "false": False, "no": False, "off": False}
    if (value := words.get(text.strip().lower())) is None:
        raise argparse.ArgumentTypeError(f"expected true or false, got {text!r}")
    return value


def _options(cls: type) -> Iterator[tuple[Field[Any], dict[str, Any], str, Any]]:
    """The option fields of ``cls``, each with its :func:`cli` metadata, flag and type (``X`` of ``X | None``)."""
    hints = get_type_hints(cls)
    for f in fields(cls):
        meta = {**cli()["cli"], **f.metadata.get("cli", {})}
        if f.init and not meta["skip"]:
            args = [a for a in get_args(hints[f.name]) if a is not type(None)]
            tp = args[0] if get_origin(hints[f.name]) in (Union, types.UnionType) and len(args) == 1 else hints[f.name]
            yield f, meta, str(meta["flag"] or "--" + f.name.replace("_", "-")), tp


def add_dataclass_options(parser: argparse.ArgumentParser, cls: type) -> None:
    """One option ``--field-name`` (or :func:`cli`'s) per field of the dataclass ``cls``, typed and defaulted as the
    field, its help the field's ``Attributes:`` entry (unit in brackets; ``[file]``: metavar ``FILE``); no default: a
    required option. Types: one-argument classes, ``X | None``, ``Literal`` (choices), ``list[X]``/``tuple[X, ...]``
    (``nargs="+"``), ``tuple[X, X]`` (``nargs=2``); ``bool``: a flag (default ``False``), a ``--no-x`` flag, else
    ``true``/``false``."""
    helps, groups = attribute_help(cls), {}
    for f, meta, flag, tp in _options(cls):
        default = f.default_factory() if f.default_factory is not MISSING else f.default
        help_text = argparse.SUPPRESS if meta["hidden"] else helps.get(f.name, "")
        kw: dict[str, Any] = {"help": help_text}
        if default is MISSING or meta["required"]:
            kw["required"] = True
        else:
            kw["default"] = list(default) if isinstance(default, tuple) else default
        origin, args = get_origin(tp), get_args(tp)
        if meta["parse"] is not None:
            kw.update(type=str, default=None)
        elif tp is bool and flag.startswith("--no-"):  # its help: what the field's help says after "--no-x: "
            kw.update(action="store_false", help=help_text.partition(f"{flag}: ")[2] or help_text)
        elif tp is bool and default is False:
            kw["action"] = "store_true"
        elif tp is bool:
            kw.update(type=parse_bool, help=f"{help_text} [true/false]")
        else:
            if origin in (list, tuple):  # the option's arguments are the items
                tp, kw["nargs"] = args[0], len(args) if origin is tuple and Ellipsis not in args else "+"
            if get_origin(tp) is Literal:
                kw.update(type=type(get_args(tp)[0]), choices=get_args(tp))
            elif isinstance(tp, type) and get_origin(tp) is None:  # (3.10: dict[str, int] is a type)
                kw["type"] = tp
            else:
                raise TypeError(f"no command-line type for {tp!r}")
        if "[file]" in help_text and not meta["positional"] and "action" not in kw:
            kw["metavar"] = "FILE"  # an option whose unit is a file shows FILE as its argument in --help
        kw.update({k: meta[k] for k in ("metavar", "choices", "nargs") if meta[k] is not None})
        if meta["group"] is not None and meta["group"] not in groups:
            groups[meta["group"]] = parser.add_mutually_exclusive_group()
        target = groups.get(meta["group"], parser)
        if meta["positional"]:
            kw.pop("required", None)
            target.add_argument(f.name, **kw)
        else:
            target.add_argument(flag, dest=f.name, **kw)


def settings_from_args(cls: type[T], namespace: argparse.Namespace, **extra: Any) -> T:
    """The settings ``cls(...)`` from the options :func:`add_dataclass_options` added (``extra``: further fields),
    ``validate()``d when ``cls`` has it; ``cli(parse=...)`` options are parsed here (a ``ValueError`` becomes ``<flag>
    <message>``)."""
    kw: dict[str, Any] = {}
    for f, meta, flag, tp in _options(cls):
        value = getattr(namespace, f.name, None)
        if value is None and (meta["parse"] is not None or not hasattr(namespace, f.name)):
            continue
        if meta["parse"] is not None and isinstance(value, str):  # else a parsed default set on the parser
            try:
                value = meta["parse"](value)
            except ValueError as exc:
                raise ValueError(f"{flag} {exc}") from None
        elif isinstance(value, list):
            value = tuple(value) if get_origin(tp) is tuple else list(value)
        kw[f.name] = value
    out = cls(**kw, **extra)
    getattr(out, "validate", lambda: None)()
    return out


def _parse(cls: type, argv: Sequence[str] | None, prog: str, doc: str) -> tuple[OneLineParser, argparse.Namespace]:
    parser = OneLineParser(prog=prog, description=doc)
    add_dataclass_options(parser, cls)
    return parser, parser.parse_args(sys.argv[1:] if argv is None else list(argv))


def parse_settings(cls: type[T], argv: Sequence[str] | None, /, prog: str, description: str = "", **extra: Any) -> T:
    """The settings ``cls`` of the command ``prog`` from ``argv`` (``None``: ``sys.argv[1:]``), ``validate()``d when
    ``cls`` has it; a bad value exits with the parser's one-line error (status 2)."""
    parser, namespace = _parse(cls, argv, prog, description)
    try:
        return settings_from_args(cls, namespace, **extra)
    except ValueError as exc:
        parser.error(str(exc))


def run_command(cls: type[T], run: Callable[[T], int | None], argv: Sequence[str] | None, prog: str, doc: str) -> int:
    """``run(settings)`` with the settings ``cls`` from ``argv``, ``validate()``d when ``cls`` has it: a malformed
    option exits (status 2); a value ``cls`` or ``run`` refuses is one line and the returned status 2."""
    namespace = _parse(cls, argv, prog, doc)[1]
    return run_guarded(lambda: run(settings_from_args(cls, namespace)), prog)


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def run_guarded(fn: Callable[[], int | None], prog: str) -> int:
    """Run ``fn``; a ``ValueError``, ``FileNotFoundError`` or ``FileExistsError`` gives one line, status 2."""
    try:
        rc = fn()
    except (ValueError, FileNotFoundError, FileExistsError) as exc:
        print(f"{prog}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    return 0 if rc is None else int(rc)


def say(message: str) -> None:
    """A progress line on stderr (a command's results go to stdout)."""
    print(message, file=sys.stderr, flush=True)


def missing_modules(modules: Sequence[str]) -> list[str]:
    """The modules of ``modules`` that ``importlib.util.find_spec`` cannot find (nothing is imported)."""
    missing = []
    for m in modules:
        with contextlib.suppress(ImportError, ValueError):
            if importlib.util.find_spec(m) is not None:
                continue
        missing.append(m)
    return missing


def install_hint(extra: str) -> str:
    """The commands that install ``extra``: from an index, and from a clone."""
    return f'pip install "amigo-gym[{extra}]" (from a clone: pip install -e ".[{extra}]")'


def check_fields(owner: str, obj: object, **ranges: tuple[float, ...]) -> None:
    """``check_real(owner, name, ...)`` of each named field of ``obj`` in ``(low, high[, low_open])``: ``None``
    passes, a tuple is checked item by item (``name[i]``)."""
    from amigo_gym.model.params import check_real

    for name, (low, high, *opened) in ranges.items():
        value = getattr(obj, name)
        items = enumerate(value) if isinstance(value, tuple) else [] if value is None else [(None, value)]
        for i, v in items:
            check_real(owner, name if i is None else f"{name}[{i}]", v, low, high, low_open=any(opened))
