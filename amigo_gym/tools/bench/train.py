"""``amigo-gym bench-train``: env-steps of *training* per second, the fast PPO against SB3's PPO, same run
(docs/performance.md, "Reference: `amigo-gym bench-train`"); ``--offpolicy``: SB3's SAC and TD3, sb3-contrib's
CrossQ and TQC ("Reference: `amigo-gym bench-train --offpolicy`")."""

from __future__ import annotations

import importlib
import os
import platform
import sys
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, Literal

import numpy as np

from amigo_gym.data import hyperparams_dir
from amigo_gym.io import atomic_write_json
from amigo_gym.tools.bench import clock, clocked, load_values, rates
from amigo_gym.tools.machine import cpu_model, simd_level
from amigo_gym.tools.options import check_fields, run_command
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
from amigo_gym.tools.training.hyperparams import Hyperparams, load_hyperparams

PROG = "amigo-gym bench-train"


def bench_fastppo(
    steps: int, threads: int, seed: int = 0, device: str = "auto", env_threads: int = 1, **overrides: Any
) -> dict[str, Any]:
    """Train the fast PPO for ``steps`` env-steps (no evaluation) and time it: ``{"env_steps", "wall_s", "sps"}``,
    the device, and the iterations' wall seconds split into the env's steps and the learner (the rest)."""
    from amigo_gym.tools.training.fastppo import FastPPOSettings, train

    s = FastPPOSettings(**{"total_steps": steps, "threads": threads, "seed": seed, "device": device,
                           "env_threads": env_threads, **overrides, "eval_every": 10**10,
                           "checkpoint_every": 10**10})  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        start = clock()
        rec = train(s, Path(tmp) / "run", log=None, evaluate_runs=False)
        out, n = clocked(int(rec["timesteps"]), start, clock()), int(rec["timesteps"])
    keys = ("num_envs", "rollout_steps", "epochs", "minibatch_size", "hidden", "env_threads", "device")
    out["config"] = {k: getattr(s, k) for k in keys}
    out |= {k: rec[k] for k in ("device", "device_name", "torch_threads", "numba_threads")}
    split, w = rec["cpu_s_this_call"], rec["wall_s_this_call"]  # CPU s of rollouts and updates; wall s of the loop
    out |= {"cpu_s_rollout": split["rollout"], "cpu_s_update": split["update"], "loop_wall_s": split["loop_wall"]}
    # steady state: the training iterations only, without building the env, the first resets and the final save
    out |= rates("sps_loop", n, split["loop_wall"], split["rollout"] + split["update"])
    return out | {"env_share": round(w["env"] / max(w["loop"], 1e-9), 3)}  # the learner's: 1 - env_share


def bench_sb3(
    steps: int, threads: int, n_envs: int, n_steps: int, batch_size: int, n_epochs: int, seed: int = 0
) -> dict[str, Any]:
    """Train SB3's PPO (``MlpPolicy``, 64x64 tanh) over the SB3 adapter of the native vector env; time ``learn``."""
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(threads)
    start = clock()
    venv = _venv(n_envs, seed)
    cfg: dict[str, Any] = {"n_steps": n_steps, "batch_size": batch_size, "n_epochs": n_epochs}
    kw: dict[str, Any] = {"learning_rate": 3e-4, "gamma": 0.98, "policy_kwargs": {"net_arch": [64, 64]}}
    model = PPO("MlpPolicy", venv, **cfg, **kw, seed=seed, verbose=0, device="cpu")
    model.learn(total_timesteps=steps)
    out = clocked(int(model.num_timesteps), start, clock())
    venv.close()
    cfg = {"n_envs": n_envs, **cfg, "net_arch": [64, 64]}
    return out | {"config": cfg, "device": "cpu", "device_name": cpu_model()}


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


def _show(name: str, r: dict[str, Any]) -> None:
    line = f"{name:<15}{r['sps']:>10,.0f} env-steps/s of training ({r['sps_cpu']:,.0f} per CPU second)"
    if "gsps_loop" in r:  # an off-policy entry
        line = (f"{name:<15}{r['sps_loop']:>10,.0f} env-steps/s of training ({r['sps_loop_cpu']:,.0f} per CPU "
                f"second), {r['gsps_loop']:,.1f} gradient steps/s ({r['gsps_loop_cpu']:,.1f} per CPU second) after "
                f"the warm-up; whole call {r['sps']:,.0f} env-steps/s")  # fmt: skip
    elif "sps_loop" in r:
        line += f"; training iterations only: {r['sps_loop']:,.0f} per s ({r['sps_loop_cpu']:,.0f} per CPU second)"
        line += f", {100 * r['env_share']:.0f} % in the env; device {r['device']} ({r['device_name']})"
    print(line, flush=True)


