"""``amigo-gym sweep``: Optuna studies over the training of :mod:`amigo_gym.training.train`, on one or many machines.

Usage (flag names as in rl-baselines3-zoo where they exist)::

    # hyperparameters of PPO, 2 worker processes on this machine, a global budget of 50 trials
    amigo-gym sweep --algo ppo --n-trials 50 --n-jobs 2 --timesteps 100000 --out runs/sweep
    # a multi-seed training grid: every (algo, seed) exactly once
    amigo-gym sweep --mode seeds --algo ppo sac td3 --seeds 0 1 2 3 4 --n-jobs 2 --out runs/grid
    # many machines: every machine runs the same command against one PostgreSQL database and joins
    amigo-gym sweep --algo sac --storage postgresql://user:pw@db-host/amigo --study-name sac-hp --n-trials 200

Storage: embedded SQLite by default (``sqlite:///<out>/sweep.db``: one machine, several worker
processes; transactions take the write lock at their start, ``BEGIN IMMEDIATE``, so two workers never
claim the same queued trial), or any SQLAlchemy URL such as ``postgresql://...`` for many machines
(install the ``bench`` extra for the ``psycopg2-binary`` driver). Every worker opens the study with
``create_study(load_if_exists=True)``; the process that actually creates it stores the command line,
the mode and the budget as study user attributes (each worker adds ``worker:<host>:<pid>`` with its
command, and each trial records its worker, sampler seed and run directory).

Modes:

* ``hyperparams``: each trial samples the algorithm's hyperparameters (:func:`sample_hyperparams`; the
  rest, e.g. ``n_steps``, ``buffer_size``, ``policy_kwargs``, comes from ``--hyperparams``, default
  ``agents/hyperparams/<algo>.yml``), trains ``--timesteps`` steps with ``--train-seed`` and returns the
  mean reward of the last periodic evaluation (maximised). The evaluations every ``--eval-freq`` steps
  are reported to the pruner (median pruner by default), which may stop a trial early (PRUNED).
* ``seeds``: the study's creator enqueues the grid ``--algo x --seeds`` once (fixed parameters
  ``algo`` and ``seed``, YAML hyperparameters); workers take queued trials until none is left. No
  pruning: every seed trains to the end.

Global budget: ``--n-trials`` counts the study's trials that ran to an end, COMPLETE, PRUNED or
FAIL through an error of the objective (a NaN evaluation is an error: FAIL, never PRUNED), on all
machines together (``MaxTrialsCallback`` stops the COMPLETE/PRUNED part; a check at the start of each
trial also counts the RUNNING trials with lower numbers, so concurrent workers cannot overshoot). A
trial that loses that race ends FAIL with the user attribute ``over_budget`` and does not count (in
seeds mode: a trial that is not from the grid). ``--n-jobs`` worker processes run on this machine.

Killed workers: RDB storages get a heartbeat (``--heartbeat-interval``, default 60 s) with a grace
period (``--grace-period``, 120 s): a trial whose worker stopped beating (SIGKILL, a lost machine) is
set FAIL by the next worker that starts a trial, and ``RetryHeartbeatStaleTrialCallback`` (Optuna >= 4.9;
``RetryFailedTrialCallback`` before) re-queues it with the same parameters (``--max-retry``, default 1;
the new trial's system attribute ``failed_trial`` names the original). A worker stopped by SIGTERM or
Ctrl-C marks its trial FAIL at once. Sampler seeds differ per worker: they are derived from ``--seed``,
the host name, the process id and the worker index.

Browse a study with optuna-dashboard (``pip install optuna-dashboard``, documentation only)::

    optuna-dashboard sqlite:///runs/sweep/sweep.db            # then open http://127.0.0.1:8080
    optuna-dashboard postgresql://user:pw@db-host/amigo

Each trial's training run is in ``<out>/<study>/trial_<number>_<id>/`` (config, TensorBoard logs with
the task metrics, ``eval.json``, models).

Imports optuna (and PyYAML) only when run; may import :mod:`amigo_gym.training.train`.
"""

from __future__ import annotations

import math
import os
import signal
import socket
import subprocess
import sys
import time
import warnings
import zlib
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from amigo_gym.cli import OneLineParser, run_guarded
from amigo_gym.io import atomic_write, atomic_write_json

