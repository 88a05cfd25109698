"""Evaluate the analytic policies and trained agents on one fixed protocol; JSON, Markdown table, plots.

Usage, the protocol, the agents and models read, the metrics and the output files: docs/baselines.md,
"Reference: `amigo-gym evaluate`".
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import pickle
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.data import pretrained_dir
from amigo_gym.envs.base import info_row
from amigo_gym.io import atomic_write, atomic_write_json, json_safe, sha256_file
from amigo_gym.model.kinematics import a_from_h, circle_steady_state
from amigo_gym.model.params import check_real
from amigo_gym.paths import CirclePath
from amigo_gym.policies.analytic import AnalyticPolicy, analytic_wheel_rates
from amigo_gym.policies.learned import FastPolicy
from amigo_gym.task.v1 import TrackingParams, v0_settings
from amigo_gym.tools.options import cli, parse_settings, run_guarded
from amigo_gym.tools.plots import pyplot, save_figure
from amigo_gym.tools.runs import CorruptFileError, check_pickle, corrupt_errors, read_json, verify_sha256
from amigo_gym.tools.training.hyperparams import sb3_class
from amigo_gym.tools.training.task_metrics import Scenario, Unavailable, _rms, md_table, run_scenario

Array = NDArray[np.float64]
ENV_ID = "AmigoBot-v0"
PRETRAINED_DIR = pretrained_dir()
ALGOS = ("ppo", "sac", "td3")
#: algorithm name (prefix) of the fast PPO's models (:mod:`amigo_gym.tools.training.fastppo`), run in numpy
FAST_ALGO = "fastppo"
SCENARIOS = ("nominal", "paper_start", "perturbed")
SETTLED_BAND_M = 1e-3
#: anything with SB3's ``predict(obs, state=, episode_start=, deterministic=) -> (action, state)``
Agent = Any


@dataclass(frozen=True)
class EvalProtocol:
    """The fixed evaluation protocol: ``steps`` per episode (400: 40 s), the ``perturbed_seeds``, the start of the
    settled window ``settle_time_s`` [s], the reference policy's ``analytic_gain`` [1/s], the ``scenarios`` run."""

    steps: int = 400
    perturbed_seeds: tuple[int, ...] = tuple(range(100, 110))
    settle_time_s: float = 5.0
    analytic_gain: float = 3.0
    scenarios: tuple[str, ...] = SCENARIOS

    def __post_init__(self) -> None:
        if isinstance(self.steps, bool) or not isinstance(self.steps, int) or self.steps < 1:
            raise ValueError(f"EvalProtocol.steps must be an integer >= 1, got {self.steps!r}")
        if not (seeds := self.perturbed_seeds) or any(not isinstance(s, int) or s < 0 for s in seeds):
            raise ValueError(f"EvalProtocol.perturbed_seeds must be non-negative integers, got {seeds!r}")
        if (bad := [s for s in self.scenarios if s not in SCENARIOS]) or not self.scenarios:
            raise ValueError(f"EvalProtocol.scenarios must be a non-empty subset of {list(SCENARIOS)}, got {bad}")
        check_real("EvalProtocol", "settle_time_s", self.settle_time_s, 0.0)
        check_real("EvalProtocol", "analytic_gain", self.analytic_gain, 0.0, 10.0)


@dataclass
class Trajectory:
    """One episode of ``T`` steps, sampled after each step: ``time`` [s], cross-track error ``e`` [m], ``h`` (T, 2)
    [m], wheel ``rates`` [rad/s] and ``angles`` [rad], the analytic ``ref_rates`` [rad/s], ``arc`` (H's unwrapped
    arc length [m]), the return ``ret``, ``terminated`` (left the path), ``h0`` (H at the start [m])."""

    time: Array
    e: Array
    h: Array
    rates: Array
    angles: Array
    ref_rates: Array
    arc: Array
    ret: float
    terminated: bool
    h0: Array = field(default_factory=lambda: np.zeros(2))


#: ``trajs[agent][scenario]``: the episodes
Trajs = dict[str, dict[str, list[Trajectory]]]


