"""``amigo-gym sweep``: Optuna studies over SB3 or fast-PPO training, on one or many machines.

Reference (objective, storage, modes, budget, stopped workers, summary, exit status): docs/benchmark.md.
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
import warnings
import zlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, get_args
from urllib.parse import quote, quote_plus, unquote, unquote_plus

import numpy as np

from amigo_gym.io import atomic_write, atomic_write_json
from amigo_gym.policies.learned import FastPolicy
from amigo_gym.tools.options import cli, json_object, parse_settings, run_guarded
from amigo_gym.tools.runs import RunLock, handling, verify_sha256
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
from amigo_gym.tools.training.evaluate import find_models, load_model
from amigo_gym.tools.training.hyperparams import load_hyperparams
from amigo_gym.tools.training.intervals import iqm
from amigo_gym.tools.training.protocol import VALIDATION_SEEDS
from amigo_gym.tools.training.protocol import validation_cells as validation_cells  # the objective's cells
from amigo_gym.tools.training.task_metrics import run_scenario
from amigo_gym.tools.training.train import ENV_IDS, HYPERPARAMS_DIR, EnvId, Settings, train

Mode = Literal["hyperparams", "seeds"]
SweepAlgo = Literal["ppo", "sac", "td3", "fastppo"]
FASTPPO = "fastppo"
#: a fast-PPO trial's rollout batch ``num_envs * rollout_steps`` is at most ``--timesteps / MIN_ITERATIONS``
MIN_ITERATIONS = 8
#: the marker in the folder of a trial whose worker was stopped or killed
ABANDONED = "ABANDONED.json"
OBJECTIVE = "validation_h_rms_iqm_m"
Validation = tuple[float, dict[str, float | None]]  # OBJECTIVE [m] and each validation cell's mean (None: not finite)
#: exit status of a worker stopped by SIGTERM / Ctrl-C
INTERRUPTED = 130
#: how long a worker joining a study waits for its creator to set it up [s]
READY_TIMEOUT_S = 120.0
#: the least value of each integer option
LOWS = {"n_trials": 1, "n_jobs": 1, "timesteps": 1, "eval_freq": 1, "eval_episodes": 1, "heartbeat_interval": 1,
        "grace_period": 1, "max_retry": 0, "threads": 1, "n_startup_trials": 0, "worker_index": 0, "train_seed": 0,
        "val_episodes": 1, "val_max_steps": 0}  # fmt: skip


# --------------------------------------------------------------------------- secrets
def scrub(text: str, url: str | None) -> str:
    """``text`` with every form (as typed, decoded, quoted) of each credential of ``url`` (``user:pw@``, credential
    parameters) replaced by ``***``."""
    m = re.match(r"[^:/?#]*://([^/?#]*)@", url or "")  # the userinfo, up to the host's last "@"
    found = {m.group(1).partition(":")[2]} if m and ":" in m.group(1) else set()
    for part in re.split(r"[&;]", (url or "").partition("?")[2]):
        name, eq, value = part.partition("=")
        if eq and re.search(r"pass|pwd|secret|token|key|auth|cred", unquote_plus(name), re.IGNORECASE):  # a credential
            found.add(value.partition("#")[0])
    forms = {g for f in found for v in (f, unquote(f), unquote_plus(f)) for g in (v, quote(v, safe=""), quote_plus(v))}
    for form in sorted(forms - {""}, key=len, reverse=True):
        text = text.replace(form, "***")
    return text


def masked_url(url: str) -> str:
    """``url`` with its credentials masked."""
    return scrub(url, url)


def public_argv(argv: Sequence[str]) -> list[str]:
    """The command line with every URL's credentials masked."""
    return [scrub(a, a.partition("=")[2] if a.startswith("--") else a) if "://" in a else a for a in argv]


def _in_memory(url: str) -> bool:
    """Whether ``url`` is an in-memory SQLite database (private to its process)."""
    from sqlalchemy.engine import make_url

    u = make_url(url)
    db = u.database or ""
    memory = db in ("", ":memory:") or db.startswith("file::memory:") or u.query.get("mode") == "memory"
    return u.drivername.startswith("sqlite") and memory