__all__ = [
    "SweepConfig",
    "budget_count",
    "driver_url",
    "main",
    "make_storage",
    "open_study",
    "run_worker",
    "sample_hyperparams",
]

ALGOS = ("ppo", "sac", "td3")
MODES = ("hyperparams", "seeds")


@dataclass
class SweepConfig:
    """Settings of one ``amigo-gym sweep`` command (see the module docstring)."""

    algos: list[str]
    mode: str = "hyperparams"
    storage: str | None = None
    study_name: str | None = None
    n_trials: int = 20
    n_jobs: int = 1
    seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    timesteps: int = 100_000
    eval_freq: int = 10_000
    eval_episodes: int = 5
    train_seed: int = 0
    hyperparams: str | None = None
    out: str = "runs/sweep"
    seed: int = 0
    sampler: str = "tpe"
    pruner: str = "median"
    n_startup_trials: int = 5
    heartbeat_interval: int = 60
    grace_period: int = 120
    max_retry: int = 1
    threads: int = 1
    worker_index: int = 0
    argv: list[str] = field(default_factory=list)

    def validate(self) -> None:
        """Raise ``ValueError`` naming a bad setting."""
        if not self.algos or any(a not in ALGOS for a in self.algos):
            raise ValueError(f"--algo must be among {list(ALGOS)}, got {self.algos}")
        if self.mode not in MODES:
            raise ValueError(f"--mode must be one of {list(MODES)}, got {self.mode!r}")
        if self.mode == "hyperparams" and len(self.algos) != 1:
            raise ValueError(f"--mode hyperparams tunes one algorithm, got --algo {' '.join(self.algos)}")
        if self.sampler not in ("tpe", "random"):
            raise ValueError(f"--sampler must be 'tpe' or 'random', got {self.sampler!r}")
        if self.pruner not in ("median", "none"):
            raise ValueError(f"--pruner must be 'median' or 'none', got {self.pruner!r}")
        for name, low in (
            ("n_trials", 1),
            ("n_jobs", 1),
            ("timesteps", 1),
            ("eval_freq", 1),
            ("eval_episodes", 1),
            ("heartbeat_interval", 1),
            ("grace_period", 1),
            ("max_retry", 0),
            ("threads", 1),
            ("n_startup_trials", 0),
            ("worker_index", 0),
            ("train_seed", 0),
        ):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < low:
                raise ValueError(f"--{name.replace('_', '-')} must be an integer >= {low}, got {v!r}")
        if self.mode == "seeds" and (not self.seeds or len(set(self.seeds)) != len(self.seeds)):
            raise ValueError(f"--seeds must be distinct integers, got {self.seeds}")

    @property
    def storage_url(self) -> str:
        """``--storage``, default ``sqlite:///<out>/sweep.db``."""
        return self.storage or f"sqlite:///{Path(self.out).resolve() / 'sweep.db'}"

    @property
    def name(self) -> str:
        """``--study-name``, default ``amigo-<algos>-<mode>``."""
        return self.study_name or f"amigo-{'-'.join(self.algos)}-{self.mode}"

    @property
    def budget(self) -> int:
        """Global number of trials: ``--n-trials``, or the grid's size in seeds mode."""
        return len(self.algos) * len(self.seeds) if self.mode == "seeds" else self.n_trials

    @property
    def command(self) -> str:
        """The command line, as typed."""
        return "amigo-gym sweep " + " ".join(self.argv)


