"""What the compiled steps' modules share and numba need not load: :func:`twin` and :func:`source_fingerprint`.

Imported by :mod:`amigo_gym.sim._kernels`, :mod:`amigo_gym.sim._kernels_v1` and :mod:`amigo_gym.sim.layout_v1`;
imports nothing of the package, never numba.
"""

from __future__ import annotations

import ast
import hashlib
import inspect
import textwrap
import types
from collections.abc import Callable, Iterable, Mapping
from typing import Any, TypeVar, cast

__all__ = ["twin", "code_text", "source_fingerprint", "check_fingerprint", "shared_compiler"]

_F = TypeVar("_F", bound=Callable[..., Any])
#: the functions already registered with numba by :func:`shared_compiler`
_REGISTERED: set[Callable[..., Any]] = set()


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
    """A short hash (16 hex digits) of ``repr(values)`` and of the code of ``functions`` (:func:`code_text`).

    numba keys its disk cache of a kernel on the kernel's own file, but compiles into it the constants and the
    reference functions it calls from other files: a kernel module states the fingerprint of those it was written
    for and refuses to load when it differs (so that a change of them comes with a change of the kernel's file,
    which invalidates the cached code). Docstrings, comments and formatting do not count.
    """
    shared = tuple(code_text(f) for f in functions)
    return hashlib.sha256(repr((values, shared)).encode()).hexdigest()[:16]


def code_text(fn: Callable[..., Any]) -> str:
    """The code of the function ``fn`` as text, without its docstrings, comments and layout: ``ast.dump`` of its
    source's syntax tree, the docstrings of it and of the functions and classes inside it removed."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef) and node.body:
            first = node.body[0]
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                node.body = node.body[1:] or [ast.Pass()]
    return ast.dump(tree)


def check_fingerprint(owner: str, stated: str, actual: str) -> None:
    """Refuse to load the kernel module ``owner`` (``ImportError``) when the fingerprint it states is not the
    :func:`source_fingerprint` of what it compiles now (:func:`source_fingerprint`)."""
    if actual != stated:
        path = owner.replace(".", "/") + ".py"
        raise ImportError(
            f"{owner} was written for the fingerprint {stated}, but its layouts and shared functions now have "
            f"{actual}: update LAYOUT_FINGERPRINT in {path}"
        )


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
    an ``ImportError`` for another (so that every function compiled into a kernel counts in its fingerprint).
    The functions of ``inline`` (a part of ``shared``) are inlined into their callers by numba itself
    (``inline="always"``: small loops that LLVM would otherwise leave as calls).
    ``scalar_forms`` maps polymorphic helpers (floats or columns, dispatching on ``isinstance``, which numba cannot
    compile) to their float forms (:data:`amigo_gym.model.numeric.SCALAR_FORMS`): compiled code calling a helper
    runs its float form (an ``overload``), which must be in ``shared`` (its source counts in the fingerprint).
    ``intrinsics`` maps Python functions to the typing functions of numba intrinsics that compiled code calls in their
    place (:func:`amigo_gym.sim.numpy_loops.call_loop`, whose Python form uses ``ctypes``); the typing functions must be
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
            raise ImportError(f"{owner} compiles {fn.__qualname__} but does not list it in SHARED (its fingerprint)")
        return cast(_F, jit(fn))

    return compiled