# --------------------------------------------------------------------------- settings
@dataclass
class SweepConfig:
    """Settings of one ``amigo-gym sweep`` command; each field is its option.

    Attributes:
        algos: algorithm(s) (required).
        mode: hyperparams (default) or seeds.
        env_id: environment the trials train on.
        env_kwargs: keywords of gym.make as JSON [json] (default: v1's training distribution; none for v0).
        storage: SQLAlchemy URL [url] (default: sqlite:///<out>/sweep.db); a password goes in PGPASSWORD or ~/.pgpass.
        study_name: study name [name] (default: amigo-<algos>-<mode>).
        n_trials: global trial budget over all workers [trials].
        n_jobs: worker processes on this machine [processes].
        seeds: training seeds (seeds mode): a count N (seeds 0..N-1) or two or more seeds [seeds].
        timesteps: training steps per trial [steps].
        eval_freq: steps between evaluations (pruning points) [steps].
        eval_episodes: episodes per evaluation [episodes].
        val_episodes: episodes per validation cell (objective) [episodes].
        val_max_steps: cut validation episodes to this length [steps] (0: the cell's).
        train_seed: training seed of hyperparameter trials [-].
        hyperparams: base YAML [file] (default: agents/hyperparams/<algo>.yml).
        save_best: at the end, write the best COMPLETE trial's hyperparameters under the --env key of this YAML
            file, other keys kept [file] (default: none).
        out: folder of the trials' runs (and the default SQLite file) [dir].
        seed: base of the workers' sampler seeds [-].
        sampler: Optuna sampler.
        pruner: Optuna pruner.
        n_startup_trials: trials before pruning and TPE start [trials].
        heartbeat_interval: time between heartbeats [s].
        grace_period: time without heartbeat before FAIL [s].
        max_retry: retries of a trial whose worker died [retries].
        threads: torch threads per worker [threads].
        enqueue_base: run the base YAML's own values as the first trial (hyperparams mode, an SB3 algorithm).
        worker_index: index of a worker process started by --n-jobs (internal).
        argv: the command line (not an option).
    """

    algos: list[SweepAlgo] = field(metadata=cli("--algo"))
    mode: Mode = "hyperparams"
    env_id: EnvId = field(default="AmigoBot-v0", metadata=cli("--env"))
    env_kwargs: dict[str, Any] | None = field(default=None, metadata=cli(parse=json_object))
    storage: str | None = None
    study_name: str | None = None
    n_trials: int = 20
    n_jobs: int = 1
    seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    timesteps: int = 100_000
    eval_freq: int = 10_000
    eval_episodes: int = 5
    val_episodes: int = 5
    val_max_steps: int = 0
    train_seed: int = 0
    hyperparams: str | None = None
    save_best: str | None = None
    out: str = "runs/sweep"
    seed: int = 0
    sampler: Literal["tpe", "random"] = "tpe"
    pruner: Literal["median", "none"] = "median"
    n_startup_trials: int = 5
    heartbeat_interval: int = 60
    grace_period: int = 120
    max_retry: int = 1
    threads: int = 1
    enqueue_base: bool = False
    worker_index: int = field(default=0, metadata=cli(hidden=True))
    argv: list[str] = field(default_factory=list, metadata=cli(skip=True))

    def __post_init__(self) -> None:
        if len(self.seeds) == 1 and isinstance(self.seeds[0], int) and not isinstance(self.seeds[0], bool):
            self.seeds = list(range(self.seeds[0]))  # a count

    def validate(self) -> None:
        if not self.algos or any(a not in get_args(SweepAlgo) for a in self.algos):
            raise ValueError(f"--algo must be among {list(get_args(SweepAlgo))}, got {self.algos}")
        choices = (("mode", self.mode, get_args(Mode)), ("sampler", self.sampler, ("tpe", "random")),
                   ("pruner", self.pruner, ("median", "none")), ("env", self.env_id, ENV_IDS))  # fmt: skip
        for flag, value, allowed in choices:
            if value not in allowed:
                raise ValueError(f"--{flag} must be one of {list(allowed)}, got {value!r}")
        for name, low in LOWS.items():
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise ValueError(f"--{name.replace('_', '-')} must be an integer >= {low}, got {v!r}")
        try:
            memory = self.storage is not None and _in_memory(self.storage)
        except ImportError:
            raise
        except Exception:  # SQLAlchemy's error for a malformed URL
            raise ValueError(f"--storage must be a SQLAlchemy URL, got {masked_url(str(self.storage))!r}") from None
        sb3, n = [a for a in self.algos if a != FASTPPO], self.study_name
        rules = (
            (self.enqueue_base and (self.mode != "hyperparams" or FASTPPO in self.algos),
             f"--enqueue-base is for --mode hyperparams of an SB3 algorithm, got {self.mode} {self.algos}"),
            (self.mode == "hyperparams" and len(self.algos) != 1,
             f"--mode hyperparams tunes one algorithm, got --algo {' '.join(self.algos)}"),
            (self.env_kwargs is not None and not isinstance(self.env_kwargs, dict),
             f"--env-kwargs must be a JSON object, got {type(self.env_kwargs).__name__}"),
            (self.val_episodes > len(VALIDATION_SEEDS),
             f"--val-episodes must be at most {len(VALIDATION_SEEDS)}, got {self.val_episodes}"),
            (self.mode == "seeds" and (not self.seeds or len(set(self.seeds)) != len(self.seeds)),
             f"--seeds must be a count >= 1 or two or more distinct seeds, got {self.seeds}"),
            (self.save_best is not None and self.mode != "hyperparams",
             f"--save-best applies to --mode hyperparams, not {self.mode}"),
            (FASTPPO in self.algos and self.env_id != "AmigoBot-v1",
             f"--algo fastppo trains the native AmigoBot-v1 vector env: add --env AmigoBot-v1 "
             f"(got --env {self.env_id})"),
            (FASTPPO in self.algos and bool(sb3) and self.hyperparams is not None,
             f"--hyperparams {self.hyperparams}: one file cannot hold the settings of fastppo and of {', '.join(sb3)}; "
             "leave it out (agents/hyperparams/<algo>.yml each)"),
            (n is not None and (not n or n.startswith(".") or ".." in n or bool(re.search(r"[/\\\x00-\x1f\x7f]", n))),
             f"--study-name must be a name, not a path (no '/', '\\', '..', leading '.' or control characters), "
             f"got {n!r}"),
            (memory and self.n_jobs > 1,
             f"--storage {masked_url(str(self.storage))} is an in-memory database, private to each process: with "
             f"--n-jobs {self.n_jobs} the workers would not share one study; use a file (sqlite:///path/sweep.db, the "
             "default) or a server"),
        )  # fmt: skip
        for bad, message in rules:
            if bad:
                raise ValueError(message)
        if FASTPPO in self.algos:  # the settings file, checked with --env-kwargs up front
            from amigo_gym.tools.training.fastppo import FastPPOSettings, load_settings_yaml

            base = load_settings_yaml(self.base_file(FASTPPO))
            try:
                FastPPOSettings.from_json({**base, "env_kwargs": self.train_env_kwargs})
            except (TypeError, ValueError) as exc:
                raise ValueError(f"--algo fastppo: {' '.join(str(exc).split())}") from None

    def base_file(self, algo: str) -> Path:
        return Path(self.hyperparams) if self.hyperparams else HYPERPARAMS_DIR / f"{algo}.yml"

    @property
    def storage_url(self) -> str:
        return self.storage or f"sqlite:///{Path(self.out).resolve() / 'sweep.db'}"

    @property
    def name(self) -> str:
        return self.study_name or f"amigo-{'-'.join(self.algos)}-{self.mode}"

    @property
    def budget(self) -> int:
        """Global number of trials: ``--n-trials``, or the grid's size (seeds mode)."""
        return len(self.algos) * len(self.seeds) if self.mode == "seeds" else self.n_trials

    @property
    def command(self) -> str:
        return "amigo-gym sweep " + " ".join(public_argv(self.argv))

    @property
    def train_env_kwargs(self) -> dict[str, Any]:
        if self.env_kwargs is not None:
            return dict(self.env_kwargs)
        default = TRAINING_DISTRIBUTION["env_kwargs"] if self.env_id == "AmigoBot-v1" else {}
        return json.loads(json.dumps(default))  # type: ignore[no-any-return]


