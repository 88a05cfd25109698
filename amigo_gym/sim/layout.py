"""What the compiled step's modules share: :func:`twin` and :func:`kernel_cache` (numba's disk cache in a folder
keyed by the package's source bytes, so that a change of any file it compiles is seen).

Imports nothing of the package; numba only inside :func:`kernel_cache`.
"""

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
    """A copy of the function ``fn`` named ``name``, for the compiled kernels: numba caches a compiled function under
    its name, so the serial and the parallel compilation of one loop need two names (else they would share a cache
    entry). Used by :mod:`amigo_gym.sim._kernels_v1`."""
    assert isinstance(fn, types.FunctionType)
    copy = types.FunctionType(fn.__code__, fn.__globals__, name, fn.__defaults__, fn.__closure__)
    copy.__qualname__ = name
    copy.__doc__ = fn.__doc__
    return copy


def source_digest() -> str:
    """A short hash (16 hex digits) of the bytes of every ``.py`` file of the environment core (the package but
    :mod:`amigo_gym.tools`, which the kernels never import), in path order.

    numba keys its disk cache of a compiled function on the function's own file, but compiles into it the constants
    and functions it uses from other files: :func:`kernel_cache` puts the cache in a folder named by this digest, so
    that a change of any source file gives a fresh cache. Bytes, not syntax trees: the same on every Python.
    """
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        if f.relative_to(root).parts[0] == "tools":
            continue
        digest.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def cache_root() -> Path:
    """Where the kernels' compiled code is kept: ``$NUMBA_CACHE_DIR/amigo_gym`` when the user sets numba's cache
    folder, else ``$XDG_CACHE_HOME/amigo_gym/numba`` (``~/.cache/amigo_gym/numba``)."""
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        return Path(user) / "amigo_gym"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "amigo_gym" / "numba"


#: how many source digests' caches :func:`kernel_cache` keeps (the most recently used; one per install or edit)
KEEP_CACHES = 8


@contextmanager
def kernel_cache() -> Iterator[Path]:
    """Import a kernel module inside this block: numba's disk cache for the functions it compiles with
    ``cache=True`` is ``cache_root() / source_digest()`` (numba reads ``config.CACHE_DIR`` when a function is
    decorated); numba's setting is restored after. Caches of other digests beyond :data:`KEEP_CACHES` are removed,
    least recently used first. Yields the folder.
    """
    from numba.core import config as numba_config

    config = cast(Any, numba_config)  # its settings are set at run time

    root = cache_root()
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
