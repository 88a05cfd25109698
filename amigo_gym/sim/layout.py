"""What the compiled steps' modules share and numba need not load: :func:`twin` and :func:`source_fingerprint`.

Imported by :mod:`amigo_gym.sim._kernels`, :mod:`amigo_gym.sim._kernels_v1` and :mod:`amigo_gym.sim.layout_v1`;
imports nothing of the package, never numba.
"""

from __future__ import annotations

import hashlib
import inspect
import types
from collections.abc import Callable, Iterable
from typing import Any

__all__ = ["twin", "source_fingerprint"]


def twin(fn: Callable[..., Any], name: str) -> Callable[..., Any]:
    """A copy of the function ``fn`` named ``name``, for the compiled kernels: numba caches a compiled function under
    its name, so the serial and the parallel compilation of one loop need two names (else they would share a cache
    entry). Used by :mod:`amigo_gym.sim._kernels` and :mod:`amigo_gym.sim._kernels_v1`."""
    assert isinstance(fn, types.FunctionType)
    copy = types.FunctionType(fn.__code__, fn.__globals__, name, fn.__defaults__, fn.__closure__)
    copy.__qualname__ = name
    copy.__doc__ = fn.__doc__
    return copy


def source_fingerprint(values: object, functions: Iterable[Callable[..., Any]]) -> str:
    """A short hash (16 hex digits) of ``repr(values)`` and of the source text of ``functions``.

    numba keys its disk cache of a kernel on the kernel's own file, but compiles into it the constants and the
    reference functions it calls from other files: a kernel module states the fingerprint of those it was written
    for and refuses to load when it differs (so that a change of them comes with a change of the kernel's file,
    which invalidates the cached code).
    """
    shared = tuple(inspect.getsource(f) for f in functions)
    return hashlib.sha256(repr((values, shared)).encode()).hexdigest()[:16]
