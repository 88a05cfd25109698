"""``python experiments/render_trail.py``: the cost of ``render_mode="rgb_array"`` in v1's vector env.

At ``--n`` robots on ``--path``, with and without rendering: the growth of the resident memory [MiB] over
``--steps`` steps (each in a fresh process) and the step-time ratio (interleaved repeats); docs/amigobot_v1.md."""

from __future__ import annotations

import contextlib
import gc
import multiprocessing
import os
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

from amigo_gym.envs import AmigoBotV1VectorEnv
from amigo_gym.io import atomic_write_json
from amigo_gym.tools.bench import stepper, time_envs
from amigo_gym.tools.bench.env import V1_HARD
from amigo_gym.tools.options import run_command

PROG = "python experiments/render_trail.py"
MiB = 2**20


def _env(n: int, path: str, render: bool) -> Any:
    kw = V1_HARD if path == "mixed" else {"path": path}
    return AmigoBotV1VectorEnv(num_envs=n, render_mode="rgb_array" if render else None, **kw)


def _rss() -> int:
    """Resident memory of this process [bytes] (``/proc/self/statm``; 0 where there is none)."""
    with contextlib.suppress(OSError, ValueError, IndexError), open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    return 0


def measure_memory(n: int, steps: int, path: str = "mixed", render: bool = True, frames: int = 2) -> dict[str, float]:
    """Growth of the resident memory [MiB] from ``reset`` to after ``steps`` steps, with or without ``render_mode``
    (then the trails of the first ``frames`` robots are read at the end, as ``render()`` reads them)."""
    env = _env(n, path, render=render)
    step = stepper(env, 0)  # reset, random actions (the same in both processes)
    gc.collect()
    first = _rss()
    for _ in range(steps):
        step()
    if render:
        _ = [env._trail_of(i) for i in range(frames)]
    gc.collect()
    second = _rss()
    ring = getattr(env, "_trail", None)
    env.close()
    return {"growth_mib": (second - first) / MiB, "trail_ring_mib": 0.0 if ring is None else ring.nbytes / MiB}


def measure_time(n: int, path: str = "mixed", repeats: int = 5, min_time: float = 0.5) -> dict[str, float]:
    """Median time of one ``step`` [s] with and without ``render_mode`` (interleaved repeats), and their ratio."""
    t = time_envs({"plain": _env(n, path, render=False), "rgb_array": _env(n, path, render=True)}, repeats, min_time)
    return {"step_s": t["plain"], "step_render_s": t["rgb_array"], "ratio": t["rgb_array"] / t["plain"]}


@dataclass(frozen=True)
class RenderTrailSettings:
    """Settings of ``python experiments/render_trail.py``, each the option of the same name.

    Attributes:
        n: robots [envs].
        steps: rendered steps of the memory measurement [steps].
        path: path= of the envs (mixed: with hard randomisation) [name].
        repeats: interleaved repeats of the timing (median) [repeats].
        min_time: least duration of one timing repeat [s].
        skip_memory: time only.
        skip_time: measure the memory only.
        json: write the figures as JSON [file].
    """

    n: int = 1024
    steps: int = 3000
    path: str = "mixed"
    repeats: int = 5
    min_time: float = 0.5
    skip_memory: bool = False
    skip_time: bool = False
    json: str | None = None

    def __post_init__(self) -> None:
        if bad := [name for name in ("n", "steps", "repeats") if getattr(self, name) < 1]:
            raise ValueError(f"--{bad[0]} must be >= 1, got {getattr(self, bad[0])}")


def run(s: RenderTrailSettings) -> int:
    """The measurements of the settings ``s``, one line per figure on stdout, ``--json``."""
    out: dict[str, Any] = {"n": s.n, "steps": s.steps, "path": s.path}
    if not s.skip_memory:
        for kind in ("render", "plain"):  # each in a fresh process
            with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
                got = pool.submit(measure_memory, s.n, s.steps, s.path, kind == "render").result()
            out[f"growth_{kind}_mib"] = got["growth_mib"]
            out.setdefault("trail_ring_mib", got["trail_ring_mib"])  # render's: the first run
        print(
            f"resident memory growth over {s.steps} steps at N={s.n} ({s.path}): "
            f"{out['growth_render_mib']:.1f} MiB with render_mode='rgb_array' (target <= 20; its trail ring: "
            f"{out['trail_ring_mib']:.1f} MiB), {out['growth_plain_mib']:.1f} MiB without"
        )
    if not s.skip_time:
        out |= measure_time(s.n, s.path, s.repeats, s.min_time)
        print(
            f"step time at N={s.n}: {out['step_s'] * 1e3:.3g} ms plain, {out['step_render_s'] * 1e3:.3g} ms with "
            f"render_mode='rgb_array': ratio {out['ratio']:.3f} (target <= 1.1)"
        )
    if s.json:
        atomic_write_json(s.json, out)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``python experiments/render_trail.py``."""
    return run_command(RenderTrailSettings, run, argv, PROG, (__doc__ or "").split("\n")[0])


if __name__ == "__main__":
    raise SystemExit(main())
