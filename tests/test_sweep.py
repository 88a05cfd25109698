"""``amigo-gym sweep`` with real storages: SQLite with two worker processes, a real PostgreSQL 15 server with two
concurrent workers (as two machines would), and a worker killed mid-trial (heartbeat -> FAIL -> retried).

Training budgets are tiny (PPO, one rollout of 32 steps, one evaluation episode, a 16-unit network); each
worker process pays torch's import once.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

optuna = pytest.importorskip("optuna")
from optuna.trial import TrialState  # noqa: E402

from amigo_gym.training.sweep import driver_url  # noqa: E402

TINY = "AmigoBot-v0:\n  n_steps: 32\n  batch_size: 32\n  n_epochs: 1\n  policy_kwargs:\n    net_arch: [16]\n"
PG_ROOT = Path("/usr/lib/postgresql")  # Debian's layout: <version>/bin/initdb (15 here; any version works)


def _common(tmp: Path, *extra: str) -> list[str]:
    hp = tmp / "tiny.yml"
    hp.write_text(TINY)
    return [
        "--algo",
        "ppo",
        "--timesteps",
        "32",
        "--eval-freq",
        "32",
        "--eval-episodes",
        "1",
        "--hyperparams",
        str(hp),
        "--out",
        str(tmp / "out"),
        "--n-startup-trials",
        "1",
        "--val-episodes",
        "1",
        "--val-max-steps",
        "20",
        *extra,
    ]


def _sweep(args: list[str], **kw: object) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    return subprocess.Popen(  # type: ignore[call-overload, no-any-return]
        [sys.executable, "-m", "amigo_gym.cli", "sweep", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        **kw,
    )


def _finish(p: subprocess.Popen[str], timeout: float = 120) -> str:
    out, _ = p.communicate(timeout=timeout)
    assert p.returncode == 0, out[-3000:]
    return out


def _no_duplicates(trials: list[optuna.trial.FrozenTrial]) -> None:
    numbers = [t.number for t in trials]
    assert len(numbers) == len(set(numbers)), numbers
    ran = [t for t in trials if t.state in (TrialState.COMPLETE, TrialState.PRUNED)]
    dirs = [t.user_attrs["run_dir"] for t in ran]
    assert len(dirs) == len(set(dirs))


def test_sqlite_two_worker_processes_share_the_budget(tmp_path: Path) -> None:
    out = _finish(_sweep([*_common(tmp_path), "--n-trials", "4", "--n-jobs", "2", "--study-name", "hp"]))
    storage = f"sqlite:///{tmp_path / 'out' / 'sweep.db'}"
    study = optuna.load_study(study_name="hp", storage=storage)
    trials = study.get_trials()
    _no_duplicates(trials)
    ran = [t for t in trials if t.state in (TrialState.COMPLETE, TrialState.PRUNED)]
    assert len(ran) == 4, [(t.number, t.state, t.user_attrs) for t in trials]
    others = [t for t in trials if t not in ran]
    assert all(t.state == TrialState.FAIL and t.user_attrs.get("over_budget") is True for t in others), others
    assert not [t for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    workers = {t.user_attrs["worker"]: t.user_attrs["sampler_seed"] for t in ran}
    assert len(set(workers.values())) == len(workers)  # distinct sampler seeds per worker
    assert "--n-trials 4" in study.user_attrs["command"] and study.user_attrs["budget"] == 4
    assert sum(k.startswith("worker:") for k in study.user_attrs) == 2
    for t in ran:  # pruning on periodic evaluations: one intermediate value per evaluation
        assert set(t.intermediate_values) == {32}
    assert (tmp_path / "out" / "hp" / "summary.json").is_file()
    assert "counted 4 of budget 4" in out


# --------------------------------------------------------------------------- PostgreSQL
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def postgres() -> Iterator[str]:
    """A throw-away PostgreSQL 15 server on 127.0.0.1 (as user postgres when run as root); its URL."""
    pytest.importorskip("psycopg2")
    found = sorted(PG_ROOT.glob("*/bin/initdb"), key=lambda p: int(p.parts[-3]) if p.parts[-3].isdigit() else 0)
    initdb = str(found[-1]) if found else shutil.which("initdb")
    if initdb is None:
        pytest.skip("PostgreSQL server binaries not installed (.ci/run installs the Debian package)")
    bindir = Path(initdb).parent
    root = Path(tempfile.mkdtemp(prefix="amigo-pg-"))
    data = root / "data"
    prefix: list[str] = []
    if os.geteuid() == 0:  # the server refuses to run as root
        import pwd

        pw = pwd.getpwnam("postgres")
        os.chown(root, pw.pw_uid, pw.pw_gid)
        prefix = ["runuser", "-u", "postgres", "--"]
    port = _free_port()
    run = lambda *a: subprocess.run([*prefix, *a], check=True, capture_output=True, text=True, timeout=120)  # noqa: E731
    run(str(bindir / "initdb"), "-D", str(data), "-U", "postgres", "--auth=trust", "-E", "UTF8", "--no-sync")
    opts = f"-c listen_addresses=127.0.0.1 -p {port} -c unix_socket_directories={data} -c fsync=off"
    try:
        run(str(bindir / "pg_ctl"), "-D", str(data), "-o", opts, "-l", str(root / "log"), "-w", "start")
        yield f"postgresql://postgres@127.0.0.1:{port}/postgres"  # the command line's form
    finally:
        with contextlib.suppress(subprocess.SubprocessError):
            run(str(bindir / "pg_ctl"), "-D", str(data), "-m", "immediate", "-w", "stop")
        shutil.rmtree(root, ignore_errors=True)


def test_postgresql_two_concurrent_workers_run_the_seed_grid_once(tmp_path: Path, postgres: str) -> None:
    args = [*_common(tmp_path), "--storage", postgres, "--study-name", "grid", "--mode", "seeds"]
    args += ["--seeds", "0", "1", "2", "3"]
    # two "machines": the same command, started together, each one worker
    procs = [_sweep([*args, "--worker-index", str(i)]) for i in range(2)]
    outs = [_finish(p) for p in procs]
    study = optuna.load_study(study_name="grid", storage=driver_url(postgres))
    trials = study.get_trials()
    _no_duplicates(trials)
    done = [t for t in trials if t.state == TrialState.COMPLETE]
    assert sorted(t.params["seed"] for t in done) == [0, 1, 2, 3], [(t.number, t.state, t.params) for t in trials]
    assert all(t.params["algo"] == "ppo" for t in done)
    assert not [t for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    # the grid was enqueued once: four grid trials; a worker that asked for a trial just after the other took the
    # last queued one got a fresh trial, which ends FAIL marked over_budget and counts nowhere (module docstring)
    grid = [t for t in trials if t.user_attrs.get("grid") is True]
    assert len(grid) == 4 and all(t.state == TrialState.COMPLETE for t in grid), trials
    extra = [t for t in trials if t not in grid]
    assert all(t.state == TrialState.FAIL and t.user_attrs.get("over_budget") is True for t in extra), extra
    assert len(extra) <= 2  # at most one per worker: a worker stops its study loop after the first
    # both workers joined the one study (which of them ran how many trials depends on the machine's load:
    # on a busy machine the first may take them all before the second starts)
    assert sum("Using an existing study" in o for o in outs) >= 1, outs
    assert study.user_attrs["mode"] == "seeds" and study.user_attrs["budget"] == 4


def test_postgresql_hyperparameter_budget_is_global(tmp_path: Path, postgres: str) -> None:
    args = [*_common(tmp_path), "--storage", postgres, "--study-name", "hp-pg", "--n-trials", "3"]
    procs = [_sweep([*args, "--worker-index", str(i)]) for i in range(2)]
    for p in procs:
        _finish(p)
    trials = optuna.load_study(study_name="hp-pg", storage=driver_url(postgres)).get_trials()
    _no_duplicates(trials)
    ran = [t for t in trials if t.state in (TrialState.COMPLETE, TrialState.PRUNED)]
    assert len(ran) == 3, [(t.number, t.state, t.user_attrs) for t in trials]


# --------------------------------------------------------------------------- a killed worker
def test_killed_worker_leaves_its_trial_failed_and_retried(tmp_path: Path) -> None:
    base = _common(tmp_path, "--mode", "seeds", "--seeds", "0", "--study-name", "kill")
    base += ["--heartbeat-interval", "1", "--grace-period", "2"]
    long = list(base)
    long[long.index("--timesteps") + 1] = "10000000"  # a trial that would run for hours
    victim = _sweep(long, start_new_session=True)
    storage = f"sqlite:///{tmp_path / 'out' / 'sweep.db'}"
    deadline = time.monotonic() + 90
    run_started = False
    while time.monotonic() < deadline and not run_started:
        time.sleep(0.5)
        run_started = any((tmp_path / "out" / "kill").glob("trial_*/run/config.json"))
        assert victim.poll() is None, victim.communicate()[0][-3000:]
    assert run_started, "the victim never started training"
    os.killpg(victim.pid, signal.SIGKILL)  # no chance to clean up, as a lost machine
    victim.communicate()
    study = optuna.load_study(study_name="kill", storage=storage)
    assert [t.state for t in study.get_trials()] == [TrialState.RUNNING]  # stale, not yet detected
    time.sleep(3)  # > grace period
    _finish(_sweep(base))
    trials = optuna.load_study(study_name="kill", storage=storage).get_trials()
    assert [t.state for t in trials] == [TrialState.FAIL, TrialState.COMPLETE]
    assert trials[1].system_attrs["failed_trial"] == trials[0].number
    assert trials[1].params == trials[0].params == {"algo": "ppo", "seed": 0}
