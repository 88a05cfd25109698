"""Atomic file writing: what a user saves is never left half-written by an interrupted run.

Every writer puts the data in a temporary file in the target's own folder (same file system), flushes
and fsyncs it, gives it the mode a plain new file would get (``0o666 & ~umask``; ``mkstemp`` makes
``0o600``) and then moves it over the target with ``os.replace``, which is atomic on POSIX and Windows.
On any error, ``KeyboardInterrupt`` included, the temporary file is removed and the target is untouched.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["atomic_save", "atomic_write", "atomic_write_json", "file_mode"]


def file_mode() -> int:
    """The mode of a new plain file under the current umask, ``0o666 & ~umask``."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _target(path: str | os.PathLike[str], parents: bool) -> Path:
    target = Path(path)
    folder = target.parent
    if parents:
        folder.mkdir(parents=True, exist_ok=True)
    elif not folder.is_dir():
        raise FileNotFoundError(f"folder {str(folder)!r} of {str(target)!r} does not exist")
    return target


def atomic_save(save: Callable[[str], object], path: str | os.PathLike[str], *, parents: bool = False) -> None:
    """Let ``save(tmp)`` write a temporary file (e.g. ``fig.savefig``, ``model.save``), then move it to ``path``.

    The temporary name keeps ``path``'s suffix, for writers that choose the format by it.

    Args:
        save: called once with the temporary file's path (a ``str``); must write the whole file.
        path: the target.
        parents: create missing parent folders (otherwise a missing folder raises ``FileNotFoundError``).
    """
    target = _target(path, parents)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.stem}.", suffix=target.suffix or ".tmp")
    os.close(fd)
    try:
        save(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.chmod(tmp, file_mode())
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write(path: str | os.PathLike[str], data: bytes | str, *, parents: bool = False) -> None:
    """Write ``data`` (``str`` as UTF-8) to ``path`` atomically (module docstring)."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    atomic_save(lambda tmp: Path(tmp).write_bytes(raw), path, parents=parents)


def atomic_write_json(path: str | os.PathLike[str], obj: Any, *, parents: bool = False) -> None:
    """``json.dumps(obj, indent=2)`` plus a newline, written atomically."""
    atomic_write(path, json.dumps(obj, indent=2) + "\n", parents=parents)
