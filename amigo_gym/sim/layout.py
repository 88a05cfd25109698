"""What the compiled steps' modules share: :func:`twin`, :func:`shared_compiler` and :func:`kernel_cache` (numba's
disk cache in a folder keyed by the package's source bytes, so that a change of any file it compiles is seen).

Imported by :mod:`amigo_gym.sim._kernels_v1` and its loader; imports nothing of
the package; numba only inside :func:`kernel_cache` and :func:`shared_compiler`.
"""

from __future__ import annotations

import hashlib
import inspect
import os
import shutil
import types
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar, cast

__all__ = ["twin", "source_digest", "cache_root", "kernel_cache", "shared_compiler"]

_F = TypeVar("_F", bound=Callable[..., Any])
#: the functions already registered with numba by :func:`shared_compiler`
_REGISTERED: set[Callable[..., Any]] = set()


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


def _calls(fn: Callable[..., Any]) -> Callable[..., Any]:
    """A function of any arguments that calls ``fn`` with them (an ``overload``'s implementation of an intrinsic)."""

    def call(*args: Any) -> Any:
        return fn(*args)

    return call


def _returns(scalar: Callable[..., Any]) -> Callable[..., Any]:
    """The typing function of an ``overload`` whose implementation is ``scalar`` for any argument types (numba
    requires the typing function's signature to be the implementation's)."""

    def typer(*args: Any) -> Callable[..., Any]:
        return scalar

    typer.__signature__ = inspect.signature(scalar)  # type: ignore[attr-defined]
    return typer


def shared_compiler(
    owner: str,
    shared: tuple[Callable[..., Any], ...],
    jit: Callable[..., Any],
    inline: tuple[Callable[..., Any], ...] = (),
    scalar_forms: Mapping[Callable[..., Any], Callable[..., Any]] | None = None,
    intrinsics: Mapping[Callable[..., Any], Callable[..., Any]] | None = None,
) -> Callable[[_F], _F]:
    """The decorator with which the kernel module ``owner`` compiles the reference's functions of ``shared``.

    Registers every function of ``shared`` with numba (``register_jitable``: compiled code may call it, as the
    shared functions call each other) and returns ``compiled(fn)``: ``jit(fn)`` for a function of ``shared``,
    an ``ImportError`` for another (so that what a kernel compiles is listed in one place).
    The functions of ``inline`` (a part of ``shared``) are inlined into their callers by numba itself
    (``inline="always"``: small loops that LLVM would otherwise leave as calls).
    ``scalar_forms`` maps polymorphic helpers (floats or columns, dispatching on ``isinstance``, which numba cannot
    compile) to their float forms (:data:`amigo_gym.model.numeric.SCALAR_FORMS`): compiled code calling a helper
    runs its float form (an ``overload``), which must be in ``shared``.
    ``intrinsics`` maps Python functions to the typing functions of numba intrinsics that compiled code calls in their
    place (:func:`amigo_gym.model.numeric.pow2_real`, whose Python form is numpy's); the typing functions must be
    in ``shared`` too.
    Only the kernel modules call this (they import numba anyway); this module stays numba-free.
    """
    from numba.extending import intrinsic, overload, register_jitable

    for fn in shared:
        if fn not in _REGISTERED:  # once per process (both kernels share some functions)
            if fn in inline:
                register_jitable(inline="always")(fn)
            else:
                register_jitable(fn)
            _REGISTERED.add(fn)
    for poly, scalar in (scalar_forms or {}).items():
        if scalar not in shared:
            raise ImportError(
                f"{owner} compiles {scalar.__qualname__} for {poly.__qualname__} but does not list it in SHARED"
            )
        if poly not in _REGISTERED:
            overload(poly, jit_options={"error_model": "numpy"})(_returns(scalar))
            _REGISTERED.add(poly)
    for python_form, typing in (intrinsics or {}).items():
        if typing not in shared:
            raise ImportError(f"{owner} compiles {typing.__qualname__} but does not list it in SHARED")
        if python_form not in _REGISTERED:
            overload(python_form)(_returns(_calls(intrinsic(typing))))
            _REGISTERED.add(python_form)

    def compiled(fn: _F) -> _F:
        if fn not in shared:
            raise ImportError(f"{owner} compiles {fn.__qualname__} but does not list it in SHARED")
        return cast(_F, jit(fn))

    return compiled
