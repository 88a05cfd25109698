"""numpy's own float64 loops called from compiled code (the step calls ``np.tan``'s; ``np.exp``'s and ``np.sin``'s
test the mechanism; ``amigo_gym/sim/numpy_loops.py``, ``_kernels.numpy_loop_in_place``): the ufunc's bits on every
length, stride and special value; the checks that refuse a wrong loop; the single env's step in one call with them
(``tests/test_direct_call.py`` compares that step with the three passes bit for bit)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from amigo_gym.sim import fast, numpy_loops

pytest.importorskip("numba")

SPECIAL = [0.0, -0.0, np.inf, -np.inf, np.nan, 1e-310, -1e-310, 709.0, 710.0, -745.0, -746.0, 1e300, np.pi / 2]


def test_the_loops_are_found_and_refuse_other_ufuncs() -> None:
    for ufunc in (np.tan, np.exp, np.sin, np.sqrt):
        loop = numpy_loops.ufunc_loop(ufunc)
        assert loop is not None and loop.address != 0
    assert numpy_loops.ufunc_loop(np.add) is None  # two inputs
    assert numpy_loops.ufunc_loop(np.isnan) is None  # no float64 -> float64 loop
    assert numpy_loops.ufunc_loop(np.tan) != numpy_loops.ufunc_loop(np.exp)
    assert numpy_loops.ufunc_loop(len) is None  # type: ignore[arg-type]
    assert numpy_loops.numpy_loops() is not None


@pytest.mark.parametrize("ufunc", [np.tan, np.exp, np.sin])
def test_a_loop_called_in_place_gives_the_ufuncs_bits(ufunc: np.ufunc) -> None:
    """Every length from 0 to 40 (numpy's SIMD loops take their tails apart), strided views, special values."""
    loop = numpy_loops.ufunc_loop(ufunc)
    assert loop is not None
    k = fast.kernels()
    meta = np.zeros(5, dtype=np.int64)
    for call in (k.numpy_loop_in_place, numpy_loops.numpy_loop_in_place):  # compiled, and Python (ctypes)
        _in_place(call, ufunc, loop, meta)


def _in_place(call: Any, ufunc: np.ufunc, loop: numpy_loops.UfuncLoop, meta: np.ndarray) -> None:
    g = np.random.default_rng(3)
    pool = np.concatenate((g.uniform(-4.0, 4.0, 500), g.uniform(-800.0, 800.0, 500), g.normal(0.0, 1e-3, 100), SPECIAL))
    g.shuffle(pool)
    with np.errstate(all="ignore"):
        for n in range(41):
            x = pool[n : 2 * n].copy()
            want = ufunc(x)
            call(loop.address, loop.data, x, meta)
            assert x.tobytes() == want.tobytes(), n
        for step in (2, 3):
            base = pool[:600].copy()
            view = base[::step]
            want = ufunc(view)
            call(loop.address, loop.data, view, meta)
            assert view.tobytes() == want.tobytes()
            assert base[1::step].tobytes() == pool[1:600:step].tobytes()  # the rows between untouched


def test_a_wrong_loop_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """The check of numpy_loops on its sample: exp's loop offered for tan gives other bits, so no loops (the single env
    then runs its other routes)."""
    exp = numpy_loops.ufunc_loop(np.exp)
    monkeypatch.setattr(numpy_loops, "ufunc_loop", lambda ufunc: exp)
    numpy_loops.numpy_loops.cache_clear()
    try:
        assert numpy_loops.numpy_loops() is None
    finally:
        monkeypatch.undo()
        numpy_loops.numpy_loops.cache_clear()
    assert numpy_loops.numpy_loops() is not None