def steady_start_pose(params: TrackingParams) -> Array:
    """Pose ``(x_A, y_A, beta)`` with H at the circle's start in the closed-form steady state
    (``beta = theta(0) - d atan(l3 / R_A)``)."""
    if not isinstance(path := params.path, CirclePath):
        raise ValueError(f"the nominal scenario needs path='circle', got {type(path).__name__}")
    ss = circle_steady_state(params.radius, params.speed, params.robot, params.direction)
    beta = float(path.tangent_angle(0.0)) - float(ss.heading_lag)
    h = path.point(0.0)
    return np.array([*a_from_h(h[0], h[1], math.cos(beta), math.sin(beta), params.robot.l3), beta])


def protocol_scenarios(proto: EvalProtocol, params: TrackingParams | None = None) -> tuple[Scenario, ...]:
    """``nominal``, ``paper_start``: an episode from a fixed pose; ``perturbed``: one per seed, a random start."""
    params = params or TrackingParams.v0()
    poses = {
        "nominal": (tuple(steady_start_pose(params).tolist()), "H on the circle, steady heading lag"),
        "paper_start": ((-params.robot.l3, 0.0, 0.0), "H at the origin, beta = 0"),
        "perturbed": (None, "env's random start (reset(seed=s))"),
    }
    return tuple(
        Scenario(n, ENV_ID, {}, proto.perturbed_seeds if pose is None else (0,), proto.steps, False, desc,
                 settle_time_s=proto.settle_time_s, pose=pose)
        for n in proto.scenarios
        for pose, desc in [poses[n]]
    )  # fmt: skip


def trajectories(agent: Agent, sc: Scenario, gain: float = 3.0) -> list[Trajectory]:
    """The episodes of ``sc``, against the analytic policy's rates (gain ``gain`` [1/s]) on the agent's observations."""
    keys = ("time", "e", "h", "rates", "angles", "ref_rates")
    cols: list[dict[str, list[Any]]] = [{k: [] for k in keys} for _ in sc.seeds]
    start: dict[str, Any] = {}

    def on_reset(venv: Any, infos: dict[str, Any]) -> None:
        start["params"] = venv.unwrapped.params
        start["h0"] = [np.asarray(info_row(infos, i)["h_position"], dtype=np.float64) for i in range(len(sc.seeds))]

    def on_row(i: int, info: dict[str, Any], _ended: bool, obs: Any) -> None:
        wmax = start["params"].robot.max_wheel_rate
        ref = np.clip(analytic_wheel_rates(obs, start["params"], gain), -wmax, wmax)
        row = (info["time"], info["cross_track_error"], info["h_position"], info["wheel_rates"], info["wheel_angles"])
        for k, v in zip(keys, (*row, ref), strict=True):
            cols[i][k].append(v)

    recs = run_scenario(agent, sc, on_reset=on_reset, on_row=on_row)
    path = start["params"].path
    out = []
    for rec, col, h0 in zip(recs, cols, start["h0"], strict=True):
        arrays = {k: np.asarray(v, dtype=np.float64) for k, v in col.items()}
        arrays |= {k: arrays[k].reshape(-1, 2) for k in keys[2:]}  # h, rates, angles, ref_rates
        # arc length of H's closest point, unwrapped at one lap on the closed circle
        ds = np.diff([float(path.project(h).s) for h in (h0, *arrays["h"])])
        if path.length < math.inf:
            ds = (ds + 0.5 * path.length) % path.length - 0.5 * path.length
        out.append(Trajectory(**arrays, arc=np.cumsum(ds), ret=sum(rec.rewards), terminated=rec.terminated, h0=h0))
    return out


