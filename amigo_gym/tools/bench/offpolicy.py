"""Off-policy entries of ``amigo-gym bench-train``: SB3's SAC and TD3, sb3-contrib's CrossQ and TQC, timed
(docs/performance.md, "Reference: `amigo-gym bench-train --offpolicy`")."""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from amigo_gym.data import hyperparams_dir
from amigo_gym.tools.bench import clock, clocked, rates
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
from amigo_gym.tools.training.hyperparams import Hyperparams, load_hyperparams

#: the off-policy algorithms measured: name -> (module, class)
ALGOS: dict[str, tuple[str, str]] = {
    "sac": ("stable_baselines3", "SAC"),
    "td3": ("stable_baselines3", "TD3"),
    "crossq": ("sb3_contrib", "CrossQ"),
    "tqc": ("sb3_contrib", "TQC"),
}

#: the two configurations: ``shipped`` reads the v1 YAML; ``ht`` overrides these keys of it
HT = {"n_envs": 128, "train_freq": 1, "gradient_steps": 8, "batch_size": 2048, "learning_starts": 10_240}
CONFIGS: dict[str, dict[str, Any]] = {"shipped": {}, "ht": HT | {"buffer_size": 500_000}}


def algo_class(algo: str) -> Any:
    """The SB3 / sb3-contrib class of ``algo`` (:data:`ALGOS`); ``ValueError`` for another name."""
    if algo not in ALGOS:
        raise ValueError(f"offpolicy: algorithm must be one of {', '.join(ALGOS)}, got {algo!r}")
    module, name = ALGOS[algo]
    return getattr(importlib.import_module(module), name)


def offpolicy_config(algo: str, config: str) -> dict[str, Any]:
    """The rl-zoo style mapping of ``algo`` in ``config`` (:data:`CONFIGS`): ``agents/hyperparams/<algo>.yml``
    (CrossQ, TQC: ``sac.yml``, CrossQ without ``tau``) for AmigoBot-v1, then the overrides."""
    if config not in CONFIGS:
        raise ValueError(f"offpolicy: configuration must be one of {', '.join(CONFIGS)}, got {config!r}")
    algo_class(algo)  # checks the name
    source = algo if algo in ("sac", "td3") else "sac"
    hp = dict(load_hyperparams(hyperparams_dir() / f"{source}.yml", "AmigoBot-v1"))
    for key in ("n_timesteps", "policy", "tau" if algo == "crossq" else ""):
        hp.pop(key, None)
    return hp | CONFIGS[config]


def make_model(algo: str, hp: Mapping[str, Any], venv: Any, seed: int = 0) -> Any:
    """The ``algo`` model of the mapping ``hp`` (:func:`offpolicy_config`) on ``venv``, CPU, ``MlpPolicy``."""
    kw = {k: v for k, v in hp.items() if k not in ("n_envs", "noise_type", "noise_std")}
    if isinstance(kw.get("train_freq"), list):
        kw["train_freq"] = tuple(kw["train_freq"])
    if hp.get("noise_type") not in (None, "normal"):
        raise ValueError(f"offpolicy: noise_type must be 'normal', got {hp['noise_type']!r}")
    parsed = Hyperparams(noise_type=hp.get("noise_type"), noise_std=float(hp.get("noise_std", 0.1)))
    noise = parsed.action_noise(int(np.prod(venv.action_space.shape)))
    return algo_class(algo)("MlpPolicy", venv, action_noise=noise, seed=seed, device="cpu", verbose=0, **kw)


def _venv(n_envs: int, seed: int) -> Any:
    from stable_baselines3.common.vec_env import VecMonitor

    from amigo_gym.tools.training.sb3_vec import AmigoBotSB3VecEnv

    venv = VecMonitor(AmigoBotSB3VecEnv(num_envs=n_envs, env_id="AmigoBot-v1", **TRAINING_DISTRIBUTION["env_kwargs"]))
    venv.seed(seed)
    return venv


def bench_offpolicy(
    algo: str, config: str, steps: int, threads: int, seed: int = 0, pre_steps: int = 0
) -> dict[str, Any]:
    """Train ``algo`` in ``config`` for its warm-up, ``pre_steps`` (timed in the whole call only: a JIT's first
    update) and ``steps`` env-steps; the counts, times and rates of the whole call and of the loop after the warm-up
    (``loop_*``, ``*_loop``; ``gsps``: gradient steps/s) and ``config``."""
    import torch

    hp = offpolicy_config(algo, config)
    torch.set_num_threads(threads)
    n_envs = int(hp.get("n_envs", 1))
    start = clock()
    venv = _venv(n_envs, seed)
    model = make_model(algo, hp, venv, seed)
    model.learn(total_timesteps=int(hp["learning_starts"]))  # warm-up: random actions, no update
    if pre_steps > 0:
        model.learn(total_timesteps=pre_steps, reset_num_timesteps=False)
    (t1, c1), n1, g1 = clock(), int(model.num_timesteps), int(model._n_updates)
    model.learn(total_timesteps=steps, reset_num_timesteps=False)
    (t2, c2), n, g = clock(), int(model.num_timesteps), int(model._n_updates)
    venv.close()
    train_freq = hp["train_freq"][0] if isinstance(hp["train_freq"], list | tuple) else hp["train_freq"]
    cfg = {k: (list(v) if isinstance(v, tuple) else v) for k, v in hp.items()} | {"net_arch": [64, 64]}
    cfg["gradient_steps_per_env_step"] = round(float(hp["gradient_steps"]) / (float(train_freq) * n_envs), 4)
    out = {"algo": algo, "grad_steps": g} | clocked(n, start, (t2, c2)) | {"warmup_wall_s": round(t1 - start[0], 2)}
    out |= {"loop_env_steps": n - n1, "loop_grad_steps": g - g1, "loop_wall_s": round(t2 - t1, 2)}
    out |= {"loop_cpu_s": round(c2 - c1, 2)} | rates("sps_loop", n - n1, t2 - t1, c2 - c1)
    return out | rates("gsps_loop", g - g1, t2 - t1, c2 - c1) | {"config": cfg}
