"""``amigo-gym bench-env``: speed of ``AmigoBot-v0`` against peers measured in the same run.

Two comparisons, each a ratio of times measured back to back on the same machine (ratios are less
sensitive to the machine's load than the absolute figures):

* **single env**: time of one ``step`` of ``gym.make("AmigoBot-v0")`` against one of
  ``gym.make("Pendulum-v1")`` (both with the wrappers of ``gym.make``: ``TimeLimit``,
  ``OrderEnforcing``, ``PassiveEnvChecker``); the loop resets on episode end, as training does.
* **vector env**: env-steps per second of the native :class:`amigo_gym.envs.AmigoBotVectorEnv`
  (``gym.make_vec``) at several ``N`` against gymnasium's native ``CartPoleVectorEnv`` and against
  ``SyncVectorEnv`` of ``AmigoBot-v0`` itself (a Python loop over ``N`` single envs; measured only
  up to ``--sync-max`` envs, as it is slow to build and to step).

Actions are uniform random in the action space, drawn in advance (a pool of 16 batches cycled), so
episodes end and autoreset at the rate of an untrained policy. One env-step is one robot advanced
by one ``dt``. Each figure is the median over ``--repeats`` repeats, each lasting at least
``--min-time`` seconds. ``--quick`` is a smoke run (small sizes, short times).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from amigo_gym.cli import OneLineParser, run_guarded
from amigo_gym.io import atomic_write_json
from amigo_gym.params import check_range

__all__ = ["SingleResult", "VectorRow", "bench_single", "bench_vector", "format_report", "main"]

from amigo_gym.bench.core import measure

PROG = "amigo-gym bench-env"
DEFAULT_SIZES = (1, 64, 1024, 4096, 16384)
QUICK_SIZES = (1, 64, 1024)
POOL = 16


def _single_stepper(env: Any, seed: int) -> Callable[[], object]:
    """One ``step`` of a single env with a random action; resets on termination or truncation."""
    rng = np.random.default_rng(seed)
    space = env.action_space
    pool = rng.uniform(space.low, space.high, (POOL, *space.shape)).astype(space.dtype)
    env.reset(seed=seed)
    k = [0]

    def step() -> object:
        i = k[0] = (k[0] + 1) % POOL
        _, _, term, trunc, _ = env.step(pool[i])
        if term or trunc:
            env.reset()
        return None

    return step


def _vector_stepper(envs: Any, seed: int) -> Callable[[], object]:
    """One ``step`` of a vector env (autoreset inside) with random actions."""
    rng = np.random.default_rng(seed)
    space = envs.action_space
    if hasattr(space, "nvec") or hasattr(space, "n"):  # CartPole: discrete actions
        pool = [space.sample() for _ in range(POOL)]
    else:
        pool = list(rng.uniform(space.low, space.high, (POOL, *space.shape)).astype(space.dtype))
    envs.reset(seed=seed)
    k = [0]

    def step() -> object:
        i = k[0] = (k[0] + 1) % POOL
        envs.step(pool[i])
        return None

    return step


@dataclass(frozen=True)
class SingleResult:
    """Time of one single-env step [us] and the ratio AmigoBot / Pendulum (goal <= 0.3)."""

    amigobot_us: float
    pendulum_us: float

    @property
    def ratio(self) -> float:
        """AmigoBot's time per step over Pendulum's (lower is better)."""
        return self.amigobot_us / self.pendulum_us


@dataclass(frozen=True)
class VectorRow:
    """Env-steps per second at ``N`` robots (``None`` where not measured)."""

    n: int
    native: float
    cartpole: float
    sync: float | None

    @property
    def ratio_cartpole(self) -> float:
        """Native AmigoBot over native CartPole throughput (goal >= 1 at N = 4096)."""
        return self.native / self.cartpole

    @property
    def ratio_sync(self) -> float | None:
        """Native over ``SyncVectorEnv`` throughput of AmigoBot itself (goal >= 20 at N = 4096)."""
        return None if self.sync is None else self.native / self.sync


def bench_single(repeats: int, min_time: float, seed: int = 0) -> SingleResult:
    """Time one step of ``gym.make("AmigoBot-v0")`` and of ``gym.make("Pendulum-v1")``."""
    import gymnasium as gym

    import amigo_gym  # noqa: F401  (registers AmigoBot-v0)

    amigo = _single_stepper(gym.make("AmigoBot-v0"), seed)
    pend = _single_stepper(gym.make("Pendulum-v1"), seed)
    t_a = measure(amigo, repeats, min_time)
    t_p = measure(pend, repeats, min_time)
    return SingleResult(t_a * 1e6, t_p * 1e6)


def bench_vector(
    sizes: Sequence[int],
    repeats: int,
    min_time: float,
    sync_max: int,
    seed: int = 0,
    log: Callable[[str], None] | None = None,
) -> list[VectorRow]:
    """Env-steps per second of the native vector env, CartPole's native one, and Sync of AmigoBot."""
    import gymnasium as gym
    from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

    import amigo_gym  # noqa: F401

    rows = []
    for n in sizes:
        native = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="vector_entry_point")
        t_n = measure(_vector_stepper(native, seed), repeats, min_time)
        native.close()
        cart = CartPoleVectorEnv(num_envs=n)
        cart.action_space.seed(seed)
        t_c = measure(_vector_stepper(cart, seed), repeats, min_time)
        sync = None
        if n <= sync_max:
            senv = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="sync")
            # Sync is slow: fewer repeats, each still at least min_time long
            sync = n / measure(_vector_stepper(senv, seed), max(1, min(3, repeats)), min_time)
            senv.close()
        row = VectorRow(n, n / t_n, n / t_c, sync)
        if log is not None:
            log(f"  N = {n}: native {row.native:.3g} steps/s, CartPole {row.cartpole:.3g}, sync {_fmt(row.sync)}")
        rows.append(row)
    return rows


