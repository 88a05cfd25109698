r"""``amigo-gym train-fast``: PPO over the native ``AmigoBot-v1`` vector env (CleanRL style, one module).

    amigo-gym train-fast --out runs/fast_s0 --hyperparams agents/hyperparams/fastppo.yml  # --resume: continue

``N = num_envs`` robots step on the CPU; networks, buffers, GAE and updates on ``device``. Features normalised by a
running mean/std, Gaussian policy ``u ~ N(mu(x), exp(2 log_std))``, rewards scaled by the running std of the
discounted return (clipped to +-10), time-limit truncation bootstrapped with ``gamma V(x_final)``, GAE, ``epochs``
passes of minibatch clipped PPO (optional CAPS and residual penalties), learning rate annealed to 0.

Outputs in ``--out``: ``settings.json``, ``checkpoint.pt`` (to continue bit for bit), ``curve.csv``/``curve.json``,
``model.zip``, ``best.zip`` (lowest validation H RMS), ``run.json``. The first ``SIGTERM``/``SIGINT`` stops after
the iteration's checkpoint (status 130), a second at once.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import functools
import importlib.util
import io
import itertools
import json
import math
import os
import pickle
import shlex
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import Executor, ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any, Literal

import gymnasium as gym
import numpy as np
import torch
from numpy.typing import NDArray
from torch import nn

from amigo_gym.io import atomic_save, atomic_write, atomic_write_json, require_trust, sha256_file, vouch
from amigo_gym.model.params import check_real
from amigo_gym.paths.families import RANDOM_RANGES
from amigo_gym.policies.learned import FastPolicy, FeatureBuilder, FeatureSpec, RunningMeanStd, env_action
from amigo_gym.sim.fast_v1 import set_threads
from amigo_gym.task import v1 as tracking
from amigo_gym.tools.machine import cpu_model
from amigo_gym.tools.options import (
    OneLineParser,
    add_dataclass_options,
    cli,
    json_object,
    run_guarded,
    settings_from_args,
)
from amigo_gym.tools.runs import RunLock, StopRequest, handling
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
from amigo_gym.tools.training.hyperparams import load_hyperparams
from amigo_gym.tools.training.task_metrics import Scenario, run_scenario
from amigo_gym.tools.training.train import git_revision, versions

Array = NDArray[np.float64]
PROG = "amigo-gym train-fast"
DEVICES = ("auto", "cpu", "cuda")
_CURVATURE_KEYS = ("max_curvature", "max_curvature_rate")

#: numba (None where it is not installed)
numba: Any = importlib.import_module("numba") if importlib.util.find_spec("numba") else None


def resolve_device(device: str) -> str:
    """``"auto"``: ``"cuda"`` when torch sees one, else ``"cpu"``; ``ValueError`` for ``"cuda"`` without one."""
    cuda = torch.cuda.is_available()
    if device == "cuda" and not cuda:
        raise ValueError("FastPPOSettings.device = 'cuda' but torch sees no CUDA device here (allowed: auto, cpu)")
    return ("cuda" if cuda else "cpu") if device == "auto" else device


def _numba_threads_limit() -> int:
    return 1 if numba is None else int(numba.config.NUMBA_NUM_THREADS)


#: the allowed interval of each numeric setting ("(" / ")": that end open)
_RANGES = {
    "total_steps": "[1, 1e10]", "num_envs": "[1, 65536]", "rollout_steps": "[1, 10000]", "epochs": "[1, 100]",
    "minibatch_size": "[1, 1e8]", "history": "[0, 20]", "seed": "[0, 2147483647]", "eval_every": "[1, 1e10]",
    "eval_envs": "[1, 4096]", "eval_seed": "[0, 2147483647]", "checkpoint_every": "[1, 1e10]", "threads": "[1, 64]",
    "env_threads": "[1, 256]", "max_episode_steps": "[1, 100000]", "curriculum_stages": "[1, 1000]",
    "learning_rate": "(0, 1]", "gamma": "[0, 1)", "gae_lambda": "[0, 1]", "clip_coef": "(0, 1]", "ent_coef": "[0, 1]",
    "vf_coef": "[0, 10]", "max_grad_norm": "(0, 100]", "log_std_init": "[-5, 1]", "caps_temporal": "[0, 100]",
    "caps_spatial": "[0, 100]", "caps_sigma": "(0, 10]", "residual_penalty": "[0, 100]", "nominal_fraction": "[0, 1)",
    "curriculum_max_curvature": "[0, 100]", "curriculum_max_curvature_rate": "[0, 1000]",
    "curriculum_fraction": "(0, 1]", "residual_gain": "(0, 10]",
}  # fmt: skip


@dataclass(frozen=True)
class FastPPOSettings:
    """Settings of a fast-PPO run, checked on construction (ranges: ``_RANGES``).

    Attributes:
        env_kwargs: keywords of gym.make_vec("AmigoBot-v1", ...) [JSON mapping]; default: the training distribution.
        total_steps: env-steps of training [steps].
        num_envs: robots stepped together N [robots].
        rollout_steps: steps per robot per iteration T [steps].
        epochs: passes over each rollout [-].
        minibatch_size: samples per gradient step [samples]; N T must be a multiple of it.
        learning_rate: Adam's initial step size [-], annealed linearly to 0.
        gamma: discount per step [-].
        gae_lambda: GAE lambda [-].
        clip_coef: PPO ratio clip eps [-].
        ent_coef: entropy bonus [-].
        vf_coef: value-loss weight [-].
        max_grad_norm: gradient-norm clip [-].
        hidden: hidden layer widths of both networks (tanh) [units].
        log_std_init: initial log standard deviation of the policy [log normalised action units].
        norm_reward: scale rewards by the running std of the discounted return.
        history: previous steps of commands and measurements in the features [steps].
        residual_bound: bound of the learned correction to the analytic action [normalised action units]; 0: none.
        residual_penalty: weight of the L2 penalty on the residual's mean correction [-]; needs residual_bound > 0.
        residual_gain: feedback gain k [1/s] of the residual's base, at most 1/dt (the analytic policy's 1).
        residual_base: the residual's base: analytic (AnalyticTrackingPolicy) or compensator (DelayCompensatedPolicy).
        residual_gate: the correction only where the compensator's quiet flag is on (residual_base compensator).
        nominal_fraction: share of the N robots simulated as the nominal robot [-].
        filter_alpha: low-pass factor of the action parameterisation [-]; 1: none.
        caps_temporal: CAPS temporal smoothness weight [-].
        caps_spatial: CAPS spatial smoothness weight [-].
        caps_sigma: CAPS spatial perturbation std [normalised feature units].
        seed: seed of the networks, the sampling and the training envs [-].
        eval_every: env-steps between evaluations [steps].
        eval_envs: evaluation episodes (validation seeds eval_seed + i) [episodes].
        eval_seed: first validation seed [-].
        checkpoint_every: env-steps between checkpoints [steps].
        threads: torch threads [threads].
        env_threads: threads of the vector env's step [threads], at most NUMBA_NUM_THREADS (same results).
        device: where the networks and updates run: auto (cuda if torch sees one), cpu or cuda.
        overlap: step the robots as two vector envs of N/2 in turn, one's env step on a second thread while this one
            computes the other's policy (N even; other numbers than without it).
        max_episode_steps: episode time limit [steps].
        curriculum_max_curvature: final bound of the random paths' curvature [1/m]; 0: no curriculum.
        curriculum_max_curvature_rate: final bound of its rate [1/m^2]; 0: the start's ratio kept.
        curriculum_fraction: share of total_steps over which the bounds rise linearly [-].
        curriculum_stages: number of raises [-].
    """

    env_kwargs: Mapping[str, Any] = field(
        default_factory=lambda: dict(TRAINING_DISTRIBUTION["env_kwargs"]), metadata=cli(parse=json_object)
    )
    total_steps: int = 15_000_000
    num_envs: int = 512
    rollout_steps: int = 32
    epochs: int = 4
    minibatch_size: int = 4096
    learning_rate: float = 3e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_coef: float = 0.2
    ent_coef: float = 0.0
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5
    hidden: tuple[int, ...] = (64, 64)
    log_std_init: float = -1.0
    norm_reward: bool = True
    history: int = 0
    residual_bound: float = 0.0
    residual_penalty: float = 0.0
    residual_gain: float = 1.0
    residual_base: Literal["analytic", "compensator"] = "analytic"
    residual_gate: bool = False
    nominal_fraction: float = 0.0
    filter_alpha: float = 1.0
    caps_temporal: float = 0.0
    caps_spatial: float = 0.0
    caps_sigma: float = 0.2
    seed: int = 0
    eval_every: int = 1_000_000
    eval_envs: int = 32
    eval_seed: int = 1_000_000
    checkpoint_every: int = 2_000_000
    threads: int = 1
    env_threads: int = 1
    device: Literal["auto", "cpu", "cuda"] = "auto"
    overlap: bool = False
    max_episode_steps: int = 600
    curriculum_max_curvature: float = 0.0
    curriculum_max_curvature_rate: float = 0.0
    curriculum_fraction: float = 0.5
    curriculum_stages: int = 8

    def __post_init__(self) -> None:
        o = "FastPPOSettings"
        for f in fields(self):
            v, rng = getattr(self, f.name), _RANGES.get(f.name)
            if f.type == "int" and (isinstance(v, bool) or not isinstance(v, (int, np.integer))):
                raise TypeError(f"{o}.{f.name} must be an integer in {rng}, got {v!r}")
            if f.type == "bool" and not isinstance(v, bool):
                raise TypeError(f"{o}.{f.name} must be True or False, got {v!r}")
            if rng is not None:
                lo, hi = (float(x) for x in rng[1:-1].split(","))
                check_real(o, f.name, v, lo, hi, low_open=rng[0] == "(", high_open=rng[-1] == ")")
        batch = self.num_envs * self.rollout_steps
        if self.minibatch_size > batch or batch % self.minibatch_size:
            raise ValueError(
                f"{o}.minibatch_size must divide num_envs * rollout_steps = {batch}, got {self.minibatch_size}"
            )
        if self.residual_penalty > 0 and not self.residual_bound > 0:
            raise ValueError(
                f"{o}.residual_penalty = {self.residual_penalty} needs residual_bound > 0 (a residual policy), "
                f"got residual_bound = {self.residual_bound}"
            )
        if self.overlap and self.num_envs % 2:
            raise ValueError(f"{o}.overlap needs an even num_envs (two halves), got {self.num_envs}")
        if self.device not in DEVICES:
            raise ValueError(f"{o}.device must be one of {', '.join(DEVICES)}, got {self.device!r}")
        hid = tuple(self.hidden)
        if not hid or any(
            isinstance(h, bool) or not isinstance(h, (int, np.integer)) or not 1 <= h <= 4096 for h in hid
        ):
            raise ValueError(f"{o}.hidden must be 1 or more integers in [1, 4096], got {self.hidden!r}")
        object.__setattr__(self, "hidden", tuple(int(h) for h in hid))
        if not isinstance(self.env_kwargs, Mapping):
            raise TypeError(f"{o}.env_kwargs must be a mapping, got {type(self.env_kwargs).__name__}")
        object.__setattr__(self, "env_kwargs", json.loads(json.dumps(dict(self.env_kwargs))))
        self.spec()  # checks history, residual_bound, filter_alpha and the env keywords
        if self.curriculum_max_curvature > 0:
            _check_curriculum(self)

    def curriculum(self) -> tuple[dict[str, float], dict[str, float]] | None:
        """``(start, final)`` random-path parameters of the curvature curriculum (None without one)."""
        if self.curriculum_max_curvature <= 0:
            return None
        start = {k: r.default for k, r in RANDOM_RANGES.items() if k in _CURVATURE_KEYS}
        start |= {str(k): float(v) for k, v in dict(self.env_kwargs.get("path_params") or {}).items()}
        k_end = float(self.curriculum_max_curvature)
        c_end = self.curriculum_max_curvature_rate or start["max_curvature_rate"] * k_end / start["max_curvature"]
        return start, {**start, "max_curvature": k_end, "max_curvature_rate": float(c_end)}

    def spec(self) -> FeatureSpec:
        return FeatureSpec(self.env_kwargs, self.history, self.residual_bound, self.filter_alpha, self.residual_gain,
                           self.residual_base, self.residual_gate)  # fmt: skip

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "hidden": list(self.hidden), "env_kwargs": dict(self.env_kwargs)}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> FastPPOSettings:
        if bad := sorted(set(d) - {f.name for f in fields(cls)}):
            raise ValueError(f"FastPPOSettings: unknown field(s) {bad}")
        return cls(**d)  # __post_init__ makes hidden a tuple


def _check_curriculum(s: FastPPOSettings) -> None:
    """Refuse a curriculum the env cannot run: a fixed path, a final curvature not above the start, infeasible."""
    o = "FastPPOSettings"
    path = s.env_kwargs.get("path", tracking.TrackingParams.path)
    if path not in ("random", "mixed"):
        raise ValueError(
            f"{o}.curriculum_max_curvature needs env_kwargs path 'random' or 'mixed' (drawn paths), got path={path!r}"
        )
    start, final = s.curriculum() or ({}, {})
    if final["max_curvature"] <= start["max_curvature"]:
        raise ValueError(
            f"{o}.curriculum_max_curvature must exceed the start max_curvature {start['max_curvature']:g} 1/m, "
            f"got {s.curriculum_max_curvature!r}"
        )
    kw = {k: v for k, v in s.env_kwargs.items() if k != "path_params"}
    p = tracking.make_tracking_params(o, path_params=final, **kw)
    if (problem := tracking.drawn_feasibility_problem(p)) is not None and p.feasibility != "off":
        raise ValueError(f"{o}.curriculum_max_curvature {s.curriculum_max_curvature:g} 1/m: {problem}")


def curriculum_path_params(s: FastPPOSettings, env_steps: int) -> dict[str, float] | None:
    """The random paths' parameters after ``g = env_steps`` (None without a curriculum): stage ``j = min(S, floor(S g
    / (f T)))`` of ``S = curriculum_stages`` (``f = curriculum_fraction``, ``T = total_steps``), each bound ``b_0 +
    (b_S - b_0) j / S``."""
    if (ends := s.curriculum()) is None:
        return None
    start, final = ends
    n, span = s.curriculum_stages, s.curriculum_fraction * s.total_steps
    j = n if env_steps >= span else min(n, int(n * env_steps // span))
    return {k: start[k] + (final[k] - start[k]) * j / n if k in _CURVATURE_KEYS else v for k, v in start.items()}


#: the key of a fast-PPO hyperparameter file's mapping, and the settings it may not hold (a run's)
YAML_ENV_ID = "AmigoBot-v1"
YAML_RUN_KEYS = ("env_kwargs", "seed")


def load_settings_yaml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The checked :data:`YAML_ENV_ID` mapping of a fast-PPO hyperparameter file; one ``ValueError`` line naming the
    file for a run key, unknown keys (all) or the first bad value."""
    hp = load_hyperparams(path, YAML_ENV_ID)
    names = [f.name for f in fields(FastPPOSettings)]
    if run_keys := sorted(str(k) for k in hp if k in YAML_RUN_KEYS):
        raise ValueError(f"{path}: {', '.join(run_keys)} belong to a run's command line, not a hyperparameter file")
    if unknown := sorted(str(k) for k in hp if k not in names):
        allowed = ", ".join(n for n in names if n not in YAML_RUN_KEYS)
        raise ValueError(f"{path}: unknown key(s) for fastppo: {', '.join(unknown)} (allowed: {allowed})")
    out = {str(k): (list(v) if isinstance(v, (list, tuple)) else v) for k, v in hp.items()}
    try:
        FastPPOSettings.from_json(out)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{path}: {' '.join(str(exc).split())}") from None
    return out


