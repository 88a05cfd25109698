"""``amigo-gym bench-env``: speed of ``AmigoBot-v0`` against peers measured in the same run.

What it times, against which peers, the speed targets, the header and the options: docs/performance.md,
"Reference: `amigo-gym bench-env`".
"""

from __future__ import annotations

import gc
import math
import os
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv
from llvmlite import binding

from amigo_gym.io import atomic_write_json
from amigo_gym.model.params import check_range
from amigo_gym.sim.fast_v1 import numba_available
from amigo_gym.tools.bench.core import _fmt, measure_many
from amigo_gym.tools.machine import cpu_model, machine_line, simd_level
from amigo_gym.tools.options import run_command, say
from amigo_gym.tools.plots import pyplot, save_figure

PROG = "amigo-gym bench-env"
DEFAULT_SIZES = (1, 64, 1024, 4096, 65536)
QUICK_SIZES = (1, 64, 1024)
SYNC_MAX = 1024
POOL = 16

Log = Callable[[str], None]


def _quiet(msg: str) -> None:
    return None


# ---------------------------------------------------------------------------------------------- steppers
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


def _vector_kernels(parallel: bool = False) -> list[str]:
    """The step implementations of the native vector env (its ``kernel``); ``parallel`` adds ``"numba-parallel"``
    (the kernel's loops on numba's threads) when numba is installed."""
    if not numba_available():
        return ["numpy"]
    return ["numpy", "numba", "numba-parallel"] if parallel else ["numpy", "numba"]


# ---------------------------------------------------------------------------------------------- single
@dataclass(frozen=True)
class SingleResult:
    """Time of one single-env step [us] and the ratio AmigoBot / Pendulum (target <= 0.5, goal <= 0.3)."""

    amigobot_us: float
    pendulum_us: float

    @property
    def ratio(self) -> float:
        """AmigoBot's time per step over Pendulum's (lower is better)."""
        return self.amigobot_us / self.pendulum_us


def bench_single(repeats: int, min_time: float, seed: int = 0) -> SingleResult:
    """Time one step of ``gym.make("AmigoBot-v0")`` and of ``gym.make("Pendulum-v1")``."""
    t = measure_many(
        {
            "amigo": _single_stepper(gym.make("AmigoBot-v0"), seed),
            "pendulum": _single_stepper(gym.make("Pendulum-v1"), seed),
        },
        repeats,
        min_time,
    )
    return SingleResult(t["amigo"] * 1e6, t["pendulum"] * 1e6)


# ---------------------------------------------------------------------------------------------- vector
@dataclass(frozen=True)
class VectorRow:
    """Env-steps per second at ``N`` robots (``None`` where not measured).

    ``native`` is the vector env as built by default; ``kernels`` the same env with each step
    implementation it offers (``{"numpy": ..., "numba": ...}``), when it offers a choice.
    """

    n: int
    native: float
    cartpole: float
    sync: float | None
    kernels: dict[str, float] = field(default_factory=dict)

    @property
    def ratio_cartpole(self) -> float:
        """Native AmigoBot over native CartPole throughput (target >= 0.8 at N = 4096)."""
        return self.native / self.cartpole

    @property
    def ratio_sync(self) -> float | None:
        """Native over ``SyncVectorEnv`` throughput of AmigoBot itself (target >= 20 at N = 4096)."""
        return None if self.sync is None else self.native / self.sync

    @property
    def call_us(self) -> float:
        """Time of one ``step`` call of the native env [us]."""
        return 1e6 * self.n / self.native

    @property
    def cartpole_call_us(self) -> float:
        """Time of one ``step`` call of ``CartPoleVectorEnv`` [us]."""
        return 1e6 * self.n / self.cartpole


def bench_vector(
    sizes: Sequence[int], repeats: int, min_time: float, sync_max: int, seed: int = 0, log: Log | None = None
) -> list[VectorRow]:
    """Env-steps per second of the native vector env, CartPole's native one, and Sync of AmigoBot."""
    say = log or _quiet
    choices = _vector_kernels(parallel=True)
    rows = []
    for n in sizes:
        # every competitor built first, then timed in interleaved repeats (measure_many)
        vec = "vector_entry_point"
        envs: dict[str, Any] = {"native": gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode=vec)}
        for name in choices:
            envs[name] = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode=vec, kernel=name)
        envs["cartpole"] = CartPoleVectorEnv(num_envs=n)
        envs["cartpole"].action_space.seed(seed)
        if n <= sync_max:
            envs["sync"] = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="sync")
        t = measure_many({k: _vector_stepper(e, seed) for k, e in envs.items()}, repeats, min_time)
        for e in envs.values():
            e.close()
        t_n, t_c = t["native"], t["cartpole"]
        sync = n / t["sync"] if "sync" in t else None
        kernels = {name: n / t[name] for name in choices}
        row = VectorRow(n, n / t_n, n / t_c, sync, kernels)
        extra = "".join(f", {k} {v:.3g}" for k, v in kernels.items())
        say(f"  N = {n}: native {row.native:.3g} steps/s{extra}, CartPole {row.cartpole:.3g}, sync {_fmt(row.sync)}")
        rows.append(row)
    return rows


