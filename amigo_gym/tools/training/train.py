"""``amigo-gym train``: a PPO, SAC or TD3 baseline with SB3 (docs/baselines.md, "Reference: `amigo-gym train`")."""

from __future__ import annotations

import importlib
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args

import gymnasium as gym
import numpy as np

from amigo_gym import __version__
from amigo_gym.data import hyperparams_dir, repository_root
from amigo_gym.envs.amigobot import make_env_params
from amigo_gym.io import atomic_save, atomic_write_json, fault_point, sha256_file, vouch
from amigo_gym.task.v1 import v0_settings
from amigo_gym.tools import runs
from amigo_gym.tools.machine import cpu_model
from amigo_gym.tools.options import cli, json_object, missing_modules, parse_settings, run_guarded, say
from amigo_gym.tools.training.hyperparams import (
    LOWPASS_POLICY,
    Hyperparams,
    load_hyperparams,
    parse_hyperparams,
    sb3_class,
)
from amigo_gym.tools.training.task_metrics import EpisodeRecorder, InfoAdapter

Algo = Literal["ppo", "sac", "td3"]
EnvId = Literal["AmigoBot-v0", "AmigoBot-v1"]
ALGOS = get_args(Algo)
ENV_ID: EnvId = "AmigoBot-v0"
ENV_IDS = get_args(EnvId)
HYPERPARAMS_DIR = hyperparams_dir()
OFF_POLICY = ("sac", "td3")
EVAL_SEED_OFFSET = 10_000
VECNORMALIZE = "vecnormalize.pkl"
#: ``train(after_eval=...)``: receives each evaluation's record; ``False`` stops training
AfterEvalHook = Callable[[dict[str, Any]], bool]


# --------------------------------------------------------------------------- settings
@dataclass
class Settings:
    """A run's settings besides the hyperparameter file (saved in ``config.json``); each field is its option.

    Attributes:
        algo: algorithm (required).
        seed: master seed [-].
        timesteps: total env steps [steps], rounded up to whole rollouts (default: the YAML's n_timesteps).
        out: run directory [dir], must be empty unless --resume (required).
        resume: continue from the latest good checkpoint in --out (pickles: resume only runs you trust).
        n_envs: parallel envs [envs] (default: the YAML's n_envs or 1).
        vec: vector env: native (AmigoBotSB3VecEnv), dummy (DummyVecEnv) or auto (native when n_envs > 1).
        hyperparams: rl-zoo YAML [file] (default: agents/hyperparams/<algo>.yml).
        eval_freq: steps between evaluations [steps], 0: none.
        eval_episodes: episodes per evaluation [episodes].
        checkpoint_freq: steps between checkpoints [steps] (0: only at the end / on interrupt).
        threads: torch threads [threads].
        progress: --no-progress: no progress bar.
        export: copy model and record to DIR/<algo>.zip, DIR/<algo>.json [dir] (default: none).
        export_model: model to export: final (model.zip) or best (best_model.zip, the best evaluation).
        env_id: environment id: AmigoBot-v0 (the paper's task) or AmigoBot-v1 (the real robot on many paths).
        env_kwargs: keywords of gym.make as JSON [json] (default {}), e.g. '{"path": "mixed"}'.
        argv: the command line (not an option).
    """

    algo: Algo
    seed: int = 0
    timesteps: int | None = None
    out: str = field(default="runs/run", metadata=cli(required=True))
    resume: bool = False
    n_envs: int | None = None
    vec: Literal["auto", "native", "dummy"] = "auto"
    hyperparams: str | None = None
    eval_freq: int = 10_000
    eval_episodes: int = 5
    checkpoint_freq: int = 20_000
    threads: int = 1
    progress: bool = field(default=True, metadata=cli("--no-progress"))
    export: str | None = None
    export_model: Literal["final", "best"] = "final"
    env_id: EnvId = field(default=ENV_ID, metadata=cli("--env"))
    env_kwargs: dict[str, Any] = field(default_factory=dict, metadata=cli(parse=json_object))
    argv: list[str] = field(default_factory=list, metadata=cli(skip=True))

    def validate(self) -> None:
        for name, allowed in (("algo", ALGOS), ("export_model", ("final", "best")), ("env_id", ENV_IDS),
                              ("vec", ("auto", "native", "dummy"))):  # fmt: skip
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {list(allowed)}, got {getattr(self, name)!r}")
        if not isinstance(self.env_kwargs, dict):
            raise ValueError(f"env_kwargs must be a mapping, got {type(self.env_kwargs).__name__}")
        lows = {"seed": 0, "eval_freq": 0, "checkpoint_freq": 0, "eval_episodes": 1, "threads": 1}
        for name, low in (lows | {"timesteps": 1, "n_envs": 1}).items():  # the last two: None is their default
            v = getattr(self, name)
            if (v is not None or name in lows) and (isinstance(v, bool) or not isinstance(v, int) or v < low):
                raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")


