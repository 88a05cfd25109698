"""The ``amigo-gym`` command: a dispatcher to one module per sub-command, imported only when it runs.

A missing extra is one line naming it (exit status 2); every other error is one line on stderr and a non-zero status
(``AMIGO_GYM_TRACEBACK=1`` shows the traceback of an unexpected error).
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Sequence
from typing import NamedTuple

from amigo_gym.tools.options import _one_line, install_hint, missing_modules


class Command(NamedTuple):
    """A sub-command: ``target`` (``module:function`` taking the remaining arguments, returning the exit status),
    ``summary`` (one line of ``--help``), the ``extra`` of ``pip install "amigo-gym[<extra>]"`` it needs (``None``:
    none), the ``modules`` of that extra it imports, and the flags that lift the need (``unless``: ``verify
    --quick`` needs no SymPy)."""

    target: str
    summary: str
    extra: str | None
    modules: tuple[str, ...]
    unless: tuple[str, ...]


#: amigo_gym.io.TRUST_ENV (this module imports the standard library only)
TRUST_ENV = "AMIGO_GYM_TRUST_UNVERIFIED"

_TRAIN = "train: torch stable_baselines3 yaml matplotlib filelock"

#: name, module under amigo_gym.tools (``:function``, default ``main``), "extra: the modules of it that the command
#: imports" ("": none; "unless FLAG": the flag lifts the need), summary
_TABLE = (
    ("inverse", "analysis.paper_figures:main_inverse", "", "analytic inverse solution of H on a path, as CSV"),
    ("paper", "analysis.paper_figures", "plot: matplotlib", "the paper's manoeuvre: Fig. 2/3-style plots and CSV"),
    ("derive", "symbolic", "symbolic: sympy", "symbolic D-H derivation; print the equations (LaTeX)"),
    ("train", "training.train", "train: torch stable_baselines3 yaml tqdm rich",
     "train a PPO/SAC/TD3 baseline on AmigoBot-v0"),
    ("evaluate", "training.evaluate", _TRAIN, "evaluate analytic and trained agents on the fixed protocol"),
    ("verify", "analysis.verify", "symbolic: sympy unless --quick",
     "exactness checks against references, PASS/FAIL (exit 1 on a FAIL)"),
    ("convergence", "analysis.convergence", "", "convergence rate of the analytic policy vs its gain"),
    ("compare", "training.compare", _TRAIN, "main job: pretrained agents vs analytic solution, report + plots"),
    ("benchmark", "training.benchmark", _TRAIN, "scenario suite x agents x seeds: IQM, bootstrap CIs, plots"),
    ("curves", "training.curves", "train: tqdm matplotlib",
     "learning curves over training seeds (eval.json), time to a tracking threshold"),
    ("sweep", "training.sweep", "bench: optuna torch stable_baselines3 yaml",
     "Optuna studies (hyperparameters, seed grids); SQLite or PostgreSQL"),
    ("replay", "analysis.replay:main_replay", "logs: matplotlib",
     "replay a robot's log (CSV or ROS 2 bag) through the model: errors, plot"),
    ("identify", "analysis.replay:main_identify", "logs: matplotlib",
     "fit wheel radii, half track, delay to a robot's log: robot.json"),
    ("train-fast", "training.fastppo", "train: torch",
     "fast PPO (or residual on the analytic controller) over the native AmigoBot-v1 vector env"),
    ("bench-train", "bench.train", "train: torch stable_baselines3",
     "training throughput: the fast PPO against SB3 PPO, same run"),
    ("bench-core", "bench.core", "", "benchmark the batched exact step"),
    ("bench-env", "bench.env", "", "benchmark the environment against peers"),
    ("gallery", "analysis.gallery", "render: pygame matplotlib",
     "pictures of every AmigoBot-v1 path family (docs/figures/v1_*.png)"),
)  # fmt: skip


def _command(target: str, needs: str, summary: str) -> Command:
    extra, _, rest = needs.partition(":")
    modules, _, unless = rest.partition(" unless ")
    target = f"amigo_gym.tools.{target}" + ("" if ":" in target else ":main")
    return Command(target, summary, extra or None, tuple(modules.split()), tuple(unless.split()))


COMMANDS: dict[str, Command] = {name: _command(target, needs, summary) for name, target, needs, summary in _TABLE}

#: optional top-level module -> the extra that installs it (for a module missing at run time)
EXTRA_OF_MODULE: dict[str, str] = {
    module: extra
    for extra, modules in (
        ("train", "torch stable_baselines3 sb3_contrib filelock yaml tqdm rich tensorboard"),
        ("symbolic", "sympy"),
        ("plot", "matplotlib"),
        ("render", "pygame"),
        ("video", "moviepy"),
        ("notebook", "nbclient nbformat"),
        ("bench", "optuna psycopg2"),
        ("logs", "rosbags"),
    )
    for module in modules.split()
}


def _needs_extra(prog: str, extra: str, missing: Sequence[str]) -> int:
    names = ", ".join(missing)
    print(f"{prog}: error: needs the {extra!r} extra: {install_hint(extra)} (missing: {names})", file=sys.stderr)
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym``."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        print("usage: amigo-gym COMMAND [options]   (amigo-gym COMMAND --help for its options)\n")
        print("Every command takes --trust-unverified: load model zips, statistics, replay buffers and checkpoints")
        print("(pickles: loading one runs code) that are neither shipped nor written by a run here.\n\ncommands:")
        for name, c in COMMANDS.items():
            print(f"  {name:<11} {c.summary}" + (f"  [{c.extra}]" if c.extra else ""))
        return 0 if args else 2
    if args[0] == "--version":
        from amigo_gym import __version__

        print(__version__)
        return 0
    name, rest = args[0], args[1:]
    if name not in COMMANDS:
        print(f"amigo-gym: error: unknown command {name!r} (choose from {', '.join(COMMANDS)})", file=sys.stderr)
        return 2
    cmd = COMMANDS[name]
    prog = f"amigo-gym {name}"
    if cmd.extra and not set(cmd.unless) & set(rest) and (missing := missing_modules(cmd.modules)):
        return _needs_extra(prog, cmd.extra, missing)
    trust = "--trust-unverified" in rest  # every command: load pickles that are neither shipped nor written here
    before = os.environ.get(TRUST_ENV)
    if trust:
        rest = [a for a in rest if a != "--trust-unverified"]
        os.environ[TRUST_ENV] = "1"  # amigo_gym.io.require_trust; inherited by the command's own subprocesses
    try:
        module, _, function = cmd.target.partition(":")
        rc = getattr(importlib.import_module(module), function)(rest)
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # an unexpected error: still one line unless asked for the traceback
        top = (exc.name or "").partition(".")[0] if isinstance(exc, ModuleNotFoundError) else None
        if top in EXTRA_OF_MODULE:
            return _needs_extra(prog, EXTRA_OF_MODULE[top], [top])
        if os.environ.get("AMIGO_GYM_TRACEBACK"):
            raise
        line = f"{type(exc).__name__}: {_one_line(exc)} (AMIGO_GYM_TRACEBACK=1 shows the traceback)"
        print(f"{prog}: error: {_one_line(exc) if top is not None else line}", file=sys.stderr)
        return 1
    finally:
        if trust and before is None:
            del os.environ[TRUST_ENV]
    return 0 if rc is None else int(rc)