# --------------------------------------------------------------------------- storage and study
def make_storage(cfg: SweepConfig) -> Any:
    """Optuna ``RDBStorage`` with heartbeat, grace period and retry of stale trials (module docstring)."""
    import optuna.storages as st

    url = driver_url(cfg.storage_url)
    engine_kwargs: dict[str, Any] = {}
    sqlite = url.startswith("sqlite")
    if sqlite:
        Path(url.removeprefix("sqlite:///")).parent.mkdir(parents=True, exist_ok=True)
        # pysqlite's own BEGIN is deferred (reads outside the write lock); take the lock at BEGIN
        engine_kwargs["connect_args"] = {"timeout": 120, "isolation_level": None}
    retry_cls = getattr(st, "RetryHeartbeatStaleTrialCallback", None)
    kwargs: dict[str, Any] = {"heartbeat_interval": cfg.heartbeat_interval, "grace_period": cfg.grace_period}
    if retry_cls is not None:
        kwargs["heartbeat_stale_trial_callback"] = retry_cls(max_retry=cfg.max_retry)
    else:  # Optuna < 4.9
        kwargs["failed_trial_callback"] = st.RetryFailedTrialCallback(max_retry=cfg.max_retry)
    last: Exception | None = None
    for attempt in range(5):  # several processes creating the tables at once may collide once
        try:
            storage = st.RDBStorage(url, engine_kwargs=engine_kwargs, **kwargs)
            break
        except ImportError:
            raise
        except Exception as exc:  # sqlalchemy's errors vary by driver
            last = exc
            time.sleep(0.5 + attempt)
    else:
        raise RuntimeError(f"cannot open the storage {url}: {last}") from last
    if sqlite:
        from sqlalchemy import event

        @event.listens_for(storage.engine, "begin")
        def _begin_immediate(conn: Any) -> None:
            conn.exec_driver_sql("BEGIN IMMEDIATE")

    return storage


def driver_url(url: str) -> str:
    """``postgresql://`` with the driver that is installed: SQLAlchemy 2.1 defaults to psycopg 3, the
    ``bench`` extra installs ``psycopg2-binary``; an explicit ``postgresql+<driver>://`` is kept."""
    if url.startswith(("postgresql://", "postgres://")):
        import importlib.util

        if importlib.util.find_spec("psycopg") is None and importlib.util.find_spec("psycopg2") is not None:
            return "postgresql+psycopg2://" + url.split("://", 1)[1]
    return url


def _worker_seed(cfg: SweepConfig) -> int:
    host = zlib.crc32(socket.gethostname().encode())
    return int(np.random.SeedSequence([cfg.seed, cfg.worker_index, host, os.getpid()]).generate_state(1)[0])


def open_study(cfg: SweepConfig, storage: Any, sampler_seed: int = 0) -> Any:
    """Create the study or join it (``load_if_exists``); its creator stores the command and enqueues a grid."""
    import optuna

    sampler: Any
    if cfg.sampler == "tpe":
        sampler = optuna.samplers.TPESampler(seed=sampler_seed, n_startup_trials=cfg.n_startup_trials)
    else:
        sampler = optuna.samplers.RandomSampler(seed=sampler_seed)
    pruner: Any = optuna.pruners.NopPruner()
    if cfg.pruner == "median" and cfg.mode == "hyperparams":
        pruner = optuna.pruners.MedianPruner(n_startup_trials=cfg.n_startup_trials, n_warmup_steps=cfg.eval_freq)
    try:  # exactly one process creates the study (unique name in the database) and enqueues the grid
        study = optuna.create_study(
            storage=storage, study_name=cfg.name, sampler=sampler, pruner=pruner, direction="maximize"
        )
        created = True
    except optuna.exceptions.DuplicatedStudyError:
        study = optuna.create_study(
            storage=storage,
            study_name=cfg.name,
            sampler=sampler,
            pruner=pruner,
            direction="maximize",
            load_if_exists=True,
        )
        created = False
    if created:
        for key, value in (
            ("command", cfg.command),
            ("argv", cfg.argv),
            ("mode", cfg.mode),
            ("algos", cfg.algos),
            ("budget", cfg.budget),
            ("created", time.strftime("%Y-%m-%dT%H:%M:%S%z")),
            ("host", socket.gethostname()),
        ):
            study.set_user_attr(key, value)
        if cfg.mode == "seeds":
            for algo in cfg.algos:
                for s in cfg.seeds:
                    study.enqueue_trial({"algo": algo, "seed": s}, user_attrs={"grid": True})
    else:
        mode = study.user_attrs.get("mode")
        if mode is not None and mode != cfg.mode:
            raise ValueError(f"study {cfg.name!r} is a {mode} study, not {cfg.mode}")
    return study


# --------------------------------------------------------------------------- budget
def _counted(t: Any) -> bool:
    from optuna.trial import TrialState

    if t.state in (TrialState.COMPLETE, TrialState.PRUNED):
        return True
    return bool(t.state == TrialState.FAIL and "fail_reason" in t.user_attrs)


