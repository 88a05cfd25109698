"""What the compiled step's modules share: :func:`twin` and :func:`kernel_cache`. Imports nothing of the package."""

from __future__ import annotations

import hashlib
import os
import shutil
import types
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, cast


def twin(fn: Callable[..., Any], name: str) -> Callable[..., Any]:
    """A copy of the function ``fn`` named ``name`` (numba caches a compiled function under its name: the serial and
    parallel compilations of one loop need two)."""
    assert isinstance(fn, types.FunctionType)
    copy = types.FunctionType(fn.__code__, fn.__globals__, name, fn.__defaults__, fn.__closure__)
    copy.__qualname__ = name
    return copy


def source_digest() -> str:
    """16 hex digits of a hash of the bytes of every ``.py`` file of the package but :mod:`amigo_gym.tools`, in path
    order (numba keys its cache on the function's own file only, but compiles in what it uses from others)."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        if f.relative_to(root).parts[0] == "tools":
            continue
        digest.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


#: how many source digests' caches :func:`kernel_cache` keeps (the most recently used; one per install or edit)
KEEP_CACHES = 8


@contextmanager
def kernel_cache() -> Iterator[Path]:
    """Within this block numba's disk cache is ``root / source_digest()`` (yielded), ``root`` being
    ``$NUMBA_CACHE_DIR/amigo_gym`` when set, else ``$XDG_CACHE_HOME/amigo_gym/numba`` (``~/.cache/...``); the least
    recently used caches of other digests beyond :data:`KEEP_CACHES` are removed."""
    from numba.core import config as numba_config

    config = cast(Any, numba_config)  # its settings are set at run time

    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        root = Path(user) / "amigo_gym"
    else:
        root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "amigo_gym" / "numba"
    folder = root / source_digest()
    folder.mkdir(parents=True, exist_ok=True)
    folder.touch()
    others = sorted((p for p in root.iterdir() if p.is_dir() and p != folder), key=lambda p: p.stat().st_mtime)
    for old in others[: max(0, len(others) - (KEEP_CACHES - 1))]:
        shutil.rmtree(old, ignore_errors=True)
    previous = config.CACHE_DIR
    config.CACHE_DIR = str(folder)
    try:
        yield folder
    finally:
        config.CACHE_DIR = previous
