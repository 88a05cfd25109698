"""``amigo-gym bench-core``: throughput of the batched exact step, with peers measured in the same run.

For each batch size N it times (median of ``--repeats`` repeats, each at least ``--min-time`` seconds):

* ``transition``: :func:`amigo_gym.task.transition`, the environment's whole pure step (action → wheel
  rates, exact arc step of pose and wheel angles, projection on the path, observation, reward terms),
  returned as ``(N, k)`` arrays;
* ``columns``: :func:`amigo_gym.task.step_columns`, the same step in the column form that the environments
  run (state and results as ``(N,)`` columns, ``minimal=True``: no arc length nor closest point);
* ``step_pose``: :func:`amigo_gym.kinematics.step_pose` alone, the exact closed-form arc step;
* ``euler``: the peer, a plain explicit-Euler step of the same unicycle written in numpy
  (``x += v cos(b) dt; y += v sin(b) dt; b += betadot dt``), the cheapest step one could write;
* ``loop``: the other peer, a Python loop of the scalar exact step (``math`` functions) over the N states
  (only up to ``--loop-max`` states, as it is slow).

It prints env-steps per second (N states advanced once = N steps) and the ratios ``step_pose/euler``
and ``step_pose/loop``, which are less sensitive to the machine's load than the absolute figures.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from amigo_gym.cli import OneLineParser, run_guarded
from amigo_gym.io import atomic_write_json
from amigo_gym.kinematics import body_velocity, step_pose
from amigo_gym.params import EnvParams, RobotParams, check_range
from amigo_gym.paths import make_path
from amigo_gym.task import State, step_columns, task_constants, transition

__all__ = ["Row", "euler_step", "loop_step", "measure", "bench", "format_table", "main"]

PROG = "amigo-gym bench-core"
Array = NDArray[np.float64]
DEFAULT_SIZES = (1, 64, 1024, 4096, 16384, 65536)


def euler_step(pose: Array, w: Array, dt: float, robot: RobotParams) -> Array:
    """Peer: one explicit-Euler step of the unicycle ``(..., 3)`` (not exact; for timing only)."""
    v, bdot = body_velocity(w, robot)
    b = pose[..., 2]
    return np.stack((pose[..., 0] + v * np.cos(b) * dt, pose[..., 1] + v * np.sin(b) * dt, b + bdot * dt), axis=-1)


def loop_step(
    poses: list[tuple[float, float, float]], w: list[tuple[float, float]], dt: float, robot: RobotParams
) -> list[tuple[float, float, float]]:
    """Peer: the exact arc step of :func:`step_pose`, one state at a time in plain Python."""
    out = []
    r1, r2, l1 = robot.r1, robot.r2, robot.l1
    for (x, y, b), (w1, w2) in zip(poses, w, strict=True):
        v = 0.5 * (r1 * w1 + r2 * w2)
        db = (r1 * w1 - r2 * w2) / (2.0 * l1) * dt
        h = 0.5 * db
        chord = v * dt * (math.sin(h) / h if h != 0.0 else 1.0)
        out.append((x + chord * math.cos(b + h), y + chord * math.sin(b + h), b + db))
    return out


def measure(fn: Callable[[], object], repeats: int, min_time: float) -> float:
    """Median time of one call [s]: each repeat runs ``fn`` enough times to last ``min_time``."""
    fn()  # warm-up
    t0 = time.perf_counter()
    fn()
    once = max(time.perf_counter() - t0, 1e-7)
    inner = max(1, math.ceil(min_time / once))
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        samples.append((time.perf_counter() - t0) / inner)
    return statistics.median(samples)


@dataclass(frozen=True)
class Row:
    """Env-steps per second at batch size ``n`` (``None`` where not measured)."""

    n: int
    transition: float
    columns: float
    step_pose: float
    euler: float
    loop: float | None

    @property
    def ratio_euler(self) -> float:
        """``step_pose / euler`` throughput (1 = as fast as the Euler peer)."""
        return self.step_pose / self.euler

    @property
    def ratio_loop(self) -> float | None:
        """``step_pose / loop`` throughput (speed-up of batching over a Python loop)."""
        return None if self.loop is None else self.step_pose / self.loop


def _bench_one(n: int, repeats: int, min_time: float, loop_max: int, rng: np.random.Generator) -> Row:
    params = EnvParams()
    robot = params.robot
    path = make_path(params)
    pose = np.column_stack((rng.normal(0.0, 0.05, (n, 2)), rng.normal(0.0, 0.1, n)))
    angles = np.zeros((n, 3))
    action = rng.uniform(0.2, 0.35, (n, 2))
    w = action * robot.max_wheel_rate
    t_tr = measure(lambda: transition(pose, angles, w, action, params, path), repeats, min_time)
    k = task_constants(params)
    state = State(*(np.ascontiguousarray(c) for c in (*pose.T, *angles.T, *w.T)))
    a1, a2 = np.ascontiguousarray(action[:, 0]), np.ascontiguousarray(action[:, 1])
    t_co = measure(lambda: step_columns(k, path, state, a1, a2, minimal=True), repeats, min_time)
    t_sp = measure(lambda: step_pose(pose, w, params.dt, robot), repeats, min_time)
    t_eu = measure(lambda: euler_step(pose, w, params.dt, robot), repeats, min_time)
    loop = None
    if n <= loop_max:
        pl = [(float(a), float(b), float(c)) for a, b, c in pose]
        wl = [(float(a), float(b)) for a, b in w]
        loop = n / measure(lambda: loop_step(pl, wl, params.dt, robot), repeats, min_time)
    return Row(n, n / t_tr, n / t_co, n / t_sp, n / t_eu, loop)


def bench(
    sizes: Sequence[int], repeats: int = 7, min_time: float = 0.05, loop_max: int = 4096, seed: int = 0
) -> list[Row]:
    """Measure every size (same random states for every method); returns one :class:`Row` each."""
    rng = np.random.default_rng(seed)
    return [_bench_one(n, repeats, min_time, loop_max, rng) for n in sizes]


def _fmt(x: float | None, spec: str = ".3g") -> str:
    return "-" if x is None else format(x, spec)


def format_table(rows: Sequence[Row]) -> str:
    """Markdown table of env-steps per second and ratios."""
    head = (
        "| N | transition [steps/s] | step_columns [steps/s] | step_pose [steps/s] | Euler peer [steps/s] "
        "| Python loop [steps/s] | step_pose/Euler | step_pose/loop |"
    )
    lines = [head, "|" + "---:|" * 8]
    for r in rows:
        lines.append(
            f"| {r.n} | {r.transition:.3g} | {r.columns:.3g} | {r.step_pose:.3g} | {r.euler:.3g} | {_fmt(r.loop)} | "
            f"{r.ratio_euler:.2f} | {_fmt(r.ratio_loop, '.3g')} |"
        )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    """Options of ``amigo-gym bench-core``."""
    p = OneLineParser(prog=PROG, description="Env-steps per second of the batched exact step, with peers.")
    p.add_argument("--sizes", type=int, nargs="+", default=list(DEFAULT_SIZES), help="batch sizes N [envs]")
    p.add_argument("--repeats", type=int, default=7, help="repeats per measurement [repeats]; the median is reported")
    p.add_argument("--min-time", type=float, default=0.05, help="least duration of one repeat [s]")
    p.add_argument("--loop-max", type=int, default=4096, help="largest N for the Python-loop peer [envs]")
    p.add_argument(
        "--json", default=None, metavar="FILE", help="also write the rows as JSON, atomically [file] (default: none)"
    )
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym bench-core``."""
    args = build_parser().parse_args(sys.argv[1:] if argv is None else list(argv))

    def go() -> int:
        for i, n in enumerate(args.sizes):
            check_range(PROG, f"sizes[{i}]", n, 1, 10_000_000)
        check_range(PROG, "repeats", args.repeats, 1, 1000)
        check_range(PROG, "min_time", args.min_time, 0.0, 60.0, low_open=True)
        check_range(PROG, "loop_max", args.loop_max, 0, 10_000_000)
        rows = bench(args.sizes, args.repeats, args.min_time, args.loop_max)
        print(f"numpy {np.__version__}, {os.cpu_count()} CPUs visible; median of {args.repeats} repeats")
        print(format_table(rows))
        if args.json is not None:
            atomic_write_json(args.json, [asdict(r) for r in rows])
        return 0

    return run_guarded(go, PROG)


if __name__ == "__main__":
    sys.exit(main())
