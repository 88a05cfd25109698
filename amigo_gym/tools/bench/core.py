"""``amigo-gym bench-core``: throughput of the batched exact step, with peers measured in the same run.

What it times per batch size, the ratios and the start-up times: docs/performance.md, "Reference: `amigo-gym
bench-core`".
"""

from __future__ import annotations

import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.io import atomic_write_json
from amigo_gym.model.kinematics import body_velocity, body_velocity_columns, castor_rate_columns, step_pose
from amigo_gym.model.params import EnvParams, RobotParams, check_range
from amigo_gym.paths import make_path
from amigo_gym.sim.fast_v1 import numba_available
from amigo_gym.sim.fast_v1_batch import BatchKernel
from amigo_gym.task import v1 as tracking
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.options import run_command

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
    """Median time of one call [s]: each repeat runs ``fn`` enough times to last ``min_time`` (:func:`measure_many`)."""
    return measure_many({"fn": fn}, repeats, min_time)["fn"]


def measure_many(fns: dict[str, Callable[[], object]], repeats: int, min_time: float) -> dict[str, float]:
    """Median time of one call [s] of each function, the repeats interleaved (round robin).

    Each repeat times every function in turn (each for at least ``min_time``), so a change of the
    machine's load during the run affects the competitors alike and their ratios stay meaningful.
    """
    inner = {}
    for name, fn in fns.items():
        fn()  # warm-up
        t0 = time.perf_counter()
        fn()
        inner[name] = max(1, math.ceil(min_time / max(time.perf_counter() - t0, 1e-7)))
    samples: dict[str, list[float]] = {name: [] for name in fns}
    for _ in range(repeats):
        for name, fn in fns.items():
            m = inner[name]
            t0 = time.perf_counter()
            for _ in range(m):
                fn()
            samples[name].append((time.perf_counter() - t0) / m)
    return {name: statistics.median(v) for name, v in samples.items()}


@dataclass(frozen=True)
class Row:
    """Env-steps per second at batch size ``n`` (``None`` where not measured)."""

    n: int
    transition: float
    columns: float
    step_pose: float
    euler: float
    loop: float | None
    kernel: float | None = None
    kernel_par: float | None = None

    @property
    def ratio_euler(self) -> float:
        """``step_pose / euler`` throughput (1 = as fast as the Euler peer)."""
        return self.step_pose / self.euler

    @property
    def ratio_loop(self) -> float | None:
        """``step_pose / loop`` throughput (speed-up of batching over a Python loop)."""
        return None if self.loop is None else self.step_pose / self.loop

    @property
    def ratio_kernel(self) -> float | None:
        """``kernel / columns`` throughput (speed-up of the compiled step over the numpy reference)."""
        return None if self.kernel is None else self.kernel / self.columns


def _bench_one(
    n: int, repeats: int, min_time: float, loop_max: int, rng: np.random.Generator, kernels: bool = False
) -> Row:
    params = EnvParams()
    robot = params.robot
    path = make_path(params)
    pose = np.column_stack((rng.normal(0.0, 0.05, (n, 2)), rng.normal(0.0, 0.1, n)))
    angles = np.zeros((n, 3))
    action = rng.uniform(0.2, 0.35, (n, 2))
    w = action * robot.max_wheel_rate
    k, st, ep = v0_columns(params, pose, w)
    ring = np.zeros((n, k.ring_length, 2))
    a1, a2 = np.ascontiguousarray(action[:, 0]), np.ascontiguousarray(action[:, 1])

    def columns() -> tracking.State:
        return tracking.step_columns(k, path, st, ep, ring, 0, a1, a2)[0]

    def transition() -> object:  # the step and the castor angle, as the env's reference route
        new = columns()
        v, bdot = body_velocity_columns(new.w1, new.w2, robot)
        return new, angles[:, 2] + castor_rate_columns(v, bdot, robot) * params.dt

    t_tr = measure(transition, repeats, min_time)
    t_co = measure(columns, repeats, min_time)
    t_sp = measure(lambda: step_pose(pose, w, params.dt, robot), repeats, min_time)
    t_eu = measure(lambda: euler_step(pose, w, params.dt, robot), repeats, min_time)
    loop = None
    if n <= loop_max:
        pl = [(float(a), float(b), float(c)) for a, b, c in pose]
        wl = [(float(a), float(b)) for a, b in w]
        loop = n / measure(lambda: loop_step(pl, wl, params.dt, robot), repeats, min_time)
    kern = kern_par = None
    if kernels:
        steppers = _kernel_steppers(params, path, pose, angles, w, action)
        kern = n / measure(steppers[0], repeats, min_time)
        kern_par = n / measure(steppers[1], repeats, min_time)
    return Row(n, n / t_tr, n / t_co, n / t_sp, n / t_eu, loop, kern, kern_par)