@dataclass(frozen=True)
class TrainSettings:
    """Settings of ``amigo-gym bench-train``, each the option of the same name (``--fast-steps`` for ``fast_steps``).

    Attributes:
        fast_steps: env-steps of the fast PPO [steps].
        sb3_steps: env-steps of each SB3 run [steps].
        threads: torch threads of every run [threads].
        device: the fast PPO's learner: auto (cuda if torch sees one, else cpu), cpu or cuda (SB3 runs on the cpu).
        env_threads: the fast PPO's env threads (above 1: the numba-parallel kernel) [threads].
        fast_hyperparams: the fast PPO's settings file, e.g. agents/hyperparams/fastppo.yml [file] (default: the
            FastPPOSettings defaults, N = 512, T = 32).
        skip_sb3_fastconfig: skip SB3 with the fast configuration.
        json: write the results here [file] (default: print only).
        offpolicy: off-policy algorithms to time, comma-separated: sac,td3,crossq,tqc [names] (default: none).
        offpolicy_steps: env-steps after the warm-up, shipped configuration [steps].
        offpolicy_ht_steps: env-steps after the warm-up, ht configuration [steps].
    """

    fast_steps: int = 1_048_576
    sb3_steps: int = 32_768
    threads: int = 1
    device: Literal["auto", "cpu", "cuda"] = "auto"
    env_threads: int = 1
    fast_hyperparams: str | None = None
    skip_sb3_fastconfig: bool = False
    json: str | None = None
    offpolicy: str = ""
    offpolicy_steps: int = 1024
    offpolicy_ht_steps: int = 16384

    def __post_init__(self) -> None:
        check_fields(PROG, self, fast_steps=(16384, 1e9), sb3_steps=(1, 1e8), threads=(1, 64), env_threads=(1, 256))
        if bad := [a for a in self.offpolicy_algos if a not in ALGOS]:
            raise ValueError(f"offpolicy: unknown algorithm(s) {', '.join(bad)}; allowed: {', '.join(ALGOS)}")
        check_fields(PROG, self, offpolicy_steps=(8, 1e8), offpolicy_ht_steps=(128, 1e9))

    @property
    def offpolicy_algos(self) -> list[str]:
        """The names of ``--offpolicy``."""
        return [a.strip() for a in self.offpolicy.split(",") if a.strip()]


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym bench-train``."""

    def run(s: TrainSettings) -> int:
        import torch

        head: dict[str, Any] = {"cpu_model": cpu_model(), "simd": simd_level(), "cpu_count": os.cpu_count()}
        head |= {"torch_threads": s.threads, "env_threads": s.env_threads, "fast_hyperparams": s.fast_hyperparams}
        head |= {"python": platform.python_version(), "numpy": np.__version__, "torch": torch.__version__}
        command = "amigo-gym bench-train " + " ".join(argv if argv is not None else sys.argv[1:])
        head |= {"load_average_start": load_values(), "command": command}
        print(f"CPU: {head['cpu_model']}, SIMD {head['simd']} ({head['cpu_count']} CPUs visible), "
              f"torch threads {s.threads}, load average {head['load_average_start']}", flush=True)  # fmt: skip
        from amigo_gym.tools.training.fastppo import load_settings_yaml, resolve_device

        hp = {} if s.fast_hyperparams is None else load_settings_yaml(s.fast_hyperparams)
        hp = {k: tuple(v) if k == "hidden" else v for k, v in hp.items() if not k.endswith(("_every", "total_steps"))}
        device = resolve_device(s.device)
        print(f"fast PPO learner on {device} "
              f"({torch.cuda.get_device_name() if device == 'cuda' else head['cpu_model']})", flush=True)  # fmt: skip
        todo = {"fastppo": partial(bench_fastppo, s.fast_steps, s.threads, 0, device, s.env_threads, **hp)}
        todo["sb3_shipped"] = partial(bench_sb3, s.sb3_steps, s.threads, 16, 256, 1024, 10)
        if not s.skip_sb3_fastconfig:
            todo["sb3_fastconfig"] = partial(bench_sb3, max(s.sb3_steps, 512 * 32), s.threads, 512, 32, 4096, 4)
        for algo in s.offpolicy_algos:  # <algo>_<config>: the shipped and the ht configuration
            for config, steps in (("shipped", s.offpolicy_steps), ("ht", s.offpolicy_ht_steps)):
                todo[f"{algo}_{config}"] = partial(bench_offpolicy, algo, config, steps, s.threads)
        runs: dict[str, Any] = {}
        for name, bench in todo.items():
            _show(name, runs.setdefault(name, bench()))
        fast = runs["fastppo"]["sps"]
        ratios = {f"fastppo/{k}": round(fast / v["sps"], 2) for k, v in runs.items() if k != "fastppo"}
        for k, v in ratios.items():
            print(f"ratio {k}: {v:.1f}x", flush=True)
        doc = head | {"runs": runs, "ratios": ratios, "load_average_end": load_values()}
        if s.json:
            atomic_write_json(s.json, doc, parents=True)
        return 0

    return run_command(TrainSettings, run, argv, PROG, __doc__.splitlines()[0] if __doc__ else "")