# --------------------------------------------------------------------------- networks
def _mlp(n_in: int, hidden: Sequence[int], n_out: int, out_gain: float) -> nn.Sequential:
    """Tanh MLP, orthogonal weights (gain sqrt 2, ``out_gain`` for the last layer) and zero biases."""
    sizes, mods = [n_in, *hidden, n_out], list[nn.Module]()
    for k, (a, b) in enumerate(itertools.pairwise(sizes)):
        lin = nn.Linear(a, b)
        nn.init.orthogonal_(lin.weight, out_gain if k == len(hidden) else math.sqrt(2.0))
        nn.init.zeros_(lin.bias)
        mods += [lin] if k == len(hidden) else [lin, nn.Tanh()]
    return nn.Sequential(*mods)


class ActorCritic(nn.Module):
    """Separate actor ``mu(x)`` ``(B, 2)`` and critic ``V(x)`` ``(B,)`` MLPs (tanh), state-independent ``log_std``."""

    def __init__(self, dim: int, hidden: Sequence[int], log_std_init: float) -> None:
        super().__init__()
        self.actor = _mlp(dim, hidden, 2, 0.01)
        self.critic = _mlp(dim, hidden, 1, 1.0)
        self.log_std = nn.Parameter(torch.full((2,), float(log_std_init)))

    def value(self, x: torch.Tensor) -> torch.Tensor:
        out: torch.Tensor = self.critic(x).squeeze(-1)
        return out