def v0_columns(params: EnvParams, pose: Array, w: Array) -> tuple[tracking.Constants, tracking.State, tracking.Episode]:
    """AmigoBot-v0's constants (:func:`amigo_gym.task.v1.v0_configuration`) and the ``(N,)`` columns of a state at the
    poses ``pose (N, 3)`` with the wheel rates ``w (N, 2)`` [rad/s] and of the nominal episode."""
    k = tracking.constants(tracking.v0_configuration(params))
    n = len(pose)
    one = tracking.begin_episode(np.random.default_rng(0), k).episode  # v0's settings draw nothing that matters
    ep = tracking.Episode(*(np.full(n, v) for v in one))
    z = np.zeros(n)
    a = w / k.w_max
    cols = [np.array(c) for c in (pose[:, 0], pose[:, 1], pose[:, 2], w[:, 0], w[:, 1], z, z, z, a[:, 0], a[:, 1])]
    st = tracking.State(*cols, np.zeros(n, dtype=np.int64))  # type: ignore[call-arg]
    return k, st, ep


def kernel_stepper(params: EnvParams, pose: Array, w: Array, action: Array, parallel: bool) -> Callable[[], object]:
    """One compiled step of AmigoBot-v0's robots at ``pose`` with the wheel rates ``w`` [rad/s] and the actions
    ``action (N, 2)`` (:class:`amigo_gym.sim.fast_v1_batch.BatchKernel`; preallocated outputs, the state advances)."""
    k, st, ep = v0_columns(params, pose, w)
    n = len(pose)
    b = BatchKernel(k, n, parallel=parallel)
    b.load(range(n), [k.params.path] * n, st, ep)
    rings = np.zeros((n, k.ring_length, 2))
    a1, a2 = np.ascontiguousarray(action[:, 0]), np.ascontiguousarray(action[:, 1])
    obs = np.empty((n, len(tracking.obs_fields(k.params))), dtype=np.float32)
    return lambda: b.step(rings, 1, a1, a2, obs)


def _kernel_steppers(
    params: EnvParams, path: Any, pose: Array, angles: Array, w: Array, action: Array
) -> tuple[Callable[[], object], Callable[[], object]]:
    """Serial and parallel kernel steps of the states (preallocated outputs; the state advances)."""
    return kernel_stepper(params, pose, w, action, False), kernel_stepper(params, pose, w, action, True)


def bench(
    sizes: Sequence[int],
    repeats: int = 7,
    min_time: float = 0.05,
    loop_max: int = 4096,
    seed: int = 0,
    kernels: bool = True,
) -> list[Row]:
    """Measure every size (same random states for every method); returns one :class:`Row` each.

    ``kernels=False`` (or numba missing) leaves the kernel columns ``None``.
    """
    rng = np.random.default_rng(seed)
    use = kernels and numba_available()
    return [_bench_one(n, repeats, min_time, loop_max, rng, use) for n in sizes]


@dataclass(frozen=True)
class Startup:
    """Wall times of fresh processes [s] (median of ``repeats``).

    Attributes:
        import_s: ``python -c "import amigo_gym"``.
        python_s: ``python -c "pass"`` (the interpreter alone), for reference.
        kernel_cold_s: import, ``gym.make_vec("AmigoBot-v0", num_envs=4)`` (the compiled v0 kernel), reset and
            the first step, with an empty numba cache (compiles).
        kernel_warm_s: the same with the cache the cold run wrote (a second process).
        v1_cold_s: import, ``gym.make("AmigoBot-v1")`` (the compiled v1 step), reset and the first step, with an
            empty numba cache.
        v1_warm_s: the same, second process.
        numba_import_s: ``python -c "import amigo_gym, numba"`` (what loading numba adds to the import).
        numpy_first_s: import, ``gym.make_vec("AmigoBot-v0", num_envs=4, kernel="numpy")`` (the reference, what
            runs without numba), reset and the first step.
        v1_numpy_first_s: import, ``gym.make("AmigoBot-v1", kernel="numpy")``, reset and the first step.
    """

    import_s: float
    python_s: float
    kernel_cold_s: float | None
    kernel_warm_s: float | None
    v1_cold_s: float | None = None
    v1_warm_s: float | None = None
    numba_import_s: float | None = None
    numpy_first_s: float | None = None
    v1_numpy_first_s: float | None = None


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
    """Wall time [s] from starting a fresh ``python -c code`` to the end of ``code`` (the child reports the
    clock when it is done: the interpreter's teardown, about 0.3 s with numba loaded, is not start-up)."""
    t0 = time.time()
    out = subprocess.run(
        [sys.executable, "-c", code + "\nimport time as _t\nprint(repr(_t.time()))"],
        check=True,
        env=env,
        capture_output=True,
        text=True,
    )
    return float(out.stdout.split()[-1]) - t0


def _cold_warm(code: str, repeats: int) -> tuple[float, float]:
    """Median wall times of ``code`` in a fresh process with an empty numba cache, then with the one it wrote."""
    colds, warms = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            colds.append(_wall(code, env))
            warms.append(_wall(code, env))
    return statistics.median(colds), statistics.median(warms)