# ---------------------------------------------------------------------------------------------- memory
@dataclass(frozen=True)
class MemoryResult:
    """Bytes per sub-env: retained (state and buffers) and the transient peak of one ``step``."""

    n: int
    amigobot_retained: float
    amigobot_step_peak: float
    cartpole_retained: float
    cartpole_step_peak: float


def _traced(make: Callable[[], Any], seed: int, steps: int = 3) -> tuple[int, int]:
    """``(retained, step_peak)`` bytes of an env built by ``make``, reset and stepped ``steps`` times."""
    gc.collect()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        envs = make()
        step = _vector_stepper(envs, seed)
        for _ in range(steps):
            step()
        gc.collect()
        retained = tracemalloc.get_traced_memory()[0] - base
        tracemalloc.reset_peak()
        before = tracemalloc.get_traced_memory()[0]
        step()
        peak = tracemalloc.get_traced_memory()[1] - before
        envs.close()
        del envs, step
    finally:
        tracemalloc.stop()
    return retained, peak


def bench_memory(n: int, seed: int = 0) -> MemoryResult:
    """Memory per sub-env of the native vector env and of ``CartPoleVectorEnv`` (differences ``n`` vs 1)."""

    def amigo(m: int) -> Callable[[], Any]:
        return lambda: gym.make_vec("AmigoBot-v0", num_envs=m, vectorization_mode="vector_entry_point")

    def cart(m: int) -> Callable[[], Any]:
        return lambda: CartPoleVectorEnv(num_envs=m)

    out = []
    for make in (amigo, cart):
        r1, p1 = _traced(make(1), seed)
        rn, pn = _traced(make(n), seed)
        out += [(rn - r1) / (n - 1), (pn - p1) / (n - 1)]
    return MemoryResult(n, *out)


# ---------------------------------------------------------------------------------------------- PPO
@dataclass(frozen=True)
class PPORow:
    """SB3 PPO ``learn`` throughput [env-steps/s] with ``n_envs`` envs, AmigoBot against Pendulum."""

    n_envs: int
    amigobot_vec: str
    amigobot: float
    pendulum: float
    #: share of ``learn``'s wall time spent in the vector env's ``reset``/``step_wait`` (AmigoBot, Pendulum) [-]
    amigobot_env_share: float = math.nan
    pendulum_env_share: float = math.nan

    @property
    def ratio(self) -> float:
        """AmigoBot over Pendulum (target >= 0.95: the env is never the bottleneck)."""
        return self.amigobot / self.pendulum


def _timed(venv: Any) -> Any:
    """``venv`` with the wall time of its ``reset`` and ``step_wait`` calls summed in ``.env_time`` [s]."""
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class _Timed(VecEnvWrapper):
        env_time = 0.0

        def reset(self) -> Any:
            t0 = time.perf_counter()
            out = self.venv.reset()
            self.env_time += time.perf_counter() - t0
            return out

        def step_wait(self) -> Any:
            t0 = time.perf_counter()
            out = self.venv.step_wait()
            self.env_time += time.perf_counter() - t0
            return out

    return _Timed(venv)


def _ppo_rate(venv: Any, timesteps: int, n_steps: int, seed: int) -> tuple[float, float]:
    """PPO ``learn`` throughput [env-steps/s] and the env's share of its wall time [-]."""
    from stable_baselines3 import PPO

    timed = _timed(venv)
    model = PPO("MlpPolicy", timed, n_steps=n_steps, batch_size=64, n_epochs=2, seed=seed, device="cpu", verbose=0)
    t0 = time.perf_counter()
    model.learn(total_timesteps=timesteps)
    wall = time.perf_counter() - t0
    timed.close()
    return float(model.num_timesteps / wall), float(timed.env_time / wall)


def _adapter(monitor: Any, adapter: Any, n: int, kw: dict[str, Any]) -> Callable[[], Any]:
    return lambda: monitor(adapter(num_envs=n, **kw))


