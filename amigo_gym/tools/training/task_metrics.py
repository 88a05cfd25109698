"""The protocol engine of ``evaluate``, ``benchmark``, ``compare`` and the training's evaluation callback: scenarios,
the episode runner, the task metrics read from the environments' ``info`` (docs/benchmark.md, "Reference: task
metrics") and the Markdown table writer."""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from amigo_gym.envs.base import info_row
from amigo_gym.io import json_safe

Array = NDArray[np.float64]

#: start of the "settled" window [s] of the ``*_settled`` metrics and of the failure test
DEFAULT_SETTLE_TIME_S = 5.0
#: settled cross-track error beyond which an episode counts as a failure [m]
DEFAULT_FAILURE_TOLERANCE_M = 0.10
#: version of the benchmark suite (:data:`amigo_gym.tools.training.benchmark.SUITES`)
SUITE_VERSION = "1.0"

#: the keys of :func:`episode_metrics`
METRIC_NAMES: tuple[str, ...] = (
    *("h_rms_m", "h_rms_settled_m", "h_max_m", "failure", "speed_err_rms", "speed_err_settled_rms", "return"),
    *("chatter_rms", "chatter_settled_rms", "effort_rms", "steps", "terminated"),
)


@dataclass(frozen=True)
class Scenario:
    """One scenario: ``gym.make(env_id, max_episode_steps=max_steps, **env_kwargs)``, one episode per seed
    (``reset(seed=s)``, from ``pose`` ``(x_A [m], y_A [m], beta [rad])`` if set); ``held_out``: outside the
    generalists' training distribution; ``settle_time_s`` [s] and ``failure_tolerance_m`` [m] of the settled metrics.
    A released suite's scenarios are never edited."""

    name: str
    env_id: str
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    seeds: tuple[int, ...] = tuple(range(100, 110))
    max_steps: int = 400
    held_out: bool = False
    description: str = ""
    version: str = SUITE_VERSION
    settle_time_s: float = DEFAULT_SETTLE_TIME_S
    failure_tolerance_m: float = DEFAULT_FAILURE_TOLERANCE_M
    pose: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        if not self.name or not isinstance(self.name, str):
            raise ValueError(f"Scenario.name must be a non-empty string, got {self.name!r}")
        if not self.seeds or any(isinstance(s, bool) or not isinstance(s, int) or s < 0 for s in self.seeds):
            raise ValueError(f"Scenario {self.name}: seeds must be non-negative integers, got {self.seeds!r}")
        if len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"Scenario {self.name}: seeds must be distinct, got {self.seeds!r}")
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, int) or self.max_steps < 1:
            raise ValueError(f"Scenario {self.name}: max_steps must be an integer >= 1, got {self.max_steps!r}")

    def cut(self, episodes: int, max_steps: int) -> Scenario:
        """The scenario on its first ``episodes`` seeds, episodes of at most ``max_steps`` steps."""
        return replace(self, seeds=self.seeds[:episodes], max_steps=min(self.max_steps, max_steps))

    @property
    def episodes(self) -> int:
        return len(self.seeds)

    def to_json(self) -> dict[str, Any]:
        """The fields and ``episodes`` as JSON data (``pose`` only when set)."""
        d = {k: v for k, v in asdict(self).items() if k != "pose" or v is not None} | {"episodes": self.episodes}
        return json_safe(d)  # type: ignore[no-any-return]


def md_row(*cells: object) -> str:
    """One Markdown table row: ``| a | b |``."""
    return "| " + " | ".join(map(str, cells)) + " |"


def md_table(header: Sequence[object], rows: Iterable[Sequence[object]], right: int = 0) -> list[str]:
    """The lines of a Markdown table: ``header``, its rule (the last ``right`` columns right-aligned), ``rows``."""
    return [md_row(*header), "|" + "---|" * (len(header) - right) + "---:|" * right, *(md_row(*r) for r in rows)]


class Unavailable(Exception):
    """An agent or scenario that cannot run here; the message says why (reported, never dropped)."""


def make_env(sc: Scenario) -> Any:
    """``gym.make(sc.env_id, max_episode_steps=sc.max_steps, **sc.env_kwargs)``; :class:`Unavailable` if it cannot."""
    if sc.env_id not in gym.registry:
        raise Unavailable(f"environment {sc.env_id} is not registered")
    try:
        return gym.make(sc.env_id, max_episode_steps=sc.max_steps, **dict(sc.env_kwargs))
    except (TypeError, ValueError) as exc:
        raise Unavailable(f"gym.make({sc.env_id!r}, ...) refused the scenario: {exc}".splitlines()[0]) from exc