def budget_count(study: Any, before: int | None = None) -> int:
    """Trials that count against the budget: ended (COMPLETE, PRUNED, FAIL by an error), plus RUNNING trials
    with a number below ``before`` (``None``: no RUNNING trial)."""
    from optuna.trial import TrialState

    n = 0
    for t in study.get_trials(deepcopy=False):
        if _counted(t) or (before is not None and t.state == TrialState.RUNNING and t.number < before):
            n += 1
    return n


def _exhausted(study: Any, cfg: SweepConfig, running: bool = False) -> bool:
    """No queued grid trial left (seeds mode), or the budget is spent (``running``: counting RUNNING trials)."""
    from optuna.trial import TrialState

    if cfg.mode == "seeds":
        return not study.get_trials(deepcopy=False, states=(TrialState.WAITING,))
    return budget_count(study, before=sys.maxsize if running else None) >= cfg.budget


class _OverBudget(Exception):
    """This trial lost the race for the last place in the budget (or is not from the grid)."""


# --------------------------------------------------------------------------- the objective
def sample_hyperparams(trial: Any, algo: str) -> dict[str, Any]:
    """Sampled hyperparameters of ``algo`` (rl-zoo style ranges; the other keys come from the base YAML)."""
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
        hp["batch_size"] = trial.suggest_categorical("batch_size", [64, 128, 256])
        if algo == "td3":
            hp["noise_type"] = "normal"
            hp["noise_std"] = trial.suggest_float("noise_std", 0.05, 0.5)
    return hp


def _objective(cfg: SweepConfig, study: Any, sampler_seed: int) -> Any:
    import optuna
    import yaml

    from amigo_gym.training.train import HYPERPARAMS_DIR, Settings, load_hyperparams, train

    def objective(trial: Any) -> float:
        trial.set_user_attr("worker", f"{socket.gethostname()}:{os.getpid()}:{cfg.worker_index}")
        trial.set_user_attr("sampler_seed", sampler_seed)
        trial.set_user_attr("command", cfg.command)
        if cfg.mode == "seeds":
            if "fixed_params" not in study._storage.get_trial_system_attrs(trial._trial_id):
                study.stop()
                trial.set_user_attr("over_budget", True)
                raise _OverBudget("the grid is exhausted")
            algo = str(trial.suggest_categorical("algo", cfg.algos))
            seed = int(trial.suggest_categorical("seed", cfg.seeds))
        else:
            if budget_count(study, before=trial.number) >= cfg.budget:
                study.stop()
                trial.set_user_attr("over_budget", True)
                raise _OverBudget(f"the global budget of {cfg.budget} trials is reached")
            algo, seed = cfg.algos[0], cfg.train_seed
        run_dir = Path(cfg.out) / cfg.name / f"trial_{trial.number}_{trial._trial_id}"
        trial.set_user_attr("run_dir", str(run_dir))
        base_file = Path(cfg.hyperparams) if cfg.hyperparams else HYPERPARAMS_DIR / f"{algo}.yml"
        hp = load_hyperparams(base_file)
        if cfg.mode == "hyperparams":
            hp |= sample_hyperparams(trial, algo)
        hp_file = run_dir / "hyperparams.yml"
        atomic_write(hp_file, yaml.safe_dump({"AmigoBot-v0": hp}, sort_keys=True), parents=True)
        pruned = False

        def after_eval(entry: dict[str, Any]) -> bool:
            nonlocal pruned
            value = float(entry["mean_reward"])
            if not math.isfinite(value):
                raise FloatingPointError(f"evaluation at step {entry['timesteps']} gave mean reward {value}")
            if cfg.mode == "hyperparams":
                trial.report(value, step=int(entry["timesteps"]))
                if trial.should_prune():
                    pruned = True
                    return False
            return True

        s = Settings(
            algo=algo,
            seed=seed,
            out=str(run_dir / "run"),
            timesteps=cfg.timesteps,
            eval_freq=cfg.eval_freq,
            eval_episodes=cfg.eval_episodes,
            checkpoint_freq=0,
            threads=cfg.threads,
            progress=False,
            hyperparams=str(hp_file),
            argv=["--algo", algo, "--seed", str(seed), "--hyperparams", str(hp_file)],
        )
        try:
            record = train(s, after_eval=after_eval)
        except (ValueError, RuntimeError, FloatingPointError, FileNotFoundError) as exc:
            trial.set_user_attr("fail_reason", f"{type(exc).__name__}: {exc}")
            raise
        last = record.get("last_eval") or {}
        for key in ("h_rms_m", "speed_err_rms", "failure_rate", "timesteps"):
            if key in last:
                trial.set_user_attr(f"last_eval_{key}", last[key])
        trial.set_user_attr("wall_time_s", record["wall_time_s"])
        if pruned:
            raise optuna.TrialPruned(f"pruned at step {last.get('timesteps')}")
        value = float(last.get("mean_reward", math.nan))
        if not math.isfinite(value):
            trial.set_user_attr("fail_reason", f"final mean reward {value}")
        return value  # NaN: Optuna marks the trial FAIL (never PRUNED)

    return objective