def summarize(trajs: Sequence[Trajectory], params: TrackingParams, proto: EvalProtocol) -> dict[str, Any]:
    """Pooled metrics of one (agent, scenario)."""
    ss_rates = circle_steady_state(params.radius, params.speed, params.robot, params.direction).wheel_rates
    e = np.concatenate([t.e for t in trajs])
    settled = [t.time >= proto.settle_time_s - 1e-9 for t in trajs]
    e_set = np.concatenate([t.e[m] for t, m in zip(trajs, settled, strict=True)])
    dev = np.concatenate([t.rates - t.ref_rates for t in trajs])
    dev_ss = np.concatenate([t.rates[m] - ss_rates for t, m in zip(trajs, settled, strict=True)])
    rets = np.array([t.ret for t in trajs])
    st: list[float | None] = []  # from the first step after the last one outside the band; None: it ends outside
    for t in trajs:
        outside = np.flatnonzero(np.abs(t.e) > SETTLED_BAND_M)
        k = int(outside[-1]) + 1 if outside.size else 0
        st.append(None if t.terminated or k == t.e.size else float(t.time[k]) if k else 0.0)
    return {
        "episodes": len(trajs),
        "h_rms_m": _rms(e),
        "h_rms_settled_m": _rms(e_set),
        "h_max_m": float(np.abs(e).max()),
        "h_max_settled_m": float(np.abs(e_set).max()) if e_set.size else float("nan"),
        "settling_time_s": None if any(x is None for x in st) else float(np.mean([x for x in st if x is not None])),
        "wheel_rate_dev_rms": _rms(dev),
        "wheel_rate_dev_steady_rms": _rms(dev_ss),
        "mean_return": float(rets.mean()),
        "std_return": float(rets.std()),
        "mean_length": float(np.mean([t.e.size for t in trajs])),
        "terminated": int(sum(t.terminated for t in trajs)),
        "laps": float(np.mean([t.arc[-1] / (2 * math.pi * params.radius) for t in trajs])),
    }


def default_agents(params: TrackingParams, gain: float = 3.0) -> dict[str, Agent]:
    """The two analytic policies: ``analytic`` (feedback gain ``gain``) and ``analytic_ff`` (gain 0)."""
    return {"analytic": AnalyticPolicy(params, gain=gain), "analytic_ff": AnalyticPolicy(params, feedforward_only=True)}


def _classical(name: str, env: Any) -> Any:
    """The classical policy ``name`` built for ``env``; :class:`Unavailable` if it has none."""
    base = env.unwrapped
    if callable(hook := getattr(base, "classical_policy", None)):
        return hook(name)
    params = getattr(base, "params", None)
    if isinstance(params, TrackingParams) and params.observation == "v1":  # the nominal robot's policies
        from amigo_gym.policies import AnalyticTrackingPolicy, DelayCompensatedPolicy, PurePursuitPolicy

        v1: dict[str, Any] = {"analytic": AnalyticTrackingPolicy, "pure_pursuit": PurePursuitPolicy}
        v1["delay_compensated"] = DelayCompensatedPolicy
        v1["pure_pursuit_textbook"] = PurePursuitPolicy.textbook  # Cao et al. (2024)'s preset
        if name in v1:
            return v1[name](params)
        raise Unavailable(f"{name}: the feedforward-only law is AmigoBot-v0's (v1 starts at rest, off the path)")
    if not isinstance(params, TrackingParams):
        raise Unavailable(f"{name}: no classical policy for {type(base).__name__}")
    if name in ("analytic", "analytic_ff"):
        return AnalyticPolicy(params, feedforward_only=name == "analytic_ff")
    raise Unavailable(f"{name}: not available on {type(base).__name__} (needs AmigoBot-v1)")


#: classical policies by name: built per scenario from the environment
CLASSICAL: dict[str, Callable[[Any], Any]] = {
    n: partial(_classical, n)
    for n in ("analytic", "analytic_ff", "pure_pursuit", "pure_pursuit_textbook", "delay_compensated")
}


