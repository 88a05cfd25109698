r"""Fast PPO over the native ``AmigoBot-v1`` vector env (CleanRL/PufferLib style, one module).

    amigo-gym train-fast --out runs/fast_s0                              # the training distribution, 15M steps
    amigo-gym train-fast --out runs/fast_s0 --resume                     # continue after an interruption
    amigo-gym train-fast --out runs/fast_s1 --hyperparams agents/hyperparams/fastppo.yml --seed 1
    amigo-gym train-fast --out runs/res_s0 --residual-bound 0.3 --history 4 \
        --env-kwargs '{"path": "mixed", "speed": [0.1, 0.4], "randomize": {"delay": [0, 0.3]}}'
    amigo-gym train-fast --out runs/res2_s0 --residual-bound 0.15 --residual-penalty 3 --nominal-fraction 0.3 \
        --history 4 --env-kwargs '{"path": "mixed", "sigma_track": 0.005, "randomize": {"delay": [0, 0.3]}}'

Why. SB3's PPO steps a handful of envs and runs small minibatches: on two cores it trains at ~600 env-steps/s
on this task. Here one ``gym.make_vec("AmigoBot-v1", num_envs=N)`` (:class:`amigo_gym.envs.AmigoBotV1VectorEnv`,
the compiled batch step) steps all ``N`` robots at once, the policy runs on the ``(N, d)`` batch, and the update
uses minibatches of thousands of samples: no Python loop over the sub-environments anywhere.

Algorithm (per iteration of ``T = rollout_steps`` steps of ``N = num_envs`` robots)
----------------------------------------------------------------------------------
* Features ``x`` of the raw observations (:class:`amigo_gym.policies.learned.FeatureBuilder`: observation, optional
  history, optional analytic base action), normalised by a running mean/std updated with every batch
  (:class:`~amigo_gym.policies.learned.RunningMeanStd`; saved with the model).
* Gaussian policy ``u ~ N(mu(x), diag(exp(2 log_std)))`` with a state-independent ``log_std``; the environment
  gets :func:`amigo_gym.policies.learned.env_action` of ``u`` (clip; residual; low-pass).
* Reward normalisation (as SB3's ``VecNormalize``/CleanRL): ``R <- gamma R + r``, ``r' = clip(r / sqrt(Var[R] +
  1e-8), -10, 10)`` with the running variance of ``R`` (reset at episode ends).
* Time-limit truncation is bootstrapped: ``r'_t += gamma V(x_final)`` for rows truncated (not terminated).
* GAE: ``delta_t = r'_t + gamma V(x_{t+1}) (1 - d_t) - V(x_t)``, ``A_t = delta_t + gamma lambda (1 - d_t) A_{t+1}``.
* ``epochs`` passes over the ``N T`` samples in minibatches of ``minibatch_size``: clipped surrogate
  ``-min(rho A, clip(rho, 1 - eps, 1 + eps) A)`` (advantages normalised per minibatch), ``vf_coef`` times
  ``(V - (A + V_old))^2 / 2``, minus ``ent_coef`` times the entropy; gradient norm clipped at ``max_grad_norm``;
  Adam, learning rate annealed linearly to 0 over the run.
* Smoothness (CAPS, Mysore et al. 2021), on the mean output ``mu``: temporal ``caps_temporal * mean ||mu(x_t) -
  mu(x_{t+1})||^2`` over steps within an episode, spatial ``caps_spatial * mean ||mu(x) - mu(x + sigma n)||^2`` with
  ``n ~ N(0, I)`` in normalised feature units, ``sigma = caps_sigma``.
* Nominal robots (``nominal_fraction = f > 0``): the last ``round(f N)`` of the ``N`` training robots are simulated
  with ``env_kwargs`` without ``randomize`` and ``true_robot`` (the nominal robot: no mismatch, delay, slip or
  noise), the others with ``env_kwargs``; the evaluations stay on ``env_kwargs``.
* Residual penalty (residual policies only): ``residual_penalty * mean ||mu(x)||^2`` over the minibatch, ``mu`` in
  units of the bound (the correction is ``residual_bound * clip(mu, -1, 1)``): pulls the correction to 0 where
  the advantages do not ask for one, so that the policy keeps the analytic action where that is already at its floor.

Outputs in ``--out``: ``settings.json``; ``checkpoint.pt`` (everything needed to continue bit for bit: networks,
optimiser, normalisers, the pickled vector env, the current observations and policy state, torch's RNG; written
atomically every ``checkpoint_every`` env-steps and at the end); ``curve.csv`` / ``curve.json`` (env-steps,
wall-clock, training throughput, evaluation metrics of :mod:`amigo_gym.tools.training.task_metrics` on ``eval_envs``
episodes of the training distribution with the fixed validation seeds ``eval_seed + i``, never the benchmark's
cells); ``model.zip`` (the final policy, :class:`amigo_gym.policies.learned.FastPolicy`, numpy only to run) and
``best.zip`` (the evaluation with the lowest mean H cross-track RMS); ``run.json`` (steps, wall time, versions,
sha256 of ``model.zip``).

Hyperparameter file (``--hyperparams``, :func:`load_settings_yaml`): the ``AmigoBot-v1`` mapping of an rl-zoo style
YAML file whose keys are :class:`FastPPOSettings` fields (``agents/hyperparams/fastppo.yml``, written by
``amigo-gym sweep --algo fastppo --save-best``); the run's own ``env_kwargs`` and ``seed`` are refused there (they
are options of the run). The file's values replace the defaults; options given on the command line override the
file.

Interruption: the first ``SIGTERM`` or ``SIGINT`` (Ctrl-C) stops the run at the end of the current iteration, after a
checkpoint (``KeyboardInterrupt``, status 130; ``--resume`` continues it bit for bit); a second one stops at once
(the last periodic checkpoint stays). Signal handlers are installed only when training runs in the main thread.
The run folder is locked for the whole run (:class:`amigo_gym.tools.runs.RunLock`, ``<out>/run.lock``): a second
``train-fast`` or ``--resume`` on a folder in use stops at once with one line and touches nothing; a killed run
leaves no lock behind (the operating system drops it).

Imports torch (this module is an edge of the package; ``import amigo_gym`` never imports it).
"""

