"""Where the time of a step goes: cProfile of the single env and of the native vector env.

``python -m amigo_gym.tools.bench.profile [--steps K] [--top T]``: per case (``gym.make("AmigoBot-v0")``, its vector
env at each N of ``--sizes``) the ``T`` functions with the largest own time as a share of the total, in Markdown.
"""

from __future__ import annotations

import cProfile
import math
import pstats
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

from amigo_gym.envs.amigobot import AmigoBotVectorEnv
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking
from amigo_gym.tools.bench import md_table, measure_many, stepper
from amigo_gym.tools.bench.core import kernel_stepper
from amigo_gym.tools.options import check_fields, run_command

PROG = "python -m amigo_gym.tools.bench.profile"


def _label(func: tuple[str, int, str]) -> str:
    file, line, name = func
    if file == "~":  # a built-in
        return name
    parts = file.replace("\\", "/").split("/")
    for root in ("amigo_gym", "gymnasium", "numpy"):
        if root in parts:
            return f"{'/'.join(parts[parts.index(root) :])}:{line}({name})"
    return f"{parts[-1]}:{line}({name})"


def profile_steps(step: Callable[[], object], steps: int, top: int) -> tuple[float, list[tuple[str, float, int]]]:
    """``(total seconds, [(function, share of the total, calls), ...])`` of ``steps`` calls of ``step``."""
    for _ in range(min(steps, 50)):  # warm-up
        step()
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(steps):
        step()
    prof.disable()
    raw: dict[Any, Any] = pstats.Stats(prof).stats  # type: ignore[attr-defined]
    total = sum(v[2] for v in raw.values())
    rows = sorted(((_label(f), v[2] / total, v[1]) for f, v in raw.items()), key=lambda r: -r[1])
    return total, rows[:top]


def _table(title: str, steps: int, total: float, rows: Sequence[tuple[str, float, int]]) -> str:
    cells = [f"`{name}` | {100 * share:.1f} % | {calls / steps:.3g}" for name, share, calls in rows]
    out = [f"### {title}: {steps} steps, {1e6 * total / steps:.1f} us per step under cProfile", ""]
    return "\n".join(out + md_table("function | own time | calls per step", cells))


def single_parts(repeats: int = 7, min_time: float = 0.1) -> str:
    """Markdown table: a single-env step and its parts against Pendulum-v1's step (interleaved repeats)."""
    env, pend = gym.make("AmigoBot-v0"), gym.make("Pendulum-v1")
    ref: Any = gym.make("AmigoBot-v0", kernel="numpy").unwrapped  # v0's reference: AmigoBot-v1's ideal step
    for e in (env, ref, pend):
        e.reset(seed=0)
    raw: Any = env.unwrapped
    a, ap = np.array([0.27, 0.27], np.float32), np.array([0.5], np.float32)
    kern = raw._kernel  # the compiled step (None without numba: the steps then go on from the last state)
    start = kern.ws.copy() if kern is not None else None
    k, ref_start, ep, ring = ref._k, ref._state, ref._episode, ref._ring  # the reference's start state (floats)

    def restarted(e: Any) -> Callable[[], None]:
        def step() -> None:
            if e is ref:
                ref._state = ref_start
            elif kern is not None:
                kern.ws[:] = start
            e.step(a)

        return step

    fns = {
        "AmigoBot `gym.make` step": restarted(env),
        "AmigoBot unwrapped `env.step`": restarted(raw),
        "AmigoBot unwrapped `env.step`, kernel=numpy (v0's reference)": restarted(ref),
        "`task.v1.step_columns` on Python floats (v0's reference step)": lambda: tracking.step_columns(
            k, ref.path, ref_start, ep, ring, 0, 0.27, 0.27
        ),
        "`task.validate_action`": lambda: task.validate_action(a).tolist(),
        "Pendulum `gym.make` step": lambda: pend.step(ap),
        "Pendulum unwrapped step": lambda: pend.unwrapped.step(ap),
    }
    t = measure_many(fns, repeats, min_time)
    cells = [f"{k} | {1e6 * v:.1f} | {v / t['Pendulum `gym.make` step']:.2f}" for k, v in t.items()]
    return "\n".join(md_table("part | [us] | / Pendulum step", cells))