def run_worker(cfg: SweepConfig) -> dict[str, Any]:
    """One worker: join the study and run trials until the budget (or the grid) is used up; a summary."""
    import optuna
    from optuna.study import MaxTrialsCallback
    from optuna.trial import TrialState

    cfg.validate()
    sampler_seed = _worker_seed(cfg)
    storage = make_storage(cfg)
    study = open_study(cfg, storage, sampler_seed)
    study.set_user_attr(f"worker:{socket.gethostname()}:{os.getpid()}", cfg.command)
    with warnings.catch_warnings():  # experimental in Optuna; used as optimize() itself uses it
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        optuna.storages.fail_stale_trials(study)  # requeue trials of dead workers before checking the budget

    def stop_when_spent(st: Any, _t: Any) -> None:
        if _exhausted(st, cfg, running=True):
            st.stop()

    if not _exhausted(study, cfg):
        study.optimize(
            _objective(cfg, study, sampler_seed),
            n_trials=None,
            catch=(ValueError, RuntimeError, FloatingPointError, FileNotFoundError, _OverBudget),
            callbacks=[MaxTrialsCallback(cfg.budget, states=(TrialState.COMPLETE, TrialState.PRUNED)), stop_when_spent],
        )
    return summarize(study)


def summarize(study: Any) -> dict[str, Any]:
    """States, the counted trials, the best trial and each trial's parameters and value."""
    from optuna.trial import TrialState

    trials = study.get_trials(deepcopy=False)
    states = {s.name: sum(t.state == s for t in trials) for s in TrialState}
    best = None
    if any(t.state == TrialState.COMPLETE for t in trials):
        b = study.best_trial
        best = {"number": b.number, "value": b.value, "params": b.params}
    return {
        "study": study.study_name,
        "states": states,
        "counted": budget_count(study),
        "best": best,
        "trials": [
            {
                "number": t.number,
                "state": t.state.name,
                "value": t.value,
                "params": t.params,
                "user_attrs": {k: v for k, v in t.user_attrs.items() if k != "command"},
            }
            for t in trials
        ],
    }