def bench_ppo(
    timesteps: int,
    n_envs: int,
    seed: int = 0,
    log: Log | None = None,
    rollout: int = 2048,
    repeats: int = 3,
    v1: bool = False,
) -> list[PPORow]:
    """PPO training throughput on AmigoBot-v0 and Pendulum-v1 with the same settings, 1 and ``n_envs`` envs.

    PPO: ``MlpPolicy``, ``n_steps = rollout // n_envs`` (at least 32; ``timesteps`` rounded up to whole
    rollouts), ``batch_size=64``, ``n_epochs=2``, CPU, one torch thread (so that torch's threads do
    not compete with the machine's other load). The AmigoBot and Pendulum runs alternate ``repeats``
    times; the medians are reported. ``v1=True`` adds ``AmigoBot-v1`` with the task of :data:`V1_HARD` through
    the native adapter (``n_envs`` envs, the default step implementation).
    """
    import torch
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecMonitor

    from amigo_gym.tools.training.sb3_vec import AmigoBotSB3VecEnv

    say = log or _quiet
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    rows = []
    try:
        # AmigoBot's configurations: one env (DummyVecEnv), n_envs through the native adapter with each
        # step implementation the vector env offers; each against Pendulum with as many envs
        configs: list[tuple[int, str, Callable[[], Any]]] = [
            (1, "DummyVecEnv", lambda: make_vec_env("AmigoBot-v0", n_envs=1, seed=seed))
        ]
        if n_envs > 1:
            for kern in _vector_kernels():
                label = f"AmigoBotSB3VecEnv(kernel={kern})"
                configs.append((n_envs, label, _adapter(VecMonitor, AmigoBotSB3VecEnv, n_envs, {"kernel": kern})))
        if v1:
            v1_kw: dict[str, Any] = {"env_id": "AmigoBot-v1", **V1_HARD}
            label = "AmigoBotSB3VecEnv(AmigoBot-v1, mixed paths, hard randomisation)"
            configs.append((n_envs, label, _adapter(VecMonitor, AmigoBotSB3VecEnv, n_envs, v1_kw)))
        for m, kind, make in configs:
            n_steps = max(32, rollout // m)
            budget = max(timesteps, n_steps * m)
            runs_a, runs_p = [], []
            for _ in range(repeats):
                runs_a.append(_ppo_rate(make(), budget, n_steps, seed))
                pend = make_vec_env(lambda: gym.make("Pendulum-v1"), n_envs=m, seed=seed)
                runs_p.append(_ppo_rate(pend, budget, n_steps, seed))
            a, p = statistics.median(r for r, _ in runs_a), statistics.median(r for r, _ in runs_p)
            sa, sp = statistics.median(f for _, f in runs_a), statistics.median(f for _, f in runs_p)
            rows.append(PPORow(m, kind, a, p, sa, sp))
            say(f"  PPO, {m} env(s): AmigoBot ({kind}) {a:.0f} steps/s (env {sa:.0%}), Pendulum {p:.0f} (env {sp:.0%})")
    finally:
        torch.set_num_threads(threads)
    return rows


# ---------------------------------------------------------------------------------------------- v1
#: the harder v1 task of the comparison: every path family, a speed range and the "hard" randomisation
V1_HARD: dict[str, Any] = {"path": "mixed", "speed": (0.1, 0.4), "randomize": "hard"}
#: largest N at which ``--v1`` times the v1 vector env (a v1 env-step costs tens of v0's)
V1_MAX_N = 4096


@dataclass(frozen=True)
class V1Result:
    """``AmigoBot-v1`` against ``AmigoBot-v0``: single step [us] and vector env-steps/s per ``N``.

    ``v1`` is the default task (the circle, no randomisation), ``v1_hard`` the task of :data:`V1_HARD`
    (mixed paths, a speed range, hard randomisation: two projections per step instead of one).
    ``vector[n] = (v1, v0)`` and ``vector_hard[n]`` the hard task's env-steps/s.
    """

    v1_us: float
    v0_us: float
    vector: dict[int, tuple[float, float]]
    v1_hard_us: float | None = None
    vector_hard: dict[int, float] = field(default_factory=dict)

    @property
    def ratio(self) -> float:
        """v1's time per single step over v0's (target <= 2)."""
        return self.v1_us / self.v0_us

    @property
    def ratio_hard(self) -> float | None:
        """The hard v1 task's time per single step over v0's."""
        return None if self.v1_hard_us is None else self.v1_hard_us / self.v0_us


def bench_v1(sizes: Sequence[int], repeats: int, min_time: float, seed: int = 0) -> V1Result | None:
    """v1 (default and :data:`V1_HARD`) against v0, single step and vector env at ``sizes`` up to
    :data:`V1_MAX_N`; ``None`` when ``AmigoBot-v1`` is not registered."""
    if "AmigoBot-v1" not in gym.registry:
        return None
    tasks: dict[str, tuple[str, dict[str, Any]]] = {
        "v1": ("AmigoBot-v1", {}),
        "v1_hard": ("AmigoBot-v1", V1_HARD),
        "v0": ("AmigoBot-v0", {}),
    }
    single = {name: _single_stepper(gym.make(env_id, **kw), seed) for name, (env_id, kw) in tasks.items()}
    ts = measure_many(single, repeats, min_time)
    vector: dict[int, tuple[float, float]] = {}
    hard: dict[int, float] = {}
    if gym.registry["AmigoBot-v1"].vector_entry_point is not None:
        for n in sizes:
            if n > V1_MAX_N:
                continue
            venvs = {
                name: gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kw)
                for name, (env_id, kw) in tasks.items()
            }
            tv = measure_many({name: _vector_stepper(e, seed) for name, e in venvs.items()}, repeats, min_time)
            for e in venvs.values():
                e.close()
            vector[n] = (n / tv["v1"], n / tv["v0"])
            hard[n] = n / tv["v1_hard"]
    return V1Result(ts["v1"] * 1e6, ts["v0"] * 1e6, vector, ts["v1_hard"] * 1e6, hard)


# ---------------------------------------------------------------------------------------------- kernels
#: the step implementations ``--kernels`` compares (the vector envs also run ``"numba-parallel"``)
KERNEL_CHOICES = ("numpy", "numba")