def _np(t: torch.Tensor) -> Array:
    """A float64 numpy copy of ``t`` (from any device)."""
    out: Array = t.detach().to("cpu", torch.float64).numpy().copy()
    return out


def evaluate_policy(policy: Any, s: FastPPOSettings) -> dict[str, float]:
    """Mean task metrics (NaN-aware) of the first deterministic episodes of ``eval_envs`` robots of ``s.env_kwargs``
    seeded ``eval_seed + i``; ``policy``: anything with SB3's ``predict``."""
    seeds = tuple(range(s.eval_seed, s.eval_seed + s.eval_envs))
    sc = Scenario("eval", "AmigoBot-v1", s.env_kwargs, seeds, s.max_episode_steps)
    rows = [r.metrics() for r in run_scenario(policy, sc)]
    vals = {k: np.array([r[k] for r in rows], dtype=np.float64) for k in rows[0]}
    return {k: float(np.nanmean(v)) if np.isfinite(v).any() else math.nan for k, v in vals.items()}


# --------------------------------------------------------------------------- training state
@dataclass
class _Run:
    """Everything a checkpoint holds besides the settings."""

    net: ActorCritic
    opt: torch.optim.Adam
    env: Any
    obs_rms: RunningMeanStd
    ret_rms: RunningMeanStd
    ret_acc: Array
    obs: Array
    fstate: Array
    starts: NDArray[np.bool_]
    ep_ret: Array
    iteration: int = 0
    global_step: int = 0
    wall_s: float = 0.0
    next_eval: int = 0
    next_ckpt: int = 0
    best_h: float = math.inf
    curve: list[dict[str, float]] = field(default_factory=list)
    episode_returns: list[float] = field(default_factory=list)