def _fmt(x: float | None, spec: str = ".3g") -> str:
    return "-" if x is None else format(x, spec)


def format_report(single: SingleResult | None, rows: Sequence[VectorRow]) -> str:
    """Markdown tables of the single-env and vector-env figures with their ratios."""
    out = []
    if single is not None:
        out += [
            "| single env (gym.make) | time per step [us] |",
            "|---|---:|",
            f"| AmigoBot-v0 | {single.amigobot_us:.1f} |",
            f"| Pendulum-v1 | {single.pendulum_us:.1f} |",
            f"| ratio AmigoBot / Pendulum (goal <= 0.3) | {single.ratio:.2f} |",
            "",
        ]
    if rows:
        out += [
            "| N | native AmigoBot [steps/s] | CartPoleVectorEnv [steps/s] | Sync AmigoBot [steps/s] "
            "| native / CartPole | native / Sync |",
            "|---:|---:|---:|---:|---:|---:|",
        ]
        for r in rows:
            out.append(
                f"| {r.n} | {r.native:.3g} | {r.cartpole:.3g} | {_fmt(r.sync)} | "
                f"{r.ratio_cartpole:.2f} | {_fmt(r.ratio_sync, '.1f')} |"
            )
    return "\n".join(out)


def build_parser() -> argparse.ArgumentParser:
    """Options of ``amigo-gym bench-env``."""
    p = OneLineParser(prog=PROG, description="Speed of AmigoBot-v0 against Pendulum, CartPoleVectorEnv and Sync.")
    p.add_argument(
        "--sizes", type=int, nargs="+", default=None, help=f"vector sizes N [envs] (default {DEFAULT_SIZES})"
    )
    p.add_argument("--repeats", type=int, default=5, help="repeats per measurement [repeats]; the median is reported")
    p.add_argument("--min-time", type=float, default=0.2, help="least duration of one repeat [s]")
    p.add_argument("--sync-max", type=int, default=4096, help="largest N for the SyncVectorEnv peer [envs]")
    p.add_argument("--skip-single", action="store_true", help="skip the single-env comparison")
    p.add_argument("--skip-vector", action="store_true", help="skip the vector-env comparison")
    p.add_argument("--quick", action="store_true", help=f"smoke run: sizes {QUICK_SIZES}, 1 repeat of 0.02 s")
    p.add_argument(
        "--json", default=None, metavar="FILE", help="also write the figures as JSON, atomically [file] (default: none)"
    )
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym bench-env``."""
    args = build_parser().parse_args(sys.argv[1:] if argv is None else list(argv))

    def go() -> int:
        if args.quick:
            sizes = list(args.sizes or QUICK_SIZES)
            repeats, min_time, sync_max = 1, 0.02, min(args.sync_max, 1024)
        else:
            sizes = list(args.sizes or DEFAULT_SIZES)
            repeats, min_time, sync_max = args.repeats, args.min_time, args.sync_max
        for i, n in enumerate(sizes):
            check_range(PROG, f"sizes[{i}]", n, 1, 1_000_000)
        check_range(PROG, "repeats", repeats, 1, 1000)
        check_range(PROG, "min_time", min_time, 0.0, 60.0, low_open=True)
        check_range(PROG, "sync_max", sync_max, 0, 1_000_000)
        print(
            f"{platform.python_implementation()} {platform.python_version()}, numpy {np.__version__}, "
            f"{os.cpu_count()} CPUs visible; median of {repeats} repeats of >= {min_time:g} s",
            flush=True,
        )
        single = None if args.skip_single else bench_single(repeats, min_time)
        rows = [] if args.skip_vector else bench_vector(sizes, repeats, min_time, sync_max, log=_log)
        print(format_report(single, rows))
        if args.json is not None:
            doc = {"single": None if single is None else asdict(single), "vector": [asdict(r) for r in rows]}
            atomic_write_json(args.json, doc)
        return 0

    return run_guarded(go, PROG)


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


if __name__ == "__main__":
    sys.exit(main())