@dataclass(frozen=True)
class KernelRow:
    """Time of one env-step [us] of ``env_id`` per step implementation, timed in interleaved repeats.

    ``n = 0`` is the single env of ``gym.make``; ``n >= 1`` the native vector env of ``gym.make_vec`` with
    ``n`` robots (the time of one call divided by ``n``). ``us`` maps ``kernel=`` values to the time.
    """

    env_id: str
    n: int
    us: dict[str, float]

    @property
    def speedup(self) -> float | None:
        """The reference's time over the compiled step's (``kernel="numpy"`` / ``kernel="numba"``)."""
        if "numpy" not in self.us or "numba" not in self.us:
            return None
        return self.us["numpy"] / self.us["numba"]


def bench_kernels(n: int, repeats: int, min_time: float, seed: int = 0) -> list[KernelRow]:
    """AmigoBot-v0 and AmigoBot-v1 (default task) with each step implementation: one single-env step and one
    env-step of the vector env at ``n`` robots (``"numba-parallel"`` too), ``[]`` without numba."""
    if not numba_available():
        return []
    rows = []
    for env_id in ("AmigoBot-v0", "AmigoBot-v1"):
        if env_id not in gym.registry:
            continue
        single = {k: _single_stepper(gym.make(env_id, kernel=k), seed) for k in KERNEL_CHOICES}
        t = measure_many(single, repeats, min_time)
        rows.append(KernelRow(env_id, 0, {k: v * 1e6 for k, v in t.items()}))
        vec = "vector_entry_point"
        venvs = {
            k: gym.make_vec(env_id, num_envs=n, vectorization_mode=vec, kernel=k)
            for k in (*KERNEL_CHOICES, "numba-parallel")
        }
        t = measure_many({k: _vector_stepper(e, seed) for k, e in venvs.items()}, repeats, min_time)
        for e in venvs.values():
            e.close()
        rows.append(KernelRow(env_id, n, {k: v * 1e6 / n for k, v in t.items()}))
    return rows


def format_kernels(rows: Sequence[KernelRow]) -> list[str]:
    """Markdown table of :func:`bench_kernels`' rows."""
    if not rows:
        return []
    names = list(dict.fromkeys(k for r in rows for k in r.us))
    out = [
        "| step implementation: time per env-step [us] | " + " | ".join(f"kernel={k}" for k in names)
        + " | numpy / numba |",
        "|---|" + "---:|" * (len(names) + 1),
    ]  # fmt: skip
    for r in rows:
        where = "single env (gym.make)" if r.n == 0 else f"vector env, N = {r.n}"
        cells = " | ".join(_fmt(r.us.get(k), ".3g") for k in names)
        out.append(f"| {r.env_id}, {where} | {cells} | {_fmt(r.speedup, '.2f')} |")
    return [*out, ""]


# ---------------------------------------------------------------------------------------------- targets
#: the speed targets for one core: name -> (comparison, bound)
TARGETS: dict[str, tuple[str, float]] = {
    "single": ("<=", 0.4),
    "vector_4096": (">=", 1.0),
    "call_n1": ("<=", 0.5),
    "v1_v0": ("<=", 1.5),
}


@dataclass(frozen=True)
class Target:
    """One speed target: measured ratio, target (``None``: reported only) and whether it is met."""

    name: str
    label: str
    ratio: float
    op: str | None = None
    bound: float | None = None

    @property
    def met(self) -> bool | None:
        """``ratio op bound``; ``None`` for a figure without a target."""
        if self.op is None or self.bound is None:
            return None
        return self.ratio <= self.bound if self.op == "<=" else self.ratio >= self.bound


def _target(name: str, label: str, ratio: float) -> Target:
    op, bound = TARGETS[name]
    return Target(name, label, ratio, op, bound)


def targets(rep: Report, n_vector: int = 4096) -> list[Target]:
    """The speed targets' figures that ``rep`` measured: the single step against Pendulum-v1, the vector env at
    ``n_vector`` against ``CartPoleVectorEnv`` (serial compiled step, and with numba's threads, reported only), the
    fixed cost per call at N = 1, and AmigoBot-v1 against AmigoBot-v0 (single step; vector env, reported only)."""
    out = []
    if rep.single is not None:
        out.append(_target("single", "single step, AmigoBot-v0 / Pendulum-v1 (time)", rep.single.ratio))
    big = [r for r in rep.vector if r.n == n_vector]
    if big:
        r = big[0]
        label = f"vector env, N = {n_vector}, native (default kernel) / CartPoleVectorEnv (env-steps/s)"
        out.append(_target("vector_4096", label, r.ratio_cartpole))
        if "numba-parallel" in r.kernels:
            label = f"vector env, N = {n_vector}, kernel=numba-parallel / CartPoleVectorEnv (env-steps/s)"
            out.append(Target("vector_4096_threads", label, r.kernels["numba-parallel"] / r.cartpole))
    fc = _fixed_cost(rep.vector)
    if fc is not None:
        out.append(_target("call_n1", "fixed cost per call at N = 1, native / CartPoleVectorEnv (time)", fc["ratio"]))
    if rep.v1 is not None:
        out.append(_target("v1_v0", "single step, AmigoBot-v1 / AmigoBot-v0 (time)", rep.v1.ratio))
        if n_vector in rep.v1.vector:
            a, b = rep.v1.vector[n_vector]
            out.append(Target("v1_v0_vector", f"vector env, N = {n_vector}, AmigoBot-v1 / AmigoBot-v0 (time)", b / a))
    return out