#: the :class:`_Run` fields a checkpoint stores under their own names (all but the objects rebuilt on loading)
_RUN_STATE = tuple(f.name for f in fields(_Run))[5:]


@dataclass
class _Buffers:
    """One rollout on the device: features ``x``, values ``v`` ``(T + 1, N, ...)``; the rest ``(T, N, ...)``."""

    x: torch.Tensor
    u: torch.Tensor
    logp: torch.Tensor
    v: torch.Tensor
    r: torch.Tensor
    done: torch.Tensor

    @classmethod
    def allocate(cls, t: int, n: int, dim: int, device: str) -> _Buffers:
        shapes = ((t + 1, n, dim), (t, n, 2), (t, n), (t + 1, n), (t, n), (t, n))
        return cls(*(torch.zeros(shape, device=device) for shape in shapes))


class _ConcatVectorEnv:
    """Vector envs side by side as one; ``step``'s info holds only ``final_obs`` (``None`` where no episode ended)."""

    def __init__(self, envs: Sequence[Any]) -> None:
        self.envs = list(envs)
        self.edges = [0, *itertools.accumulate(int(e.num_envs) for e in self.envs)]
        self.num_envs = self.edges[-1]

    def _split(self, x: Any) -> list[Any]:
        return [x[a:b] for a, b in itertools.pairwise(self.edges)]

    def reset(self, seed: list[int]) -> tuple[Array, dict[str, Any]]:
        return np.concatenate([e.reset(seed=s)[0] for e, s in zip(self.envs, self._split(seed), strict=True)]), {}

    def step(self, action: Array) -> tuple[Array, Array, Array, Array, dict[str, Any]]:
        outs = [e.step(a) for e, a in zip(self.envs, self._split(action), strict=True)]
        final = np.full(self.num_envs, None, dtype=object)
        for (*_, info), k in zip(outs, self.edges, strict=False):
            for i in np.flatnonzero(info.get("_final_obs", ())).tolist():
                final[k + i] = info["final_obs"][i]
        o, r, te, tr = (np.concatenate([out[j] for out in outs]) for j in range(4))
        return o, r, te, tr, {"final_obs": final}

    @property
    def params(self) -> Any:
        return self.envs[0].params

    def set_path_params(self, path_params: Mapping[str, Any]) -> None:
        for e in self.envs:
            e.set_path_params(path_params)

    def close(self) -> None:
        for e in self.envs:
            e.close()


