"""Atomic file writing (temporary file, fsync, ``os.replace``, fsync of the folder; on any error the target is
untouched), strict JSON, file digests and the trust check of pickles. Fault injection (tests only):
``AMIGO_GYM_FAULT=<stage>[@<n>]`` kills the process the ``n``-th time it reaches ``<stage>``: ``write:<file name>``
(written, not moved), ``rename:<file name>`` (moved, folder not fsynced), and the stages of ``amigo_gym.tools.runs``."""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import signal
import sys
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

FAULT_ENV = "AMIGO_GYM_FAULT"
_fault_counts: dict[str, int] = {}


def fault_point(stage: str) -> None:
    """Kill this process here if ``AMIGO_GYM_FAULT`` names ``stage`` (module docstring; tests only)."""
    name, _, nth = os.environ.get(FAULT_ENV, "").partition("@")
    if name != stage:  # (unset: name "", never a stage)
        return
    _fault_counts[stage] = count = _fault_counts.get(stage, 0) + 1
    if count == int(nth or 1):
        if hasattr(signal, "SIGKILL"):
            os.kill(os.getpid(), signal.SIGKILL)
        os._exit(137)  # pragma: no cover - no SIGKILL (Windows)


def fsync_dir(folder: str | os.PathLike[str]) -> None:
    """fsync a folder, so that renames in it are durable (a no-op where folders cannot be opened)."""
    with contextlib.suppress(OSError):  # Windows; file systems without directory fsync
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def json_safe(obj: Any) -> Any:
    """``obj`` for strict JSON: non-finite floats as ``None``, numpy values as Python ones, mappings as dicts with
    ``str`` keys, tuples as lists."""
    if isinstance(obj, Mapping):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    if hasattr(obj, "tolist") and hasattr(obj, "shape"):  # a numpy scalar or array
        return json_safe(obj.tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def finite_float(text: str, message: Callable[[bool], str], error: type[ValueError] = ValueError) -> float:
    """``float(text)`` if finite; else raises ``error(message(is_number))``, ``is_number`` True for NaN and inf."""
    try:
        value = float(text)
    except ValueError:
        raise error(message(False)) from None
    if not math.isfinite(value):
        raise error(message(True))
    return value


def sha256_file(path: str | os.PathLike[str]) -> str:
    """Hex SHA-256 of a file's bytes (read in 1 MiB blocks)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


#: environment variable that, set to ``1``, trusts every pickle (what ``amigo-gym ... --trust-unverified`` sets)
TRUST_ENV = "AMIGO_GYM_TRUST_UNVERIFIED"
#: environment variable naming the folder of ``written.sha256`` (default ``$XDG_STATE_HOME/amigo_gym`` or
#: ``~/.local/state/amigo_gym``)
STATE_ENV = "AMIGO_GYM_STATE_DIR"


class UntrustedFileError(ValueError):
    """A pickle that neither a shipped manifest nor a run of this installation recorded (the message names it)."""


def _written_list() -> Path:
    state = os.environ.get("XDG_STATE_HOME") or os.path.join(os.path.expanduser("~"), ".local", "state")
    return Path(os.environ.get(STATE_ENV) or os.path.join(state, "amigo_gym")) / "written.sha256"


def vouch(*digests: str) -> None:
    """Append the sha256 of pickles this installation wrote to ``written.sha256`` in the state folder
    (:data:`STATE_ENV`), so that loading them needs no trust flag; a failure is a warning."""
    path = _written_list()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
        try:
            os.write(fd, "".join(f"{d}\n" for d in digests).encode())  # one append: whole lines, any process
        finally:
            os.close(fd)
    except OSError as exc:
        print(f"warning: cannot record the sha256 of what this run wrote in {path} ({exc})", file=sys.stderr)


def _shipped_digests() -> set[str]:
    from amigo_gym.data import pretrained_dir

    out: set[str] = set()
    for manifest in pretrained_dir().rglob("*.json"):
        if isinstance(doc := json.loads(manifest.read_bytes()), dict):
            files = doc.get("files")
            digests = [doc.get("sha256"), *(files.values() if isinstance(files, dict) else ())]
            out |= {d for d in digests if isinstance(d, str)}
    return out


def require_trust(path: str | os.PathLike[str], digest: str | None = None, trust: bool = False) -> None:
    """Refuse to unpickle ``path`` (sha256 ``digest``, computed if ``None``) unless ``trust`` (or
    ``AMIGO_GYM_TRUST_UNVERIFIED=1``), or a shipped manifest (``agents/pretrained``) or :func:`vouch` recorded it:
    :class:`UntrustedFileError`, one line naming the file and the flag."""
    if trust or os.environ.get(TRUST_ENV) == "1":
        return
    digest = digest or sha256_file(path)
    written = _written_list()
    if digest in _shipped_digests() or (written.is_file() and digest in written.read_text().split()):
        return
    raise UntrustedFileError(
        f"{path}: refused: a pickle (loading it runs code) that no shipped manifest and no run of this installation "
        "recorded; pass --trust-unverified (Python: trust=True) to load it if you trust where it came from"
    )


def file_mode(folder: bool = False) -> int:
    """The mode of a new file under the current umask, ``0o666 & ~umask`` (``folder``: ``0o777 & ~umask``)."""
    umask = os.umask(0)
    os.umask(umask)
    return (0o777 if folder else 0o666) & ~umask


def atomic_save(save: Callable[[str], object], path: str | os.PathLike[str], *, parents: bool = False) -> None:
    """Let ``save(tmp)`` write the whole file at ``tmp`` (a ``str`` with ``path``'s suffix), then move it to ``path``.
    ``parents``: create missing folders (else a missing folder raises ``FileNotFoundError``)."""
    target = Path(path)
    if parents:
        target.parent.mkdir(parents=True, exist_ok=True)
    elif not target.parent.is_dir():
        raise FileNotFoundError(f"folder {str(target.parent)!r} of {str(target)!r} does not exist")
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.stem}.", suffix=target.suffix or ".tmp")
    os.close(fd)
    try:
        save(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, file_mode())
        fault_point(f"write:{target.name}")
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    fault_point(f"rename:{target.name}")
    fsync_dir(target.parent)


def atomic_write(path: str | os.PathLike[str], data: bytes | str, *, parents: bool = False) -> None:
    """Write ``data`` (``str`` as UTF-8) to ``path`` atomically (module docstring)."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    atomic_save(lambda tmp: Path(tmp).write_bytes(raw), path, parents=parents)


def atomic_write_json(path: str | os.PathLike[str], obj: Any, *, parents: bool = False) -> None:
    """``json.dumps(obj, indent=2)`` plus a newline, written atomically; NaN and inf as ``null`` (:func:`json_safe`)."""
    atomic_write(path, json.dumps(json_safe(obj), indent=2, allow_nan=False) + "\n", parents=parents)