# --------------------------------------------------------------------------- command line
def parse_args(argv: Sequence[str]) -> SweepConfig:
    """Settings from the command line (``amigo-gym sweep --help``)."""
    p = OneLineParser(prog="amigo-gym sweep", description="Optuna studies over amigo-gym training runs.")
    p.add_argument("--algo", nargs="+", required=True, choices=ALGOS, help="algorithm(s) (required)")
    p.add_argument("--mode", choices=MODES, default="hyperparams", help="hyperparams (default) or seeds")
    p.add_argument("--storage", default=None, help="SQLAlchemy URL [url] (default: sqlite:///<out>/sweep.db)")
    p.add_argument("--study-name", default=None, help="study name [name] (default: amigo-<algos>-<mode>)")
    p.add_argument("--n-trials", type=int, default=20, help="global trial budget over all workers [trials]")
    p.add_argument("--n-jobs", type=int, default=1, help="worker processes on this machine [processes]")
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4], help="training seeds (seeds mode) [seeds]")
    p.add_argument("--timesteps", type=int, default=100_000, help="training steps per trial [steps]")
    p.add_argument("--eval-freq", type=int, default=10_000, help="steps between evaluations (pruning points) [steps]")
    p.add_argument("--eval-episodes", type=int, default=5, help="episodes per evaluation [episodes]")
    p.add_argument("--train-seed", type=int, default=0, help="training seed of hyperparameter trials [-]")
    p.add_argument("--hyperparams", default=None, help="base YAML [file] (default: agents/hyperparams/<algo>.yml)")
    p.add_argument("--out", default="runs/sweep", help="folder of the trials' runs (and the default SQLite file) [dir]")
    p.add_argument("--seed", type=int, default=0, help="base of the workers' sampler seeds [-]")
    p.add_argument("--sampler", choices=("tpe", "random"), default="tpe", help="Optuna sampler")
    p.add_argument("--pruner", choices=("median", "none"), default="median", help="Optuna pruner")
    p.add_argument("--n-startup-trials", type=int, default=5, help="trials before pruning and TPE start [trials]")
    p.add_argument("--heartbeat-interval", type=int, default=60, help="time between heartbeats [s]")
    p.add_argument("--grace-period", type=int, default=120, help="time without heartbeat before FAIL [s]")
    p.add_argument("--max-retry", type=int, default=1, help="retries of a trial whose worker died [retries]")
    p.add_argument("--threads", type=int, default=1, help="torch threads per worker [threads]")
    p.add_argument("--worker-index", type=int, default=0, help=argparse_suppress())
    a = p.parse_args(list(argv))
    cfg = SweepConfig(
        algos=list(a.algo),
        mode=a.mode,
        storage=a.storage,
        study_name=a.study_name,
        n_trials=a.n_trials,
        n_jobs=a.n_jobs,
        seeds=list(a.seeds),
        timesteps=a.timesteps,
        eval_freq=a.eval_freq,
        eval_episodes=a.eval_episodes,
        train_seed=a.train_seed,
        hyperparams=a.hyperparams,
        out=a.out,
        seed=a.seed,
        sampler=a.sampler,
        pruner=a.pruner,
        n_startup_trials=a.n_startup_trials,
        heartbeat_interval=a.heartbeat_interval,
        grace_period=a.grace_period,
        max_retry=a.max_retry,
        threads=a.threads,
        worker_index=a.worker_index,
        argv=[x for x in argv],
    )
    try:
        cfg.validate()
    except ValueError as exc:
        p.error(str(exc))
    return cfg


def argparse_suppress() -> str:
    """``argparse.SUPPRESS`` (hides an internal option from ``--help``)."""
    import argparse

    return argparse.SUPPRESS


def _spawn_workers(cfg: SweepConfig) -> int:
    """Open the study once (tables, grid), then run ``n_jobs`` worker processes of this command and wait."""
    storage = make_storage(cfg)
    open_study(cfg, storage, _worker_seed(cfg))
    storage.engine.dispose()
    base = [a for a in cfg.argv]
    procs: list[subprocess.Popen[bytes]] = []
    try:
        for i in range(cfg.n_jobs):
            args = [*base, "--n-jobs", "1", "--worker-index", str(i)]
            procs.append(subprocess.Popen([sys.executable, "-m", "amigo_gym.cli", "sweep", *args]))
        codes = [p.wait() for p in procs]
    except BaseException:
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in procs:
            p.wait()
        raise
    return max(codes) if codes else 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``amigo-gym sweep``."""
    args = list(sys.argv[1:] if argv is None else argv)
    cfg = parse_args(args)

    def run() -> int:
        if cfg.n_jobs > 1:
            rc = _spawn_workers(cfg)
            storage = make_storage(cfg)
            import optuna

            summary = summarize(optuna.load_study(study_name=cfg.name, storage=storage))
        else:
            rc = 0
            summary = run_worker(cfg)
        atomic_write_json(Path(cfg.out) / cfg.name / "summary.json", summary | {"config": asdict(cfg)}, parents=True)
        print(f"study {summary['study']}: {summary['states']}; counted {summary['counted']} of budget {cfg.budget}")
        if summary["best"] is not None:
            print(f"best trial {summary['best']['number']}: {summary['best']['value']:.4g} {summary['best']['params']}")
        return rc

    return run_guarded(run, "amigo-gym sweep")


if __name__ == "__main__":
    sys.exit(main())