def format_targets(items: Sequence[Target], machine: str) -> list[str]:
    """Markdown table of :func:`targets` with the machine (CPU, SIMD level, numba threads) in its header."""
    if not items:
        return []
    out = [f"| speed targets on {machine} | measured | target | met |", "|---|---:|---:|---|"]
    for t in items:
        bound = "reported" if t.op is None else f"{t.op} {t.bound:g}"
        met = "-" if t.met is None else ("yes" if t.met else "no")
        out.append(f"| {t.label} | {t.ratio:.2f} | {bound} | {met} |")
    return [*out, ""]


def numba_state() -> str:
    """numba's version, the CPU it compiles for (``NUMBA_CPU_NAME``, else the host's: e.g. ``znver4``) and with which
    features (``NUMBA_CPU_FEATURES``, else the host's: ``haswell`` with ``NUMBA_CPU_FEATURES=""`` makes AVX2 code on an
    AVX-512 machine, the name alone keeps AVX-512), its threads (``NUMBA_NUM_THREADS``, ``--threads``) and whether it
    uses Intel SVML."""
    if not numba_available():
        return "numba not installed"
    import numba

    target = getattr(numba.config, "CPU_NAME", None) or binding.get_host_cpu_name()
    svml = "on" if getattr(numba.config, "USING_SVML", False) else "off"
    features = getattr(numba.config, "CPU_FEATURES", None)
    own = "the host's features" if features is None else (f"features {features}" if features else "its own features")
    return f"numba {numba.__version__} for {target} ({own}), {numba.get_num_threads()} thread(s), SVML {svml}"


def load_average() -> str:
    """The machine's load average over 1, 5 and 15 minutes (``"-"`` where the OS has none)."""
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "-"


# ---------------------------------------------------------------------------------------------- report
@dataclass
class Report:
    """Everything one run measured (``None`` or empty where skipped), with notes on what was skipped."""

    single: SingleResult | None = None
    vector: list[VectorRow] = field(default_factory=list)
    memory: MemoryResult | None = None
    ppo: list[PPORow] = field(default_factory=list)
    v1: V1Result | None = None
    kernels: list[KernelRow] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: the load average at the start and at the end of the run (:func:`load_average`)
    load: tuple[str, str] = ("-", "-")

    def to_json(self) -> dict[str, Any]:
        """A JSON document of the figures, with the ratios."""
        vector = [
            {
                **asdict(r),
                "ratio_cartpole": r.ratio_cartpole,
                "ratio_sync": r.ratio_sync,
                "call_us": r.call_us,
                "cartpole_call_us": r.cartpole_call_us,
            }
            for r in self.vector
        ]
        return {
            "machine": {
                "cpu_model": cpu_model(),
                "simd": simd_level(),
                "cpu_count": os.cpu_count(),
                "numba": numba_state(),
                "load_average": {"start": self.load[0], "end": self.load[1]},
            },
            "single": None if self.single is None else {**asdict(self.single), "ratio": self.single.ratio},
            "vector": vector,
            "fixed_cost_n1": _fixed_cost(self.vector),
            "memory": None if self.memory is None else asdict(self.memory),
            "ppo": [{**asdict(r), "ratio": r.ratio} for r in self.ppo],
            "v1": None
            if self.v1 is None
            else {
                "v1_us": self.v1.v1_us,
                "v0_us": self.v1.v0_us,
                "ratio": self.v1.ratio,
                "v1_hard_us": self.v1.v1_hard_us,
                "ratio_hard": self.v1.ratio_hard,
                "hard_task": {k: list(v) if isinstance(v, tuple) else v for k, v in V1_HARD.items()},
                "vector": {
                    str(n): {"v1": a, "v0": b, "v1_hard": self.v1.vector_hard.get(n)}
                    for n, (a, b) in self.v1.vector.items()
                },
            },
            "kernels": [{**asdict(r), "speedup": r.speedup} for r in self.kernels],
            "targets": [{**asdict(t), "met": t.met} for t in targets(self)],
            "notes": self.notes,
        }


def _fixed_cost(rows: Sequence[VectorRow]) -> dict[str, float] | None:
    one = [r for r in rows if r.n == 1]
    if not one:
        return None
    r = one[0]
    out = {"amigobot_us": r.call_us, "cartpole_us": r.cartpole_call_us, "ratio": r.call_us / r.cartpole_call_us}
    for k, v in r.kernels.items():
        out[f"amigobot_{k}_us"] = 1e6 / v
    return out


