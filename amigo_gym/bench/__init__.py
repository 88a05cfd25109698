"""Benchmarks of the exact step and of the environments against peers measured in the same run.

Each command's settings are one frozen dataclass: its fields give the options (one source for each default and
help text, :func:`amigo_gym.options.add_dataclass_options`) and its ``__post_init__`` refuses a value out of range
in one line; :func:`run_command` runs the command.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TypeVar

__all__ = ["run_command"]

T = TypeVar("T")


def run_command(
    cls: type[T], run: Callable[[T], int | None], argv: Sequence[str] | None, prog: str, description: str
) -> int:
    """``run(settings)`` with the settings ``cls`` of the command line ``argv`` (default ``sys.argv[1:]``).

    A malformed option is the parser's one-line error (``SystemExit`` 2; ``--help``: 0); a value ``cls`` refuses, or
    a bad input met by ``run``, is one line on stderr and the returned status 2
    (:func:`amigo_gym.options.run_guarded`).
    """
    import sys

    from amigo_gym.options import OneLineParser, add_dataclass_options, run_guarded, settings_from_args

    parser = OneLineParser(prog=prog, description=description)
    add_dataclass_options(parser, cls)
    namespace = parser.parse_args(sys.argv[1:] if argv is None else list(argv))
    return run_guarded(lambda: run(settings_from_args(cls, namespace)), prog)
