"""Benchmarks of the exact step and of the environments against peers measured in the same run."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import TypeVar

from amigo_gym.options import OneLineParser, add_dataclass_options, run_guarded, settings_from_args

T = TypeVar("T")


def run_command(cls: type[T], run: Callable[[T], int | None], argv: Sequence[str] | None, prog: str, doc: str) -> int:
    """``run(settings)`` with the settings dataclass ``cls`` from the command line ``argv`` (default ``sys.argv[1:]``):
    a malformed option exits with the parser's one-line error (status 2), a value ``cls`` refuses (or a bad input met
    by ``run``) is one line and the returned status 2 (:func:`amigo_gym.options.run_guarded`). An option whose unit
    is ``[file]`` shows ``FILE`` as its argument in ``--help``."""
    parser = OneLineParser(prog=prog, description=doc)
    add_dataclass_options(parser, cls)
    for action in parser._actions:
        action.metavar = "FILE" if "[file]" in str(action.help) else action.metavar
    namespace = parser.parse_args(sys.argv[1:] if argv is None else list(argv))
    return run_guarded(lambda: run(settings_from_args(cls, namespace)), prog)