from __future__ import annotations

import argparse
import csv
import functools
import io as _io
import itertools
import json
import math
import os
import pickle
import shlex
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from numpy.typing import NDArray
from torch import nn

from amigo_gym.io import atomic_save, atomic_write, atomic_write_json, require_trust, sha256_file, vouch
from amigo_gym.model.params import check_range
from amigo_gym.policies.learned import FastPolicy, FeatureBuilder, FeatureSpec, RunningMeanStd, env_action
from amigo_gym.tools.options import cli, json_object
from amigo_gym.tools.runs import RunLock, StopRequest, handling
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
from amigo_gym.tools.training.task_metrics import episode_metrics
from amigo_gym.tools.training.train import versions

__all__ = [
    "YAML_ENV_ID",
    "YAML_RUN_KEYS",
    "FastPPOSettings",
    "HyperparamsFile",
    "TrainFastRun",
    "ActorCritic",
    "curriculum_path_params",
    "evaluate_policy",
    "load_settings_yaml",
    "main",
    "train",
]

Array = NDArray[np.float64]
PROG = "amigo-gym train-fast"


def _default_env_kwargs() -> dict[str, Any]:
    return dict(TRAINING_DISTRIBUTION["env_kwargs"])


@dataclass(frozen=True)
class FastPPOSettings:
    """Settings of a fast-PPO run (module docstring); every field is checked on construction.

    Attributes:
        env_kwargs: keywords of gym.make_vec("AmigoBot-v1", ...) [JSON mapping]; default: the training distribution.
        total_steps: env-steps of training [steps], in [1, 1e10].
        num_envs: robots stepped together N, in [1, 65536].
        rollout_steps: steps per robot per iteration T, in [1, 10000].
        epochs: passes over each rollout, in [1, 100].
        minibatch_size: samples per gradient step, in [1, N T]; N T must be a multiple of it.
        learning_rate: Adam's initial step size [-], in (0, 1]; annealed linearly to 0.
        gamma: discount per step [-], in [0, 1).
        gae_lambda: GAE lambda [-], in [0, 1].
        clip_coef: PPO ratio clip eps [-], in (0, 1].
        ent_coef: entropy bonus [-], in [0, 1].
        vf_coef: value-loss weight [-], in [0, 10].
        max_grad_norm: gradient-norm clip [-], in (0, 100].
        hidden: hidden layer widths of both networks (tanh) [units], each in [1, 4096].
        log_std_init: initial log standard deviation of the policy [log of normalised action units], in [-5, 1].
        norm_reward: scale rewards by the running std of the discounted return.
        history: previous steps of commands and measurements in the features [steps], in [0, 20].
        residual_bound: bound of the learned correction to the analytic action [normalised action units], in
            [0, 2]; 0: plain policy.
        residual_penalty: weight of the L2 penalty on the residual policy's mean correction [-, per (bound units)^2],
            in [0, 100]; needs residual_bound > 0 when > 0 (module docstring).
        nominal_fraction: share of the N training robots simulated as the nominal robot [-], in [0, 1)
            (module docstring); 0: all robots from env_kwargs.
        filter_alpha: low-pass factor of the action parameterisation [-], in (0, 1]; 1: none.
        caps_temporal: CAPS temporal smoothness weight [-], in [0, 100].
        caps_spatial: CAPS spatial smoothness weight [-], in [0, 100].
        caps_sigma: CAPS spatial perturbation std [normalised feature units], in (0, 10].
        seed: seed of the networks, the sampling and the training envs [-], in [0, 2**31).
        eval_every: env-steps between evaluations [steps], in [1, 1e10].
        eval_envs: evaluation episodes (validation seeds eval_seed + i), in [1, 4096].
        eval_seed: first validation seed [-], in [0, 2**31).
        checkpoint_every: env-steps between checkpoints [steps], in [1, 1e10].
        threads: torch threads, in [1, 64].
        max_episode_steps: episode time limit [steps], in [1, 100000].
        curriculum_max_curvature: final bound of ``|kappa|`` of the random paths [1/m] of a curvature curriculum
            (:func:`curriculum_path_params`), in [0, 100]; 0 (default): no curriculum. Needs ``path`` "random" or
            "mixed" (whose random paths it changes), a value above the start (``env_kwargs``'s ``path_params``, else
            the family's 1 1/m), and the final paths feasible at the highest speed (the env's check).
        curriculum_max_curvature_rate: final bound of ``|dkappa/ds|`` [1/m^2], in [0, 1000]; 0: the start rate
            times ``curriculum_max_curvature`` / the start curvature (the family's ratio kept).
        curriculum_fraction: fraction of ``total_steps`` over which the bounds rise linearly from the start to the
            final values [-], in (0, 1].
        curriculum_stages: number of raises [-], in [1, 1000] (the pool of random paths is rebuilt at each).
    """

    env_kwargs: Mapping[str, Any] = field(default_factory=_default_env_kwargs, metadata=cli(parse=json_object))
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
    max_episode_steps: int = 600
    curriculum_max_curvature: float = 0.0
    curriculum_max_curvature_rate: float = 0.0
    curriculum_fraction: float = 0.5
    curriculum_stages: int = 8

    def __post_init__(self) -> None:
        o = "FastPPOSettings"
        ints = {
            "total_steps": (1, 10**10),
            "num_envs": (1, 65536),
            "rollout_steps": (1, 10000),
            "epochs": (1, 100),
            "minibatch_size": (1, 10**8),
            "history": (0, 20),
            "seed": (0, 2**31 - 1),
            "eval_every": (1, 10**10),
            "eval_envs": (1, 4096),
            "eval_seed": (0, 2**31 - 1),
            "checkpoint_every": (1, 10**10),
            "threads": (1, 64),
            "max_episode_steps": (1, 100000),
            "curriculum_stages": (1, 1000),
        }
        for name, (lo, hi) in ints.items():
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)):
                raise TypeError(f"{o}.{name} must be an integer in [{lo}, {hi}], got {v!r}")
            check_range(o, name, v, lo, hi)
        batch = self.num_envs * self.rollout_steps
        if self.minibatch_size > batch or batch % self.minibatch_size:
            raise ValueError(
                f"{o}.minibatch_size must divide num_envs * rollout_steps = {batch}, got {self.minibatch_size}"
            )
        check_range(o, "learning_rate", self.learning_rate, 0.0, 1.0, low_open=True)
        check_range(o, "gamma", self.gamma, 0.0, 1.0, high_open=True)
        check_range(o, "gae_lambda", self.gae_lambda, 0.0, 1.0)
        check_range(o, "clip_coef", self.clip_coef, 0.0, 1.0, low_open=True)
        check_range(o, "ent_coef", self.ent_coef, 0.0, 1.0)
        check_range(o, "vf_coef", self.vf_coef, 0.0, 10.0)
        check_range(o, "max_grad_norm", self.max_grad_norm, 0.0, 100.0, low_open=True)
        check_range(o, "log_std_init", self.log_std_init, -5.0, 1.0)
        check_range(o, "caps_temporal", self.caps_temporal, 0.0, 100.0)
        check_range(o, "caps_spatial", self.caps_spatial, 0.0, 100.0)
        check_range(o, "caps_sigma", self.caps_sigma, 0.0, 10.0, low_open=True)
        check_range(o, "residual_penalty", self.residual_penalty, 0.0, 100.0)
        check_range(o, "nominal_fraction", self.nominal_fraction, 0.0, 1.0, high_open=True)
        if self.residual_penalty > 0 and not self.residual_bound > 0:
            raise ValueError(
                f"{o}.residual_penalty = {self.residual_penalty} needs residual_bound > 0 (a residual policy), "
                f"got residual_bound = {self.residual_bound}"
            )
        if not isinstance(self.norm_reward, bool):
            raise TypeError(f"{o}.norm_reward must be True or False, got {self.norm_reward!r}")
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
        check_range(o, "curriculum_max_curvature", self.curriculum_max_curvature, 0.0, 100.0)
        check_range(o, "curriculum_max_curvature_rate", self.curriculum_max_curvature_rate, 0.0, 1000.0)
        check_range(o, "curriculum_fraction", self.curriculum_fraction, 0.0, 1.0, low_open=True)
        if self.curriculum_max_curvature > 0:
            _check_curriculum(self)

    def curriculum(self) -> tuple[dict[str, float], dict[str, float]] | None:
        """``(start, final)`` random-path parameters of the curvature curriculum (``max_curvature`` [1/m],
        ``max_curvature_rate`` [1/m^2] and the ``env_kwargs``' other ``path_params``), or None without one."""
        if self.curriculum_max_curvature <= 0:
            return None
        from amigo_gym.paths.families import RANDOM_RANGES

        given = {str(k): float(v) for k, v in dict(self.env_kwargs.get("path_params") or {}).items()}
        start = {k: r.default for k, r in RANDOM_RANGES.items() if k in ("max_curvature", "max_curvature_rate")}
        start |= given
        k_end = float(self.curriculum_max_curvature)
        c_end = (
            float(self.curriculum_max_curvature_rate) or start["max_curvature_rate"] * k_end / start["max_curvature"]
        )
        return start, {**start, "max_curvature": k_end, "max_curvature_rate": c_end}

    def spec(self) -> FeatureSpec:
        """The policy's :class:`~amigo_gym.policies.learned.FeatureSpec`."""
        return FeatureSpec(self.env_kwargs, self.history, self.residual_bound, self.filter_alpha)

    def to_json(self) -> dict[str, Any]:
        return {**asdict(self), "hidden": list(self.hidden), "env_kwargs": dict(self.env_kwargs)}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> FastPPOSettings:
        names = {f.name for f in fields(cls)}
        bad = sorted(set(d) - names)
        if bad:
            raise ValueError(f"FastPPOSettings: unknown field(s) {bad}")
        kw: dict[str, Any] = {k: (tuple(v) if k == "hidden" else v) for k, v in d.items()}
        return cls(**kw)