def validate_agent(agent: Any, cells: Sequence[Any]) -> Validation:
    """IQM over ``cells`` of ``agent``'s mean H cross-track RMS [m] on each cell's seeds, and the per-cell values
    (``None``: not finite; then the IQM is NaN)."""
    vals = {sc.name: np.array([r.metrics()["h_rms_m"] for r in run_scenario(agent, sc)], float) for sc in cells}
    per_cell = {name: float(v.mean()) if np.isfinite(v).all() else None for name, v in vals.items()}
    return (math.nan if None in per_cell.values() else float(iqm(np.array([list(per_cell.values())])))), per_cell


# --------------------------------------------------------------------------- storage and study
@contextlib.contextmanager
def _experimental_ok() -> Iterator[None]:
    """Optuna's experimental features used on purpose (heartbeat, its retry, ``fail_stale_trials``): no warning."""
    import optuna

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        yield


def make_storage(cfg: SweepConfig) -> Any:
    """Optuna ``RDBStorage`` with heartbeat, grace period and retry of stale trials (in memory: without them)."""
    import optuna.storages
    from sqlalchemy import event

    url = driver_url(cfg.storage_url)
    sqlite, memory = url.startswith("sqlite"), _in_memory(url)
    if sqlite and not memory:
        Path(url.removeprefix("sqlite:///")).parent.mkdir(parents=True, exist_ok=True)
    # pysqlite's BEGIN is deferred: the listener below takes the write lock at BEGIN
    connect = {"connect_args": {"timeout": 120, "isolation_level": None}}
    kwargs: dict[str, Any] = {"engine_kwargs": connect if sqlite else {}}
    if not memory:  # in memory: no other worker, and the heartbeat's thread would get its own database
        kwargs |= {"heartbeat_interval": cfg.heartbeat_interval, "grace_period": cfg.grace_period}
        if (retry := getattr(optuna.storages, "RetryHeartbeatStaleTrialCallback", None)) is not None:  # Optuna >= 4.9
            with _experimental_ok():
                kwargs["heartbeat_stale_trial_callback"] = retry(max_retry=cfg.max_retry)
        else:
            kwargs["failed_trial_callback"] = optuna.storages.RetryFailedTrialCallback(max_retry=cfg.max_retry)
    for attempt in range(5):  # several processes creating the tables at once may collide once
        try:
            with _experimental_ok():
                storage = optuna.storages.RDBStorage(url, **kwargs)
            break
        except ImportError:
            raise
        except Exception as exc:  # sqlalchemy's errors vary by driver
            last = exc
            time.sleep(0.5 + attempt)
    else:
        detail = scrub(" ".join(f"{type(last).__name__}: {last}".split()), url)
        raise RuntimeError(f"cannot open the storage {masked_url(url)}: {detail}") from None
    if sqlite:
        event.listen(storage.engine, "begin", lambda conn: conn.exec_driver_sql("BEGIN IMMEDIATE"))
    return storage


def driver_url(url: str) -> str:
    """``postgresql://`` with the installed driver (psycopg 3, else psycopg2); ``postgresql+<driver>://`` kept."""
    postgres = url.startswith(("postgresql://", "postgres://"))
    if postgres and importlib.util.find_spec("psycopg") is None and importlib.util.find_spec("psycopg2") is not None:
        return "postgresql+psycopg2://" + url.split("://", 1)[1]
    return url


def _worker_seed(cfg: SweepConfig) -> int:
    host = zlib.crc32(socket.gethostname().encode())
    return int(np.random.SeedSequence([cfg.seed, cfg.worker_index, host, os.getpid()]).generate_state(1)[0])


