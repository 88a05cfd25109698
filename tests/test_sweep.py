"""``amigo-gym sweep`` with real storages: SQLite with two worker processes, a real PostgreSQL 15 server with two
concurrent workers (as two machines would), and a worker killed mid-trial (heartbeat -> FAIL -> retried).

Training budgets are tiny (PPO, one rollout of 32 steps, one evaluation episode, a 16-unit network); each
worker process pays torch's import once.
"""

from __future__ import annotations

import contextlib
import json
import math
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
from typing import Any

import numpy as np
import pytest

optuna = pytest.importorskip("optuna")
from optuna.trial import TrialState  # noqa: E402

from amigo_gym.tools.training.sweep import SweepConfig, driver_url  # noqa: E402

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
        [sys.executable, "-m", "amigo_gym.tools.cli", "sweep", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        **kw,
    )


def _finish(p: subprocess.Popen[str], timeout: float = 400) -> str:
    """A worker's output; ``timeout`` only guards against a hang (a loaded 2-core machine takes ~2 min)."""
    out, _ = p.communicate(timeout=timeout)
    assert p.returncode == 0, out[-3000:]
    return out


def _sweep_here(capsys: pytest.CaptureFixture[str], args: list[str]) -> str:
    """``amigo-gym sweep ARGS`` with one job in this process (``amigo_gym.tools.cli.main``; one job runs its trials in
    the calling process, as :func:`_sweep`'s process did): for the runs that nobody kills, without another
    process paying torch's import. Its printed output (stdout and stderr). Optuna's experimental-feature warnings
    (the heartbeat) are ignored, as :func:`_sweep`'s ``PYTHONWARNINGS=ignore`` does; every other warning counts."""
    import warnings

    from amigo_gym.tools.cli import main

    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        rc = main(["sweep", *args])
    out, err = capsys.readouterr()
    assert rc == 0, (out + err)[-3000:]
    return out + err


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
def test_killed_worker_leaves_its_trial_failed_and_retried(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    base = _common(tmp_path, "--mode", "seeds", "--seeds", "1", "--study-name", "kill")
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
    _sweep_here(capsys, base)
    trials = optuna.load_study(study_name="kill", storage=storage).get_trials()
    assert [t.state for t in trials] == [TrialState.FAIL, TrialState.COMPLETE]
    assert trials[1].system_attrs["failed_trial"] == trials[0].number
    assert trials[1].params == trials[0].params == {"algo": "ppo", "seed": 0}


# --------------------------------------------------------------------------- faults, secrets, names (issue 21)
def _wait_running(
    storage: str, name: str, n: int, procs: list[subprocess.Popen[str]], study_dir: Path, timeout: float = 150
) -> list:
    """Wait until ``n`` trials are RUNNING with their training started (``run/config.json``); those trials.

    The storage is read only once ``n`` trial folders under ``study_dir`` hold a ``run/config.json``: by then
    the workers have created the tables, so this process never races them at schema creation (a plain
    ``optuna.load_study`` has no retry: SQLite's ``alembic_version`` insert can collide with a worker's).
    """
    deadline = time.monotonic() + timeout
    last: Exception | None = None
    while time.monotonic() < deadline:
        time.sleep(0.5)
        for p in procs:
            assert p.poll() is None, p.communicate()[0][-3000:]
        if len(list(study_dir.glob("trial_*/run/config.json"))) < n:
            continue  # training has not started in n trials yet
        try:
            trials = optuna.load_study(study_name=name, storage=storage).get_trials()
        except Exception as exc:  # a transient lock; kept to report if it never clears
            last = exc
            continue
        started = [
            t
            for t in trials
            if t.state == TrialState.RUNNING
            and "run_dir" in t.user_attrs
            and (Path(t.user_attrs["run_dir"]) / "run" / "config.json").is_file()
        ]
        if len(started) >= n:
            return started
    raise AssertionError(f"{n} trials never started training (last storage error: {last!r})")


def _long(args: list[str]) -> list[str]:
    out = list(args)
    out[out.index("--timesteps") + 1] = "10000000"  # a trial that would run for hours
    return out


def test_sigterm_requeues_the_cell_and_a_rerun_completes_the_grid(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    base = _common(tmp_path, "--mode", "seeds", "--seeds", "0", "1", "--study-name", "term")
    storage = f"sqlite:///{tmp_path / 'out' / 'sweep.db'}"
    victim = _sweep(_long(base))
    (trial,) = _wait_running(storage, "term", 1, [victim], tmp_path / "out" / "term")
    victim.send_signal(signal.SIGTERM)
    out, _ = victim.communicate(timeout=120)
    assert victim.returncode == 130, out[-3000:]
    trials = optuna.load_study(study_name="term", storage=storage).get_trials()
    stopped = next(t for t in trials if t.number == trial.number)
    assert stopped.state == TrialState.FAIL and "SIGTERM" in stopped.user_attrs["interrupted"]
    again = [t for t in trials if t.user_attrs.get("retry_of") == trial.number]
    assert len(again) == 1 and again[0].state == TrialState.WAITING
    assert again[0].system_attrs["fixed_params"] == stopped.params and again[0].user_attrs.get("grid") is True
    marker = json.loads((Path(stopped.user_attrs["run_dir"]) / "ABANDONED.json").read_text())
    assert marker["trial"] == trial.number and marker["retried_as"] == [again[0].number]
    summary = json.loads((tmp_path / "out" / "term" / "summary.json").read_text())
    assert summary["status"] == "running"  # queued cells left: the study is not over
    # the rerun (the same command, a short budget) takes the re-queued cell and the rest of the grid
    out = _sweep_here(capsys, base)
    trials = optuna.load_study(study_name="term", storage=storage).get_trials()
    done = sorted(t.params["seed"] for t in trials if t.state == TrialState.COMPLETE)
    assert done == [0, 1], [(t.number, t.state, t.params) for t in trials]
    summary = json.loads((tmp_path / "out" / "term" / "summary.json").read_text())
    assert summary["status"] == "complete" and "complete" in out


def test_a_killed_worker_process_makes_the_sweep_exit_non_zero(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    base = _common(tmp_path, "--mode", "seeds", "--seeds", "0", "1", "--study-name", "died", "--n-jobs", "2")
    base += ["--heartbeat-interval", "1", "--grace-period", "2"]
    storage = f"sqlite:///{tmp_path / 'out' / 'sweep.db'}"
    parent = _sweep(_long(base))
    running = _wait_running(storage, "died", 2, [parent], tmp_path / "out" / "died")
    pids = [int(t.user_attrs["worker"].split(":")[1]) for t in running]
    os.kill(pids[0], signal.SIGKILL)  # one worker dies ...
    time.sleep(1)
    os.kill(pids[1], signal.SIGTERM)  # ... the other is stopped (its cell queued again)
    out, _ = parent.communicate(timeout=120)
    assert parent.returncode == 1, out[-3000:]  # not max([130, -9]): a death is an error
    assert "killed by SIGKILL" in out, out[-3000:]
    time.sleep(3)  # > grace period: the killed worker's trial is stale
    rerun = list(base)
    rerun[rerun.index("--n-jobs") + 1] = "1"
    _sweep_here(capsys, rerun)  # one job: in this process
    trials = optuna.load_study(study_name="died", storage=storage).get_trials()
    done = sorted(t.params["seed"] for t in trials if t.state == TrialState.COMPLETE)
    assert done == [0, 1], [(t.number, t.state, t.params, t.user_attrs) for t in trials]
    by_number = {t.number: t for t in trials}
    for t in running:  # the killed and the stopped trial failed, and their abandoned folders say so
        ended = by_number[t.number]
        assert ended.state == TrialState.FAIL, ended
        assert (Path(ended.user_attrs["run_dir"]) / "ABANDONED.json").is_file(), ended


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--study-name", "../../escaped"], "--study-name must be a name"),
        (["--study-name", "a/b"], "--study-name must be a name"),
        (["--study-name", "..x"], "--study-name must be a name"),
        (["--storage", "sqlite:///:memory:", "--n-jobs", "2"], "in-memory database"),
        (["--storage", "sqlite://", "--n-jobs", "2"], "in-memory database"),
        (["--env", "AmigoBot-v1", "--env-kwargs", "[1]"], "--env-kwargs must be a JSON object"),
    ],
)
def test_bad_sweep_settings_are_refused_in_one_line(
    tmp_path: Path, extra: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from amigo_gym.tools.training.sweep import main

    with pytest.raises(SystemExit) as exc:
        main(["--algo", "ppo", "--out", str(tmp_path / "out"), *extra])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists() and not list(tmp_path.parent.glob("escaped"))


def test_bad_sweep_settings_messages(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from amigo_gym.tools.training.sweep import main

    for extra, message in (
        (["--study-name", "../../escaped"], "--study-name must be a name"),
        (["--storage", "sqlite:///:memory:", "--n-jobs", "2"], "in-memory database"),
        (["--storage", "postgresql://u:Hunter2-xyz@host:notaport/db"], "--storage must be a SQLAlchemy URL"),
    ):
        with pytest.raises(SystemExit):
            main(["--algo", "ppo", "--out", str(tmp_path / "out"), *extra])
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
        assert "Hunter2" not in err


def test_password_masking_helpers() -> None:
    from amigo_gym.tools.training.sweep import masked_url, public_argv, scrub

    url = "postgresql://user:p%40ss w0rd@db:5432/amigo"
    assert masked_url(url) == "postgresql://user:***@db:5432/amigo"
    assert public_argv(["--storage", url, "--storage=" + url, "--n-jobs", "2"]) == [
        "--storage",
        "postgresql://user:***@db:5432/amigo",
        "--storage=postgresql://user:***@db:5432/amigo",
        "--n-jobs",
        "2",
    ]
    text = f"failed for {url} (password 'p@ss w0rd', p%40ss+w0rd)"
    cleaned = scrub(text, url)
    assert "p@ss" not in cleaned and "p%40ss" not in cleaned and "w0rd" not in cleaned
    assert scrub("nothing secret", "sqlite:///x.db") == "nothing secret"
    assert masked_url("sqlite:///:memory:") == "sqlite:///:memory:"  # no password: as typed
    # credentials in the query (issue 37): every form masked, the other parameters kept
    q = "postgresql://db/amigo?sslmode=require&password=Qw%2Be%20rt&sslpassword=Zx-9&application_name=sweep"
    assert masked_url(q) == "postgresql://db/amigo?sslmode=require&password=***&sslpassword=***&application_name=sweep"
    said = scrub(f"cannot connect to {q}: password 'Qw+e rt' (Qw%2Be+rt), key Zx-9", q)
    assert not [x for x in ("Qw", "Zx-9") if x in said], said
    assert public_argv([f"--storage={q}"]) == [f"--storage={masked_url(q)}"]


def test_the_sweep_scores_the_protocols_validation_cells() -> None:
    from amigo_gym.tools.training import protocol
    from amigo_gym.tools.training.sweep import validation_cells

    for env_id in ("AmigoBot-v0", "AmigoBot-v1"):
        assert validation_cells(env_id, 3, 50) == protocol.validation_cells(env_id, 3, 50)
    with pytest.raises(ValueError, match="--val-episodes must be at most 100, got 101"):
        SweepConfig(algos=["ppo"], val_episodes=101).validate()


SECRET = "Pw-7f3b9cQ"


def _leaks(secret: str, *roots: Path) -> list[str]:
    """Files under ``roots`` whose bytes hold ``secret`` (as typed or URL-quoted)."""
    forms = {secret.encode(), secret.replace("-", "%2D").encode()}
    return [str(f) for r in roots for f in r.rglob("*") if f.is_file() and any(x in f.read_bytes() for x in forms)]


def test_no_credential_of_any_url_form_in_files_attributes_or_messages(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A storage URL with ``?password=`` (SQLite ignores it): the secret in no file under --out, no study or trial
    attribute and no printed line, from a run, from a refused input and from an error."""
    url = f"sqlite:///{tmp_path / 's.db'}?password={SECRET}&sslpassword={SECRET}x"
    said = _sweep_here(capsys, _common(tmp_path, "--storage", url, "--study-name", "q", "--n-trials", "1"))
    study = optuna.load_study(study_name="q", storage=f"sqlite:///{tmp_path / 's.db'}")
    attrs = json.dumps([study.user_attrs] + [[t.user_attrs, t.system_attrs] for t in study.trials])
    assert "password=***" in json.dumps(study.user_attrs)
    from amigo_gym.tools.cli import main

    for bad in (["--n-trials", "0"], ["--n-jobs", "2", "--storage", f"sqlite:///:memory:?password={SECRET}"]):
        with pytest.raises(SystemExit):
            main(["sweep", *_common(tmp_path, "--storage", url, "--study-name", "q", *bad)])
    said += "".join(capsys.readouterr())
    assert SECRET not in said + attrs and not _leaks(SECRET, tmp_path / "out"), said[-2000:]


def test_postgresql_killed_and_stopped_workers_leave_every_cell_run_once(tmp_path: Path, postgres: str) -> None:
    """Two workers on one PostgreSQL study, one SIGKILLed and one SIGTERMed mid-trial, then restarted: every
    grid cell COMPLETE exactly once, the summary complete, both abandoned folders marked, and the URL's
    password (accepted and ignored by the trust authentication) in no file, attribute or message."""
    url = postgres.replace("postgres@", f"postgres:{SECRET}@")
    base = _common(tmp_path, "--heartbeat-interval", "1", "--grace-period", "2", "--storage", url)
    base += ["--study-name", "faults", "--mode", "seeds", "--seeds", "0", "1", "2"]
    storage = driver_url(postgres)
    procs = [_sweep([*_long(base), "--worker-index", str(i)]) for i in range(2)]
    running = _wait_running(storage, "faults", 2, procs, tmp_path / "out" / "faults")
    pid_of = {int(t.user_attrs["worker"].split(":")[1]): t.number for t in running}
    assert set(pid_of) == {p.pid for p in procs}
    procs[0].send_signal(signal.SIGKILL)
    procs[1].send_signal(signal.SIGTERM)
    outs = [p.communicate(timeout=120)[0] for p in procs]
    assert procs[0].returncode == -signal.SIGKILL and procs[1].returncode == 130, outs[1][-3000:]
    trials = optuna.load_study(study_name="faults", storage=storage).get_trials()
    states = {t.number: t.state for t in trials}
    assert states[pid_of[procs[0].pid]] == TrialState.RUNNING  # stale, not yet found
    assert states[pid_of[procs[1].pid]] == TrialState.FAIL  # stopped and queued again at once
    time.sleep(3)  # > grace period
    again = [_sweep([*base, "--worker-index", str(i)]) for i in range(2)]
    outs += [_finish(p, timeout=300) for p in again]
    study = optuna.load_study(study_name="faults", storage=storage)
    trials = study.get_trials()
    _no_duplicates(trials)
    done = [t for t in trials if t.state == TrialState.COMPLETE]
    assert sorted(t.params["seed"] for t in done) == [0, 1, 2], [(t.number, t.state, t.params) for t in trials]
    assert not [t for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    for number in pid_of.values():
        t = next(x for x in trials if x.number == number)
        assert t.state == TrialState.FAIL
        marker = json.loads((Path(t.user_attrs["run_dir"]) / "ABANDONED.json").read_text())
        detail = [(x.number, x.state, x.user_attrs.get("retry_of"), x.system_attrs.get("failed_trial")) for x in trials]
        assert marker["trial"] == number and len(marker["retried_as"]) == 1, (marker, detail)
    summary = json.loads((tmp_path / "out" / "faults" / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["states"]["COMPLETE"] == 3
    # no password anywhere: files, study and trial attributes, every message
    assert not _leaks(SECRET, tmp_path / "out")
    study_system = study._storage.get_study_system_attrs(study._study_id)
    attrs = json.dumps([study.user_attrs, study_system, [(t.user_attrs, t.system_attrs) for t in trials]])
    assert SECRET not in attrs and "postgres:***@" in attrs
    assert not [o for o in outs if SECRET in o]


def test_a_failed_connection_prints_no_password(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("psycopg2")
    from amigo_gym.tools.training.sweep import main

    url = f"postgresql://someone:{SECRET}@127.0.0.1:{_free_port()}/nowhere"
    rc = main(["--algo", "ppo", "--storage", url, "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert rc == 1 and "cannot open the storage postgresql" in captured.err, captured.err
    assert SECRET not in captured.err + captured.out and "someone:***@" in captured.err
    assert not (tmp_path / "out").exists() or not _leaks(SECRET, tmp_path / "out")


def test_v1_trials_train_on_the_training_distribution_and_score_on_validation_cells(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION
    from amigo_gym.tools.training.protocol import VALIDATION_SEEDS, validation_cells

    hp = tmp_path / "tiny_v1.yml"
    hp.write_text(TINY.replace("AmigoBot-v0", "AmigoBot-v1"))
    args = _common(tmp_path, "--env", "AmigoBot-v1", "--n-trials", "1", "--study-name", "v1")
    args[args.index("--hyperparams") + 1] = str(hp)
    out = _sweep_here(capsys, args)
    storage = f"sqlite:///{tmp_path / 'out' / 'sweep.db'}"
    study = optuna.load_study(study_name="v1", storage=storage)
    (trial,) = study.get_trials()
    assert trial.state == TrialState.COMPLETE and study.direction == optuna.study.StudyDirection.MINIMIZE
    assert study.user_attrs["env_id"] == "AmigoBot-v1" and study.user_attrs["objective"] == "validation_h_rms_iqm_m"
    assert study.user_attrs["env_kwargs"] == TRAINING_DISTRIBUTION["env_kwargs"]  # the default distribution
    run_dir = Path(trial.user_attrs["run_dir"])
    import yaml

    assert list(yaml.safe_load((run_dir / "hyperparams.yml").read_text())) == ["AmigoBot-v1"]
    config = json.loads((run_dir / "run" / "config.json").read_text())
    assert config["env_id"] == "AmigoBot-v1" and config["env_kwargs"] == TRAINING_DISTRIBUTION["env_kwargs"]
    val = trial.user_attrs["validation"]
    held_in = [sc.name for sc in validation_cells("AmigoBot-v1")]
    assert list(val["cells"]) == held_in and val["seeds"] == [VALIDATION_SEEDS[0]]
    assert all(v is not None and v > 0 for v in val["cells"].values())
    # the value is the IQM (25 % trimmed mean) of the per-cell values
    cells = np.sort(np.array(list(val["cells"].values())))
    k = int(0.25 * cells.size)
    assert trial.value == pytest.approx(float(cells[k : cells.size - k].mean()), rel=1e-12)
    summary = json.loads((tmp_path / "out" / "v1" / "summary.json").read_text())
    assert summary["status"] == "complete" and "complete" in out


@pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")  # the heartbeat thread's own DB
def test_in_memory_storage_with_one_job_runs_and_summarises(tmp_path: Path) -> None:
    from amigo_gym.tools.training.sweep import main

    args = _common(tmp_path, "--storage", "sqlite:///:memory:", "--n-trials", "1", "--study-name", "mem")
    assert main(args) == 0
    summary = json.loads((tmp_path / "out" / "mem" / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["states"]["COMPLETE"] == 1
    assert summary["study_attrs"]["argv"][summary["study_attrs"]["argv"].index("--storage") + 1] == "sqlite:///:memory:"


def test_a_trials_end_records_validation_errors_and_a_nan_objective() -> None:
    """The end both kinds of trial share (``_validated_trial``): the per-cell values as ``validation`` and the value
    (COMPLETE); an error of the training or validation as ``fail_reason``, raised again (FAIL); a NaN objective
    with a ``fail_reason`` naming it (Optuna: FAIL, never PRUNED)."""
    from types import SimpleNamespace

    from amigo_gym.tools.training.sweep import OBJECTIVE, _validated_trial

    cells = [SimpleNamespace(seeds=(1_000_000, 1_000_001))]
    outcomes: list[Any] = [(0.25, {"a": 0.2, "b": 0.3}), ValueError("no model.zip"), (math.nan, {"a": None})]

    def fit_and_validate() -> tuple[float, dict[str, float | None]]:
        got = outcomes.pop(0)
        if isinstance(got, Exception):
            raise got
        return got

    optuna.logging.set_verbosity(optuna.logging.ERROR)
    study = optuna.create_study()
    study.optimize(lambda t: _validated_trial(t, cells, fit_and_validate), n_trials=3, catch=(ValueError,))
    ok, err, nan = study.get_trials()
    assert ok.state == TrialState.COMPLETE and ok.value == 0.25 and "fail_reason" not in ok.user_attrs
    assert ok.user_attrs["validation"] == {
        "metric": OBJECTIVE,
        "seeds": [1_000_000, 1_000_001],
        "cells": {"a": 0.2, "b": 0.3},
    }
    assert err.state == TrialState.FAIL and err.user_attrs["fail_reason"] == "ValueError: no model.zip"
    assert "validation" not in err.user_attrs
    assert (
        nan.state == TrialState.FAIL
        and nan.user_attrs["fail_reason"] == "validation H RMS IQM nan (cells: {'a': None})"
    )
    assert nan.user_attrs["validation"]["cells"] == {"a": None}


def test_enqueue_base_runs_the_base_files_values_first() -> None:
    """``--enqueue-base``: the study's first trial is the base YAML's own values (read back by the same
    sampling code as every trial), and the high-throughput file samples its batch sizes from its own range."""
    from amigo_gym.tools.training.hyperparams import load_hyperparams
    from amigo_gym.tools.training.sweep import HT_BATCH_SIZES, SweepConfig, base_params, open_study, sample_hyperparams

    base_file = Path(__file__).resolve().parents[1] / "agents" / "hyperparams" / "td3_lowpass.yml"
    base = load_hyperparams(base_file, "AmigoBot-v1")
    # the file's literal values (agents/hyperparams/td3_lowpass.yml)
    want = {"learning_rate": 0.001, "gamma": 0.98, "tau": 0.005, "batch_size": 2048, "noise_std": 0.1}
    got = sample_hyperparams(optuna.trial.FixedTrial(base_params("td3", base)), "td3", base)
    assert {k: got[k] for k in want} == pytest.approx(want, rel=1e-12)
    cfg = SweepConfig(
        algos=["td3"], env_id="AmigoBot-v1", hyperparams=str(base_file), enqueue_base=True, study_name="base"
    )
    cfg.validate()
    study = open_study(cfg, "sqlite:///:memory:")
    (first,) = study.get_trials()
    assert first.state == TrialState.WAITING and first.user_attrs["baseline"] is True
    run = study.ask()  # the worker's next trial is the enqueued one: it samples the file's values
    assert run.number == first.number
    assert {k: v for k, v in sample_hyperparams(run, "td3", base).items() if k in want} == pytest.approx(want)
    # many sub-envs: batch sizes from the high-throughput range; one env: rl-zoo's
    rs, rs1 = (optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=0)) for _ in range(2))
    ht = {sample_hyperparams(rs.ask(), "td3", base)["batch_size"] for _ in range(40)}
    small = {sample_hyperparams(rs1.ask(), "sac", {"n_envs": 1})["batch_size"] for _ in range(40)}
    assert ht == set(HT_BATCH_SIZES) and small == {64, 128, 256}


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"algos": ["td3"], "mode": "seeds"}, "--enqueue-base is for --mode hyperparams"),
        ({"algos": ["fastppo"]}, "--enqueue-base is for --mode hyperparams of an SB3 algorithm"),
    ],
)
def test_enqueue_base_refuses_seeds_mode_and_fastppo(kw: dict[str, Any], match: str) -> None:
    from amigo_gym.tools.training.sweep import SweepConfig, base_params

    with pytest.raises(ValueError, match=match):
        SweepConfig(enqueue_base=True, **kw).validate()  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="the base file has no noise_std for td3"):
        base_params("td3", {"learning_rate": 1e-3, "gamma": 0.98, "tau": 0.005, "batch_size": 256})
    with pytest.raises(ValueError, match=r"batch_size must be one of \[512, 1024, 2048, 4096\], got 256"):
        base_params("sac", {"learning_rate": 1e-3, "gamma": 0.98, "tau": 0.005, "batch_size": 256, "n_envs": 128})


def test_seeds_is_a_count_like_every_other_seeds_or_a_list() -> None:
    from amigo_gym.tools.training.sweep import SweepConfig

    assert SweepConfig(algos=["ppo"], mode="seeds", seeds=[3]).seeds == [0, 1, 2]
    assert SweepConfig(algos=["ppo"], mode="seeds", seeds=[3, 7]).seeds == [3, 7]
    with pytest.raises(ValueError, match=r"--seeds must be a count >= 1 or two or more distinct seeds, got \[\]"):
        SweepConfig(algos=["ppo"], mode="seeds", seeds=[0]).validate()
