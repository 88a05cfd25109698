"""``amigo-gym bench-core``: throughput of the batched exact step, with peers measured in the same run
(docs/performance.md, "Reference: `amigo-gym bench-core`")."""

from __future__ import annotations

import ctypes
import functools
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.io import atomic_write_json
from amigo_gym.model.kinematics import body_velocity, body_velocity_columns, castor_rate_columns, step_pose
from amigo_gym.model.params import RobotParams
from amigo_gym.sim.fast_v1 import numba_available, set_threads
from amigo_gym.sim.fast_v1_batch import BatchKernel
from amigo_gym.task import v1 as tracking
from amigo_gym.tools.bench import fmt, md_table, measure_many
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.options import check_fields, run_command, say

PROG = "amigo-gym bench-core"
Array = NDArray[np.float64]
#: the methods timed per batch size (docs/performance.md), keys of a row with ``n`` and ``ratio_kernel``
METHODS = ("transition", "columns", "step_pose", "euler", "loop", "kernel", "kernel_par")
Row = dict[str, Any]
DEFAULT_SIZES = (1, 64, 1024, 4096, 16384, 65536)


def euler_step(pose: Array, w: Array, dt: float, robot: RobotParams) -> Array:
    """Peer: one explicit-Euler step of the unicycle ``(..., 3)`` (not exact; for timing only)."""
    v, bdot = body_velocity(w, robot)
    b = pose[..., 2]
    return np.stack((pose[..., 0] + v * np.cos(b) * dt, pose[..., 1] + v * np.sin(b) * dt, b + bdot * dt), axis=-1)


