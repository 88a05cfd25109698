"""Run folders: one process at a time, checkpoints that survive any kill, corrupt files named, output sets
(docs/reliability.md, "Reference: run folders")."""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import os
import re
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from amigo_gym.io import (
    atomic_save,
    atomic_write_json,
    fault_point,
    file_mode,
    fsync_dir,
    require_trust,
    sha256_file,
    vouch,
)

LOCK_NAME = "run.lock"
POINTER = "checkpoint.json"
CHECKPOINTS = "checkpoints"
META = "meta.json"
#: files of a run folder that a checkpoint snapshots and a resume restores
SNAPSHOT = ("eval.json", "best_model.zip")


@dataclasses.dataclass
class StopRequest:
    """A ``SIGTERM``/``SIGINT`` handler: the first signal sets :attr:`requested` (the run stops at its next safe
    point) and prints ``message`` to stderr; a second raises ``KeyboardInterrupt``."""

    message: str
    requested: bool = False

    def __call__(self, signum: int, frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True
        print(self.message, file=sys.stderr, flush=True)


@contextlib.contextmanager
def handling(handler: Callable[[int, Any], None], *signals: signal.Signals) -> Iterator[None]:
    """``handler`` on ``signals`` (default ``SIGTERM`` and ``SIGINT``) inside the block (main thread only)."""
    main = threading.current_thread() is threading.main_thread()
    old = {sig: signal.signal(sig, handler) for sig in signals or (signal.SIGTERM, signal.SIGINT)} if main else {}
    try:
        yield
    finally:
        for sig, previous in old.items():
            signal.signal(sig, previous)


class RunLockedError(FileExistsError):
    """Another process holds the run folder's lock."""


class CorruptFileError(ValueError):
    """A file of a run (or a model) is damaged or not what it should be; the message names it."""


def warn(message: str) -> None:
    """A one-line warning on stderr."""
    print(f"amigo-gym: warning: {message}", file=sys.stderr, flush=True)


class RunLock:
    """Exclusive lock on ``folder/name`` (created) while the context is entered; ``wait``: seconds to wait for another
    holder, else :class:`RunLockedError` (one line with its pid)."""

    def __init__(self, folder: str | os.PathLike[str], name: str = LOCK_NAME, wait: float = 0.0) -> None:
        self.folder = Path(folder)
        self.name = name
        self.wait = float(wait)
        self._lock: Any = None

    def acquire(self) -> RunLock:
        import filelock

        self.folder.mkdir(parents=True, exist_ok=True)
        path = self.folder / self.name
        lock = filelock.FileLock(path, timeout=self.wait, mode=file_mode(), thread_local=False)
        try:
            while True:
                lock.acquire()
                fd = getattr(getattr(lock, "_context", None), "lock_file_fd", None)
                if fd is None or is_current_lock(fd, path):
                    break
                lock.release()  # a finishing owner removed the file we locked: take the new one
        except filelock.Timeout:
            owner = "?"
            with contextlib.suppress(OSError):
                owner = path.read_text(errors="replace").strip() or "?"
            raise RunLockedError(
                f"{self.folder} is in use by another amigo-gym process (pid {owner}); wait for it to finish "
                "or stop it, then --resume"
            ) from None
        path.write_text(f"{os.getpid()}\n")  # the path names the locked file: only a holder removes it
        self._lock = lock
        return self

    def release(self) -> None:
        """Remove the lock file (while still locked) and unlock it."""
        if self._lock is not None:
            if sys.platform != "win32":  # Windows cannot remove an open file; its lock file stays
                with contextlib.suppress(OSError):
                    os.unlink(self.folder / self.name)
            self._lock.release()
            self._lock = None

    __enter__ = acquire

    def __exit__(self, *exc: object) -> None:
        self.release()


def is_current_lock(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the file open as ``fd`` (same device and inode)."""
    with contextlib.suppress(FileNotFoundError):
        return os.path.samestat(os.stat(path), os.fstat(fd))
    return False


#: the package's temporaries: ``.tmp-*``, ``.staging-*``, ``.trash-*`` and :func:`amigo_gym.io.atomic_save`'s
#: ``.<stem>.<8 random characters><suffix>``
TEMPORARY_NAME = re.compile(r"^\.(?:tmp|staging|trash)-.+$|^\..+\.[A-Za-z0-9_]{8}(?:\.[A-Za-z0-9]+)?$")


def clean_temporaries(folder: Path) -> None:
    """Remove the package's temporaries (:data:`TEMPORARY_NAME`) from ``folder`` and its ``checkpoints/`` (call only
    while holding the folder's :class:`RunLock`)."""
    for d in (folder, folder / CHECKPOINTS):
        remove_matching(d, TEMPORARY_NAME)


def remove_matching(folder: Path, pattern: re.Pattern[str]) -> list[str]:
    """Remove the entries of ``folder`` whose names ``pattern`` matches (links, never their targets); their names."""
    removed = [p for p in folder.iterdir() if pattern.match(p.name)] if folder.is_dir() else []
    for p in removed:
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
    return [p.name for p in removed]


def has_run_files(folder: Path) -> bool:
    """Whether ``folder`` holds anything besides the lock file and temporaries."""
    return folder.is_dir() and any(p.name != LOCK_NAME and not p.name.startswith(".") for p in folder.iterdir())


def verify_sha256(path: Path, expected: str, source: str) -> None:
    """Raise :class:`CorruptFileError` unless ``path``'s sha256 is ``expected`` (as recorded in ``source``)."""
    if not path.is_file():
        raise CorruptFileError(f"{path}: missing (listed in {source})")
    if (got := sha256_file(path)) != expected:
        raise CorruptFileError(
            f"{path}: sha256 {got[:12]}... does not match {expected[:12]}... recorded in {source} "
            "(changed, truncated or replaced)"
        )


def publish(targets: Mapping[Path, Path], out: Path, manifest: str, **extra: Any) -> dict[str, str]:
    """Move the staged files ``{target: staged file}`` to their targets as one set; the manifest's ``{file: sha256}``.

    The manifest ``out/<manifest>`` (``{"files": {file: sha256}, **extra, "written": time}``) is removed first and
    written last. Fault stages: ``publish:<file name>`` after each move.
    """
    files: dict[str, str] = {}
    for dest, src in targets.items():  # a file's name: relative to ``out`` when inside it, else absolute
        path, root = dest.resolve(), out.resolve()
        files[str(path.relative_to(root) if path.is_relative_to(root) else path)] = sha256_file(src)
    (out / manifest).unlink(missing_ok=True)
    fsync_dir(out)
    for dest, src in targets.items():
        dest.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.replace(src, dest)
        except OSError:  # another file system: copy beside the target, then rename
            atomic_save(functools.partial(shutil.copyfile, src), dest)
        fault_point(f"publish:{dest.name}")
        fsync_dir(dest.parent)
    atomic_write_json(out / manifest, {"files": files, **extra, "written": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
    return files


def verify_manifest(out: Path, manifest: str) -> dict[str, str]:
    """The ``{file: sha256}`` of the manifest ``out/<manifest>`` of :func:`publish`, after checking every file;
    ``FileNotFoundError`` without a manifest, :class:`CorruptFileError` for a file missing or changed."""
    if not (path := out / manifest).is_file():
        raise FileNotFoundError(f"{path}: missing; the outputs in {out} are not a complete set")
    doc = read_json(path)
    if not isinstance(doc, dict) or not isinstance(doc.get("files"), dict):
        raise CorruptFileError(f"{path}: not a manifest (needs 'files')")
    for name, digest in doc["files"].items():
        verify_sha256(out / name, str(digest), str(path))
    return dict(doc["files"])


def check_pickle(path: Path, expected: str | None, source: str | None, trust: bool = False) -> None:
    """Check a pickle before it is unpickled: against the sha256 ``expected`` of the manifest ``source`` if any
    (:class:`CorruptFileError`), then that it is trusted (:func:`amigo_gym.io.require_trust`)."""
    if expected is not None:
        verify_sha256(path, expected, str(source))
    require_trust(path, expected, trust)


def read_json(path: Path, what: str = "") -> Any:
    """Parse a JSON file; :class:`CorruptFileError` naming the file on a decoding error."""
    try:
        return json.loads(path.read_bytes())
    except (ValueError, UnicodeDecodeError) as exc:
        detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CorruptFileError(f"{path}: not valid JSON{' ' + what if what else ''} ({detail})") from None


def _fsync_file(path: Path) -> None:
    with open(path, "rb+") as fh:
        os.fsync(fh.fileno())


@dataclasses.dataclass
class Checkpoint:
    """A verified checkpoint folder ``<run>/checkpoints/step_<n>[.<k>]``, its ``num_timesteps`` and ``meta.json``."""

    folder: Path
    step: int
    meta: dict[str, Any]

    @property
    def wall_time_s(self) -> float:
        return float(self.meta.get("wall_time_s", 0.0))


def verify_checkpoint(folder: Path, algo: str) -> Checkpoint:
    """Read ``meta.json`` of a checkpoint folder and check every file's sha256 (no unpickling);
    :class:`CorruptFileError` for a missing or damaged ``meta.json``, another algorithm, a file missing or changed."""
    if not (meta_path := folder / META).is_file():
        raise CorruptFileError(f"{meta_path}: missing (the checkpoint is incomplete)")
    meta = read_json(meta_path)
    if not (
        isinstance(meta, dict) and isinstance(meta.get("num_timesteps"), int) and isinstance(meta.get("files"), dict)
    ):
        raise CorruptFileError(f"{meta_path}: not a checkpoint record (needs num_timesteps and files)")
    if meta.get("algo") != algo:
        raise CorruptFileError(f"{meta_path}: a checkpoint of {meta.get('algo')!r}, not {algo!r}")
    if "model.zip" not in meta["files"]:
        raise CorruptFileError(f"{meta_path}: lists no model.zip")
    for name, digest in meta["files"].items():
        if not isinstance(name, str) or "/" in name or name.startswith("."):
            raise CorruptFileError(f"{meta_path}: bad file name {name!r}")
        verify_sha256(folder / name, str(digest), str(meta_path))
    return Checkpoint(folder, int(meta["num_timesteps"]), meta)


def _read_pointer(out: Path, report: bool = False) -> dict[str, Any] | None:
    """The parsed ``checkpoint.json``; ``None`` if absent or damaged (``report``: with a warning)."""
    path = out / POINTER
    try:
        doc = read_json(path) if path.is_file() else None
        if doc is not None and not (isinstance(doc, dict) and isinstance(doc.get("path"), str)):
            raise CorruptFileError(f"{path}: not a checkpoint pointer (needs a 'path')")
    except CorruptFileError as exc:
        if report:
            warn(f"{exc}; looking for checkpoints in {out / CHECKPOINTS}")
        return None
    return doc


def _inside(out: Path, rel: Any) -> Path | None:
    """``out / rel`` if ``rel`` names a checkpoint folder inside ``out/checkpoints`` (else ``None``)."""
    parts = Path(rel).parts if isinstance(rel, str) else ()
    return out / rel if len(parts) == 2 and parts[0] == CHECKPOINTS and not parts[1].startswith(".") else None


def _step_of(folder: Path) -> tuple[int, int]:
    """Sort key of ``step_<n>[.<k>]``: ``(n, k)`` (``(-1, 0)`` if the name does not parse)."""
    m = re.fullmatch(r"step_(\d+)(?:\.(\d+))?", folder.name)
    return (int(m[1]), int(m[2] or 0)) if m else (-1, 0)


def candidates(out: Path, report: bool = True) -> list[Path]:
    """Checkpoint folders to try, best first: the pointer's, its previous one, then the others newest first (a
    damaged pointer is reported with a warning)."""
    ptr = _read_pointer(out, report) or {}
    found = list(dict.fromkeys(p for key in ("path", "previous") if (p := _inside(out, ptr.get(key))) and p.is_dir()))
    if (root := out / CHECKPOINTS).is_dir():
        rest = [p for p in root.iterdir() if p.is_dir() and p.name.startswith("step_") and p not in found]
        found += sorted(rest, key=_step_of, reverse=True)
    return found


def load_checkpoint(out: Path, algo: str, load: Callable[[Checkpoint], Any]) -> tuple[Checkpoint, Any] | None:
    """``(checkpoint, load(checkpoint))`` of the newest good checkpoint in ``out`` (``None``: no checkpoint folder).

    A candidate that fails with :class:`CorruptFileError` warns and falls back to the next; ``checkpoint.json`` is
    rewritten to name the checkpoint loaded. :class:`CorruptFileError` (one line) if none is usable.
    """
    tried: list[str] = []
    cands = candidates(out)
    for i, folder in enumerate(cands):
        try:
            ck = verify_checkpoint(folder, algo)
            for name, digest in ck.meta["files"].items():  # meta.json is the run folder's: no proof of origin
                require_trust(folder / name, str(digest))
            result = load(ck)
        except CorruptFileError as exc:
            tried.append(str(exc))
            nxt = f"falling back to {cands[i + 1].name}" if i + 1 < len(cands) else "no other checkpoint"
            warn(f"checkpoint {folder.name} is unusable: {exc}; {nxt}")
            continue
        if (ptr := _read_pointer(out)) is None or _inside(out, ptr.get("path")) != folder:  # repair the pointer
            _write_pointer(out, algo, folder, ck.step)
        return ck, result
    if tried:
        raise CorruptFileError(f"no usable checkpoint in {out}: " + "; ".join(tried))
    return None


def save_checkpoint(out: Path, algo: str, step: int, write: Callable[[Path], list[str]], wall_time_s: float) -> Path:
    """Write a complete checkpoint of ``step`` (``write(folder)`` writes the model files, returns their names) into
    the run folder ``out`` (its :class:`RunLock` held), switch ``checkpoint.json`` to it, delete all but the last two;
    the new folder. ``meta.json`` records ``algo``, the step and ``wall_time_s`` [s].

    Fault stages (``AMIGO_GYM_FAULT``): ``write``'s, ``checkpoint:files``, ``checkpoint:meta``, ``checkpoint:rename``,
    ``write:checkpoint.json`` / ``rename:checkpoint.json``, ``checkpoint:trash``.
    """
    root = out / CHECKPOINTS
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=root, prefix=".tmp-"))
    try:
        os.chmod(tmp, file_mode(folder=True))
        names = list(write(tmp))
        for name in SNAPSHOT:  # the run's evaluation record as of this step
            if (src := out / name).is_file():
                try:
                    os.link(src, tmp / name)  # the run replaces these files atomically: a link is a snapshot
                except OSError:
                    shutil.copyfile(src, tmp / name)
                names.append(name)
        for name in names:
            _fsync_file(tmp / name)
        fault_point("checkpoint:files")
        files = {name: sha256_file(tmp / name) for name in names}
        vouch(*files.values())  # written here: resuming from it needs no trust flag
        meta = {"num_timesteps": int(step), "algo": algo, "wall_time_s": float(wall_time_s), "files": files}
        (tmp / META).write_text(json.dumps(meta, indent=2) + "\n")
        _fsync_file(tmp / META)
        fsync_dir(tmp)
        fault_point("checkpoint:meta")
        k = 0
        while (final := root / (f"step_{step}.{k}" if k else f"step_{step}")).exists():
            k += 1
        os.replace(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    fsync_dir(root)
    fault_point("checkpoint:rename")
    kept = _write_pointer(out, algo, final, step)
    for old in [p for p in root.iterdir() if not p.name.startswith(".") and str(p.relative_to(out)) not in kept]:
        trash = root / f".trash-{old.name}"
        os.replace(old, trash)
        fault_point("checkpoint:trash")
        shutil.rmtree(trash, ignore_errors=True)
    fsync_dir(root)
    return final


def _write_pointer(out: Path, algo: str, folder: Path, step: int) -> tuple[str, str | None]:
    """Switch ``checkpoint.json`` atomically to ``folder`` and the previous good checkpoint (the first other
    candidate that verifies); their names."""
    previous = None
    for other in (p for p in candidates(out, report=False) if p != folder):
        with contextlib.suppress(CorruptFileError):
            previous = str(verify_checkpoint(other, algo).folder.relative_to(out))
            break
    rel = str(folder.relative_to(out))
    atomic_write_json(out / POINTER, {"num_timesteps": int(step), "path": rel, "previous": previous})
    return rel, previous


def restore_snapshot(out: Path, ck: Checkpoint | None) -> None:
    """Put the run's evaluation record (:data:`SNAPSHOT`) back to the checkpoint's (``None``: none)."""
    for name in SNAPSHOT:
        if ck is not None and (src := ck.folder / name).is_file():
            tmp = out / f".{name}.restore"
            shutil.copyfile(src, tmp)
            _fsync_file(tmp)
            os.replace(tmp, out / name)
        else:
            (out / name).unlink(missing_ok=True)
    fsync_dir(out)


@contextlib.contextmanager
def corrupt_errors(path: Path, what: str) -> Iterator[None]:
    """Any exception while loading ``path`` becomes one :class:`CorruptFileError` line naming the file."""
    try:
        yield
    except CorruptFileError:
        raise
    except FileNotFoundError:
        raise CorruptFileError(f"{path}: missing") from None
    except Exception as exc:
        detail = " ".join(str(exc).split())[:160] or "no detail"
        raise CorruptFileError(f"{path}: not a loadable {what} ({type(exc).__name__}: {detail})") from None