def open_study(cfg: SweepConfig, storage: Any, sampler_seed: int = 0) -> Any:
    """Create the study (store the command, enqueue a grid) or join it once its creator made it ready;
    ``ValueError``: the existing study is of another mode, environment or objective."""
    import optuna

    sampler: Any = optuna.samplers.RandomSampler(seed=sampler_seed)
    if cfg.sampler == "tpe":
        sampler = optuna.samplers.TPESampler(seed=sampler_seed, n_startup_trials=cfg.n_startup_trials)
    pruner: Any = optuna.pruners.NopPruner()
    if cfg.pruner == "median" and cfg.mode == "hyperparams":
        pruner = optuna.pruners.MedianPruner(n_startup_trials=cfg.n_startup_trials, n_warmup_steps=cfg.eval_freq)
    kw: dict[str, Any] = {"storage": storage, "study_name": cfg.name, "sampler": sampler, "pruner": pruner}
    try:  # exactly one process creates the study (unique name) and enqueues the grid
        study = optuna.create_study(direction="minimize", **kw)
    except optuna.exceptions.DuplicatedStudyError:
        study = optuna.create_study(direction="minimize", load_if_exists=True, **kw)
        deadline = time.monotonic() + READY_TIMEOUT_S
        while not study.user_attrs.get("ready"):
            if time.monotonic() > deadline:
                raise RuntimeError(
                    f"study {cfg.name!r} was created but not made ready within {READY_TIMEOUT_S:g} s (its creator "
                    "stopped while queuing the grid?); delete the study and start again"
                ) from None
            time.sleep(0.5)
        for key, mine in (("mode", cfg.mode), ("env_id", cfg.env_id), ("objective", OBJECTIVE)):
            if (theirs := study.user_attrs.get(key)) is not None and theirs != mine:
                raise ValueError(f"study {cfg.name!r} has {key} {theirs!r}, not {mine!r}") from None
        return study
    attrs = {"command": cfg.command, "argv": public_argv(cfg.argv), "mode": cfg.mode, "algos": cfg.algos,
             "budget": cfg.budget, "env_id": cfg.env_id, "env_kwargs": cfg.train_env_kwargs, "objective": OBJECTIVE,
             "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "host": socket.gethostname()}  # fmt: skip
    for key, value in attrs.items():
        study.set_user_attr(key, value)
    if cfg.mode == "seeds":
        for algo in cfg.algos:
            for s in cfg.seeds:
                study.enqueue_trial({"algo": algo, "seed": s}, user_attrs={"grid": True})
    elif cfg.enqueue_base:
        base = load_hyperparams(cfg.base_file(cfg.algos[0]), cfg.env_id)
        study.enqueue_trial(base_params(cfg.algos[0], base), user_attrs={"baseline": True})
    study.set_user_attr("ready", True)  # joiners wait for the whole grid
    return study


# --------------------------------------------------------------------------- budget, status, abandoned trials
def budget_count(study: Any, before: int | None = None) -> int:
    """Trials that count against the budget: COMPLETE, PRUNED, FAIL by an error, and RUNNING below ``before``."""
    return sum(
        t.state.name in ("COMPLETE", "PRUNED")
        or (t.state.name == "FAIL" and "fail_reason" in t.user_attrs)
        or (before is not None and t.state.name == "RUNNING" and t.number < before)
        for t in study.get_trials(deepcopy=False)
    )


def _exhausted(study: Any, cfg: SweepConfig, running: bool = False) -> bool:
    """No queued trial left and (hyperparams mode) the budget spent, counting RUNNING trials when ``running``."""
    if any(t.state.name == "WAITING" for t in study.get_trials(deepcopy=False)):
        return False
    return cfg.mode == "seeds" or budget_count(study, before=sys.maxsize if running else None) >= cfg.budget


def _abandoned(t: Any) -> bool:
    """Whether trial ``t`` ended FAIL because its worker was stopped or killed (no error of its own)."""
    ua = t.user_attrs
    return bool(t.state.name == "FAIL" and "run_dir" in ua and not {"fail_reason", "over_budget"} & set(ua))


def mark_abandoned(study: Any) -> None:
    """Write (or update the ``retried_as`` of) ``ABANDONED.json`` in the folder of every trial that ended FAIL
    because its worker was stopped or killed."""
    trials = study.get_trials(deepcopy=False)
    for t in trials:
        ua, origin = t.user_attrs, t.system_attrs.get("failed_trial")
        if not _abandoned(t) or not Path(str(ua["run_dir"])).is_dir():
            continue
        if any(u.number == origin != t.number and u.user_attrs.get("run_dir") == ua["run_dir"] for u in trials):
            continue  # a retry that died before it had a folder of its own: the folder is its original's
        retries = [
            u.number
            for u in trials
            if u.number != t.number and t.number in (u.system_attrs.get("failed_trial"), u.user_attrs.get("retry_of"))
        ]
        path = Path(str(ua["run_dir"])) / ABANDONED
        old: Any = {}
        with contextlib.suppress(OSError, ValueError):  # marked before: rewritten only when a retry appeared since
            old = json.loads(path.read_text())
        old = old if isinstance(old, dict) else {}
        if old.get("retried_as") == retries:
            continue
        reason = ua.get("interrupted") or "its worker stopped sending heartbeats (killed, or its machine lost)"
        marked = old.get("marked") or time.strftime("%Y-%m-%dT%H:%M:%S%z")
        atomic_write_json(path, {"study": study.study_name, "trial": t.number, "state": "FAIL", "reason": reason,
                                 "retried_as": retries, "worker": ua.get("worker"), "marked": marked})  # fmt: skip


# --------------------------------------------------------------------------- search spaces
#: off-policy batch sizes sampled over a base YAML of many sub-envs (>= HT_MIN_ENVS), else rl-zoo's
HT_BATCH_SIZES = (512, 1024, 2048, 4096)
HT_MIN_ENVS = 64
BATCH_SIZES = (64, 128, 256)
#: fast-PPO sampling choices (powers of two: every minibatch count divides the batch ``N T``)
FAST_NUM_ENVS = (64, 128, 256, 512, 1024)
FAST_ROLLOUT_STEPS = (8, 16, 32, 64, 128)
FAST_MINIBATCHES = (1, 2, 4, 8, 16, 32)


def batch_choices(base: Mapping[str, Any] | None) -> tuple[int, ...]:
    return HT_BATCH_SIZES if int((base or {}).get("n_envs", 1)) >= HT_MIN_ENVS else BATCH_SIZES


def sample_hyperparams(trial: Any, algo: str, base: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Sampled hyperparameters of ``algo`` (rl-zoo ranges; batch sizes by the base YAML ``base``). The low-pass
    factor is not sampled (the objective, H's error alone, would trade smoothness)."""
    hp: dict[str, Any] = {
        "learning_rate": trial.suggest_float("learning_rate", 1e-5, 3e-3, log=True),
        "gamma": 1.0 - trial.suggest_float("one_minus_gamma", 1e-4, 0.1, log=True),
    }
    if algo == "ppo":
        hp["gae_lambda"] = trial.suggest_float("gae_lambda", 0.8, 1.0)
        hp["ent_coef"] = trial.suggest_float("ent_coef", 1e-8, 1e-2, log=True)
        hp["clip_range"] = trial.suggest_categorical("clip_range", [0.1, 0.2, 0.3])
        hp["n_epochs"] = trial.suggest_int("n_epochs", 1, 10)
    else:
        hp["tau"] = trial.suggest_float("tau", 1e-3, 5e-2, log=True)
        hp["batch_size"] = trial.suggest_categorical("batch_size", list(batch_choices(base)))
        if algo == "td3":
            hp["noise_type"] = "normal"
            hp["noise_std"] = trial.suggest_float("noise_std", 0.05, 0.5)
    return hp


def base_params(algo: str, base: Mapping[str, Any]) -> dict[str, Any]:
    """The Optuna parameters of :func:`sample_hyperparams` that reproduce the base YAML ``base`` (``--enqueue-base``);
    ``ValueError``: a sampled key is missing or outside its range."""
    names = ["learning_rate", "gamma"] + (["gae_lambda", "ent_coef", "clip_range", "n_epochs"] if algo == "ppo"
                                          else ["tau", "batch_size"] + ["noise_std"] * (algo == "td3"))  # fmt: skip
    if missing := [n for n in names if n not in base]:
        raise ValueError(f"--enqueue-base: the base file has no {', '.join(missing)} for {algo}")
    if algo != "ppo" and base["batch_size"] not in batch_choices(base):
        raise ValueError(
            f"--enqueue-base: batch_size must be one of {list(batch_choices(base))}, got {base['batch_size']!r}"
        )
    return {n: base[n] for n in names if n != "gamma"} | {"one_minus_gamma": 1.0 - float(base["gamma"])}


def sample_fastppo(trial: Any, timesteps: int) -> dict[str, Any]:
    """Sampled fast-PPO settings of a trial of ``timesteps`` env-steps: at least :data:`MIN_ITERATIONS` updates."""
    cap = max(timesteps // MIN_ITERATIONS, 1)
    t_min, n_min = min(FAST_ROLLOUT_STEPS), min(FAST_NUM_ENVS)
    n_choices = [n for n in FAST_NUM_ENVS if n * t_min <= cap] or [n_min]
    t_choices = [t for t in FAST_ROLLOUT_STEPS if n_min * t <= cap] or [t_min]
    n = int(trial.suggest_categorical("num_envs", n_choices))
    t_len = int(trial.suggest_categorical("rollout_steps", t_choices))
    t_len = max([t for t in FAST_ROLLOUT_STEPS if t <= t_len and n * t <= cap] or [t_min])
    n_mb = int(trial.suggest_categorical("n_minibatches", FAST_MINIBATCHES))
    return {
        "learning_rate": trial.suggest_float("learning_rate", 3e-5, 3e-3, log=True),
        "epochs": trial.suggest_int("epochs", 1, 10),
        "num_envs": n,
        "rollout_steps": t_len,
        "minibatch_size": n * t_len // n_mb,
        "gamma": 1.0 - trial.suggest_float("one_minus_gamma", 1e-3, 0.1, log=True),
        "gae_lambda": trial.suggest_float("gae_lambda", 0.8, 1.0),
        "clip_coef": trial.suggest_categorical("clip_coef", [0.1, 0.2, 0.3, 0.4]),
        "ent_coef": trial.suggest_float("ent_coef", 1e-8, 1e-2, log=True),
        "log_std_init": trial.suggest_float("log_std_init", -3.0, 0.0),
        "filter_alpha": trial.suggest_float("filter_alpha", 0.2, 1.0),
        "caps_temporal": trial.suggest_float("caps_temporal", 1e-4, 1.0, log=True),
    }


# --------------------------------------------------------------------------- the objective
def _validated_trial(trial: Any, cells: Sequence[Any], fit_and_validate: Callable[[], Validation]) -> float:
    """``fit_and_validate()``'s value, cells in ``validation``; an error (not a prune) or NaN sets ``fail_reason``."""
    import optuna

    try:
        value, per_cell = fit_and_validate()
    except optuna.TrialPruned:
        raise
    except Exception as exc:
        trial.set_user_attr("fail_reason", f"{type(exc).__name__}: {exc}")
        raise
    trial.set_user_attr("validation", {"metric": OBJECTIVE, "seeds": list(cells[0].seeds), "cells": per_cell})
    if not math.isfinite(value):
        trial.set_user_attr("fail_reason", f"validation H RMS IQM {value} (cells: {per_cell})")
    return value


def _objective(cfg: SweepConfig, study: Any, sampler_seed: int) -> Callable[[Any], float]:
    cells = validation_cells(cfg.env_id, cfg.val_episodes, cfg.val_max_steps)

    def objective(trial: Any) -> float:
        mark_abandoned(study)  # trials Optuna just found stale
        trial.set_user_attr("worker", f"{socket.gethostname()}:{os.getpid()}:{cfg.worker_index}")
        trial.set_user_attr("sampler_seed", sampler_seed)
        trial.set_user_attr("command", cfg.command)
        if cfg.mode == "seeds":
            over = "fixed_params" not in study._storage.get_trial_system_attrs(trial._trial_id)
            why = "the grid is exhausted"
        else:
            over = budget_count(study, before=trial.number) >= cfg.budget
            why = f"the global budget of {cfg.budget} trials is reached"
        if over:
            study.stop()
            trial.set_user_attr("over_budget", True)
            raise RuntimeError(f"over budget: {why}")
        algo: str = trial.suggest_categorical("algo", cfg.algos) if cfg.mode == "seeds" else cfg.algos[0]
        seed = int(trial.suggest_categorical("seed", cfg.seeds)) if cfg.mode == "seeds" else cfg.train_seed
        run_dir = (Path(cfg.out) / cfg.name / f"trial_{trial.number}_{trial._trial_id}").resolve()
        trial.set_user_attr("run_dir", str(run_dir))
        try:
            return _validated_trial(trial, cells, lambda: _trial(cfg, study, trial, algo, seed, run_dir, cells))
        except KeyboardInterrupt:  # queue the trial again before the worker stops
            trial.set_user_attr("interrupted", "stopped by SIGTERM or Ctrl-C")
            frozen = study._storage.get_trial(trial._trial_id)
            attrs = {"retry_of": trial.number} | ({"grid": True} if frozen.user_attrs.get("grid") is True else {})
            study.enqueue_trial(dict(frozen.params), user_attrs=attrs, skip_if_exists=False)
            raise

    return objective


def _trial(
    cfg: SweepConfig, study: Any, trial: Any, algo: str, seed: int, run_dir: Path, cells: Sequence[Any]
) -> Validation:
    """One trial: its settings in ``run_dir/hyperparams.yml``; ``amigo-gym train`` or ``train-fast`` (resumed:
    :func:`_resume_fastppo`) in ``run_dir/run``, each evaluation reported to the pruner; the value on ``cells``."""
    import optuna
    import yaml

    from amigo_gym.tools.training import fastppo

    fast, pre = algo == FASTPPO, "eval_" if algo == FASTPPO else ""  # fast-PPO's evaluation keys: eval_<metric>
    hp = fastppo.load_settings_yaml(cfg.base_file(algo)) if fast else load_hyperparams(cfg.base_file(algo), cfg.env_id)
    if cfg.mode == "hyperparams":
        hp |= sample_fastppo(trial, cfg.timesteps) if fast else sample_hyperparams(trial, algo, hp)
    trial.set_user_attr("hyperparams", hp)
    hp_key = fastppo.YAML_ENV_ID if fast else cfg.env_id
    env_kwargs, hp_file, out = cfg.train_env_kwargs, run_dir / "hyperparams.yml", run_dir / "run"
    atomic_write(hp_file, yaml.safe_dump({hp_key: hp}, sort_keys=True), parents=True)
    reported: set[int] = set()
    pruned: list[int] = []

    def report(row: Mapping[str, Any]) -> bool:
        """Report evaluation ``row`` at its env-step (fast-PPO: floored to a multiple of --eval-freq); False: pruned."""
        value, at = float(row.get(f"{pre}h_rms_m", math.nan)), int(row["env_steps" if fast else "timesteps"])
        step = at // cfg.eval_freq * cfg.eval_freq if fast else at
        if not math.isfinite(value):
            raise FloatingPointError(f"evaluation at step {at} gave h_rms_m {value}")
        if cfg.mode == "hyperparams" and step not in reported:
            reported.add(step)
            trial.report(value, step=step)
            if trial.should_prune():
                pruned.append(at)
                return False
        return True

    if fast:
        run = {"seed": seed, "total_steps": cfg.timesteps, "eval_every": cfg.eval_freq, "eval_envs": cfg.eval_episodes,
               "threads": cfg.threads}  # fmt: skip
        s = fastppo.FastPPOSettings.from_json({**hp, **run, "env_kwargs": env_kwargs})
        resumed = _resume_fastppo(study, trial, s, out)
        if resumed is not None:
            trial.set_user_attr("resumed_from", resumed)
        flags = " ".join(f"--{k.replace('_', '-')} {v}" for k, v in run.items())
        command = f"amigo-gym train-fast --out {out} --hyperparams {hp_file} {flags} --env-kwargs "
        command += repr(json.dumps(env_kwargs)) + (" --resume" if resumed else "")
        config = {"settings": {"algo": FASTPPO, "seed": seed, "timesteps": cfg.timesteps, "hyperparams": str(hp_file)},
                  "fastppo_settings": s.to_json(), "env_id": cfg.env_id, "env_kwargs": env_kwargs, "command": command,
                  "resumed_from": resumed, "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}  # fmt: skip
        atomic_write_json(out / "config.json", config, parents=True)  # the trial's training starts now
        with open(out / "train.log", "a", encoding="utf-8") as log:
            record = fastppo.train(s, out, resume=resumed is not None, log=lambda m: print(m, file=log, flush=True),
                                   command=command, after_eval=report)  # fmt: skip
        keys = ("h_rms_m", "h_rms_settled_m", "chatter_settled_rms", "speed_err_settled_rms", "failure")
    else:
        argv = ["--algo", algo, "--seed", str(seed), "--out", str(out), "--timesteps", str(cfg.timesteps),
                "--eval-freq", str(cfg.eval_freq), "--eval-episodes", str(cfg.eval_episodes), "--checkpoint-freq", "0",
                "--threads", str(cfg.threads), "--no-progress", "--hyperparams", str(hp_file), "--env", cfg.env_id,
                "--env-kwargs", json.dumps(env_kwargs)]  # fmt: skip
        record = train(parse_settings(Settings, argv, "amigo-gym train", argv=argv), after_eval=report)
        keys = ("h_rms_m", "speed_err_rms", "failure_rate", "timesteps", "mean_reward")
    last = record.get("last_eval") or {}
    attrs = {f"last_eval_{k}": last[pre + k] for k in keys if pre + k in last}
    attrs |= {"last_eval_timesteps": record["timesteps"], "train_sps": record["train_sps"]} if fast else {}
    for key, value in (attrs | {"wall_time_s": record["wall_time_s"]}).items():
        trial.set_user_attr(key, value)
    if pruned:
        raise optuna.TrialPruned(f"pruned at step {pruned[0]}")
    if fast:
        manifest = out / "run.json"
        verify_sha256(out / "model.zip", str(json.loads(manifest.read_text()).get("sha256")), str(manifest))
    return validate_agent(FastPolicy.load(out / "model.zip") if fast else load_model(find_models(out)[0]), cells)


def _resume_fastppo(study: Any, trial: Any, s: Any, out: Path) -> dict[str, Any] | None:
    """Copy into ``out`` the newest run of an abandoned trial of these params and settings ``s``; its origin or None."""
    found: list[tuple[float, int, Path]] = []  # (checkpoint mtime, trial, run)
    for t in study.get_trials(deepcopy=False):
        if t.number == trial.number or t.params != trial.params or not _abandoned(t):
            continue
        src = Path(str(t.user_attrs["run_dir"])) / "run"
        with contextlib.suppress(OSError, ValueError):
            if json.loads((src / "settings.json").read_text()) == s.to_json():
                found.append(((src / "checkpoint.pt").stat().st_mtime, t.number, src))
    if not found:
        return None
    _, number, src = max(found, key=lambda f: f[0])  # the first of equal times
    out.mkdir(parents=True, exist_ok=True)
    for f in src.iterdir():
        if f.is_file() and f.name not in ("config.json", "run.lock", ABANDONED):
            shutil.copy2(f, out / f.name)
    return {"trial": number, "run_dir": str(src)}


def summarize(study: Any, budget: int | None = None) -> dict[str, Any]:
    """The study's summary, from the study alone (the same for every worker); status ``running`` (a trial RUNNING or
    WAITING), else ``complete`` (seeds: every grid cell COMPLETE; else the budget counted) or ``incomplete``."""
    from optuna.trial import TrialState

    trials = sorted(study.get_trials(deepcopy=False), key=lambda t: t.number)
    best = study.best_trial if any(t.state == TrialState.COMPLETE for t in trials) else None
    attrs = dict(sorted(study.user_attrs.items()))
    if any(t.state.name in ("RUNNING", "WAITING") for t in trials):
        status = "running"
    elif attrs.get("mode") == "seeds":
        cells = {(str(t.params.get("algo")), t.params.get("seed")) for t in trials if t.user_attrs.get("grid") is True}
        done = {(str(t.params.get("algo")), t.params.get("seed")) for t in trials if t.state.name == "COMPLETE"}
        status = "complete" if cells and cells <= done else "incomplete"
    else:
        status = "complete" if budget_count(study) >= int(attrs.get("budget", budget or 0)) else "incomplete"
    return {
        "study": study.study_name,
        "status": status,
        "budget": attrs.get("budget", budget),
        "states": {s.name: sum(t.state == s for t in trials) for s in TrialState},
        "finished": sum(t.state not in (TrialState.RUNNING, TrialState.WAITING) for t in trials),
        "counted": budget_count(study),
        "best": best and {"number": best.number, "value": best.value, "params": best.params},
        "study_attrs": attrs,
        "trials": [
            {
                "number": t.number,
                "state": t.state.name,
                "value": t.value,
                "params": t.params,
                "user_attrs": {k: v for k, v in sorted(t.user_attrs.items()) if k != "command"},
                "failed_trial": t.system_attrs.get("failed_trial"),
            }
            for t in trials
        ],
    }


# --------------------------------------------------------------------------- the winners into a YAML file
def replace_yaml_block(text: str, key: str, block: str) -> str:
    """``text`` (YAML of top-level mappings) with ``key``'s lines and the comment lines above them replaced by
    ``block`` (appended when missing); the rest kept as written."""
    text = text if not text or text.endswith("\n") else text + "\n"
    block = block if block.endswith("\n") else block + "\n"
    names = "|".join(re.escape(q + key + q) for q in ("", "'", '"'))
    m = re.search(rf"^(?:#.*\n)*(?:{names}):.*\n(?:[ \t].*\n|\n)*", text, re.MULTILINE)
    if m is None:
        return text + ("\n" if text and not text.endswith("\n\n") else "") + block
    old = m.group(0)
    blank = "\n" * (len(old) - len(old.rstrip("\n")) - 1)  # the blank lines before the next block stay
    return text[: m.start()] + block + blank + text[m.end() :]


def write_best_yaml(path: str | Path, study: Any, env_id: str) -> dict[str, Any] | None:
    """``--save-best``: the best COMPLETE trial's hyperparameters under ``env_id`` in the YAML file ``path``, with
    comments naming the command, trial and value; the mapping written (``None``: no COMPLETE trial)."""
    import yaml

    trials = study.get_trials(deepcopy=False)
    if not any(t.state.name == "COMPLETE" and t.value is not None for t in trials):
        return None
    best, attrs = study.best_trial, study.user_attrs
    hp = best.user_attrs["hyperparams"]
    seeds = (best.user_attrs.get("validation") or {}).get("seeds") or ["?"]
    finished = sum(t.state.name in ("COMPLETE", "PRUNED") for t in trials)
    block = (
        f"# {env_id}: the best of {finished} finished trials (COMPLETE or PRUNED) of the study {study.study_name!r}\n"
        f"# ({attrs.get('objective', OBJECTIVE)}, held-in validation cells, seeds {seeds[0]}..{seeds[-1]}): "
        f"trial {best.number}, {1e3 * float(best.value):.4g} mm; written {time.strftime('%Y-%m-%d %H:%M %Z')}.\n"
        f"# Found by: {attrs.get('command', '?')}\n"
    ) + yaml.safe_dump({env_id: hp}, sort_keys=False, default_flow_style=None)
    path = Path(path)
    old = path.read_text(encoding="utf-8") if path.is_file() else ""
    new = replace_yaml_block(old, env_id, block)
    want = (yaml.safe_load(old) or {}) | {env_id: hp}
    if yaml.safe_load(new) != want:  # pragma: no cover - a file layout replace_yaml_block does not understand
        raise ValueError(f"--save-best {path}: could not replace the {env_id} block of this file safely")
    atomic_write(path, new, parents=True)
    return dict(hp)


# --------------------------------------------------------------------------- command line
def _describe(code: int) -> str:
    name = signal.Signals(-code).name if -code in signal.valid_signals() else f"signal {-code}"
    return f"exit status {code}" if code >= 0 else f"killed by {name}"


def _run(cfg: SweepConfig) -> int:
    """The command: the study opened, then ``--n-jobs`` worker processes of this command (SIGTERM'd on a stop), or
    this process as the one worker (it joins the study and runs trials until the budget or the grid is spent); then
    the summary, the ``--save-best`` file and the exit status."""
    import optuna

    failed: list[str] = []
    procs: list[subprocess.Popen[bytes]] = []
    study: Any = None  # this process's own study when it has one (an in-memory storage lives only in it)
    interrupted = False

    def stop_when_spent(st: Any, _t: Any) -> None:
        if _exhausted(st, cfg, running=True):
            st.stop()

    with handling(signal.default_int_handler, signal.SIGTERM):
        try:
            if cfg.n_jobs > 1:
                storage = make_storage(cfg)
                open_study(cfg, storage, _worker_seed(cfg))
                storage.engine.dispose()
                try:
                    for i in range(cfg.n_jobs):
                        args = [*cfg.argv, "--n-jobs", "1", "--worker-index", str(i)]
                        procs.append(subprocess.Popen([sys.executable, "-m", "amigo_gym.tools.cli", "sweep", *args]))
                    codes = [p.wait() for p in procs]
                except BaseException:
                    for p in procs:
                        if p.poll() is None:
                            p.send_signal(signal.SIGTERM)
                    for p in procs:
                        p.wait()
                    raise
                failed = [f"worker {i}: {_describe(c)}" for i, c in enumerate(codes) if c not in (0, INTERRUPTED)]
                interrupted = INTERRUPTED in codes
            else:
                sampler_seed = _worker_seed(cfg)
                study = open_study(cfg, make_storage(cfg), sampler_seed)
                study.set_user_attr(f"worker:{socket.gethostname()}:{os.getpid()}", cfg.command)
                with _experimental_ok():
                    optuna.storages.fail_stale_trials(study)  # requeue dead workers' trials before checking the budget
                mark_abandoned(study)
                if not _exhausted(study, cfg):
                    errors = (ValueError, RuntimeError, FloatingPointError, FileNotFoundError)  # a trial's: FAIL, go on
                    study.optimize(_objective(cfg, study, sampler_seed), catch=errors, callbacks=[stop_when_spent])
        except KeyboardInterrupt:
            interrupted = True
    study = study or optuna.load_study(study_name=cfg.name, storage=make_storage(cfg))
    mark_abandoned(study)
    summary, folder = summarize(study, cfg.budget), Path(cfg.out) / cfg.name
    with RunLock(folder, name="summary.lock", wait=60.0):  # summary.json, unless the one there saw more finished trials
        newer = False
        with contextlib.suppress(OSError, ValueError, TypeError, AttributeError):  # no readable summary there
            newer = int(json.loads((folder / "summary.json").read_text()).get("finished", -1)) > summary["finished"]
        if not newer:
            atomic_write_json(folder / "summary.json", summary, parents=True)
    status, best = summary["status"], summary["best"]
    counted = f"counted {summary['counted']} of budget {summary['budget']}"
    print(f"study {cfg.name}: {status}; {summary['states']}; {counted}")
    if best is not None:
        print(f"best trial {best['number']}: {best['value']:.4g} {best['params']}")
    if status == "running":
        print("the study is still running (trials RUNNING or WAITING on other workers)")
    if cfg.save_best is not None:
        saved = write_best_yaml(cfg.save_best, study, cfg.env_id) is not None
        print(f"wrote the best trial's hyperparameters under {cfg.env_id} in {cfg.save_best}" if saved
              else f"no COMPLETE trial yet: {cfg.save_best} not written")  # fmt: skip
    error = "; ".join(failed) + "; rerun to continue the study" if failed else None  # a worker that died comes first
    if error is None and not interrupted and status == "incomplete":
        error = "the study is incomplete (trials failed or were lost); see summary.json"
    if error is not None:
        print(f"amigo-gym sweep: error: {error}", file=sys.stderr)
        return 1
    if interrupted:
        print("amigo-gym sweep: stopped; the interrupted trial is queued again: rerun to continue", file=sys.stderr)
        return INTERRUPTED
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym sweep``."""
    args = list(sys.argv[1:] if argv is None else argv)
    cfg = parse_settings(SweepConfig, args, "amigo-gym sweep", "Optuna studies over amigo-gym training.", argv=args)

    def guarded() -> int:
        try:
            return _run(cfg)
        except (KeyboardInterrupt, FileNotFoundError, FileExistsError):
            raise
        except ValueError as exc:  # status 2, one line, password masked
            raise ValueError(scrub(str(exc), cfg.storage_url)) from None
        except Exception as exc:
            if os.environ.get("AMIGO_GYM_TRACEBACK"):
                raise
            detail = scrub(" ".join(f"{type(exc).__name__}: {exc}".split()), cfg.storage_url)
            print(f"amigo-gym sweep: error: {detail}", file=sys.stderr)
            return 1

    return run_guarded(guarded, "amigo-gym sweep")