@dataclass
class NormalizedAgent:
    """A model trained on ``VecNormalize``d observations, normalizing each observation with the saved statistics."""

    model: Any
    vecnormalize: Any

    observation_space: Any = None  # the model's

    def predict(
        self, observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[Any, Any]:
        obs = self.vecnormalize.normalize_obs(np.asarray(observation, dtype=np.float32))
        return tuple(self.model.predict(obs, state=state, episode_start=episode_start, deterministic=deterministic))


@dataclass
class AgentSpec:
    """One training seed of one agent: a classical policy (``path is None``) or a model zip (``algo``: ``ppo``,
    ``sac``, ``td3`` or ``fastppo*``) with the ``manifest`` read beside it (``<zip>.json``), its training ``record``
    (``<algo>.json`` or ``run.json``) and ``vecnormalize`` statistics, if any."""

    name: str
    seed: int = 0
    path: str | None = None
    algo: str | None = None
    manifest: dict[str, Any] | None = None
    record: Path | None = None
    vecnormalize: Path | None = None
    _model: Any = field(default=None, repr=False)

    @property
    def model(self) -> Path:
        return Path(str(self.path))

    @property
    def fast(self) -> bool:
        """A :class:`amigo_gym.policies.learned.FastPolicy` model (numpy weights and JSON, no pickle)."""
        return str(self.algo).startswith(FAST_ALGO)

    def load(self, trust: bool = False) -> Agent:
        """The model, loaded on the CPU (with its ``VecNormalize`` statistics). Each pickle is checked first against
        the sha256 its manifest or record gives (:class:`CorruptFileError` on a mismatch, as for a file that is no
        loadable model), then that it is shipped, written here, or ``trust``ed (:class:`UntrustedFileError`)."""
        if self._model is not None:
            return self._model
        record: Any = self.manifest
        if record is None and self.record is not None:
            record = read_json(self.record)
            if not isinstance(record, dict):
                raise CorruptFileError(f"{self.record}: not a training record (a JSON object)")
        record = record or {}
        # a run's run.json records the sha256 of its final model.zip, and under "files" of every file beside it
        files = record.get("files") if isinstance(record.get("files"), dict) else {}
        digest = files.get(self.model.name)
        if digest is None and (self.record is None or self.record.name != "run.json"):
            digest = record.get("sha256")
        source = str(self.record or self.model.with_suffix(".json"))
        if self.fast:
            if digest is not None:
                verify_sha256(self.model, str(digest), source)
            return FastPolicy.load(self.model)
        if self.vecnormalize is not None:  # checked first: it is unpickled after the model
            stats_digest = files.get(self.vecnormalize.name)
            check_pickle(self.vecnormalize, None if stats_digest is None else str(stats_digest), source, trust)
        check_pickle(self.model, None if digest is None else str(digest), source, trust)
        # for acting: the learning rate is not loaded, a schedule being code pickled by the Python that trained it
        # (ppo.zip's, by 3.11: calling it on 3.13 crashes the process)
        with corrupt_errors(self.model, f"{str(self.algo).upper()} model"):
            model = sb3_class(str(self.algo)).load(self.model, device="cpu", custom_objects={"learning_rate": 0.0})
        if self.vecnormalize is None:
            return model
        with corrupt_errors(self.vecnormalize, "VecNormalize statistics"), open(self.vecnormalize, "rb") as f:
            stats = pickle.load(f)  # VecNormalize.load without a venv: the statistics only
        stats.training = False
        return NormalizedAgent(model, stats, model.observation_space)

    def instantiate(self, env: Any) -> Any:
        """A classical policy for ``env``, or the model if its observation space matches (else :class:`Unavailable`)."""
        if self.path is None:
            return CLASSICAL[self.name](env)
        self._model = model = self.load()
        want = (model.builder.obs_dim,) if self.fast else getattr(model.observation_space, "shape", None)
        if want != (got := getattr(env.observation_space, "shape", None)):
            raise Unavailable(
                f"observation shape {got}{'' if self.fast else ' of the scenario'} differs from the model's {want}"
            )
        return model

    def describe(self) -> dict[str, Any]:
        """JSON description (path, algo, seed, sha256 of the zip, manifest)."""
        d: dict[str, Any] = {"agent": self.name, "seed": self.seed}
        if self.path is None:
            return d | {"kind": "classical"}
        d |= {"kind": "fastppo" if self.fast else "sb3", "algo": self.algo, "path": self.path}
        d["sha256"] = sha256_file(self.path)
        return d if self.manifest is None else d | {"manifest": self.manifest}


def _spec(name: str, model: Path, algo: str, record: str, stats: bool = True) -> AgentSpec:
    beside = [f if (f := model.parent / n).is_file() else None for n in (record, "vecnormalize.pkl")]
    return AgentSpec(name, 0, str(model), algo, None, beside[0], beside[1] if stats else None)


def _run_ref(run_dir: Path, model: Path | None = None) -> AgentSpec:
    model, cfg = model or run_dir / "model.zip", run_dir / "config.json"
    try:
        algo = json.loads(cfg.read_text())["settings"]["algo"]
    except (OSError, ValueError, KeyError, TypeError):
        raise ValueError(f"--models: {run_dir} has a model.zip but no readable config.json naming its algo") from None
    if algo not in ALGOS:
        raise ValueError(f"--models: {cfg} names an unknown algo {algo!r}")
    return _spec(run_dir.name, model, algo, "run.json")


def _is_run(d: Path) -> bool:
    return (d / "model.zip").is_file() and (d / "config.json").is_file()


def v0_name(name: str) -> str:
    """``<algo>_v0`` for the pretrained layout's ``<algo>.zip``, a run's own name otherwise."""
    return f"{name}_v0" if name in ALGOS else name


def find_models(path: str | os.PathLike[str]) -> list[AgentSpec]:
    """The trained models at ``path``: a run folder, a folder of them, a model ``.zip`` or a folder of ``<algo>.zip``;
    ``FileNotFoundError`` if it does not exist, ``ValueError`` if it holds no model or one of an unknown algorithm."""
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"--models: no file or directory {p}")
    if p.is_file():
        if p.suffix != ".zip":
            raise ValueError(f"--models: {p} is not a model .zip")
        if p.stem in ALGOS:
            return [_spec(p.stem, p, p.stem, f"{p.stem}.json")]
        if (p.parent / "config.json").is_file():
            return [_run_ref(p.parent, p)]
        raise ValueError(f"--models: cannot tell the algorithm of {p} (name it <algo>.zip or keep its config.json)")
    if _is_run(p):
        return [_run_ref(p)]
    refs = [_spec(a, p / f"{a}.zip", a, f"{a}.json", stats=False) for a in ALGOS if (p / f"{a}.zip").is_file()]
    refs += [_run_ref(d) for d in sorted(p.iterdir()) if d.is_dir() and _is_run(d)]
    if not refs:
        raise ValueError(
            f"--models: no models in {p} (expected a run folder with model.zip and config.json, "
            "folders of such runs, or <algo>.zip files)"
        )
    if len(set(names := [r.name for r in refs])) != len(names):
        raise ValueError(f"--models: two models in {p} share a name: {sorted(names)}")
    return refs