def git_revision() -> str:
    """``git rev-parse HEAD`` of the repository holding this file, with ``-dirty`` if tracked files changed."""
    root = repository_root()
    if root is None:
        return "not a git checkout"

    def git(*args: str) -> str:
        return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, check=True, timeout=10).stdout

    try:
        rev, dirty = git("rev-parse", "HEAD").strip(), git("status", "--porcelain", "--untracked-files=no").strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return rev + ("-dirty" if dirty else "")


def versions(libraries: Sequence[str] = ("gymnasium", "stable_baselines3", "torch")) -> dict[str, str]:
    """Versions of Python, amigo_gym, numpy and ``libraries``."""
    found = {name: str(importlib.import_module(name).__version__) for name in libraries}
    return {"python": platform.python_version(), "amigo_gym": __version__, "numpy": np.__version__} | found


def env_kwargs(env_id: str = ENV_ID, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """The trained env's settings as JSON: v0 every one of its settings, v1 the ``overrides`` as given."""
    if env_id != ENV_ID:
        return json.loads(json.dumps(overrides or {}))  # type: ignore[no-any-return]
    params = make_env_params("train", None, **(overrides or {}))
    v0 = v0_settings(params) or {}
    return json.loads(json.dumps({**v0, "robot": asdict(params.robot)}))  # type: ignore[no-any-return]


def _native(vec: str, n_envs: int) -> bool:
    return vec == "native" or (vec == "auto" and n_envs > 1)


def make_train_env(
    n_envs: int,
    vec: str,
    seed: int,
    normalize: dict[str, Any] | None = None,
    env_id: str = ENV_ID,
    kwargs: dict[str, Any] | None = None,
) -> Any:
    """SB3 VecEnv of ``n_envs`` monitored ``env_id`` envs seeded ``seed + i``; ``normalize``: ``VecNormalize``
    keywords (``None``: none); ``kwargs``: of ``gym.make``."""
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import DummyVecEnv, VecMonitor

    from amigo_gym.tools.training.sb3_vec import AmigoBotSB3VecEnv

    venv: Any
    if _native(vec, n_envs):
        venv = VecMonitor(AmigoBotSB3VecEnv(n_envs, env_id=env_id, **(kwargs or {})))
    else:
        venv = DummyVecEnv([lambda: Monitor(gym.make(env_id, **(kwargs or {}))) for _ in range(n_envs)])
    venv.seed(seed)
    venv.action_space.seed(seed)
    if normalize is not None:
        from stable_baselines3.common.vec_env import VecNormalize

        venv = VecNormalize(venv, **normalize)
    return venv


class _StopAtBoundary(Exception):
    """A stop asked for, raised at a rollout boundary after the checkpoint."""


def _callbacks(
    s: Settings,
    out: Path,
    n_envs: int,
    done_steps: int,
    wall: Callable[[], float],
    stop: runs.StopRequest,
    normalize: bool = False,
    after_eval: AfterEvalHook | None = None,
) -> list[Any]:
    from stable_baselines3.common.callbacks import BaseCallback, EvalCallback

    class Checkpoint(BaseCallback):
        """At a rollout's start: a checkpoint every ``checkpoint_freq`` steps, and the stop asked for by a signal."""

        last = done_steps

        def _on_rollout_start(self) -> None:
            freq = s.checkpoint_freq
            if (freq and self.num_timesteps - self.last >= freq) or stop.requested:
                self.last = self.num_timesteps
                save_checkpoint(self.model, out, s.algo, wall())
            if stop.requested:
                raise _StopAtBoundary

        def _on_step(self) -> bool:
            return True

    class TaskEvalCallback(EvalCallback):
        """SB3's ``EvalCallback`` that also logs ``eval/h_rms_m``, ``eval/h_rms_settled_m`` [m],
        ``eval/speed_err_rms`` [m/s] and ``eval/failure_rate`` of its episodes (means); after each evaluation: a new
        best saved as ``best_model.zip``, the evaluation appended to ``eval.json``, ``after_eval``'s verdict."""

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            probe = gym.make(s.env_id, **s.env_kwargs)
            self.adapter = InfoAdapter.for_env(probe)
            self.dt = float(probe.unwrapped.params.dt)  # type: ignore[attr-defined]
            probe.close()
            self.recorders: dict[int, EpisodeRecorder] = {}
            self.episodes: list[dict[str, float]] = []
            self.task_metrics: dict[str, float] = {}
            f = out / "eval.json"
            self.history: list[dict[str, float]] = json.loads(f.read_text()) if f.is_file() else []
            if self.history:  # resumed: a new best must beat the evaluations before the interruption
                self.best_mean_reward = max(h["mean_reward"] for h in self.history)

        def _on_step(self) -> bool:
            if not (self.eval_freq > 0 and self.n_calls % self.eval_freq == 0):
                return True
            self.recorders, self.episodes = {}, []
            best = self.best_mean_reward
            go = bool(super()._on_step())
            if self.best_mean_reward > best:
                atomic_save(self.model.save, out / "best_model.zip", parents=True)
            entry = {
                "timesteps": int(self.num_timesteps),
                "mean_reward": float(self.last_mean_reward),
                "best_mean_reward": float(self.best_mean_reward),
                "wall_time_s": wall(),
            } | self.task_metrics
            self.history.append(entry)
            atomic_write_json(out / "eval.json", self.history, parents=True)
            return go and (after_eval is None or bool(after_eval(entry)))

        def _log_success_callback(self, locals_: dict[str, Any], globals_: dict[str, Any]) -> None:
            super()._log_success_callback(locals_, globals_)
            i, info = int(locals_["i"]), locals_["info"]
            rec = self.recorders.setdefault(i, EpisodeRecorder(self.dt))
            rec.add(self.adapter.read(info), float(locals_["reward"]))
            if locals_["done"]:
                ended = not info.get("TimeLimit.truncated", False)
                rec.terminated = ended and not bool(info.get("end_of_path", False))  # v1: path end = success
                self.episodes.append(rec.metrics())
                del self.recorders[i]
                for key in ("h_rms_m", "h_rms_settled_m", "speed_err_rms", "failure_rate"):
                    vals = np.array([e["failure" if key == "failure_rate" else key] for e in self.episodes])
                    vals = vals[np.isfinite(vals)]
                    self.task_metrics[key] = value = float(vals.mean()) if vals.size else float("nan")
                    self.logger.record(f"eval/{key}", value)

    cbs: list[Any] = [Checkpoint()]
    if s.eval_freq > 0:
        # the training's VecEnv type (SB3 warns otherwise); EvalCallback copies the VecNormalize statistics
        vec = "native" if _native(s.vec, n_envs) else "dummy"
        stats = {"training": False, "norm_reward": False} if normalize else None
        eval_env = make_train_env(1, vec, s.seed + EVAL_SEED_OFFSET, stats, s.env_id, s.env_kwargs)
        every = max(1, s.eval_freq // n_envs)
        ev = TaskEvalCallback(eval_env, n_eval_episodes=s.eval_episodes, eval_freq=every, deterministic=True, verbose=0)
        ev.n_calls = done_steps // n_envs  # resumed: evaluate at the same steps as an uninterrupted run
        cbs.append(ev)
    return cbs


def save_checkpoint(model: Any, out: Path, algo: str, wall_time_s: float = 0.0) -> Path:
    """A checkpoint of ``model`` with its replay buffer (SAC/TD3) and VecNormalize statistics."""

    def write(folder: Path) -> list[str]:
        model.save(folder / "model.zip")
        fault_point("checkpoint:model")
        names = ["model.zip"]
        if algo in OFF_POLICY:
            model.save_replay_buffer(folder / "replay_buffer.pkl")
            fault_point("checkpoint:replay")
            names.append("replay_buffer.pkl")
        if (vecnormalize := model.get_vec_normalize_env()) is not None:
            vecnormalize.save(folder / VECNORMALIZE)
            names.append(VECNORMALIZE)
        return names

    return runs.save_checkpoint(out, algo, int(model.num_timesteps), write, wall_time_s)


def _load_checkpoint(algo_cls: Any, algo: str, ck: runs.Checkpoint, n_envs: int, s: Settings) -> Any:
    """The model (and replay buffer) of a verified checkpoint, on a new training env seeded for its step."""
    venv = make_train_env(n_envs, s.vec, s.seed + ck.step, None, s.env_id, s.env_kwargs)
    if (ck.folder / VECNORMALIZE).is_file():
        from stable_baselines3.common.vec_env import VecNormalize

        with runs.corrupt_errors(ck.folder / VECNORMALIZE, "VecNormalize statistics"):
            venv = VecNormalize.load(str(ck.folder / VECNORMALIZE), venv)
    path = ck.folder / "model.zip"
    with runs.corrupt_errors(path, f"{algo.upper()} model"):
        model = algo_cls.load(path, env=venv, device="cpu")
    if int(model.num_timesteps) != ck.step:
        raise runs.CorruptFileError(f"{path}: holds step {model.num_timesteps}, meta.json says {ck.step}")
    if algo in OFF_POLICY:
        rb_path = ck.folder / "replay_buffer.pkl"
        with runs.corrupt_errors(rb_path, "replay buffer"):
            model.load_replay_buffer(rb_path)
        rb = model.replay_buffer
        per_env = ck.step // n_envs
        if rb.n_envs != n_envs or rb.pos != per_env % rb.buffer_size or rb.full != (per_env >= rb.buffer_size):
            raise runs.CorruptFileError(
                f"{rb_path}: holds {rb.buffer_size if rb.full else rb.pos} transitions per env, "
                f"not the {per_env} of step {ck.step}"
            )
    return model


def train(s: Settings, after_eval: AfterEvalHook | None = None) -> dict[str, Any]:
    """Run (or resume) one run, its folder locked; the record (``run.json``). ``after_eval(entry)`` after each
    evaluation: ``False`` stops training (the run ends normally). Raises ``RunLockedError``, ``CorruptFileError``."""
    s.validate()
    hp_path = Path(s.hyperparams) if s.hyperparams else HYPERPARAMS_DIR / f"{s.algo}.yml"
    hp = load_hyperparams(hp_path, s.env_id)
    parsed = parse_hyperparams(s.algo, hp, str(hp_path))  # a refused run writes nothing
    gym.make(s.env_id, **s.env_kwargs).close()
    stop = runs.StopRequest("amigo-gym train: stopping at the end of this rollout (checkpoint first)")
    with runs.handling(stop), runs.RunLock(s.out):
        result = _train(s, hp_path, hp, parsed, stop, after_eval)
    if result is None:  # stopped by a signal, after the checkpoint
        raise KeyboardInterrupt
    return result


def planned_timesteps(model: Any, total: int) -> tuple[int, str]:
    """The step a run of ``total`` steps ends at and why: SB3 checks the budget after whole rollouts (``n_steps``, or
    a ``train_freq`` in steps, times ``n_envs``; episodes: at once)."""
    done, n, freq = int(model.num_timesteps), int(model.n_envs), getattr(model, "train_freq", None)
    if hasattr(model, "n_steps"):
        size, why = int(model.n_steps) * n, f"n_steps {int(model.n_steps)} x {n} envs"
    elif freq is not None and getattr(freq.unit, "value", None) == "step":
        size, why = int(freq.frequency) * n, f"train_freq {int(freq.frequency)} x {n} envs"
    else:
        return max(done, total), ""
    return done + -(-max(total - done, 0) // size) * size, why


def _new_config(s: Settings, total: int, n_envs: int, hp_path: Path, hp: dict[str, Any]) -> dict[str, Any]:
    return {
        "settings": asdict(s) | {"timesteps": total, "n_envs": n_envs, "hyperparams": str(hp_path)},
        "hyperparams": hp,
        "env_id": s.env_id,
        "env_kwargs": env_kwargs(s.env_id, s.env_kwargs),
        "git_revision": git_revision(),
        "versions": versions(),
        "command": "amigo-gym train " + " ".join(s.argv),
        "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    }


def _train(
    s: Settings, hp_path: Path, hp: dict[str, Any], parsed: Hyperparams, stop: runs.StopRequest,
    after_eval: AfterEvalHook | None,
) -> dict[str, Any] | None:  # fmt: skip
    import torch
    from stable_baselines3.common.utils import set_random_seed

    algo_cls = sb3_class(s.algo)
    out = Path(s.out)
    total = int(s.timesteps if s.timesteps is not None else (parsed.n_timesteps or 100_000))
    n_envs = int(s.n_envs if s.n_envs is not None else (parsed.n_envs or 1))

    config_file = out / "config.json"
    recovered = s.resume and not config_file.is_file()
    if recovered:
        if not runs.candidates(out, report=False):
            raise FileNotFoundError(f"--resume: no checkpoint in {out} (no run started there: missing config.json)")
        runs.warn(
            f"--resume: {config_file} is missing; resuming from the checkpoints in {out / runs.CHECKPOINTS} "
            "with the settings of this command (config.json written again, marked 'recovered')"
        )
    elif s.resume:
        config = runs.read_json(config_file)
        if not isinstance(config, dict) or not isinstance(config.get("settings"), dict):
            raise runs.CorruptFileError(f"{config_file}: not a run configuration (no 'settings')")
        if config["settings"].get("algo") != s.algo:
            raise ValueError(f"--resume: {out} holds a {config['settings'].get('algo')} run, not {s.algo}")
    elif runs.has_run_files(out):
        raise FileExistsError(f"{out} is not empty; pass --resume to continue it or choose another --out")
    runs.clean_temporaries(out)  # we hold the lock

    torch.set_num_threads(s.threads)
    set_random_seed(s.seed)

    loaded = None
    if s.resume:
        loaded = runs.load_checkpoint(out, s.algo, lambda ck: _load_checkpoint(algo_cls, s.algo, ck, n_envs, s))
        if loaded is None:
            runs.warn(f"--resume: no checkpoint yet in {out}; starting from step 0")
        runs.restore_snapshot(out, None if loaded is None else loaded[0])
        if recovered:
            config = _new_config(s, total, n_envs, hp_path, hp) | {"recovered": True}
        entry = {"command": "amigo-gym train " + " ".join(s.argv), "from_step": 0 if loaded is None else loaded[0].step}
        config["resumes"] = [*config.get("resumes", []), entry | {"git_revision": git_revision()}]
    else:
        config = _new_config(s, total, n_envs, hp_path, hp)
    atomic_write_json(config_file, config, parents=True)

    if loaded is not None:
        done_steps, previous_wall, model = loaded[0].step, loaded[0].wall_time_s, loaded[1]
        set_random_seed(s.seed + done_steps)
    else:
        venv = make_train_env(n_envs, s.vec, s.seed, parsed.normalize, s.env_id, s.env_kwargs)
        kw = dict(parsed.kwargs)
        if (noise := parsed.action_noise(int(venv.action_space.shape[0]))) is not None:
            kw["action_noise"] = noise
        policy: Any = parsed.policy
        if policy == LOWPASS_POLICY:
            from amigo_gym.tools.training.sb3_lowpass import policy_for

            policy, kw["policy_kwargs"] = policy_for(venv, kw.get("policy_kwargs"))
        model = algo_cls(policy, venv, seed=s.seed, device="cpu", tensorboard_log=str(out / "tb"), verbose=0, **kw)
        done_steps, previous_wall = 0, 0.0
    venv = model.get_env()

    remaining = total - int(model.num_timesteps)
    planned = planned_timesteps(model, total)
    if planned[0] != total:
        say(f"amigo-gym train: --timesteps {total} becomes {planned[0]} steps: SB3 trains whole rollouts "
            f"({planned[1]})")  # fmt: skip
    t0 = time.perf_counter()

    def wall() -> float:
        return previous_wall + time.perf_counter() - t0

    normalize = model.get_vec_normalize_env() is not None
    cbs = _callbacks(s, out, n_envs, done_steps, wall, stop, normalize, after_eval)
    try:
        if remaining > 0:
            model.learn(
                remaining,
                callback=cbs,
                reset_num_timesteps=loaded is None and not s.resume,
                tb_log_name=s.algo,
                progress_bar=s.progress,
            )
    except _StopAtBoundary:
        venv.close()
        return None
    if int(model.num_timesteps) != done_steps or loaded is None:
        save_checkpoint(model, out, s.algo, wall())
    atomic_save(model.save, out / "model.zip", parents=True)
    if (vecnormalize := model.get_vec_normalize_env()) is not None:
        atomic_save(vecnormalize.save, out / VECNORMALIZE, parents=True)

    evals = runs.read_json(out / "eval.json") if (out / "eval.json").is_file() else []
    record = {
        "algo": s.algo,
        "seed": s.seed,
        "timesteps": int(model.num_timesteps),
        "n_envs": n_envs,
        "wall_time_s": round(wall(), 1),
        "resumed_from": done_steps if s.resume else None,
        "last_eval": evals[-1] if evals else None,
        "command": config["command"],
        "resumes": config.get("resumes", []),
        "git_revision": config["git_revision"],
        "versions": versions(),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "torch_threads": s.threads,
        "numba_threads": None if missing_modules(["numba"]) else importlib.import_module("numba").get_num_threads(),
        "device": "cpu",  # SB3 on the CPU here (its MLPs are faster there)
        "sha256": sha256_file(out / "model.zip"),
    }
    # every pickle a loader reads, with its sha256 (checked before unpickling); written here: trusted
    record["files"] = {
        n: sha256_file(out / n) for n in ("model.zip", "best_model.zip", VECNORMALIZE) if (out / n).is_file()
    }
    vouch(*record["files"].values())
    atomic_write_json(out / "run.json", record, parents=True)
    if s.export:
        exp, src = Path(s.export), out / "model.zip"
        exported = {"exported_model": "final", "exported_timesteps": record["timesteps"]}
        if s.export_model == "best":
            if not evals or not (out / "best_model.zip").is_file():
                raise FileNotFoundError(f"--export-model best: no evaluation / best_model.zip in {out}")
            src = out / "best_model.zip"
            best = max(evals, key=lambda e: e["mean_reward"])
            exported = {"exported_model": "best", "exported_timesteps": best["timesteps"], "best_eval": best}
        exported["sha256"] = sha256_file(src)
        atomic_save(lambda tmp: shutil.copyfile(src, tmp), exp / f"{s.algo}.zip", parents=True)
        atomic_write_json(exp / f"{s.algo}.json", record | exported, parents=True)
    venv.close()
    return record


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym train``."""
    args = list(sys.argv[1:] if argv is None else argv)
    doc = "Train a PPO/SAC/TD3 baseline on AmigoBot-v0 or -v1."
    s = parse_settings(Settings, args, "amigo-gym train", doc, argv=args)

    def run() -> None:
        record = train(s)
        lines = [f"{k}: {record[k]}" for k in ("algo", "seed", "timesteps", "wall_time_s")]
        if record["last_eval"]:
            lines.append(f"last eval mean reward: {record['last_eval']['mean_reward']:.2f}")
        print("\n".join(lines))

    return run_guarded(run, "amigo-gym train")