def gap(sizes: Sequence[int], repeats: int = 7, min_time: float = 0.2) -> str:
    """Markdown table: time per ``step`` call [us] of the kernel alone, the kernel env without and with episode
    restarts, and CartPole's (CartPole's time over each in brackets). Needs numba."""
    rows = []
    for n in sizes:
        quiet = AmigoBotVectorEnv(num_envs=n, kernel="numba", termination_distance=10.0, max_episode_steps=None)
        bench = AmigoBotVectorEnv(num_envs=n, kernel="numba", max_episode_steps=400)
        a = np.ascontiguousarray(np.random.default_rng(0).uniform(-1.0, 1.0, (n, 2)))
        kernel = kernel_stepper(tracking.TrackingParams.v0(), np.zeros((n, 3)), np.full((n, 2), 4.0), a, False)
        fns = {"kernel": kernel, "fresh": kernel, "quiet": stepper(quiet, 0), "bench": stepper(bench, 0)}
        t = measure_many(fns | {"cart": stepper(CartPoleVectorEnv(num_envs=n), 0)}, repeats, min_time)
        cells = " | ".join(f"{1e6 * t[k]:.0f} ({t['cart'] / t[k]:.2f})" for k in fns)
        rows.append(f"{n} | {cells} | {1e6 * t['cart']:.0f}")
    head = (
        "N | kernel alone, preallocated | kernel, fresh outputs | env.step, no episode ends "
        "| env.step, random actions (benchmark) | CartPoleVectorEnv"
    )
    return "\n".join(md_table(head, rows, first="---:"))


def libm(n: int = 100_000, seed: int = 0) -> str:
    """Markdown table: how many of ``n`` float64 arguments (uniform in [-10, 10]; ``log``: (0, 20]) get other bits from
    numpy's ``sin``, ``cos``, ``tan``, ``exp``, ``log`` than from the C library's (Python's ``math``)."""
    g = np.random.default_rng(seed)
    x = g.uniform(-10.0, 10.0, n)
    pos = g.uniform(0.0, 20.0, n) + 1e-300
    rows = []
    for name, args in (("sin", x), ("cos", x), ("tan", x), ("exp", x), ("log", pos)):
        ours = np.array([getattr(math, name)(v) for v in args.tolist()])
        theirs = getattr(np, name)(args)
        rows.append(f"`{name}` | {n} | {int(np.count_nonzero(ours.view(np.int64) != theirs.view(np.int64)))}")
    return "\n".join(md_table("function | arguments | numpy != C library", rows))


@dataclass(frozen=True)
class ProfileSettings:
    """Settings of ``python -m amigo_gym.tools.bench.profile``, each the option of the same name.

    Attributes:
        steps: profiled steps per case (vector: divided by N/64).
        top: functions listed per case.
        sizes: vector env sizes N.
        kernel: the vector env's kernel argument, when it has one.
        gap: instead: the kernel env against CartPole, with/without restarts.
        single_parts: instead: a single step and its parts vs Pendulum.
        libm: instead: numpy's transcendental functions vs the C library's.
    """

    steps: int = 3000
    top: int = 12
    sizes: tuple[int, ...] = (1, 4096)
    kernel: str | None = None
    gap: bool = False
    single_parts: bool = False
    libm: bool = False

    def __post_init__(self) -> None:
        check_fields(PROG, self, steps=(1, 1e9), top=(1, 1e6), sizes=(1, 1e7))


def run(s: ProfileSettings) -> int:
    """The tables of the settings ``s`` on stdout."""
    if s.gap or s.single_parts or s.libm:
        print(gap(s.sizes) if s.gap else single_parts() if s.single_parts else libm())
        return 0
    total, rows = profile_steps(stepper(gym.make("AmigoBot-v0"), 0), s.steps, s.top)
    print(_table('`gym.make("AmigoBot-v0")`, one step', s.steps, total, rows), end="\n\n")
    kw: dict[str, Any] = {} if s.kernel is None else {"kernel": s.kernel}
    for n in s.sizes:
        steps = max(20, s.steps // max(1, n // 64))
        envs = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="vector_entry_point", **kw)
        total, rows = profile_steps(stepper(envs, 0), steps, s.top)
        name = f"`AmigoBotVectorEnv`, N = {n}" + ("" if s.kernel is None else f", kernel={s.kernel}")
        print(_table(name, steps, total, rows), end="\n\n")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point."""
    return run_command(ProfileSettings, run, argv, PROG, "cProfile of AmigoBot-v0's single and vector env steps.")


if __name__ == "__main__":
    sys.exit(main())