#: :meth:`AgentSpec.load` as a function of the spec
load_model = AgentSpec.load


def load_agents(models: str | os.PathLike[str], trust: bool = False) -> dict[str, Agent]:
    """Every model :func:`find_models` finds at ``models``, loaded, by name."""
    return {ref.name: ref.load(trust) for ref in find_models(models)}


def protocol_agents(
    steps: int, seeds: int, models: str | os.PathLike[str] | None
) -> tuple[EvalProtocol, dict[str, Agent], list[AgentSpec], dict[str, Any]]:
    """The protocol of ``steps`` per episode and ``seeds`` perturbed starts (100, 101, ...), its agents by name (the
    analytic policies and the models at ``models``, if any, loaded and named by :func:`v0_name`), their specs (a
    model's seed: its record's, else 0) and the models' training records by name."""
    proto = EvalProtocol(steps=steps, perturbed_seeds=tuple(range(100, 100 + seeds)))
    agents = default_agents(TrackingParams.v0(), proto.analytic_gain)
    specs, training = [AgentSpec(name) for name in agents], dict[str, Any]()
    for ref in find_models(models) if models is not None else []:
        name, model = v0_name(ref.name), ref.load()
        agents[name] = model
        if ref.record is not None:
            training[name] = json.loads(ref.record.read_text())
        seed = training.get(name, {}).get("seed")
        specs.append(replace(ref, name=name, seed=seed if isinstance(seed, int) else 0, _model=model))
    return proto, agents, specs, training