def loop_step(
    poses: Sequence[Sequence[float]], w: Sequence[Sequence[float]], dt: float, robot: RobotParams
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


def _bench_one(n: int, repeats: int, min_time: float, loop_max: int, rng: np.random.Generator, kernels: bool) -> Row:
    """Env-steps per second of each method at batch size ``n`` (``None``: not measured) and ``ratio_kernel``."""
    params = tracking.TrackingParams.v0()
    robot, dt = params.robot, params.dt
    pose = np.column_stack((rng.normal(0.0, 0.05, (n, 2)), rng.normal(0.0, 0.1, n)))
    action = rng.uniform(0.2, 0.35, (n, 2))
    w = action * robot.max_wheel_rate
    k = tracking.constants(params)
    one = tracking.begin_episode(np.random.default_rng(0), k).episode  # v0's settings draw nothing that matters
    ep = tracking.Episode(*(np.full(n, v) for v in one))  # the (N,) columns of the state and the nominal episode
    z, a = np.zeros(n), w / k.w_max
    cols = [np.array(c) for c in (pose[:, 0], pose[:, 1], pose[:, 2], w[:, 0], w[:, 1], z, z, z, a[:, 0], a[:, 1])]
    st = tracking.State(*cols, np.zeros(n, dtype=np.int64))  # type: ignore[call-arg]
    ring, castor = np.zeros((n, k.ring_length, 2)), np.zeros(n)
    a1, a2 = np.ascontiguousarray(action[:, 0]), np.ascontiguousarray(action[:, 1])

    def columns() -> tracking.State:
        return tracking.step_columns(k, params.path, st, ep, ring, 0, a1, a2)[0]

    def transition() -> object:  # the step and the castor angle, as the env's reference route
        new = columns()
        return new, castor + castor_rate_columns(*body_velocity_columns(new.w1, new.w2, robot), robot) * dt

    fns: dict[str, Callable[[], object]] = {
        "transition": transition,
        "columns": columns,
        "step_pose": lambda: step_pose(pose, w, dt, robot),
        "euler": lambda: euler_step(pose, w, dt, robot),
    }
    if n <= loop_max:
        pl, wl = pose.tolist(), w.tolist()
        fns["loop"] = lambda: loop_step(pl, wl, dt, robot)
    if kernels:  # one compiled step each, outputs preallocated
        obs = np.empty((n, len(tracking.obs_fields(params))), dtype=np.float32)
        for m in ("kernel", "kernel_par"):
            b = BatchKernel(k, n, parallel=m == "kernel_par")
            b.load(range(n), [params.path] * n, st, ep)
            fns[m] = functools.partial(b.step, np.zeros_like(ring), 1, a1, a2, obs)
    t = measure_many(fns, repeats, min_time)
    row: Row = {"n": n} | {m: n / t[m] if m in t else None for m in METHODS}
    row["ratio_kernel"] = None if row["kernel"] is None else row["kernel"] / row["columns"]
    return row


_FIRST_STEP = (
    "import numpy as np, gymnasium as gym, amigo_gym\n"
    "e = gym.make_vec('AmigoBot-v0', num_envs=4, vectorization_mode='vector_entry_point', kernel='numba')\n"
    "e.reset(seed=0); e.step(np.zeros((4, 2), np.float32))\n"
)
_FIRST_STEP_V1 = (
    "import numpy as np, gymnasium as gym, amigo_gym\n"
    "e = gym.make('AmigoBot-v1', kernel='numba')\n"
    "e.reset(seed=0); e.step(np.zeros(2, np.float32))\n"
)


def _numpy_route(code: str) -> str:
    """``code`` with the reference step (``kernel='numpy'``) instead of the compiled one."""
    return code.replace("kernel='numba'", "kernel='numpy'")


def _wall(code: str, env: dict[str, str] | None = None) -> float:
    """Wall time [s] from starting ``python -c code`` to the end of ``code`` (the interpreter's teardown excluded)."""
    t0 = time.time()
    code += "\nimport time as _t\nprint(repr(_t.time()))"
    out = subprocess.run([sys.executable, "-c", code], check=True, env=env, capture_output=True, text=True)
    return float(out.stdout.split()[-1]) - t0


def _cold_warm(code: str, repeats: int) -> tuple[float, float]:
    """Median wall times of ``code`` with an empty numba cache, then with the one it wrote."""
    colds, warms = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            colds.append(_wall(code, env))
            warms.append(_wall(code, env))
    return statistics.median(colds), statistics.median(warms)


#: the start-up rows: key of :func:`bench_startup`'s result, label
STARTUP_ROWS = (
    ("python_s", 'python -c "pass"'),
    ("import_s", 'python -c "import amigo_gym"'),
    ("numba_import_s", 'python -c "import amigo_gym, numba"'),
    ("numpy_first_s", "import + first v0 vector step, kernel=numpy (no numba)"),
    ("kernel_cold_s", "import + first v0 vector step (kernel), empty numba cache"),
    ("kernel_warm_s", "the same, second process (cached; target < 1)"),
    ("v1_cold_s", "import + first AmigoBot-v1 step (compiled), empty numba cache"),
    ("v1_warm_s", "the same, second process (cached; target < 1)"),
    ("v1_numpy_first_s", "import + first AmigoBot-v1 step, kernel=numpy"),
)


def bench_startup(repeats: int = 3) -> dict[str, float | None]:
    """Wall times of fresh processes [s] (median of ``repeats``) by the keys of :data:`STARTUP_ROWS`; the compiled
    ones ``None`` without numba."""

    def median(code: str) -> float:
        return statistics.median(_wall(code) for _ in range(repeats))

    out: dict[str, float | None] = dict.fromkeys(key for key, _ in STARTUP_ROWS)
    out |= {"import_s": median("import amigo_gym"), "python_s": median("pass")}
    out["numpy_first_s"], out["v1_numpy_first_s"] = (median(_numpy_route(c)) for c in (_FIRST_STEP, _FIRST_STEP_V1))
    if numba_available():
        out["kernel_cold_s"], out["kernel_warm_s"] = _cold_warm(_FIRST_STEP, repeats)
        out["v1_cold_s"], out["v1_warm_s"] = _cold_warm(_FIRST_STEP_V1, repeats)
        out["numba_import_s"] = median("import amigo_gym, numba")
    return out


def format_table(
    rows: Sequence[Row], startup: dict[str, float | None] | None = None, threads: int | None = None
) -> str:
    """Markdown table of env-steps per second and ratios (and of the start-up times, if measured)."""
    head = (
        "N | transition [steps/s] | step_columns [steps/s] | step_pose [steps/s] | Euler peer [steps/s] "
        f"| Python loop [steps/s] | kernel [steps/s] | kernel, {threads or '-'} threads [steps/s] "
        "| step_pose/Euler | step_pose/loop | kernel/step_columns"
    )
    cells = [
        f"{r['n']} | " + " | ".join(fmt(r[m]) for m in METHODS) + f" | {r['step_pose'] / r['euler']:.2f} | "
        + fmt(None if r["loop"] is None else r["step_pose"] / r["loop"]) + f" | {fmt(r['ratio_kernel'], '.1f')}"
        for r in rows
    ]  # fmt: skip
    lines = md_table(head, cells, first="---:")
    if startup is not None:
        cells = [f"{label} | {fmt(startup[key], '.3f')}" for key, label in STARTUP_ROWS]
        lines += ["", *md_table("fresh process | wall time [s]", cells)]
    return "\n".join(lines)


@dataclass(frozen=True)
class CoreSettings:
    """Settings of ``amigo-gym bench-core``, each the option of the same name (``--min-time`` for ``min_time``).

    Attributes:
        sizes: batch sizes [envs] (default: (1, 64, 1024, 4096, 16384, 65536)).
        repeats: repeats per measurement [repeats]; the median is reported.
        min_time: least duration of one repeat [s].
        loop_max: largest N for the Python-loop peer [envs].
        threads: numba threads [threads] (default: all).
        skip_kernel: skip the compiled kernel (numba).
        skip_startup: skip the fresh-process start-up times.
        quick: smoke run: sizes 1 64, 1 repeat of 0.01 s, one start-up run.
        json: JSON output [file] (default: none).
    """

    sizes: tuple[int, ...] | None = None
    repeats: int = 7
    min_time: float = 0.05
    loop_max: int = 4096
    threads: int | None = None
    skip_kernel: bool = False
    skip_startup: bool = False
    quick: bool = False
    json: str | None = None

    def __post_init__(self) -> None:
        ranges = {"sizes": (1, 1e7), "repeats": (1, 1000), "min_time": (0, 60, True), "loop_max": (0, 1e7)}
        check_fields(PROG, self, **ranges, threads=(1, 4096))


def hold_heap() -> bool:
    """glibc only: keep freed memory in the heap (``mallopt``: no ``mmap`` below 32 MiB, no trimming), so that the numpy
    routes' temporaries reuse their pages at every N instead of faulting them in again on each call, whatever the
    process did before (docs/core.md); ``False`` elsewhere (the C library's own policy then)."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError, TypeError):
        return False
    return bool(mallopt(-3, 1 << 25)) and bool(mallopt(-1, 1 << 30))  # M_MMAP_THRESHOLD, M_TRIM_THRESHOLD [bytes]


def run(s: CoreSettings) -> int:
    """``amigo-gym bench-core`` with the settings ``s``: the table on stdout (progress on stderr), ``--json``."""
    sizes = list(s.sizes or ((1, 64) if s.quick else DEFAULT_SIZES))
    repeats, min_time = (1, 0.01) if s.quick else (s.repeats, s.min_time)
    threads, kernels = None, not s.skip_kernel and numba_available()
    if kernels:
        import numba

        if s.threads is not None:
            set_threads(s.threads)
        threads = int(numba.get_num_threads())
    heap = "glibc's heap held (mallopt)" if hold_heap() else "the C library's heap policy"
    print(f"{machine_line()}; {heap}; median of {repeats} repeats", flush=True)
    say(f"{PROG}: sizes {sizes}")
    rng = np.random.default_rng(0)
    rows = [_bench_one(n, repeats, min_time, s.loop_max, rng, kernels) for n in sizes]  # kernels off: columns None
    startup = None
    if not s.skip_startup:
        say(f"{PROG}: start-up of fresh processes")
        startup = bench_startup(1 if s.quick else 3)
    print(format_table(rows, startup, threads))
    if s.json is not None:
        doc = {"rows": rows, "threads": threads, "startup": startup, "machine": machine_line(), "heap": heap}
        atomic_write_json(s.json, doc)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym bench-core``."""
    return run_command(CoreSettings, run, argv, PROG, "Env-steps per second of the batched exact step, with peers.")
