"""Speed benchmarks against peers timed in the same run (interleaved repeats), and their timing harness."""

from __future__ import annotations

import itertools
import math
import os
import statistics
import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import gymnasium as gym

#: random actions drawn in advance per env, cycled
POOL = 16


def measure_many(fns: Mapping[str, Callable[[], object]], repeats: int, min_time: float) -> dict[str, float]:
    """Median time of one call [s] of each function over ``repeats`` round-robin repeats of >= ``min_time`` [s] each
    (a change of the machine's load affects the competitors alike)."""
    inner = {}
    for name, fn in fns.items():
        fn()  # warm-up
        t0 = time.perf_counter()
        fn()
        inner[name] = max(1, math.ceil(min_time / max(time.perf_counter() - t0, 1e-7)))
    samples: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.perf_counter()
            for _ in range(inner[name]):
                fn()
            samples[name].append((time.perf_counter() - t0) / inner[name])
    return {name: statistics.median(v) for name, v in samples.items()}


def stepper(env: Any, seed: int = 0, warmup: int = 0) -> Callable[[], object]:
    """One ``step`` of ``env`` (reset here, then stepped ``warmup`` times untimed) with random actions from a pool of
    :data:`POOL`, drawn with ``seed``; a single env is reset when its episode ends."""
    env.action_space.seed(seed)
    actions = itertools.cycle([env.action_space.sample() for _ in range(POOL)])
    env.reset(seed=seed)
    single = not isinstance(env, gym.vector.VectorEnv)

    def step() -> object:
        out = env.step(next(actions))
        if single and (out[2] or out[3]):
            env.reset()
        return None

    for _ in range(warmup):
        step()
    return step


def time_envs(
    envs: Mapping[str, Any], repeats: int, min_time: float, seed: int = 0, warmup: int = 0
) -> dict[str, float]:
    """Median time of one ``step`` [s] of each env (:func:`stepper` after ``warmup`` steps, :func:`measure_many`);
    closes the envs."""
    try:
        return measure_many({k: stepper(e, seed, warmup) for k, e in envs.items()}, repeats, min_time)
    finally:
        for e in envs.values():
            e.close()


def fmt(x: float | None, spec: str = ".3g") -> str:
    """``x`` formatted, ``"-"`` for ``None``."""
    return "-" if x is None else format(x, spec)


def md_table(head: str, rows: Iterable[str], first: str = "---", last: str = "---:") -> list[str]:
    """A Markdown table's lines from its header and rows (cells joined by ``" | "``); the rule aligns the first and
    last column by ``first`` and ``last``, the others right."""
    return [f"| {head} |", f"|{first}|" + "---:|" * (head.count(" | ") - 1) + f"{last}|", *(f"| {r} |" for r in rows)]


def rates(name: str, count: int, wall: float, cpu: float) -> dict[str, float]:
    """``count`` per wall second (``name``) and per CPU second of this process, all threads (``name_cpu``)."""
    return {name: round(count / max(wall, 1e-9), 1), f"{name}_cpu": round(count / max(cpu, 1e-9), 1)}


def clock() -> tuple[float, float]:
    """Wall and CPU clocks of this process [s]."""
    return time.perf_counter(), time.process_time()


def clocked(count: int, start: tuple[float, float], end: tuple[float, float]) -> dict[str, Any]:
    """``env_steps``, ``wall_s`` and ``cpu_s`` between two :func:`clock` readings, and :func:`rates` ``sps``."""
    wall, cpu = end[0] - start[0], end[1] - start[1]
    return {"env_steps": count, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2)} | rates("sps", count, wall, cpu)


def load_values() -> list[float]:
    """The machine's load average over 1, 5 and 15 minutes (``[]`` where the OS has none)."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:  # pragma: no cover - Windows
        return []


def load_average() -> str:
    """:func:`load_values` as text (``"-"`` where the OS has none)."""
    return " ".join(f"{x:.2f}" for x in load_values()) or "-"