def evaluate_agents(agents: dict[str, Agent], proto: EvalProtocol | None = None) -> tuple[list[dict[str, Any]], Trajs]:
    """Every agent on ``proto``: a :func:`summarize` row per (agent, scenario), the episodes ``[agent][scenario]``."""
    proto, params = proto or EvalProtocol(), TrackingParams.v0()
    results: list[dict[str, Any]] = []
    trajs: Trajs = {}
    for name, agent in agents.items():
        trajs[name] = {}
        for sc in protocol_scenarios(proto, params):
            trajs[name][sc.name] = eps = trajectories(agent, sc, proto.analytic_gain)
            results.append({"agent": name, "scenario": sc.name, **summarize(eps, params, proto)})
    return results, trajs


COLUMNS: tuple[tuple[str, str, Callable[[Any], str]], ...] = (
    ("agent", "agent", str),
    ("scenario", "scenario", str),
    ("h_rms_m", "H RMS [mm]", lambda v: f"{v * 1e3:.3f}"),
    ("h_rms_settled_m", "H RMS t≥5 s [mm]", lambda v: f"{v * 1e3:.3f}"),
    ("h_max_m", "H max [mm]", lambda v: f"{v * 1e3:.2f}"),
    ("settling_time_s", "settle ≤1 mm [s]", lambda v: "never" if v is None else f"{v:.1f}"),
    ("wheel_rate_dev_rms", "rate dev RMS [rad/s]", lambda v: f"{v:.3f}"),
    ("wheel_rate_dev_steady_rms", "rate dev steady [rad/s]", lambda v: f"{v:.3f}"),
    ("mean_return", "return", lambda v: f"{v:.1f}"),
    ("terminated", "left path", str),
)


def markdown_table(results: Sequence[dict[str, Any]]) -> str:
    """The results as a Markdown table (one row per agent and scenario)."""
    rows = []
    for r in results:  # a metric that does not exist: None (as read back from JSON) or NaN
        missing = {k for k, v in r.items() if v is None or (isinstance(v, float) and math.isnan(v))}
        rows.append(["n/a" if k in missing and k != "settling_time_s" else fmt(r[k]) for k, _, fmt in COLUMNS])
    return "\n".join(md_table([c[1] for c in COLUMNS], rows)) + "\n"


