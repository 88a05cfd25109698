"""numpy's own float64 inner loop of ``np.tan``, for the compiled single step to call in place.

The reference computes the step's tangents with numpy's ufunc, whose float64 loop numpy picks at run time for the CPU
(its SIMD code: on AVX-512, numpy's SVML ``tan``), so its bits are the CPU's and the C library's ``tan`` gives other
bits on some CPUs (AVX-512). (The reward's exponentials are the package's own, in plain arithmetic:
:func:`amigo_gym.model.kinematics.col_exp`.) numpy keeps the
loop it picked for each type signature in its ufunc object (``PyUFuncObject.functions``, with ``data`` and
``types``: numpy's public C API, ``ufuncobject.h``, unchanged from numpy 1.0 to 2.x). :func:`ufunc_loop` reads the
address of a ufunc's ``float64 -> float64`` loop, which the compiled steps receive as an integer and call
(:func:`numpy_loop_in_place`, which the kernels compile, its :func:`call_loop` an intrinsic there:
:func:`loop_call_typing`). That runs numpy's own machine code, so it gives
numpy's bits on every CPU, inside one compiled call instead of a ufunc call from Python (about 0.3 us each).

Where the object does not look as expected (another Python implementation, a numpy that moved the fields, no
``float64`` loop), :func:`ufunc_loop` returns None and the callers use numpy's ufuncs from Python instead (v0's single
step its three passes); so they do where the loop found does not give the ufunc's
bits on a sample (:func:`numpy_loops`).
"""

from __future__ import annotations

import ctypes
import sys
from functools import lru_cache
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.params import HEADING_LIMIT

__all__ = [
    "UfuncLoop",
    "call_loop",
    "loop_call_typing",
    "numpy_loop_in_place",
    "numpy_loops",
    "tan_sample",
    "TanLoop",
    "ufunc_loop",
]

#: numpy's type number of float64 (``NPY_DOUBLE``)
_NPY_DOUBLE = 12
#: offsets of the fields read from ``PyUFuncObject`` on a 64-bit CPython: ``PyObject_HEAD`` (16 bytes), then
#: ``int nin, nout, nargs, identity``, ``functions``, ``data`` (pointers), ``int ntypes, reserved1``,
#: ``const char *name``, ``const char *types``
_NIN, _NOUT, _NARGS, _FUNCTIONS, _DATA, _NTYPES, _NAME, _TYPES = 16, 20, 24, 32, 40, 48, 56, 64


class UfuncLoop(NamedTuple):
    """The inner loop numpy runs for a unary ufunc on float64: ``void loop(char **args, npy_intp *dimensions,
    npy_intp *steps, void *data)`` at ``address``, with its ``data`` pointer (0 for none)."""

    address: int
    data: int


class TanLoop(NamedTuple):
    """The loop of ``np.tan`` (:func:`numpy_loops`)."""

    tan: UfuncLoop


def ufunc_loop(ufunc: np.ufunc) -> UfuncLoop | None:
    """The ``float64 -> float64`` loop of the unary ``ufunc`` (the first for that signature, the one numpy's type
    resolution picks), read from its ``PyUFuncObject``; None where the object does not look as expected."""
    if sys.implementation.name != "cpython" or ctypes.sizeof(ctypes.c_void_p) != 8 or not isinstance(ufunc, np.ufunc):
        return None
    base = id(ufunc)

    def read(offset: int, kind: type[Any]) -> Any:
        return kind.from_address(base + offset).value

    if (read(_NIN, ctypes.c_int), read(_NOUT, ctypes.c_int), read(_NARGS, ctypes.c_int)) != (1, 1, 2):
        return None
    ntypes, functions, data = (
        read(_NTYPES, ctypes.c_int),
        read(_FUNCTIONS, ctypes.c_void_p),
        read(_DATA, ctypes.c_void_p),
    )
    name, types = read(_NAME, ctypes.c_void_p), read(_TYPES, ctypes.c_void_p)
    if ntypes != ufunc.ntypes or not functions or not types or not name:
        return None
    if ctypes.string_at(name) != ufunc.__name__.encode():
        return None
    codes = ctypes.string_at(types, 2 * ntypes)
    for i in range(ntypes):
        if codes[2 * i] == codes[2 * i + 1] == _NPY_DOUBLE:
            address = ctypes.c_void_p.from_address(functions + 8 * i).value
            extra = ctypes.c_void_p.from_address(data + 8 * i).value if data else None
            return UfuncLoop(address, extra or 0) if address else None
    return None