def run_scenario(
    agent: Any,
    sc: Scenario,
    *,
    on_reset: Callable[[Any, dict[str, Any]], object] | None = None,
    on_row: Callable[[int, dict[str, Any], bool, Any], object] | None = None,
) -> list[EpisodeRecorder]:
    """Run ``agent`` (SB3's ``predict``) deterministically for one episode per seed of ``sc``, side by side in its
    native vector env (else Gymnasium's ``SyncVectorEnv``), until every row's first episode has ended; one recorder
    per episode. The whole batch is predicted at every step (a network's outputs do not depend on how many rows still
    run); reaching the end of an open path is a success. ``on_reset(venv, infos)`` is called after the reset,
    ``on_row(i, info, ended, obs)`` after each recorded step of row ``i`` (``obs``: what the agent acted on)."""
    mode = "sync" if gym.spec(sc.env_id).vector_entry_point is None else "vector_entry_point"
    kw = dict(sc.env_kwargs)
    venv: Any = gym.make_vec(sc.env_id, len(sc.seeds), vectorization_mode=mode, max_episode_steps=sc.max_steps, **kw)
    try:
        options = None if sc.pose is None else {"pose": np.asarray(sc.pose, dtype=np.float64)}
        obs, infos = venv.reset(seed=list(sc.seeds), options=options)
        if on_reset is not None:
            on_reset(venv, infos)
        dt = getattr(getattr(venv.unwrapped, "params", None), "dt", None)
        dt = float(dt) if isinstance(dt, (int, float)) else float(sc.env_kwargs.get("dt", 0.1))
        recs = [EpisodeRecorder(dt, sc.settle_time_s, sc.failure_tolerance_m) for _ in sc.seeds]
        adapter, live, state = InfoAdapter.for_env(venv), np.ones(len(recs), dtype=np.bool_), None
        start = live.copy()
        while live.any():
            action, state = agent.predict(obs, state=state, episode_start=start, deterministic=True)
            seen = obs
            obs, reward, terminated, truncated, vinfo = venv.step(np.asarray(action))
            for i in np.flatnonzero(live).tolist():
                info = info_row(vinfo, i)
                recs[i].add(adapter.read(info), float(reward[i]))
                if ended := bool(terminated[i] or truncated[i]):
                    recs[i].terminated = bool(terminated[i]) and not bool(info.get("end_of_path", False))
                    live[i] = False
                if on_row is not None:
                    on_row(i, info, ended, seen[i])
            start = ~live  # rows that ended were reset by the autoreset: tell a stateful agent
    finally:
        venv.close()
    return recs


@dataclass
class Grid:
    """What :func:`run_grid` ran: ``runs`` ``(agent spec, scenario, result)``, ``status`` per scenario, the
    ``unavailable`` runs with their reasons, AmigoBot-v1's ``feasibility`` report of each fixed path."""

    runs: list[tuple[Any, Scenario, Any]] = field(default_factory=list)
    status: dict[str, str] = field(default_factory=dict)
    unavailable: list[dict[str, Any]] = field(default_factory=list)
    feasibility: dict[str, Any] = field(default_factory=dict)


def run_grid(
    agents: Sequence[Any],
    scenarios: Sequence[Scenario],
    run: Callable[[Any, Scenario], Any] | None = None,
    *,
    desc: str = "benchmark",
    progress: bool = True,
) -> Grid:
    """``run(agent, scenario)`` (default: the metrics of each episode) for every agent spec (``name``, ``seed``,
    ``instantiate(env)``) on every scenario; what raises :class:`Unavailable` is listed with the reason."""
    from tqdm.auto import tqdm

    run = run or (lambda agent, sc: [r.metrics() for r in run_scenario(agent, sc)])
    grid = Grid()
    envs: dict[str, Any] = {}
    for sc in scenarios:
        try:
            envs[sc.name] = env = make_env(sc)
        except Unavailable as exc:
            grid.status[sc.name] = f"unavailable: {exc}"
            grid.unavailable.append({"agent": None, "seed": None, "scenario": sc.name, "reason": str(exc)})
            continue
        grid.status[sc.name] = "ok"
        if (report := getattr(env.unwrapped, "feasibility", None)) is not None:
            grid.feasibility[sc.name] = report
    total = sum(sc.episodes for sc in scenarios if sc.name in envs) * len(agents)
    bar = tqdm(total=total, desc=desc, unit="ep", file=sys.stderr, disable=not progress)
    try:
        for spec in agents:
            for sc in (sc for sc in scenarios if sc.name in envs):
                bar.set_postfix_str(f"{spec.name} s{spec.seed} {sc.name}", refresh=False)
                try:
                    grid.runs.append((spec, sc, run(spec.instantiate(envs[sc.name]), sc)))
                except Unavailable as exc:
                    grid.unavailable.append(dict(agent=spec.name, seed=spec.seed, scenario=sc.name, reason=str(exc)))
                bar.update(sc.episodes)
    finally:
        bar.close()
        for env in envs.values():
            env.close()
    return grid