def plot_trajectories(trajs: Trajs, params: TrackingParams, path: Path) -> None:
    """Top: H's trajectory of every agent against the circle, whole and near the start. Bottom: ``|e(t)|``."""
    plt = pyplot()
    have = {s for s in SCENARIOS if all(s in v for v in trajs.values())}
    top = "perturbed" if "perturbed" in have else sorted(have)[0]
    fig, axes = plt.subplots(2, 2, figsize=(12.0, 10.0))
    circle = params.path.point(np.linspace(0.0, 2 * math.pi * params.radius, 1441))
    for j, zoom in enumerate((False, True)):
        ax = axes[0, j]
        ax.plot(circle[:, 0], circle[:, 1], color="0.6", lw=6 if zoom else 4, alpha=0.4, label="path (eq. 6)")
        for name, per in trajs.items():
            tr = per[top][0]
            h = np.vstack([tr.h0, tr.h])
            ax.plot(h[:, 0], h[:, 1], lw=1.2, marker="." if zoom else None, ms=3, label=name)
        if zoom:
            ax.set(xlim=(-0.03, 0.25), ylim=(-0.025, 0.04), title=f"H's trajectory near the start ({top} start)")
        else:
            ax.set(aspect="equal", title=f"H's trajectory, {top} start")
        ax.set(xlabel="x0 [m]", ylabel="y0 [m]")
        ax.legend(fontsize=8, loc="upper left" if zoom else "center")
    for j, sc in enumerate(s for s in ("nominal", "perturbed") if s in have):
        ax = axes[1, j]
        for name, per in trajs.items():
            tr = per[sc][0]
            ax.semilogy(tr.time, np.maximum(np.abs(tr.e), 1e-12), lw=1.0, label=name)
        ax.axhline(SETTLED_BAND_M, color="k", ls=":", lw=0.8)
        ax.set(xlabel="t [s]", ylabel="|cross-track error of H| [m]", title=f"tracking error, {sc} start")
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_wheels(trajs: Trajs, params: TrackingParams, path: Path, scenario: str = "perturbed") -> None:
    """Per agent (the paper's Figs. 2–5): wheel angles, wheel rates over 10 s, angles minus the analytic policy's."""
    plt = pyplot()
    if "analytic" not in trajs:
        raise ValueError("plot_wheels needs the 'analytic' agent as the reference")
    ref = trajs["analytic"][scenario][0]
    others = [a for a in trajs if a != "analytic"] or ["analytic"]
    ss = circle_steady_state(params.radius, params.speed, params.robot, params.direction).wheel_rates
    fig, axes = plt.subplots(len(others), 3, figsize=(16.0, 2.9 * len(others)), squeeze=False)
    for i, name in enumerate(others):
        tr = trajs[name][scenario][0]
        n = min(tr.time.size, ref.time.size)
        ax_angle, ax_rate, ax_diff = axes[i]
        for k, c in ((0, "C0"), (1, "C3")):
            a = f"alpha{k + 1}"
            ax_angle.plot(ref.time, ref.angles[:, k], color=c, lw=3, alpha=0.35, label=f"{a} analytic")
            ax_angle.plot(tr.time, tr.angles[:, k], color=c, lw=1.0, label=f"{a} {name}")
            ax_rate.step(ref.time, ref.rates[:, k], where="pre", color=c, lw=3, alpha=0.35, label=f"{a}dot analytic")
            ax_rate.step(tr.time, tr.rates[:, k], where="pre", color=c, lw=1.0, label=f"{a}dot {name}")
            ax_rate.axhline(ss[k], color=c, ls=":", lw=0.8)
            ax_diff.plot(tr.time[:n], tr.angles[:n, k] - ref.angles[:n, k], color=c, lw=1.0, label=a)
        ax_rate.set_xlim(0.0, 10.0)
        ax_diff.axhline(0.0, color="k", lw=0.5)
        ax_angle.set(ylabel="wheel angle [rad]", title=f"{name}: wheel angles ({scenario} start)")
        ax_rate.set(ylabel="wheel rate [rad/s]", title=f"{name}: wheel rates, first 10 s (dotted: steady state)")
        ax_diff.set(ylabel="angle minus analytic [rad]", title=f"{name}: wheel angles minus the analytic policy's")
        for ax in axes[i]:
            ax.legend(fontsize=7, ncol=1 if ax is ax_diff else 2)
            ax.set_xlabel("t [s]" if i == len(others) - 1 else "")
    fig.tight_layout()
    save_figure(fig, path)


def write_outputs(
    results: list[dict[str, Any]],
    trajs: Trajs,
    proto: EvalProtocol,
    out: Path,
    json_path: Path,
    extra: dict[str, Any] | None = None,
    plots: bool = True,
    markdown_path: Path | None = None,
) -> dict[str, Any]:
    """The JSON document (``protocol``, ``results``, ``extra``), written with the table (default ``out/eval.md``) and
    the figures."""
    params = TrackingParams.v0()
    v0 = v0_settings(params) or {}
    protocol = {
        "env_id": ENV_ID,
        "env_params": json_safe({**v0, "robot": asdict(params.robot)}),
        "steps": proto.steps,
        "duration_s": proto.steps * params.dt,
        "lap_time_s": 2 * math.pi * math.sqrt(params.radius**2 - params.robot.l3**2) / v0["speed"],
        "scenarios": {
            sc.name: ({"seeds": list(sc.seeds)} if sc.pose is None else {"start_pose": list(sc.pose)})
            | {"note": sc.description}
            for sc in protocol_scenarios(replace(proto, scenarios=SCENARIOS), params)
        },
        "run_scenarios": list(proto.scenarios),
        "settle_time_s": proto.settle_time_s,
        "settled_band_m": SETTLED_BAND_M,
        "analytic_gain": proto.analytic_gain,
        "wheel_rate_reference": (
            f"the analytic policy (feedback gain k = {proto.analytic_gain:g}/s) on the agent's own observations"
        ),
        "deterministic": True,
    }
    doc = {"protocol": protocol, "results": results, **(extra or {})}
    atomic_write_json(json_path, doc, parents=True)
    atomic_write(markdown_path or out / "eval.md", markdown_table(results).encode(), parents=True)
    if plots:
        plot_trajectories(trajs, params, out / "eval_trajectories.png")
        plot_wheels(trajs, params, out / "eval_wheels.png")
    return doc