def _training_env(s: FastPPOSettings, n: int = 0) -> Any:
    """The ``n`` (0: ``N``) training robots: one native vector env of ``env_kwargs``, or that and one of nominal
    robots; ``overlap``: two such halves of ``N / 2`` side by side."""
    if s.overlap and not n:
        return _ConcatVectorEnv([_training_env(s, s.num_envs // 2) for _ in range(2)])
    n = n or s.num_envs
    kernel: dict[str, Any] = {"kernel": "numba-parallel"} if s.env_threads > 1 else {}

    def make(n: int, kw: Mapping[str, Any]) -> Any:
        return gym.make_vec("AmigoBot-v1", num_envs=n, max_episode_steps=s.max_episode_steps,
                            autoreset_mode="SameStep", **kernel, **kw)  # fmt: skip

    k = round(s.nominal_fraction * n)
    nominal = {key: v for key, v in s.env_kwargs.items() if key not in ("randomize", "true_robot")}
    if k in (0, n):
        return make(n, nominal if k else s.env_kwargs)
    return _ConcatVectorEnv([make(n - k, s.env_kwargs), make(k, nominal)])


def _networks(s: FastPPOSettings, dim: int, device: str) -> tuple[ActorCritic, torch.optim.Adam]:
    net = ActorCritic(dim, s.hidden, s.log_std_init).to(device)
    fused = device == "cuda" or torch.__version__ >= "2.4"  # one kernel per step; on the CPU from torch 2.4
    return net, torch.optim.Adam(net.parameters(), lr=s.learning_rate, eps=1e-5, fused=fused)


def _new_run(s: FastPPOSettings, builder: FeatureBuilder, device: str) -> _Run:
    torch.manual_seed(s.seed)  # every device's generator
    net, opt = _networks(s, builder.dim, device)
    env = _training_env(s)
    seeds = np.random.SeedSequence(s.seed).generate_state(s.num_envs, dtype=np.uint32)
    obs, _ = env.reset(seed=[int(x) for x in seeds])
    n = s.num_envs
    return _Run(
        net, opt, env, RunningMeanStd.zeros(builder.dim), RunningMeanStd.zeros(1), np.zeros(n),
        np.asarray(obs, dtype=np.float64), builder.initial_state(n), np.ones(n, dtype=bool), np.zeros(n),
        next_ckpt=s.checkpoint_every,
    )  # fmt: skip


def checkpoint(path: Path, s: FastPPOSettings, r: _Run) -> None:
    """Write (atomically) everything needed to continue bit for bit, the vector env pickled."""
    obj = {
        "settings": s.to_json(),
        "net": r.net.state_dict(),
        "opt": r.opt.state_dict(),
        "env": pickle.dumps(r.env),
        "obs_rms": r.obs_rms.to_dict(),
        "ret_rms": r.ret_rms.to_dict(),
        "torch_rng": torch.get_rng_state(),
        "cuda_rng": torch.cuda.get_rng_state_all() if r.net.log_std.is_cuda else None,
        **{k: getattr(r, k) for k in _RUN_STATE},
        "episode_returns": r.episode_returns[-1000:],
    }
    atomic_save(lambda tmp: torch.save(obj, tmp), path)
    vouch(sha256_file(path))


def _load_checkpoint(path: Path, s: FastPPOSettings, builder: FeatureBuilder, device: str) -> _Run:
    require_trust(path)
    ck = torch.load(path, weights_only=False, map_location="cpu")
    if FastPPOSettings.from_json(ck["settings"]).to_json() != s.to_json():
        raise ValueError(f"{path}: the checkpoint's settings differ from these (resume with the same settings)")
    net, opt = _networks(s, builder.dim, device)
    net.load_state_dict(ck["net"])
    opt.load_state_dict(ck["opt"])  # Adam moves its state to the parameters' device
    torch.set_rng_state(ck["torch_rng"])
    if device == "cuda" and ck.get("cuda_rng") is not None:
        torch.cuda.set_rng_state_all(ck["cuda_rng"])
    rms = RunningMeanStd.from_dict
    return _Run(
        net, opt, pickle.loads(ck["env"]), rms(ck["obs_rms"]), rms(ck["ret_rms"]), **{k: ck[k] for k in _RUN_STATE}
    )


def _policy(s: FastPPOSettings, r: _Run, info: Mapping[str, Any] | None = None) -> FastPolicy:
    """The actor as numpy ``[(W (in, out), b)]`` layers with a copy of the normaliser."""
    layers = [(_np(m.weight).T.copy(), _np(m.bias)) for m in r.net.actor if isinstance(m, nn.Linear)]
    obs_rms = RunningMeanStd(r.obs_rms.mean.copy(), r.obs_rms.var.copy(), r.obs_rms.count)
    return FastPolicy(s.spec(), layers, _np(r.net.log_std), obs_rms, info)


def machine_record(device: str) -> dict[str, Any]:
    """Where a run ran: git revision (``"unknown"`` outside a checkout), CPU, thread counts, device."""
    rev = git_revision()
    return {
        "git_revision": rev if rev and " " not in rev else "unknown",
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "numba_threads": None if numba is None else int(numba.get_num_threads()),
        "device": device,
        "device_name": torch.cuda.get_device_name() if device == "cuda" else cpu_model(),
    }


# --------------------------------------------------------------------------- rollout, update
#: False: ``overlap``'s halves stepped inline, in the same order (the tests' reference for the threaded schedule)
_OVERLAP_THREAD = True


def _timed_step(env: Any, a: Array) -> tuple[tuple[Any, ...], float]:
    t0 = time.perf_counter()
    return env.step(a), time.perf_counter() - t0


def rollout(
    s: FastPPOSettings, r: _Run, builder: FeatureBuilder, buf: _Buffers, device: str, pool: Executor | None = None
) -> float:
    """Step the ``N`` robots ``T`` times into ``buf``; the wall seconds spent in the env. ``overlap``: the halves of
    ``r.env`` in turn, each one's env step on ``pool``'s one thread while this one does the other's features, policy
    and storage (so never two env steps at once); ``pool`` None: inline, the same numbers."""
    net, gamma, t_len = r.net, s.gamma, s.rollout_steps
    rew_buf, done_buf = np.zeros((t_len, s.num_envs)), np.zeros((t_len, s.num_envs), dtype=bool)
    x_host = torch.empty(buf.x.shape[1:], pin_memory=buf.x.is_cuda)  # a step's features and outputs on the host
    u_host = torch.empty(buf.u.shape[1:], dtype=torch.float64, pin_memory=buf.x.is_cuda)
    std, log_norm = net.log_std.detach().exp(), net.log_std.detach().sum() + math.log(2.0 * math.pi)
    finals: list[tuple[NDArray[np.intp], ...]] = []  # time-limit cuts: (steps, rows, features)
    envs = r.env.envs if s.overlap else [r.env]
    parts = [slice(a, b) for a, b in itertools.pairwise(r.env.edges)] if s.overlap else [slice(0, s.num_envs)]
    pending: dict[int, Callable[[], tuple[tuple[Any, ...], float]]] = {}  # each part's env step under way
    s_next: dict[int, Array] = {}  # each part's feature state after it
    env_s = 0.0
    for t in range(t_len + 1):  # t = T: the features alone, for the values (the next rollout learns them)
        for p, sl in enumerate(parts):
            if t:  # the part's step t - 1
                (obs, rew, term, trunc, info), dt = pending[p]()
                env_s += dt
                done = np.logical_or(term, trunc, out=done_buf[t - 1, sl])
                ep_ret, ret_acc = r.ep_ret[sl], r.ret_acc[sl]
                ep_ret += rew
                if done.any():
                    r.episode_returns.extend(ep_ret[done].tolist())
                    ep_ret[done] = 0.0
                rew_t = rew_buf[t - 1, sl]
                rew_t[:] = rew
                if s.norm_reward:
                    ret_acc *= gamma
                    ret_acc += rew
                    r.ret_rms.update(ret_acc)
                    np.clip(rew_t / np.sqrt(r.ret_rms.var[0] + 1e-8), -10.0, 10.0, out=rew_t)
                    ret_acc[done] = 0.0
                cut = np.flatnonzero(np.logical_and(trunc, np.logical_not(term)))
                if cut.size:  # the time limit: bootstrapped below with V of the final observation
                    final = np.stack([np.asarray(info["final_obs"][i], dtype=np.float64) for i in cut])
                    f_fin, _, _ = builder(final, s_next[p][cut], np.zeros(cut.size, dtype=bool))
                    finals.append((np.full(cut.size, t - 1), sl.start + cut,
                                   r.obs_rms.normalize(f_fin).astype(np.float32)))  # fmt: skip
                r.obs[sl], r.fstate[sl], r.starts[sl] = obs, s_next[p], done
            feats, base, nxt = builder(r.obs[sl], r.fstate[sl], r.starts[sl])
            if t < t_len:
                r.obs_rms.update(feats)
            host = x_host if buf.x.is_cuda else buf.x[t]  # on the CPU: x[t] itself
            r.obs_rms.normalize(feats, out=host[sl].numpy())
            buf.x[t, sl].copy_(host[sl])  # the step's one host-to-device copy
            if t == t_len:
                continue
            with torch.inference_mode():
                mu = net.actor(buf.x[t, sl])
                eps = torch.randn_like(mu)  # u = mu + std eps; its log density: -|eps|^2 / 2 - sum log std - log 2 pi
                torch.add(mu, std * eps, out=buf.u[t, sl])
                torch.sub(-0.5 * eps.pow(2).sum(-1), log_norm, out=buf.logp[t, sl])
                u_host[sl].copy_(buf.u[t, sl])  # the step's one device-to-host copy
            prev, mask = builder.previous_command(r.obs[sl]), builder.correcting(feats)
            a = env_action(u_host[sl].numpy(), base, prev, s.residual_bound, s.filter_alpha, mask)
            step = functools.partial(_timed_step, envs[p], a)  # inline (no pool): stepped when collected
            pending[p] = step if pool is None else pool.submit(step).result
            s_next[p] = nxt
    if finals:  # one forward pass for every truncated row of the rollout
        steps, rows, feats = (np.concatenate(z) for z in zip(*finals, strict=True))
        with torch.inference_mode():
            rew_buf[steps, rows] += gamma * _np(net.value(torch.from_numpy(feats).to(device)))
    with torch.inference_mode():  # the values of all T + 1 steps' features in one pass
        buf.v.copy_(net.value(buf.x))
    buf.r.copy_(torch.from_numpy(rew_buf))
    buf.done.copy_(torch.from_numpy(done_buf))
    r.global_step += s.num_envs * t_len
    return env_s


def gae(s: FastPPOSettings, buf: _Buffers) -> tuple[torch.Tensor, torch.Tensor]:
    """Advantages and returns ``(T, N)`` (GAE; an episode end cuts the recursion)."""
    adv, last = torch.zeros_like(buf.r), torch.zeros_like(buf.r[0])
    for t in reversed(range(s.rollout_steps)):
        nonterm = 1.0 - buf.done[t]
        delta = buf.r[t] + s.gamma * buf.v[t + 1] * nonterm - buf.v[t]
        last = delta + s.gamma * s.gae_lambda * nonterm * last
        adv[t] = last
    return adv, adv + buf.v[:-1]


def update(s: FastPPOSettings, r: _Run, buf: _Buffers) -> None:
    """``epochs`` passes of minibatch PPO over the rollout, on the buffers' device; the loss's gradient in closed form.

    Minibatch of ``B``: ``A`` advantages normalised to mean 0, std 1; ``z = (u - mu) / std``; ``r = pi(u) / pi_old(u)``;
    ``L = mean max(-A r, -A clip(r, 1 +- eps)) + vf_coef mean (V - R)^2 / 2 - ent_coef H + caps_temporal sum w ||mu(x')
    - mu||^2 + residual_penalty mean ||mu||^2 + caps_spatial mean ||mu(x + caps_sigma n) - mu||^2`` (``w``: 1 where the
    episode goes on to ``x'``, over their count). ``dL/dlog pi = -A r / B`` where the unclipped term is the larger, else
    0; ``dlog pi/dmu = z / std``; ``dlog pi/dlog std = z^2 - 1``; ``dH/dlog std = 1``; autograd backpropagates
    ``dL/dmu`` and ``dL/dV``. One actor pass gives ``mu(x)`` and ``mu(x')`` (features row ``i + N`` follows row ``i``).
    """
    net, t_len, n, mb = r.net, s.rollout_steps, s.num_envs, s.minibatch_size
    batch, d = n * t_len, buf.x.shape[-1]
    adv, ret = gae(s, buf)
    # per sample: action (2), old log-probability, advantage, return, 1 if the episode goes on
    cols = torch.stack((buf.u[..., 0], buf.u[..., 1], buf.logp, adv, ret, 1.0 - buf.done), -1).reshape(batch, 6)
    shift = torch.tensor([0, n] if s.caps_temporal > 0 else [0], device=buf.x.device).view(1, -1, 1)
    for _ in range(s.epochs):  # each gathers its shuffled samples once
        perm = torch.randperm(batch, device=buf.x.device).view(-1, 1, mb)
        xs = buf.x.reshape(-1, d).index_select(0, (perm + shift).flatten()).view(batch // mb, -1, d)  # j: x, then x'
        c = cols.index_select(0, perm.flatten()).view(batch // mb, mb, 6)
        neg_a = (c[..., 3].mean(1, keepdim=True) - c[..., 3]) / (c[..., 3].std(1, keepdim=True) + 1e-8)
        w = c[..., 5:] * (2.0 * s.caps_temporal) / c[..., 5:].sum(1, keepdim=True).clamp(min=1.0)
        for j in range(batch // mb):
            outs = [net.actor(xs[j]), net.value(xs[j, :mb])]
            if s.caps_spatial > 0:
                outs.append(net.actor(xs[j, :mb] + s.caps_sigma * torch.randn_like(xs[j, :mb])))
            with torch.no_grad():
                mu, inv_std = outs[0][:mb], (-net.log_std).exp()
                z = (c[j, :, :2] - mu) * inv_std
                ratio = (-0.5 * z.pow(2).sum(-1) - (net.log_std.sum() + math.log(2.0 * math.pi)) - c[j, :, 2]).exp()
                nar = neg_a[j] * ratio
                g = torch.where(nar >= neg_a[j] * ratio.clamp(1.0 - s.clip_coef, 1.0 + s.clip_coef), nar / mb, 0.0)
                g_mu = g[:, None] * z * inv_std + (2.0 * s.residual_penalty / mb) * mu
                grads = [g_mu, (outs[1] - c[j, :, 4]) * (s.vf_coef / mb)]
                if s.caps_spatial > 0:
                    grads.append((2.0 * s.caps_spatial / mb) * (outs[2] - mu))
                    grads[0] = g_mu - grads[2]
                if s.caps_temporal > 0:
                    dmu = (outs[0][mb:] - mu) * w[j]
                    grads[0] = torch.cat((grads[0] - dmu, dmu))
            r.opt.zero_grad()
            torch.autograd.backward(outs, grads)
            net.log_std.grad = (g[:, None] * (z * z - 1.0)).sum(0) - s.ent_coef  # g, z: no graph
            nn.utils.clip_grad_norm_(net.parameters(), s.max_grad_norm)
            r.opt.step()


# --------------------------------------------------------------------------- the run
def _check_start(out: Path, resume: bool) -> None:
    ckpt = out / "checkpoint.pt"
    if ckpt.exists() and not resume:
        raise FileExistsError(f"{ckpt} exists: pass --resume to continue it or choose another --out")
    if resume and not ckpt.exists():
        raise FileNotFoundError(f"--resume: no checkpoint {ckpt}")


def train(
    s: FastPPOSettings,
    out: str | Path,
    *,
    resume: bool = False,
    until_steps: int | None = None,
    log: Callable[[str], None] | None = print,
    command: str | None = None,
    evaluate_runs: bool = True,
    after_eval: Callable[[dict[str, float]], bool] | None = None,
) -> dict[str, Any]:
    """Train (or ``resume`` with the same settings) a run in ``out``, locked; the record (``run.json``).

    ``until_steps``: stop after a checkpoint at this many env-steps; ``log``: progress lines (``None``: quiet);
    ``command``: recorded; ``evaluate_runs`` False: no evaluations; ``after_eval(row)`` False: stop at once (no
    checkpoint, no ``model.zip``, ``stopped_by`` ``after_eval``). Raises ``FileExistsError`` (a checkpoint without
    ``resume``), ``FileNotFoundError``, ``ValueError``, ``RunLockedError``, ``KeyboardInterrupt`` (a signal).
    """
    out, say = Path(out), log or (lambda _msg: None)
    with _run_folder(s, out, resume) as (device, stop_request):
        if numba is not None:  # first: starting numba's threads resets torch's count
            set_threads(s.env_threads)
        torch.set_num_threads(s.threads)
        where = machine_record(device)  # at the start: the revision whose code this call runs
        builder = FeatureBuilder(s.spec())
        r = _load_checkpoint(out / "checkpoint.pt", s, builder, device) if resume else _new_run(s, builder, device)
        if not resume:
            atomic_write_json(out / "settings.json", s.to_json())
        batch = s.num_envs * s.rollout_steps
        n_iter = -(-s.total_steps // batch)
        if n_iter * batch != s.total_steps and not resume:
            say(f"total_steps {s.total_steps:,d} rounded up to {n_iter * batch:,d}: whole rollouts of num_envs x "
                f"rollout_steps = {batch:,d} env-steps")  # fmt: skip
        stop = s.total_steps if until_steps is None else min(s.total_steps, until_steps)
        t_start, wall0 = time.perf_counter(), r.wall_s

        def evaluate() -> bool:
            """Evaluate, record and say; advance ``next_eval``; ``after_eval``'s verdict."""
            t0 = time.perf_counter()
            pol = _policy(s, r)
            m = evaluate_policy(pol, s)
            wall = wall0 + time.perf_counter() - t_start
            train_wall = max(wall - sum(c.get("eval_s", 0.0) for c in r.curve), 1e-9)
            row = {
                "env_steps": float(r.global_step),
                "wall_s": round(wall, 2),
                "train_sps": round(r.global_step / train_wall, 1),
            }
            if s.curriculum_max_curvature > 0:
                row["curriculum_max_curvature"] = float(dict(r.env.params.path_params).get("max_curvature", 1.0))
            row |= {f"eval_{k}": v for k, v in m.items()}
            row["eval_s"] = round(time.perf_counter() - t0, 2)
            r.curve.append(row)
            atomic_write_json(out / "curve.json", r.curve)
            text = io.StringIO()
            w = csv.DictWriter(text, fieldnames=list(r.curve[0]))
            w.writeheader()
            w.writerows(r.curve)
            atomic_write(out / "curve.csv", text.getvalue())
            if m["h_rms_m"] < r.best_h:
                r.best_h = m["h_rms_m"]
                pol.info.update({"env_steps": r.global_step, "selected_by": "lowest eval_h_rms_m (validation seeds)"})
                pol.save(out / "best.zip")
            say(
                f"[eval] {r.global_step:>11,d} steps {wall:7.0f} s  H rms {1e3 * m['h_rms_m']:.2f} mm  settled "
                f"{1e3 * m['h_rms_settled_m']:.2f} mm  chatter(settled) {m['chatter_settled_rms']:.2f} rad/s  speed err"
                f"(settled) {1e3 * m.get('speed_err_settled_rms', math.nan):.1f} mm/s  fail {m['failure']:.2f}"
            )
            while r.next_eval <= r.global_step:
                r.next_eval += s.eval_every
            return True if after_eval is None else bool(after_eval(dict(row)))

        stopped_by = "after_eval" if evaluate_runs and r.global_step >= r.next_eval and not evaluate() else None
        env_s, spent = 0.0, np.zeros(4)  # this call's seconds: CPU of rollouts, updates; wall of rollouts, updates
        buf = _Buffers.allocate(s.rollout_steps, s.num_envs, builder.dim, device)

        sync: Callable[[], None] = torch.cuda.synchronize if device == "cuda" else lambda: None
        threads = functools.partial(set_threads, s.env_threads) if numba else None  # numba's count is per thread
        pool = ThreadPoolExecutor(1, initializer=threads) if s.overlap and _OVERLAP_THREAD else None
        while r.global_step < stop and stopped_by is None:
            stage = curriculum_path_params(s, r.global_step)
            if stage is not None and dict(r.env.params.path_params) != stage:
                r.env.set_path_params(stage)
                say(f"[curriculum] {r.global_step:>11,d} steps: random paths {stage}")
            r.iteration += 1
            for g in r.opt.param_groups:
                g["lr"] = (1.0 - (r.iteration - 1.0) / n_iter) * s.learning_rate
            c0, w0 = time.process_time(), time.perf_counter()
            env_s += rollout(s, r, builder, buf, device, pool)
            sync()
            c1, w1 = time.process_time(), time.perf_counter()
            update(s, r, buf)
            sync()
            c2, w2 = time.process_time(), time.perf_counter()
            spent += (c1 - c0, c2 - c1, w1 - w0, w2 - w1)
            r.wall_s = wall = wall0 + time.perf_counter() - t_start
            if r.iteration % 20 == 0 or r.global_step >= stop:
                recent = r.episode_returns[-200:]
                ret = f"episode return {np.mean(recent):7.1f}" if recent else "no episode finished yet"
                say(f"{r.global_step:>11,d} / {n_iter * batch:,d} steps  {wall:7.0f} s  "
                    f"{r.global_step / max(wall, 1e-9):8.0f} steps/s  {ret}  "
                    f"std {float(r.net.log_std.detach().exp().mean()):.3f}")  # fmt: skip
            if evaluate_runs and (r.global_step >= r.next_eval or r.global_step >= s.total_steps) and not evaluate():
                stopped_by = "after_eval"
                break
            if stop_request.requested and r.global_step < stop:
                stopped_by = "signal"
            if r.global_step >= r.next_ckpt or r.global_step >= stop or stopped_by == "signal":
                r.wall_s = wall0 + time.perf_counter() - t_start
                checkpoint(out / "checkpoint.pt", s, r)
                while r.next_ckpt <= r.global_step:
                    r.next_ckpt += s.checkpoint_every
        r.wall_s = wall0 + time.perf_counter() - t_start
        r.env.close()
        if pool is not None:
            pool.shutdown()
        cpu_s = dict(zip(("rollout", "update", "loop_wall"), (*spent[:2], spent[2:].sum()), strict=True))
        wall_s = dict(zip(("env", "rollout", "update", "loop"), (env_s, *spent[2:], spent[2:].sum()), strict=True))
        record: dict[str, Any] = {
            "algo": "fastppo_residual" if s.residual_bound > 0 else "fastppo",
            "seed": s.seed,
            "timesteps": r.global_step,
            "finished": r.global_step >= s.total_steps and stopped_by is None,
            "stopped_by": stopped_by,
            "n_envs": s.num_envs,
            "wall_time_s": round(r.wall_s, 1),
            "train_sps": round(r.global_step / max(r.wall_s, 1e-9), 1),
            "last_eval": r.curve[-1] if r.curve else None,
            "settings": s.to_json(),
            "command": command,
            "versions": versions(("gymnasium", "torch")),
            **where,
            "cpu_s_this_call": {k: round(float(v), 2) for k, v in cpu_s.items()},
            "wall_s_this_call": {k: round(float(v), 6) for k, v in wall_s.items()},
        }
        if record["finished"]:
            _policy(s, r, {"env_steps": r.global_step, "seed": s.seed}).save(out / "model.zip")
            record["sha256"] = sha256_file(out / "model.zip")
            atomic_write_json(out / "run.json", record)
    if stop_request.requested and stopped_by == "signal":
        raise KeyboardInterrupt
    return record


@contextlib.contextmanager
def _run_folder(s: FastPPOSettings, out: Path, resume: bool) -> Iterator[tuple[str, StopRequest]]:
    """The checks of a run's start, then ``out`` locked and the signals handled: the device and the stop request."""
    _check_start(out, resume)
    stop = StopRequest(f"{PROG}: stopping at the end of this iteration (checkpoint first)")
    with handling(stop):
        device = resolve_device(s.device)
        if s.env_threads > (limit := _numba_threads_limit()):
            raise ValueError(f"FastPPOSettings.env_threads must be in [1, {limit}] on this machine (numba's "
                             f"NUMBA_NUM_THREADS), got {s.env_threads}")  # fmt: skip
        out.mkdir(parents=True, exist_ok=True)
        with RunLock(out):
            _check_start(out, resume)  # again, under the lock
            yield device, stop


# --------------------------------------------------------------------------- CLI
@dataclass(frozen=True)
class HyperparamsFile:
    """The option read first (its file's values become the other options' defaults).

    Attributes:
        hyperparams: settings file [YAML]: its AmigoBot-v1 mapping replaces the defaults; options override it
            (default: none).
    """

    hyperparams: str | None = None


@dataclass(frozen=True)
class TrainFastRun(HyperparamsFile):
    """The run's options besides the :class:`FastPPOSettings`.

    Attributes:
        out: run folder [folder] (required).
        resume: continue the run in --out from its checkpoint.
        quiet: no progress lines.
    """

    out: str = field(kw_only=True)
    resume: bool = False
    quiet: bool = False


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym train-fast``."""
    args_in = list(sys.argv[1:] if argv is None else argv)
    first = argparse.ArgumentParser(add_help=False)
    add_dataclass_options(first, HyperparamsFile)
    defaults: dict[str, Any] = {}
    hp_file = first.parse_known_args(args_in)[0].hyperparams
    if hp_file is not None and (rc := run_guarded(lambda: defaults.update(load_settings_yaml(hp_file)), PROG)):
        return rc
    p = OneLineParser(prog=PROG, description=__doc__.splitlines()[0] if __doc__ else "")
    for cls in (TrainFastRun, FastPPOSettings):
        add_dataclass_options(p, cls)
    p.set_defaults(**defaults)
    args = p.parse_args(args_in)
    run_opts = settings_from_args(TrainFastRun, args)

    def run() -> None:
        s = settings_from_args(FastPPOSettings, args)
        cmd = f"{PROG} " + " ".join(shlex.quote(a) for a in args_in)
        log = None if run_opts.quiet else functools.partial(print, flush=True)
        rec = train(s, run_opts.out, resume=run_opts.resume, log=log, command=cmd)
        print(json.dumps({k: rec[k] for k in ("timesteps", "wall_time_s", "train_sps", "last_eval")}, default=str))

    return run_guarded(run, PROG)