class StepSample(NamedTuple):
    """What the metrics need from one step's ``info``."""

    cross_track_error: float
    speed_error: float
    command: tuple[float, float]
    wheel_rates: tuple[float, float]


@dataclass(frozen=True)
class InfoAdapter:
    """Read a :class:`StepSample` from an ``info``; without ``speed_error`` (v0) it is computed from ``robot``'s
    wheel radii and the ``reference_speed`` [m/s] (NaN without them)."""

    robot: Any = None
    reference_speed: float | None = None

    @classmethod
    def for_env(cls, env: Any) -> InfoAdapter:
        """Adapter of ``env.unwrapped.params``' ``robot`` and ``speed``, if present."""
        params = getattr(getattr(env, "unwrapped", env), "params", None)
        robot, speed = getattr(params, "robot", None), getattr(params, "speed", None)
        ok = robot is not None and isinstance(speed, (int, float)) and not isinstance(speed, bool)
        return cls(robot, float(speed)) if ok else cls()  # type: ignore[arg-type]

    def read(self, info: Mapping[str, Any]) -> StepSample:
        """The step's sample; ``KeyError`` if ``cross_track_error`` or ``wheel_rates`` is missing."""
        e = float(info["cross_track_error"])
        w = np.asarray(info["wheel_rates"], dtype=np.float64).reshape(2)
        cmd = np.asarray(info["command"], dtype=np.float64).reshape(2) if "command" in info else w
        if "speed_error" in info:
            ve = float(info["speed_error"])
        elif self.robot is not None and self.reference_speed is not None:
            ve = 0.5 * (self.robot.r1 * w[0] + self.robot.r2 * w[1]) - self.reference_speed
        else:
            ve = math.nan
        return StepSample(e, ve, (float(cmd[0]), float(cmd[1])), (float(w[0]), float(w[1])))


@dataclass
class EpisodeRecorder:
    """Collects the steps of one episode for :func:`episode_metrics`."""

    dt: float
    settle_time_s: float = DEFAULT_SETTLE_TIME_S
    failure_tolerance_m: float = DEFAULT_FAILURE_TOLERANCE_M
    samples: list[StepSample] = field(default_factory=list)
    rewards: list[float] = field(default_factory=list)
    terminated: bool = False

    def add(self, sample: StepSample, reward: float) -> None:
        self.samples.append(sample)
        self.rewards.append(float(reward))

    def metrics(self) -> dict[str, float]:
        e, ve, cmd, w = (np.asarray([x[k] for x in self.samples], dtype=np.float64) for k in range(4))
        return episode_metrics(
            e, ve, cmd.reshape(-1, 2), w.reshape(-1, 2), np.asarray(self.rewards, dtype=np.float64), dt=self.dt,
            terminated=self.terminated, settle_time_s=self.settle_time_s, failure_tolerance_m=self.failure_tolerance_m,
        )  # fmt: skip


def _rms(x: Array) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else math.nan


def episode_metrics(
    e: Array,
    speed_error: Array,
    command: Array,
    wheel_rates: Array,
    rewards: Array,
    *,
    dt: float,
    terminated: bool,
    settle_time_s: float = DEFAULT_SETTLE_TIME_S,
    failure_tolerance_m: float = DEFAULT_FAILURE_TOLERANCE_M,
) -> dict[str, float]:
    """Metrics (:data:`METRIC_NAMES`) of one episode of ``T`` steps, step ``k`` at ``t = (k + 1) dt`` [s]: ``e`` [m],
    ``speed_error`` [m/s] ``(T,)``, ``command`` and ``wheel_rates`` ``(T, 2)`` [rad/s], ``rewards`` ``(T,)``; a failure
    is ``terminated`` or ``|e| > failure_tolerance_m`` [m] at some ``t >= settle_time_s`` [s]."""
    settled = dt * np.arange(1, e.size + 1) >= settle_time_s - 1e-9  # step k at t = (k + 1) dt
    e_set = e[settled]
    dcmd = np.diff(command, axis=0)
    fail = bool(terminated) or bool(e_set.size and float(np.max(np.abs(e_set))) > failure_tolerance_m)
    return {
        "h_rms_m": _rms(e),
        "h_rms_settled_m": _rms(e_set),
        "h_max_m": float(np.max(np.abs(e))) if e.size else math.nan,
        "failure": float(fail),
        "speed_err_rms": _rms(speed_error),
        "speed_err_settled_rms": _rms(speed_error[settled]),
        "return": float(np.sum(rewards)),
        "chatter_rms": _rms(dcmd),
        "chatter_settled_rms": _rms(dcmd[settled[1:]]),
        "effort_rms": _rms(wheel_rates),
        "steps": float(e.size),
        "terminated": float(bool(terminated)),
    }