def one_torch_thread() -> None:
    """``torch.set_num_threads(1)`` when torch is installed: small MLPs run fastest on one thread."""
    with contextlib.suppress(ImportError):
        import torch

        torch.set_num_threads(1)


PROG, DEFAULT_OUT = "amigo-gym evaluate", "results/evaluate"  # compare writes to results


@dataclass(frozen=True)
class EvaluateSettings:
    """Options of ``amigo-gym evaluate``, each the option of the same name unless its ``cli(flag)`` names one.

    Attributes:
        models: what train wrote: a run folder, a folder of run folders, a model .zip, or a folder of <algo>.zip
            [path] (default: the pretrained agents/pretrained). Model zips are pickles: loading one runs its code,
            so only shipped ones and those a run here wrote load without --trust-unverified.
        out: directory for eval.md and the plots [dir]; a folder holding another command's output set
            (manifest.json, e.g. compare's) is refused unless --force.
        force: write into a folder that holds another command's files.
        json: JSON file [file] (default: <out>/results.json).
        markdown: Markdown table file [file] (default: <out>/eval.md).
        steps: steps per episode [steps] (dt = 0.1 s).
        seeds: number of perturbed starts, seeds 100.. [episodes], >= 1.
        load_models: evaluate the trained models too; --no-models: only the analytic policies.
        plots: draw the figures; --no-plots: skip the figures.
    """

    models: str | None = None
    out: str = DEFAULT_OUT
    force: bool = False
    json: str | None = None
    markdown: str | None = None
    steps: int = 400
    seeds: int = 10
    load_models: bool = field(default=True, metadata=cli("--no-models"))
    plots: bool = field(default=True, metadata=cli("--no-plots"))

    def validate(self) -> None:
        if self.seeds < 1:
            raise ValueError(f"--seeds must be an integer >= 1, got {self.seeds}")


def main(argv: Sequence[str] | None = None) -> int:
    a = parse_settings(EvaluateSettings, argv, PROG, "Evaluate analytic and trained agents (fixed protocol).")

    def run() -> int:
        one_torch_thread()
        models = (a.models if a.models is not None else PRETRAINED_DIR) if a.load_models else None
        proto, agents, _, training = protocol_agents(a.steps, a.seeds, models)
        results, trajs = evaluate_agents(agents, proto)
        out = Path(a.out)
        if (out / "manifest.json").is_file() and not a.force:
            raise FileExistsError(
                f"--out {out} holds another command's output set (manifest.json, e.g. amigo-gym compare's); "
                f"evaluate would overwrite its results.json, eval.md and plots: choose another --out "
                f"(default {DEFAULT_OUT}) or pass --force"
            )
        json_path = Path(a.json) if a.json else out / "results.json"
        md_path = Path(a.markdown) if a.markdown else out / "eval.md"
        extra = {"training": training} if training else None
        write_outputs(results, trajs, proto, out, json_path, extra, plots=a.plots, markdown_path=md_path)
        print(markdown_table(results), end="")
        print(f"wrote {json_path}, {md_path}" + (f", {out}/eval_*.png" if a.plots else ""))
        return 0

    return run_guarded(run, PROG)