def _check_curriculum(s: FastPPOSettings) -> None:
    """One-line errors for a curriculum the env cannot run: a fixed path, a final curvature not above the start, a
    final stage the env's feasibility check refuses (at the highest reference speed)."""
    from amigo_gym.task import v1 as tracking

    o = "FastPPOSettings"
    path = s.env_kwargs.get("path", tracking.TrackingParams.path)
    if path not in ("random", "mixed"):
        raise ValueError(
            f"{o}.curriculum_max_curvature needs env_kwargs path 'random' or 'mixed' (drawn paths), got path={path!r}"
        )
    ends = s.curriculum()
    assert ends is not None
    start, final = ends
    if final["max_curvature"] <= start["max_curvature"]:
        raise ValueError(
            f"{o}.curriculum_max_curvature must exceed the start max_curvature {start['max_curvature']:g} 1/m, "
            f"got {s.curriculum_max_curvature!r}"
        )
    kw = {k: v for k, v in s.env_kwargs.items() if k != "path_params"}
    p = tracking.make_tracking_params(o, path_params=final, **kw)
    problem = tracking.drawn_feasibility_problem(p)
    if problem is not None and p.feasibility != "off":
        raise ValueError(f"{o}.curriculum_max_curvature {s.curriculum_max_curvature:g} 1/m: {problem}")