def format_report(report: Report) -> str:
    """Markdown tables of every figure of ``report`` with its ratio, the targets, the load average and the notes."""
    out: list[str] = []
    single, rows = report.single, report.vector
    if single is not None:
        out += [
            "| single env (gym.make) | time per step [us] |",
            "|---|---:|",
            f"| AmigoBot-v0 | {single.amigobot_us:.1f} |",
            f"| Pendulum-v1 | {single.pendulum_us:.1f} |",
            f"| ratio AmigoBot / Pendulum (target <= 0.4) | {single.ratio:.2f} |",
            "",
        ]
    if rows:
        names = list(rows[0].kernels)
        head = "| N | native AmigoBot [steps/s] | " + "".join(f"native, {k} [steps/s] | " for k in names)
        head += "CartPoleVectorEnv [steps/s] | Sync AmigoBot [steps/s] | native / CartPole | native / Sync |"
        out += [head, "|---:|" + "---:|" * (5 + len(names))]
        for r in rows:
            ks = "".join(f"{r.kernels[k]:.3g} | " for k in names)
            out.append(
                f"| {r.n} | {r.native:.3g} | {ks}{r.cartpole:.3g} | {_fmt(r.sync)} | "
                f"{r.ratio_cartpole:.2f} | {_fmt(r.ratio_sync, '.1f')} |"
            )
        out.append(f"(Sync measured up to N = {max([r.n for r in rows if r.sync is not None], default=0)})")
        fc = _fixed_cost(rows)
        if fc is not None:
            out += [
                "",
                "| fixed cost per step call at N = 1 | [us] |",
                "|---|---:|",
                f"| AmigoBotVectorEnv | {fc['amigobot_us']:.1f} |",
            ]
            out += [f"| AmigoBotVectorEnv, {k} | {1e6 / v:.1f} |" for k, v in rows[0].kernels.items() if rows[0].n == 1]
            out += [
                f"| CartPoleVectorEnv | {fc['cartpole_us']:.1f} |",
                f"| ratio AmigoBot / CartPole (target <= 0.5) | {fc['ratio']:.2f} |",
            ]
        out.append("")
    if report.memory is not None:
        m = report.memory
        out += [
            f"| memory per sub-env (N = {m.n} vs 1, tracemalloc) | retained [bytes] | peak of one step [bytes] |",
            "|---|---:|---:|",
            f"| AmigoBotVectorEnv | {m.amigobot_retained:.0f} | {m.amigobot_step_peak:.0f} |",
            f"| CartPoleVectorEnv | {m.cartpole_retained:.0f} | {m.cartpole_step_peak:.0f} |",
            "",
        ]
    if report.ppo:
        out += [
            "| SB3 PPO learn | AmigoBot [steps/s] | Pendulum-v1 [steps/s] | AmigoBot / Pendulum (target >= 0.95) "
            "| env's share of learn: AmigoBot | Pendulum |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        for pr in report.ppo:
            name = f"{pr.n_envs} env(s), AmigoBot{'' if 'v1' in pr.amigobot_vec else '-v0'} via {pr.amigobot_vec}"
            out.append(
                f"| {name} | {pr.amigobot:.0f} | {pr.pendulum:.0f} | {pr.ratio:.2f} "
                f"| {pr.amigobot_env_share:.1%} | {pr.pendulum_env_share:.1%} |"
            )
        out.append("")
    if report.v1 is not None:
        v = report.v1
        hard = "path=mixed, speed=(0.1, 0.4), randomize=hard"
        out += [
            f"| AmigoBot-v1 vs v0 | v1 | v1 ({hard}) | v0 | v1 / v0 | v1 hard / v0 |",
            "|---|---:|---:|---:|---:|---:|",
            f"| single step [us] (target <= 1.5) | {v.v1_us:.1f} | {_fmt(v.v1_hard_us, '.1f')} | {v.v0_us:.1f} "
            f"| {v.ratio:.2f} | {_fmt(v.ratio_hard, '.2f')} |",
        ]
        for n, (a, b) in v.vector.items():
            h = v.vector_hard.get(n)
            out.append(
                f"| vector, N = {n} [steps/s] | {a:.3g} | {_fmt(h)} | {b:.3g} | {b / a:.2f} (time) "
                f"| {_fmt(None if h is None else b / h, '.2f')} (time) |"
            )
        out.append("")
    out += format_kernels(report.kernels)
    out += format_targets(targets(report), f"{cpu_model()} (SIMD {simd_level()}; {numba_state()})")
    out.append(f"load average (1, 5, 15 min): {report.load[0]} at the start, {report.load[1]} at the end")
    out += [f"note: {n}" for n in report.notes]
    return "\n".join(out).rstrip()


def plot_vector(rows: Sequence[VectorRow], path: str, v1: V1Result | None = None) -> None:
    """Env-steps/s against N (log-log): the native env (per step implementation), CartPole, Sync, and with
    ``v1`` the native AmigoBot-v1 vector env (its default task and the hard one, :data:`V1_HARD`)."""
    plt = pyplot()

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ns = [r.n for r in rows]
    kernels = list(rows[0].kernels) if rows else []
    if not kernels:  # with a choice of kernels, the default is one of them
        ax.plot(ns, [r.native for r in rows], "o-", label="AmigoBotVectorEnv (native)")
    for k, style in zip(kernels, ("^--", "o-", "v-."), strict=False):
        ax.plot(ns, [r.kernels[k] for r in rows], style, label=f"AmigoBotVectorEnv, {k} step")
    ax.plot(ns, [r.cartpole for r in rows], "s-", label="CartPoleVectorEnv (Gymnasium)")
    sync = [(r.n, r.sync) for r in rows if r.sync is not None]
    if sync:
        ax.plot(*zip(*sync, strict=True), "x:", label="SyncVectorEnv(AmigoBot-v0)")
    if v1 is not None and v1.vector:
        n1 = sorted(v1.vector)
        ax.plot(n1, [v1.vector[n][0] for n in n1], "D-", label="AmigoBotV1VectorEnv (default task)")
        hard = [(n, v1.vector_hard[n]) for n in n1 if n in v1.vector_hard]
        if hard:
            ax.plot(*zip(*hard, strict=True), "d--", label="AmigoBotV1VectorEnv (mixed paths, hard)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("number of sub-envs N")
    ax.set_ylabel("env-steps per second")
    ax.set_title("Vector env throughput (one run, same machine)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


# ---------------------------------------------------------------------------------------------- tables
def headline_table(env_doc: dict[str, Any], core_doc: dict[str, Any] | None = None) -> str:
    """The README's performance table (figure, measured, target), generated from the JSON of a
    ``bench-env --v1 --json`` run (``env_doc``) and of a ``bench-core --json`` run (``core_doc``, for the
    start-up row), so that no copy of a figure is typed by hand: ``amigo-gym bench-env --table-from FILE``.

    Raises:
        KeyError: a document without the figures of a full ``--v1`` run.
    """
    vec = {int(v["n"]): v for v in env_doc["vector"]}
    ppo1 = next(p for p in env_doc["ppo"] if p["n_envs"] == 1)
    ppo8 = next(p for p in env_doc["ppo"] if p["n_envs"] > 1 and "numba" in str(p["amigobot_vec"]))
    v1 = env_doc["v1"]
    rows = [
        ("one `AmigoBot-v0` step via `gym.make` / one `Pendulum-v1` step (time)", f"{env_doc['single']['ratio']:.2f}",
         "<= 0.5"),
        (f"one `AmigoBot-v1` step / one `AmigoBot-v0` step (time; mixed paths and hard randomisation: "
         f"{v1['ratio_hard']:.1f})", f"{v1['ratio']:.2f}", "<= 2"),
        ("vector env, N = 4096 / `CartPoleVectorEnv` (env-steps/s, one core)", f"{vec[4096]['ratio_cartpole']:.2f}",
         ">= 0.8"),
        ("vector env, N = 1024 / the same env under `SyncVectorEnv`", f"{vec[1024]['ratio_sync']:.0f}", ">= 20"),
        ("vector env, fixed cost per call at N = 1 / `CartPoleVectorEnv` (time)",
         f"{env_doc['fixed_cost_n1']['ratio']:.2f}", "<= 1"),
        (f"SB3 PPO training, 1 env / {ppo8['n_envs']} envs, AmigoBot / Pendulum (steps/s)",
         f"{ppo1['ratio']:.2f} / {ppo8['ratio']:.2f}", ">= 0.95"),
    ]  # fmt: skip
    if core_doc is not None and core_doc.get("startup"):
        st = core_doc["startup"]
        rows.append(
            (
                "second process, import to first compiled step (`amigo-gym bench-core`)",
                f"{st['kernel_warm_s']:.2f} s (v1: {st['v1_warm_s']:.2f} s)",
                "< 1 s",
            )
        )
    lines = ["| figure | measured | target |", "|---|---:|---:|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c in rows]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------- CLI
@dataclass(frozen=True)
class EnvSettings:
    """Settings of ``amigo-gym bench-env``, each the option of the same name (``--min-time`` for ``min_time``).

    Attributes:
        sizes: vector sizes [envs] (default: (1, 64, 1024, 4096, 65536)).
        repeats: repeats per measurement [repeats]; the median is reported.
        min_time: least duration of one repeat [s].
        sync_max: largest N for the SyncVectorEnv peer [envs].
        memory_n: N of the memory measurement (against N = 1) [envs].
        ppo_steps: PPO budget per run [env-steps].
        ppo_envs: envs of the vectorised PPO comparison [envs].
        ppo_repeats: alternating AmigoBot/Pendulum PPO runs (median) [runs].
        skip_single: skip the single-env comparison.
        skip_vector: skip the vector-env comparison.
        skip_memory: skip the memory measurement.
        skip_ppo: skip the SB3 PPO comparison.
        v1: also AmigoBot-v1 against v0 (when registered).
        kernels: also each step implementation (numpy, numba, numba-parallel) of AmigoBot-v0 and v1, single and vector
            env at the largest of --sizes up to 4096 (needs numba).
        threads: numba's threads for kernel=numba-parallel [threads] (default: NUMBA_NUM_THREADS, else all CPUs).
        quick: smoke run: sizes (1, 64, 1024), 1 repeat of 0.02 s, tiny memory/PPO runs.
        json: JSON output [file] (default: none).
        plot: plot throughput against N [file] (default: none).
        table_from: measure nothing: print the README's performance table from this --json file of a --v1 run
            [file], with the start-up row from --core-json (default: none).
        core_json: bench-core --json file for --table-from [file] (default: none).
    """

    sizes: tuple[int, ...] | None = None
    repeats: int = 5
    min_time: float = 0.2
    sync_max: int = SYNC_MAX
    memory_n: int = 65536
    ppo_steps: int = 8192
    ppo_envs: int = 8
    ppo_repeats: int = 3
    skip_single: bool = False
    skip_vector: bool = False
    skip_memory: bool = False
    skip_ppo: bool = False
    v1: bool = False
    kernels: bool = False
    threads: int | None = None
    quick: bool = False
    json: str | None = None
    plot: str | None = None
    table_from: str | None = None
    core_json: str | None = None

    def __post_init__(self) -> None:
        for i, n in enumerate(self.sizes or ()):
            check_range(PROG, f"sizes[{i}]", n, 1, 1_000_000)
        check_range(PROG, "min_time", self.min_time, 0.0, 60.0, low_open=True)
        for name, low, high in (
            ("repeats", 1, 1000),
            ("sync_max", 0, 1_000_000),
            ("memory_n", 2, 10_000_000),
            ("ppo_steps", 1, 10_000_000),
            ("ppo_envs", 1, 4096),
            ("ppo_repeats", 1, 100),
        ):
            check_range(PROG, name, getattr(self, name), low, high)
        if self.threads is not None:
            check_range(PROG, "threads", self.threads, 1, os.cpu_count() or 1)


def run(s: EnvSettings) -> int:
    """``amigo-gym bench-env`` with the settings ``s``: the report on stdout (progress on stderr), ``--plot``,
    ``--json``; with ``--table-from``, only :func:`headline_table` of the JSON files."""
    if s.table_from is not None:
        import json

        env_doc = json.loads(Path(s.table_from).read_text(encoding="utf-8"))
        core_doc = json.loads(Path(s.core_json).read_text(encoding="utf-8")) if s.core_json else None
        try:
            print(headline_table(env_doc, core_doc), end="")
        except (KeyError, StopIteration) as exc:
            raise ValueError(f"--table-from {s.table_from}: not the JSON of a full --v1 run ({exc})") from None
        return 0
    if s.quick:
        sizes = list(s.sizes or QUICK_SIZES)
        repeats, min_time, sync_max = 1, 0.02, min(s.sync_max, SYNC_MAX)
        memory_n, ppo_steps = min(s.memory_n, 256), min(s.ppo_steps, 128)
    else:
        sizes = list(s.sizes or DEFAULT_SIZES)
        repeats, min_time, sync_max = s.repeats, s.min_time, s.sync_max
        memory_n, ppo_steps = s.memory_n, s.ppo_steps
    if s.threads is not None and numba_available():
        import numba

        # numba's pool has NUMBA_NUM_THREADS threads (default: the CPUs)
        check_range(PROG, "threads", s.threads, 1, int(getattr(numba.config, "NUMBA_NUM_THREADS", 1)))
        numba.set_num_threads(s.threads)
    rep = Report()
    rep.load = (load_average(), "-")
    print(f"{machine_line()}; {numba_state()}; load average {rep.load[0]}", flush=True)
    print(f"median of {repeats} repeats of >= {min_time:g} s", flush=True)
    if not s.skip_single:
        say("single env: AmigoBot-v0 vs Pendulum-v1")
        rep.single = bench_single(repeats, min_time)
    if not s.skip_vector:
        say(f"vector env at N = {sizes} (Sync up to N = {sync_max})")
        rep.vector = bench_vector(sizes, repeats, min_time, sync_max, log=say)
    if not s.skip_memory:
        say(f"memory per sub-env (N = {memory_n} vs 1)")
        rep.memory = bench_memory(memory_n)
    if not s.skip_ppo:
        try:
            import stable_baselines3  # noqa: F401
            import torch  # noqa: F401
        except ImportError:
            rep.notes.append("SB3 PPO comparison skipped: install amigo_gym[train] (torch, stable-baselines3)")
        else:
            say(f"SB3 PPO learn, {ppo_steps} steps per run")
            rollout, rounds = (64, 1) if s.quick else (2048, s.ppo_repeats)
            rep.ppo = bench_ppo(ppo_steps, s.ppo_envs, log=say, rollout=rollout, repeats=rounds, v1=s.v1)
    if s.v1:
        say("AmigoBot-v1 vs v0")
        rep.v1 = bench_v1(sizes, repeats, min_time)
        if rep.v1 is None:
            rep.notes.append("--v1: AmigoBot-v1 is not in gymnasium's registry; v1 vs v0 skipped")
    if s.kernels:
        n_k = max([n for n in sizes if n <= V1_MAX_N], default=min(sizes))
        say(f"step implementations of AmigoBot-v0 and v1, single env and N = {n_k}")
        rep.kernels = bench_kernels(n_k, repeats, min_time)
        if not rep.kernels:
            rep.notes.append("--kernels: numba is not installed; only the numpy step exists")
    rep.load = (rep.load[0], load_average())
    print(format_report(rep))
    if s.plot is not None and rep.vector:
        plot_vector(rep.vector, s.plot, rep.v1)
        say(f"wrote {s.plot}")
    if s.json is not None:
        atomic_write_json(s.json, rep.to_json())
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym bench-env``."""
    description = "Speed of AmigoBot-v0 against Pendulum, CartPoleVectorEnv and SyncVectorEnv."
    return run_command(EnvSettings, run, argv, PROG, description)


if __name__ == "__main__":
    sys.exit(main())
