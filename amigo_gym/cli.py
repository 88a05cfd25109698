"""The ``amigo-gym`` command: a thin dispatcher; each sub-command lives in its own module.

Sub-commands import their (possibly heavy) modules only when they run, so ``amigo-gym inverse``
needs no torch and ``amigo-gym --help`` needs nothing but the standard library.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable, Sequence
from typing import NoReturn

__all__ = ["COMMANDS", "OneLineParser", "main", "run_guarded"]

#: sub-command -> (module:function taking argv, one-line summary)
COMMANDS: dict[str, tuple[str, str]] = {
    "inverse": ("amigo_gym.cli_inverse:main", "analytic inverse solution of H on a path, as CSV"),
    "paper": ("amigo_gym.analysis.paper_figures:main", "the paper's manoeuvre: Fig. 2/3-style plots and CSV"),
    "derive": ("amigo_gym.symbolic:main", "symbolic D-H derivation; print the equations (LaTeX)"),
    "train": ("amigo_gym.training.train:main", "train a PPO/SAC/TD3 baseline on AmigoBot-v0"),
    "evaluate": ("amigo_gym.training.evaluate:main", "evaluate analytic and trained agents on the fixed protocol"),
    "verify": ("amigo_gym.analysis.verify:main", "exactness figures against references (steady state, laps, symbolic)"),
    "convergence": ("amigo_gym.analysis.convergence:main", "convergence rate of the analytic policy vs its gain"),
    "compare": ("amigo_gym.training.compare:main", "main job: pretrained agents vs analytic solution, report + plots"),
    "benchmark": ("amigo_gym.training.benchmark:main", "scenario suite x agents x seeds: IQM, bootstrap CIs, plots"),
    "sweep": ("amigo_gym.training.sweep:main", "Optuna studies (hyperparameters, seed grids); SQLite or PostgreSQL"),
    "bench-core": ("amigo_gym.bench.core:main", "benchmark the batched exact step"),
    "bench-env": ("amigo_gym.bench.env:main", "benchmark the environment against peers"),
}


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line on stderr and exit status 2 (no usage dump)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def run_guarded(fn: Callable[[], int | None], prog: str) -> int:
    """Run ``fn``; turn ``ValueError``/``FileNotFoundError`` into a one-line error and exit status 2."""
    try:
        rc = fn()
    except (ValueError, FileNotFoundError, FileExistsError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    return 0 if rc is None else int(rc)


def _load(target: str) -> Callable[[Sequence[str]], int | None]:
    mod, _, fn = target.partition(":")
    func: Callable[[Sequence[str]], int | None] = getattr(importlib.import_module(mod), fn)
    return func


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        lines = ["usage: amigo-gym COMMAND [options]   (amigo-gym COMMAND --help for its options)", "", "commands:"]
        lines += [f"  {name:<11} {summary}" for name, (_, summary) in COMMANDS.items()]
        print("\n".join(lines))
        return 0 if args else 2
    if args[0] == "--version":
        from amigo_gym import __version__

        print(__version__)
        return 0
    name, rest = args[0], args[1:]
    if name not in COMMANDS:
        print(f"amigo-gym: error: unknown command {name!r} (choose from {', '.join(COMMANDS)})", file=sys.stderr)
        return 2
    rc = _load(COMMANDS[name][0])(rest)
    return 0 if rc is None else int(rc)


if __name__ == "__main__":
    sys.exit(main())