def curriculum_path_params(s: FastPPOSettings, env_steps: int) -> dict[str, float] | None:
    r"""The random paths' parameters of the curvature curriculum after ``env_steps`` env-steps (None without one).

    Stage ``j = min(S, floor(S g / (f T)))`` of ``S = curriculum_stages`` after ``g`` env-steps of ``T =
    total_steps`` (``f = curriculum_fraction``), and each bound ``b_j = b_0 + (b_S - b_0) j / S`` between the
    start ``b_0`` and the final ``b_S`` (:meth:`FastPPOSettings.curriculum`): ``max_curvature`` [1/m] and
    ``max_curvature_rate`` [1/m^2]. ``j`` depends on ``g`` alone: a resumed run raises at the same steps.
    """
    ends = s.curriculum()
    if ends is None:
        return None
    start, final = ends
    n = s.curriculum_stages
    span = s.curriculum_fraction * s.total_steps
    j = n if env_steps >= span else min(n, int(n * env_steps // span))
    return {k: start[k] + (final[k] - start[k]) * j / n if k in ("max_curvature", "max_curvature_rate") else v
            for k, v in start.items()}  # fmt: skip


#: the key of a fast-PPO hyperparameter file's mapping (rl-zoo layout: one mapping per environment id)
YAML_ENV_ID = "AmigoBot-v1"
#: settings a hyperparameter file may not hold: they belong to a run (its command line), not to tuned settings
YAML_RUN_KEYS = ("env_kwargs", "seed")


def check_settings_mapping(hp: Mapping[str, Any], where: str = "hyperparams") -> dict[str, Any]:
    """``hp`` (a hyperparameter file's mapping) checked as :class:`FastPPOSettings` values; a plain copy.

    Raises:
        ValueError / TypeError: one line naming the file, the unknown keys (all of them) or the first bad value.
    """
    names = [f.name for f in fields(FastPPOSettings)]
    run_keys = sorted(str(k) for k in hp if k in YAML_RUN_KEYS)
    if run_keys:
        raise ValueError(f"{where}: {', '.join(run_keys)} belong to a run's command line, not a hyperparameter file")
    unknown = sorted(str(k) for k in hp if k not in names)
    if unknown:
        allowed = ", ".join(n for n in names if n not in YAML_RUN_KEYS)
        raise ValueError(f"{where}: unknown key(s) for fastppo: {', '.join(unknown)} (allowed: {allowed})")
    out = {str(k): (list(v) if isinstance(v, (list, tuple)) else v) for k, v in hp.items()}
    try:
        FastPPOSettings.from_json(out)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {' '.join(str(exc).split())}") from None
    return out


def load_settings_yaml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The checked :data:`YAML_ENV_ID` mapping of a fast-PPO hyperparameter file (module docstring).

    Raises:
        FileNotFoundError: no such file. ValueError: not YAML, no ``AmigoBot-v1`` mapping, or a bad key or value.
    """
    from amigo_gym.tools.training.hyperparams import load_hyperparams

    return check_settings_mapping(load_hyperparams(path, YAML_ENV_ID), str(path))


# --------------------------------------------------------------------------- networks
def _layer(n_in: int, n_out: int, gain: float) -> nn.Linear:
    lin = nn.Linear(n_in, n_out)
    nn.init.orthogonal_(lin.weight, gain)
    nn.init.zeros_(lin.bias)
    return lin


def _mlp(n_in: int, hidden: Sequence[int], n_out: int, out_gain: float) -> nn.Sequential:
    mods: list[nn.Module] = []
    d = n_in
    for h in hidden:
        mods += [_layer(d, h, math.sqrt(2.0)), nn.Tanh()]
        d = h
    mods.append(_layer(d, n_out, out_gain))
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

    def numpy_layers(self) -> list[tuple[Array, Array]]:
        """The actor as ``[(W (in, out), b (out,))]`` for :class:`FastPolicy` (``x W + b``)."""
        lins = [m for m in self.actor if isinstance(m, nn.Linear)]
        return [(m.weight.detach().double().numpy().T.copy(), m.bias.detach().double().numpy().copy()) for m in lins]


def _log_prob(mu: torch.Tensor, log_std: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
    """Diagonal Gaussian log density summed over the 2 action components."""
    z = (u - mu) / log_std.exp()
    return (-0.5 * z * z - log_std - 0.5 * math.log(2.0 * math.pi)).sum(-1)


# --------------------------------------------------------------------------- evaluation
def evaluate_policy(policy: Any, s: FastPPOSettings) -> dict[str, float]:
    """Mean task metrics of ``eval_envs`` deterministic episodes of ``s.env_kwargs`` (validation seeds).

    ``policy``: anything with SB3's ``predict(obs, state, episode_start, deterministic)`` (its state passed through).

    One vector env of ``eval_envs`` robots, ``reset(seed=[eval_seed + i])``, stepped until every robot's first
    episode ended (``NextStep`` autoreset: later steps are ignored); per robot
    :func:`amigo_gym.tools.training.task_metrics.episode_metrics`; the mean over robots (NaN-aware for settled values).
    """
    n = s.eval_envs
    env = gym.make_vec("AmigoBot-v1", num_envs=n, max_episode_steps=s.max_episode_steps, **s.env_kwargs)
    try:
        obs, _ = env.reset(seed=[s.eval_seed + i for i in range(n)])  # type: ignore[arg-type]
        dt = float(env.params.dt)  # type: ignore[attr-defined]
        steps = s.max_episode_steps
        e = np.zeros((steps, n))
        ve = np.zeros((steps, n))
        cmd = np.zeros((steps, n, 2))
        wr = np.zeros((steps, n, 2))
        rew = np.zeros((steps, n))
        length = np.full(n, steps)
        term = np.zeros(n, dtype=bool)
        alive = np.ones(n, dtype=bool)
        state: Any = None  # any SB3-style predict: FastPolicy, AnalyticTrackingPolicy, an SB3 model
        starts = np.ones(n, dtype=bool)
        for k in range(steps):
            act, state = policy.predict(obs, state=state, episode_start=starts)
            starts = np.zeros(n, dtype=bool)
            obs, r, te, tr, info = env.step(act)
            e[k], ve[k], rew[k] = info["cross_track_error"], info["speed_error"], r
            cmd[k], wr[k] = info["command"], info["wheel_rates"]
            ended = alive & (te | tr)
            length[ended] = k + 1
            # reaching the end of an open path ends the episode as a success (as in the benchmark)
            term[ended & te & ~np.asarray(info["end_of_path"], dtype=bool)] = True
            alive &= ~ended
            if not alive.any():
                break
    finally:
        env.close()
    rows = [
        episode_metrics(e[: length[i], i], ve[: length[i], i], cmd[: length[i], i], wr[: length[i], i],
                        rew[: length[i], i], dt=dt, terminated=bool(term[i]))
        for i in range(n)
    ]  # fmt: skip
    out: dict[str, float] = {}
    for key in rows[0]:
        vals = np.array([r[key] for r in rows], dtype=np.float64)
        out[key] = float(np.nanmean(vals)) if np.isfinite(vals).any() else math.nan
    return out


# --------------------------------------------------------------------------- training
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
    iteration: int = 0
    global_step: int = 0
    wall_s: float = 0.0
    next_eval: int = 0
    next_ckpt: int = 0
    best_h: float = math.inf
    curve: list[dict[str, float]] = field(default_factory=list)
    episode_returns: list[float] = field(default_factory=list)
    ep_ret: Array = field(default_factory=lambda: np.zeros(0))


class _ConcatVectorEnv:
    """Vector envs side by side as one of ``sum(n_i)`` robots (the rows of ``envs[0]`` first), for the trainer only.

    ``step``'s info holds only ``final_obs`` (an object array of ``(obs_dim,)`` arrays, ``None`` where no episode
    ended), the one info field the trainer reads.
    """

    def __init__(self, envs: Sequence[Any]) -> None:
        self.envs = list(envs)
        self.sizes = [int(e.num_envs) for e in self.envs]
        self.num_envs = sum(self.sizes)

    def _split(self, x: Sequence[Any] | Array) -> list[Any]:
        edges = [0, *itertools.accumulate(self.sizes)]
        return [x[a:b] for a, b in itertools.pairwise(edges)]

    def reset(self, seed: list[int]) -> tuple[Array, dict[str, Any]]:
        obs = [e.reset(seed=part)[0] for e, part in zip(self.envs, self._split(seed), strict=True)]
        return np.concatenate(obs), {}

    def step(self, action: Array) -> tuple[Array, Array, Array, Array, dict[str, Any]]:
        outs = [e.step(a) for e, a in zip(self.envs, self._split(action), strict=True)]
        final = np.full(self.num_envs, None, dtype=object)
        k = 0
        for (*_, info), n in zip(outs, self.sizes, strict=True):
            if "final_obs" in info:
                mask = np.asarray(info["_final_obs"], dtype=bool)
                for i in np.flatnonzero(mask):
                    final[k + i] = info["final_obs"][i]
            k += n
        cat = [np.concatenate([o[j] for o in outs]) for j in range(4)]
        return cat[0], cat[1], cat[2], cat[3], {"final_obs": final}

    @property
    def params(self) -> Any:
        """The first env's task settings (all envs share ``path_params``: :meth:`set_path_params` sets them all)."""
        return self.envs[0].params

    def set_path_params(self, path_params: Mapping[str, Any]) -> None:
        """The curriculum's stage, for every env (randomised and nominal robots alike)."""
        for e in self.envs:
            e.set_path_params(path_params)

    def close(self) -> None:
        for e in self.envs:
            e.close()


def _training_env(s: FastPPOSettings) -> Any:
    """The training robots: one native vector env of ``env_kwargs``, or that and one of nominal robots."""

    def make(n: int, kw: Mapping[str, Any]) -> Any:
        return gym.make_vec(
            "AmigoBot-v1", num_envs=n, max_episode_steps=s.max_episode_steps, autoreset_mode="SameStep", **kw
        )

    k = round(s.nominal_fraction * s.num_envs)
    if k == 0:
        return make(s.num_envs, s.env_kwargs)
    nominal = {key: v for key, v in s.env_kwargs.items() if key not in ("randomize", "true_robot")}
    if k == s.num_envs:
        return make(k, nominal)
    return _ConcatVectorEnv([make(s.num_envs - k, s.env_kwargs), make(k, nominal)])


def _new_run(s: FastPPOSettings, builder: FeatureBuilder) -> _Run:
    torch.manual_seed(s.seed)
    net = ActorCritic(builder.dim, s.hidden, s.log_std_init)
    opt = torch.optim.Adam(net.parameters(), lr=s.learning_rate, eps=1e-5)
    env = _training_env(s)
    seeds = np.random.SeedSequence(s.seed).generate_state(s.num_envs, dtype=np.uint32)
    obs, _ = env.reset(seed=[int(x) for x in seeds])  # gymnasium accepts a list
    n = s.num_envs
    return _Run(
        net, opt, env, RunningMeanStd.zeros(builder.dim), RunningMeanStd.zeros(1), np.zeros(n),
        np.asarray(obs, dtype=np.float64), builder.initial_state(n), np.ones(n, dtype=bool),
        next_eval=0, next_ckpt=s.checkpoint_every, ep_ret=np.zeros(n),
    )  # fmt: skip


def _save_checkpoint(path: Path, s: FastPPOSettings, r: _Run) -> None:
    obj = {
        "settings": s.to_json(),
        "net": r.net.state_dict(),
        "opt": r.opt.state_dict(),
        "env": pickle.dumps(r.env),
        "obs_rms": r.obs_rms.to_dict(),
        "ret_rms": r.ret_rms.to_dict(),
        "torch_rng": torch.get_rng_state(),
        **{k: getattr(r, k) for k in ("ret_acc", "obs", "fstate", "starts", "ep_ret")},
        **{k: getattr(r, k) for k in ("iteration", "global_step", "wall_s", "next_eval", "next_ckpt", "best_h")},
        "curve": r.curve,
        "episode_returns": r.episode_returns[-1000:],
    }
    atomic_save(lambda tmp: torch.save(obj, tmp), path)
    vouch(sha256_file(path))  # written here: resuming it needs no trust flag (amigo_gym.io.require_trust)


def _load_checkpoint(path: Path, s: FastPPOSettings, builder: FeatureBuilder) -> _Run:
    require_trust(path)  # a pickle (the vector env): shipped, written here, or --trust-unverified
    ck = torch.load(path, weights_only=False)
    # a checkpoint written before a field existed holds its default (FastPPOSettings.from_json fills it in)
    if FastPPOSettings.from_json(ck["settings"]).to_json() != s.to_json():
        raise ValueError(f"{path}: the checkpoint's settings differ from these (resume with the same settings)")
    net = ActorCritic(builder.dim, s.hidden, s.log_std_init)
    net.load_state_dict(ck["net"])
    opt = torch.optim.Adam(net.parameters(), lr=s.learning_rate, eps=1e-5)
    opt.load_state_dict(ck["opt"])
    torch.set_rng_state(ck["torch_rng"])
    r = _Run(
        net, opt, pickle.loads(ck["env"]), RunningMeanStd.from_dict(ck["obs_rms"]),
        RunningMeanStd.from_dict(ck["ret_rms"]), ck["ret_acc"], ck["obs"], ck["fstate"], ck["starts"],
    )  # fmt: skip
    for k in ("iteration", "global_step", "wall_s", "next_eval", "next_ckpt", "best_h", "curve", "episode_returns"):
        setattr(r, k, ck[k])
    r.ep_ret = ck["ep_ret"]
    return r


def _policy(s: FastPPOSettings, r: _Run, info: Mapping[str, Any] | None = None) -> FastPolicy:
    obs_rms = RunningMeanStd(r.obs_rms.mean.copy(), r.obs_rms.var.copy(), r.obs_rms.count)
    log_std = r.net.log_std.detach().double().numpy().copy()
    return FastPolicy(s.spec(), r.net.numpy_layers(), log_std, obs_rms, info)


def _write_curve(out: Path, curve: list[dict[str, float]]) -> None:
    atomic_write_json(out / "curve.json", curve)
    if curve:
        buf = _io.StringIO()
        w = csv.DictWriter(buf, fieldnames=list(curve[0]))
        w.writeheader()
        w.writerows(curve)
        atomic_write(out / "curve.csv", buf.getvalue())


def _check_start(out: Path, resume: bool) -> None:
    """Refuse to overwrite a run (a checkpoint without ``resume``) or to resume nothing."""
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
    """Train (or continue) a fast-PPO run in ``out`` (module docstring); returns the run record (``run.json``).

    Args:
        s: the settings. out: the run folder (created). resume: continue from ``out/checkpoint.pt`` (the settings
            must be the same); without it an existing checkpoint is an error (nothing is overwritten).
        until_steps: stop (after a checkpoint) once this many env-steps are done, as an interruption would;
            ``None``: train to ``total_steps``.
        log: progress lines (``None``: quiet). command: the command line recorded in ``run.json``.
        evaluate_runs: run the evaluations (False: none, no curve, no ``best.zip``; for throughput benchmarks).
        after_eval: called with each evaluation's ``curve.csv`` row (``env_steps``, ``eval_h_rms_m``, ...); ``False``
            stops training at once (no checkpoint, no ``model.zip``: the record says ``finished`` False and
            ``stopped_by`` ``after_eval``); used by ``amigo-gym sweep`` for pruning.

    Raises:
        FileExistsError: a checkpoint exists and ``resume`` is False. FileNotFoundError: ``resume`` without one.
        runs.RunLockedError: another process trains in ``out`` (the folder is locked for the whole call).
        KeyboardInterrupt: stopped by ``SIGTERM``/``SIGINT`` (module docstring), after a checkpoint.
    """
    out = Path(out)
    _check_start(out, resume)
    out.mkdir(parents=True, exist_ok=True)
    stop = StopRequest(f"{PROG}: stopping at the end of this iteration (checkpoint first)")
    with RunLock(out), handling(stop):  # one process per run folder: a second train-fast on it stops with one line
        record = _train(s, out, resume, until_steps, log, command, evaluate_runs, after_eval, stop)
    if stop.requested and record.get("stopped_by") == "signal":
        raise KeyboardInterrupt
    return record


def _train(
    s: FastPPOSettings,
    out: str | Path,
    resume: bool,
    until_steps: int | None,
    log: Callable[[str], None] | None,
    command: str | None,
    evaluate_runs: bool,
    after_eval: Callable[[dict[str, float]], bool] | None,
    stop_request: StopRequest,
) -> dict[str, Any]:
    out = Path(out)
    ckpt = out / "checkpoint.pt"
    _check_start(out, resume)  # again, under the lock: another process may have written a checkpoint meanwhile
    torch.set_num_threads(s.threads)
    builder = FeatureBuilder(s.spec())
    r = _load_checkpoint(ckpt, s, builder) if resume else _new_run(s, builder)
    if not resume:
        atomic_write_json(out / "settings.json", s.to_json())
    n, t_len = s.num_envs, s.rollout_steps
    batch = n * t_len
    n_iter = -(-s.total_steps // batch)
    stop = s.total_steps if until_steps is None else min(s.total_steps, until_steps)
    d = builder.dim
    gamma = s.gamma
    net = r.net
    t_start = time.perf_counter()
    wall0 = r.wall_s

    def say(msg: str) -> None:
        if log is not None:
            log(msg)

    if s.total_steps % batch and not resume:
        say(f"--total-steps {s.total_steps:,} becomes {n_iter * batch:,}: whole rollouts of {n} envs x {t_len} steps")

    def evaluate() -> bool:
        t0 = time.perf_counter()
        pol = _policy(s, r)
        m = evaluate_policy(pol, s)
        wall = wall0 + time.perf_counter() - t_start
        row = {"env_steps": float(r.global_step), "wall_s": round(wall, 2), "train_sps": 0.0}
        train_wall = max(wall - sum(c.get("eval_s", 0.0) for c in r.curve), 1e-9)
        row["train_sps"] = round(r.global_step / train_wall, 1)
        if s.curriculum_max_curvature > 0:  # the random paths' bound being trained on [1/m]
            row["curriculum_max_curvature"] = float(dict(r.env.params.path_params).get("max_curvature", 1.0))
        row |= {f"eval_{k}": v for k, v in m.items()}
        row["eval_s"] = round(time.perf_counter() - t0, 2)
        r.curve.append(row)
        _write_curve(out, r.curve)
        if m["h_rms_m"] < r.best_h:
            r.best_h = m["h_rms_m"]
            pol.info.update({"env_steps": r.global_step, "selected_by": "lowest eval_h_rms_m (validation seeds)"})
            pol.save(out / "best.zip")
        say(
            f"[eval] {r.global_step:>11,d} steps {wall:7.0f} s  H rms {1e3 * m['h_rms_m']:.2f} mm  settled "
            f"{1e3 * m['h_rms_settled_m']:.2f} mm  chatter(settled) {m['chatter_settled_rms']:.2f} rad/s  speed err"
            f"(settled) {1e3 * m.get('speed_err_settled_rms', math.nan):.1f} mm/s  fail {m['failure']:.2f}"
        )
        return True if after_eval is None else bool(after_eval(dict(row)))

    stopped_by: str | None = None
    if evaluate_runs and r.global_step >= r.next_eval:
        if not evaluate():
            stopped_by = "after_eval"
        r.next_eval += s.eval_every

    # CPU seconds of this call's rollouts and updates (process_time, all threads) and wall seconds of its iterations
    cpu_split = {"rollout": 0.0, "update": 0.0, "loop_wall": 0.0}
    buf_x = torch.zeros((t_len + 1, n, d))
    buf_u = torch.zeros((t_len, n, 2))
    buf_logp = torch.zeros((t_len, n))
    buf_v = torch.zeros((t_len + 1, n))
    buf_r = torch.zeros((t_len, n))
    buf_done = torch.zeros((t_len, n))
    while r.global_step < stop and stopped_by is None:
        stage = curriculum_path_params(s, r.global_step)
        if stage is not None and dict(r.env.params.path_params) != stage:  # between rollouts; no random draw
            r.env.set_path_params(stage)
            say(f"[curriculum] {r.global_step:>11,d} steps: random paths {stage}")
        r.iteration += 1
        frac = 1.0 - (r.iteration - 1.0) / n_iter
        for g in r.opt.param_groups:
            g["lr"] = frac * s.learning_rate
        # ---------------------------------------------------------------- rollout
        c0, w0 = time.process_time(), time.perf_counter()
        for t in range(t_len):
            feats, base, s_next = builder(r.obs, r.fstate, r.starts)
            r.obs_rms.update(feats)
            x = torch.as_tensor(r.obs_rms.normalize(feats), dtype=torch.float32)
            with torch.no_grad():
                mu = net.actor(x)
                v = net.value(x)
                u = mu + net.log_std.exp() * torch.randn_like(mu)
                logp = _log_prob(mu, net.log_std, u)
            a = env_action(u.double().numpy(), base, builder.previous_command(r.obs), s.residual_bound, s.filter_alpha)
            obs, rew, term, trunc, info = r.env.step(a)
            rew = np.asarray(rew, dtype=np.float64)
            done = np.logical_or(term, trunc)
            r.ep_ret += rew
            if done.any():
                r.episode_returns.extend(r.ep_ret[done].tolist())
                r.ep_ret[done] = 0.0
            if s.norm_reward:
                r.ret_acc = r.ret_acc * gamma + rew
                r.ret_rms.update(r.ret_acc)
                rew = np.clip(rew / np.sqrt(r.ret_rms.var[0] + 1e-8), -10.0, 10.0)
                r.ret_acc[done] = 0.0
            cut = np.flatnonzero(np.logical_and(trunc, np.logical_not(term)))
            if cut.size:  # bootstrap the time limit: V of the final observation
                final = np.stack([np.asarray(info["final_obs"][i], dtype=np.float64) for i in cut])
                f_fin, _, _ = builder(final, s_next[cut], np.zeros(cut.size, dtype=bool))
                with torch.no_grad():
                    xf = torch.as_tensor(r.obs_rms.normalize(f_fin), dtype=torch.float32)
                    rew[cut] += gamma * net.value(xf).double().numpy()
            buf_x[t], buf_u[t], buf_logp[t], buf_v[t] = x, u, logp, v
            buf_r[t] = torch.as_tensor(rew, dtype=torch.float32)
            buf_done[t] = torch.as_tensor(done, dtype=torch.float32)
            r.obs, r.fstate, r.starts = np.asarray(obs, dtype=np.float64), s_next, done
        feats, _, _ = builder(r.obs, r.fstate, r.starts)
        x_last = torch.as_tensor(r.obs_rms.normalize(feats), dtype=torch.float32)
        buf_x[t_len] = x_last
        with torch.no_grad():
            buf_v[t_len] = net.value(x_last)
        r.global_step += batch
        c1 = time.process_time()
        cpu_split["rollout"] += c1 - c0
        # ---------------------------------------------------------------- GAE
        adv = torch.zeros((t_len, n))
        last = torch.zeros(n)
        for t in reversed(range(t_len)):
            nonterm = 1.0 - buf_done[t]
            delta = buf_r[t] + gamma * buf_v[t + 1] * nonterm - buf_v[t]
            last = delta + gamma * s.gae_lambda * nonterm * last
            adv[t] = last
        ret = adv + buf_v[:t_len]
        # ---------------------------------------------------------------- update
        bx, bu, blogp = buf_x[:t_len].reshape(batch, d), buf_u.reshape(batch, 2), buf_logp.reshape(batch)
        badv, bret = adv.reshape(batch), ret.reshape(batch)
        bnext = buf_x[1:].reshape(batch, d)
        bsame = 1.0 - buf_done.reshape(batch)
        for _ in range(s.epochs):
            perm = torch.randperm(batch)
            for k in range(0, batch, s.minibatch_size):
                idx = perm[k : k + s.minibatch_size]
                xb = bx[idx]
                mu = net.actor(xb)
                logp = _log_prob(mu, net.log_std, bu[idx])
                ratio = (logp - blogp[idx]).exp()
                ab = badv[idx]
                ab = (ab - ab.mean()) / (ab.std() + 1e-8)
                pg = torch.max(-ab * ratio, -ab * ratio.clamp(1.0 - s.clip_coef, 1.0 + s.clip_coef)).mean()
                vloss = 0.5 * (net.value(xb) - bret[idx]).pow(2).mean()
                entropy = (net.log_std + 0.5 * math.log(2.0 * math.pi * math.e)).sum()
                loss = pg + s.vf_coef * vloss - s.ent_coef * entropy
                if s.caps_temporal > 0:
                    same = bsame[idx]
                    dmu = (net.actor(bnext[idx]) - mu).pow(2).sum(-1)
                    loss = loss + s.caps_temporal * (dmu * same).sum() / same.sum().clamp(min=1.0)
                if s.residual_penalty > 0:
                    loss = loss + s.residual_penalty * mu.pow(2).sum(-1).mean()
                if s.caps_spatial > 0:
                    mu_n = net.actor(xb + s.caps_sigma * torch.randn_like(xb))
                    loss = loss + s.caps_spatial * (mu_n - mu).pow(2).sum(-1).mean()
                r.opt.zero_grad()
                loss.backward()  # type: ignore[no-untyped-call]
                nn.utils.clip_grad_norm_(net.parameters(), s.max_grad_norm)
                r.opt.step()
        cpu_split["update"] += time.process_time() - c1
        cpu_split["loop_wall"] += time.perf_counter() - w0
        wall = wall0 + time.perf_counter() - t_start
        r.wall_s = wall
        if r.iteration % 20 == 0 or r.global_step >= stop:
            recent = r.episode_returns[-200:]
            mean_ret = float(np.mean(recent)) if recent else math.nan
            say(
                f"{r.global_step:>11,d} / {s.total_steps:,d} steps  {wall:7.0f} s  "
                f"{r.global_step / max(wall, 1e-9):8.0f} steps/s  episode return "
                f"{f'{mean_ret:7.1f}' if recent else 'n/a (none ended yet)'}  "
                f"std {float(net.log_std.detach().exp().mean()):.3f}"
            )
        if evaluate_runs and (r.global_step >= r.next_eval or r.global_step >= s.total_steps):
            if not evaluate():
                stopped_by = "after_eval"
                break
            while r.next_eval <= r.global_step:
                r.next_eval += s.eval_every
        if stop_request.requested and r.global_step < stop:
            stopped_by = "signal"
        if r.global_step >= r.next_ckpt or r.global_step >= stop or stopped_by == "signal":
            r.wall_s = wall0 + time.perf_counter() - t_start
            _save_checkpoint(ckpt, s, r)
            while r.next_ckpt <= r.global_step:
                r.next_ckpt += s.checkpoint_every
    r.wall_s = wall0 + time.perf_counter() - t_start
    r.env.close()
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
        "cpu_count": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "cpu_s_this_call": {k: round(v, 2) for k, v in cpu_split.items()},
    }
    if record["finished"]:
        _policy(s, r, {"env_steps": r.global_step, "seed": s.seed}).save(out / "model.zip")
        record["sha256"] = sha256_file(out / "model.zip")
        atomic_write_json(out / "run.json", record)
    return record


# --------------------------------------------------------------------------- CLI
@dataclass(frozen=True)
class HyperparamsFile:
    """The option of ``amigo-gym train-fast`` read first: the file whose values become the defaults of the others.

    Attributes:
        hyperparams: settings file [YAML]: its AmigoBot-v1 mapping of settings replaces the defaults below; options
            given here override it (e.g. agents/hyperparams/fastppo.yml) (default: none).
    """

    hyperparams: str | None = None


@dataclass(frozen=True)
class TrainFastRun(HyperparamsFile):
    """Options of ``amigo-gym train-fast`` besides the :class:`FastPPOSettings` (the run, not the training).

    Attributes:
        out: run folder [folder] (required).
        resume: continue the run in --out from its checkpoint.
        quiet: no progress lines.
    """

    out: str = field(kw_only=True)
    resume: bool = False
    quiet: bool = False


def _parser(cls: type, defaults: Mapping[str, Any] | None = None, **kw: Any) -> argparse.ArgumentParser:
    """The options of ``cls`` (and the :class:`FastPPOSettings`' unless ``cls`` is :class:`HyperparamsFile`);
    ``defaults``: a hyperparameter file's values, which replace the fields' defaults."""
    from amigo_gym.tools.options import OneLineParser, add_dataclass_options

    p = OneLineParser(prog=PROG, description=__doc__.splitlines()[0] if __doc__ else "", **kw)
    add_dataclass_options(p, cls)
    if cls is not HyperparamsFile:
        add_dataclass_options(p, FastPPOSettings)
    p.set_defaults(**(defaults or {}))
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym train-fast``: ``--hyperparams`` is read first; its file's values become the other defaults."""
    from amigo_gym.tools.options import run_guarded, settings_from_args

    args_in = list(sys.argv[1:] if argv is None else argv)
    known, _ = _parser(HyperparamsFile, add_help=False).parse_known_args(args_in)
    defaults: dict[str, Any] = {}
    if known.hyperparams is not None:
        rc = run_guarded(lambda: defaults.update(load_settings_yaml(known.hyperparams)), PROG)
        if rc:
            return rc
    args = _parser(TrainFastRun, defaults).parse_args(args_in)
    run_opts = settings_from_args(TrainFastRun, args)

    def run() -> int:
        s = settings_from_args(FastPPOSettings, args)
        cmd = "amigo-gym train-fast " + " ".join(shlex.quote(a) for a in args_in)
        log = None if run_opts.quiet else functools.partial(print, flush=True)
        rec = train(s, run_opts.out, resume=run_opts.resume, log=log, command=cmd)
        print(json.dumps({k: rec[k] for k in ("timesteps", "wall_time_s", "train_sps", "last_eval")}, default=str))
        return 0

    return run_guarded(run, PROG)