#: the C type of a numpy inner loop, for :func:`call_loop` in Python
_LOOP_T = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)


def call_loop(loop: int, args: int, dims: int, steps: int, data: int) -> None:
    """``loop(args, dims, steps, data)``: the numpy inner loop at the address ``loop``, ``void (char **args, npy_intp
    const *dimensions, npy_intp const *steps, void *data)`` (numpy's C API, ``ufuncobject.h``), its arguments given as
    addresses. In Python by ``ctypes``; compiled code calls it directly (:func:`loop_call_typing`, which the kernels
    register in its place: ``amigo_gym.sim.layout.shared_compiler``'s ``intrinsics``)."""
    _LOOP_T(loop)(args, dims, steps, data or None)


def numpy_loop_in_place(loop: int, data: int, x: Any, meta: Any) -> None:
    """``x = f(x)`` in place, ``x`` a float64 ``(n,)`` array, by numpy's own float64 loop of a unary ufunc ``f`` at
    the address ``loop`` (with its ``data`` pointer: :func:`numpy_loops`), called as numpy calls it for ``f(x,
    out=x)``: the arguments' addresses, ``x``'s length and strides in ``meta`` (an int64 ``(5,)`` scratch array). The
    same code in Python and compiled (the kernels list it in their ``SHARED``)."""
    meta[0] = x.ctypes.data
    meta[1] = x.ctypes.data
    meta[2] = x.shape[0]
    meta[3] = x.strides[0]
    meta[4] = x.strides[0]
    base = meta.ctypes.data
    call_loop(loop, base, base + 16, base + 24, data)


def loop_call_typing(typingctx: object, loop: Any, args: Any, dims: Any, steps: Any, data: Any) -> Any:
    """The typing and code of :func:`call_loop` in compiled code (numba's ``intrinsic``): the loop called at its address
    (an argument, never a constant of the compiled code, so numba's disk cache holds nothing of one process), its
    arguments integers turned into pointers. numba imported here, when a kernel is compiled."""
    from llvmlite import ir
    from numba.core import types

    if not all(isinstance(a, types.Integer) for a in (loop, args, dims, steps, data)):
        return None

    def codegen(context: object, builder: Any, signature: object, values: list[Any]) -> Any:
        char_p, intp_p = ir.IntType(8).as_pointer(), ir.IntType(64).as_pointer()
        fn_t = ir.FunctionType(ir.VoidType(), [char_p.as_pointer(), intp_p, intp_p, char_p])
        fn = builder.inttoptr(values[0], fn_t.as_pointer())
        kinds = (char_p.as_pointer(), intp_p, intp_p, char_p)
        builder.call(fn, [builder.inttoptr(v, kind) for v, kind in zip(values[1:], kinds, strict=True)])
        return context.get_dummy_value()  # type: ignore[attr-defined]

    return types.none(loop, args, dims, steps, data), codegen


def tan_sample() -> NDArray[np.float64]:
    """The fixed sample of :func:`numpy_loops`: 5000 arguments of ``tan`` (half turns, and headings of many laps up to
    :data:`amigo_gym.model.params.HEADING_LIMIT`)."""
    g = np.random.default_rng(20261126)
    return np.concatenate(
        (
            g.uniform(-2.0, 2.0, 2000),
            g.normal(0.0, 1e-3, 1000),
            g.uniform(-2000.0, 2000.0, 1000),
            g.uniform(-HEADING_LIMIT, HEADING_LIMIT, 1000),
        )
    )


@lru_cache(maxsize=1)
def numpy_loops() -> TanLoop | None:
    """numpy's float64 loop of ``np.tan`` (:func:`ufunc_loop`), checked once per process: called by
    :func:`numpy_loop_in_place`, it gives the ufunc's bits on the sample of :func:`tan_sample`. None where the loop is
    not found or gives other bits."""
    tan = ufunc_loop(np.tan)
    if tan is None:
        return None
    x = tan_sample()
    y = x.copy()
    numpy_loop_in_place(tan.address, tan.data, y, np.zeros(5, dtype=np.int64))  # in Python (ctypes): as compiled
    with np.errstate(all="ignore"):
        if not np.array_equal(y.view(np.int64), np.tan(x).view(np.int64)):
            return None
    return TanLoop(tan)