def bench_startup(repeats: int = 3) -> Startup:
    """Time fresh processes: the import, and the first compiled steps (v0 vector, v1 single) from an empty then a
    filled numba cache."""
    py = statistics.median(_wall("pass") for _ in range(repeats))
    imp = statistics.median(_wall("import amigo_gym") for _ in range(repeats))
    first = statistics.median(_wall(_numpy_route(_FIRST_STEP)) for _ in range(repeats))
    first1 = statistics.median(_wall(_numpy_route(_FIRST_STEP_V1)) for _ in range(repeats))
    if not numba_available():
        return Startup(imp, py, None, None, numpy_first_s=first, v1_numpy_first_s=first1)
    with_numba = statistics.median(_wall("import amigo_gym, numba") for _ in range(repeats))
    cold, warm = _cold_warm(_FIRST_STEP, repeats)
    cold1, warm1 = _cold_warm(_FIRST_STEP_V1, repeats)
    return Startup(imp, py, cold, warm, cold1, warm1, with_numba, first, first1)


def _fmt(x: float | None, spec: str = ".3g") -> str:
    return "-" if x is None else format(x, spec)


def format_table(rows: Sequence[Row], startup: Startup | None = None, threads: int | None = None) -> str:
    """Markdown table of env-steps per second and ratios (and of the start-up times, if measured)."""
    head = (
        "| N | transition [steps/s] | step_columns [steps/s] | step_pose [steps/s] | Euler peer [steps/s] "
        f"| Python loop [steps/s] | kernel [steps/s] | kernel, {threads or '-'} threads [steps/s] "
        "| step_pose/Euler | step_pose/loop | kernel/step_columns |"
    )
    lines = [head, "|" + "---:|" * 11]
    for r in rows:
        lines.append(
            f"| {r.n} | {r.transition:.3g} | {r.columns:.3g} | {r.step_pose:.3g} | {r.euler:.3g} | {_fmt(r.loop)} | "
            f"{_fmt(r.kernel)} | {_fmt(r.kernel_par)} | "
            f"{r.ratio_euler:.2f} | {_fmt(r.ratio_loop, '.3g')} | {_fmt(r.ratio_kernel, '.1f')} |"
        )
    if startup is not None:
        lines += [
            "",
            "| fresh process | wall time [s] |",
            "|---|---:|",
            f'| python -c "pass" | {startup.python_s:.3f} |',
            f'| python -c "import amigo_gym" | {startup.import_s:.3f} |',
            f'| python -c "import amigo_gym, numba" | {_fmt(startup.numba_import_s, ".3f")} |',
            f"| import + first v0 vector step, kernel=numpy (no numba) | {_fmt(startup.numpy_first_s, '.3f')} |",
            f"| import + first v0 vector step (kernel), empty numba cache | {_fmt(startup.kernel_cold_s, '.3f')} |",
            f"| the same, second process (cached; target < 1) | {_fmt(startup.kernel_warm_s, '.3f')} |",
            f"| import + first AmigoBot-v1 step (compiled), empty numba cache | {_fmt(startup.v1_cold_s, '.3f')} |",
            f"| the same, second process (cached; target < 1) | {_fmt(startup.v1_warm_s, '.3f')} |",
            f"| import + first AmigoBot-v1 step, kernel=numpy | {_fmt(startup.v1_numpy_first_s, '.3f')} |",
        ]
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
        for i, n in enumerate(self.sizes or ()):
            check_range(PROG, f"sizes[{i}]", n, 1, 10_000_000)
        check_range(PROG, "repeats", self.repeats, 1, 1000)
        check_range(PROG, "min_time", self.min_time, 0.0, 60.0, low_open=True)
        check_range(PROG, "loop_max", self.loop_max, 0, 10_000_000)
        if self.threads is not None:
            check_range(PROG, "threads", self.threads, 1, 4096)


def run(s: CoreSettings) -> int:
    """``amigo-gym bench-core`` with the settings ``s``: the table on stdout (progress on stderr), ``--json``."""
    sizes = list(s.sizes or ((1, 64) if s.quick else DEFAULT_SIZES))
    repeats, min_time = (1, 0.01) if s.quick else (s.repeats, s.min_time)
    threads = None
    if not s.skip_kernel and numba_available():
        import numba

        if s.threads is not None:
            numba.set_num_threads(s.threads)
        threads = int(numba.get_num_threads())
    print(f"{machine_line()}; median of {repeats} repeats", flush=True)
    print(f"{PROG}: sizes {sizes}", file=sys.stderr, flush=True)
    rows = bench(sizes, repeats, min_time, s.loop_max, kernels=not s.skip_kernel)
    startup = None
    if not s.skip_startup:
        print(f"{PROG}: start-up of fresh processes", file=sys.stderr, flush=True)
        startup = bench_startup(1 if s.quick else 3)
    print(format_table(rows, startup, threads))
    if s.json is not None:
        doc = {
            "rows": [{**asdict(r), "ratio_kernel": r.ratio_kernel} for r in rows],
            "threads": threads,
            "startup": None if startup is None else asdict(startup),
        }
        atomic_write_json(s.json, doc)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym bench-core``."""
    return run_command(CoreSettings, run, argv, PROG, "Env-steps per second of the batched exact step, with peers.")


if __name__ == "__main__":
    sys.exit(main())
