"""The pieces of AmigoBot-v1's evaluation, step noise and command ring that are written once (issue 19) give the same
bits on their three routes: on ``(N,)`` columns (the vector env's reference), on Python floats (the single env's
reference) and compiled into the kernel (``sim/_kernels_v1.py``, through ``layout_v1.SHARED`` and the overloads of
``task.v1``'s polymorphic helpers ``_clip``, ``_min``, ``_max0``, ``_abs`` and ``randomization._uint64``).

Inputs include the cases where the routes could part: values past the clip bounds, exactly on them, signed zeros,
NaN and infinities for the clipped fields, keys at and above ``2**63`` for the counter generator (``uint64`` in the
kernel, Python ints in the reference), and ring counters below the lag (Python's modulo).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from amigo_gym.model import actuators, randomization
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking

pytest.importorskip("numba", reason="the compiled v1 step needs numba (the extra amigo_gym[fast])")

N = 257


def same(a: Any, b: Any, zero_sign: bool = True) -> bool:
    """Bit for bit, the sign of a zero included unless ``zero_sign`` is false (NaN equal to NaN); bools as bools.

    Between the float route and the column route the sign of a zero that a clip or a minimum returns for two zeros is
    numpy's SIMD loop's choice, which differs between CPUs (x86-64, ARM): not compared there."""
    if isinstance(a, (bool, np.bool_)) or isinstance(b, (bool, np.bool_)):
        return bool(a) == bool(b)
    a = float(a)
    b = float(b)
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b and (not zero_sign or math.copysign(1.0, a) == math.copysign(1.0, b))


def _column(rng: np.random.Generator, scale: float, special: tuple[float, ...] = ()) -> np.ndarray:
    x = rng.normal(0.0, scale, N)
    x[: len(special)] = special
    return x


def _kernels() -> Any:
    from amigo_gym.sim import _kernels_v1

    return _kernels_v1


def check_routes(
    piece: Callable[..., Any], compiled: Callable[..., Any], columns: list[Any], floats: list[Any]
) -> None:
    """``piece`` on the columns, and ``piece`` and ``compiled`` row by row on floats, give the same bits."""
    with np.errstate(invalid="ignore", over="ignore"):  # the infinities and NaN of the inputs
        by_columns = piece(*columns)
    for i in range(N):
        row = [c[i] if isinstance(c, np.ndarray) else c for c in floats]
        args = [float(v) if isinstance(v, np.floating) else v for v in row]
        by_float = piece(*args)
        by_kernel = compiled(*args)
        for j, (col, f, k) in enumerate(zip(by_columns, by_float, by_kernel, strict=True)):
            want = np.asarray(col).reshape(-1)
            want_i = want[i] if want.size > 1 else want[0]
            assert type(f) in (float, bool), (piece.__name__, j, type(f))  # the float route stays on Python scalars
            assert same(f, k) and same(f, want_i, zero_sign=False), (piece.__name__, i, j, f, k, want_i)


EDGES = (math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 2.0, -2.0, 1e300, -1e300)


def test_observation_pieces_three_routes() -> None:
    kv = _kernels()
    rng = np.random.default_rng(0)
    l3, error_scale, e_max, scale, bound, v_max, w_max = 0.2, 0.1, 4.0, 0.5, 1.7, 0.75, 8.5
    m_e = _column(rng, 0.5, (*EDGES, 0.4, -0.4))  # +-e_max error_scale: exactly on the bound
    m_k = _column(rng, 5.0, (*EDGES, 5.0, -5.0))  # +-1 / l3
    sin_psi, cos_psi = _column(rng, 1.0, EDGES), _column(rng, 1.0)
    head = [m_e, sin_psi, cos_psi, m_k, l3, error_scale, e_max]
    check_routes(task.observe_head, kv._observe_head, head, head)

    cols = [_column(rng, 1.0, EDGES) for _ in range(7)]
    preview = [*cols, l3, scale, bound]
    check_routes(tracking.preview_entry, kv._preview_entry, preview, preview)

    v_ref = _column(rng, 0.5, (*EDGES, 0.75))
    v_meas = v_ref + _column(rng, 1.0, (*EDGES, 1.5))  # v_meas - v_ref = 2 v_max: on the bound
    w = _column(rng, 15.0, (*EDGES, 17.0, -17.0))
    speeds = [v_ref, _column(rng, 0.5), v_meas, w, w[::-1].copy(), v_max, w_max]
    check_routes(tracking.speed_observations, kv._speed_observations, speeds, speeds)

    noise = [_column(rng, 1.0, EDGES) for _ in range(10)]
    check_routes(tracking.measurements, kv._measurements, noise, noise)

    a = [_column(rng, 1.0, EDGES), _column(rng, 2.0, EDGES[::-1]), w_max]
    check_routes(tracking.action_commands, kv._action_commands, a, a)


def test_end_flags_three_routes() -> None:
    kv = _kernels()
    rng = np.random.default_rng(1)
    e = _column(rng, 0.3, (*EDGES, 0.5, -0.5))
    status = rng.integers(0, 4, N)  # STATUS_INTERIOR, START, END, WINDOW
    closed = rng.integers(0, 2, N).astype(np.bool_)
    by_columns = tracking.end_flags(e, 0.5, closed, status)
    for i in range(N):
        by_float = tracking.end_flags(float(e[i]), 0.5, bool(closed[i]), int(status[i]))  # the single env's types
        by_kernel = kv._end_flags(float(e[i]), 0.5, 1.0 if closed[i] else 0.0, int(status[i]))  # pv[P_CLOSED]
        for col, f, k in zip(by_columns, by_float, by_kernel, strict=True):
            assert type(f) is bool and f == bool(col[i]) == bool(k), (i, e[i], status[i], closed[i])


def test_reference_speed_three_routes() -> None:
    """The trapezoid and the constant speed, at finite times and speeds (the min's NaN rule differs between
    ``min_scalar`` and ``np.minimum``, as it always has between the float and the column route; neither ever sees a
    NaN time)."""
    kv = _kernels()
    rng = np.random.default_rng(2)
    v = rng.uniform(0.0, 0.75, N)
    t = rng.uniform(-1.0, 30.0, N)
    t_brake = rng.uniform(0.0, 25.0, N)
    t[:4] = (0.0, -0.0, t_brake[4] + v[4] / 0.3, 5.0)  # the brake ends exactly at t: v - decel (t - t_b) = 0
    t_brake[3] = math.inf  # a constant speed after the start
    args = [v, 0.4, 0.3, t_brake, t]
    for trapezoid in (True, False):

        def piece(*a: Any, flag: bool = trapezoid) -> tuple[Any]:
            return (tracking.reference_speed_of(flag, *a),)

        def compiled(*a: Any, flag: bool = trapezoid) -> tuple[Any]:
            return (kv._reference_speed_of(flag, *a),)

        check_routes(piece, compiled, args, args)


def test_step_draws_compiled_equal_python_ints() -> None:
    """``step_uniforms`` (SplitMix64) compiled on ``uint64`` against Python ints, keys past ``2**63`` and large step
    counters included, and against the column generator ``counter_uniform``; ``step_normals`` compiled against
    Python on the same logarithms and cosines."""
    kv = _kernels()
    rng = np.random.default_rng(3)
    levels = (0.005, 0.0, 0.2)  # position on, heading off, wheel rates on: 4 channels on
    on_channels = (0, 1, 3, 4)
    for i in range(200):
        key = int(rng.integers(0, 2**63)) * 2 + int(rng.integers(0, 2))
        key = (2**64 - 1, 2**63, 0)[i] if i < 3 else key
        step = int(rng.integers(0, 2**40)) if i % 2 else int(rng.integers(0, 1000))
        slip = float(rng.uniform(0.0, 0.1)) if i % 3 else 0.0
        buf = [0.0] * 10
        want = randomization.step_uniforms(buf, 0, 5, key, step, slip, *levels)
        ws = np.zeros(10)
        got = kv._step_uniforms(ws, 0, 5, np.uint64(key), step, slip, *levels)
        assert want == got and want[2] == 4, (key, step)
        assert all(same(a, b) for a, b in zip(buf, ws.tolist(), strict=True)), (key, step)
        for j, ch in enumerate(on_channels):
            u1 = randomization.counter_uniform(np.array([key], np.uint64), np.array([step]), 2 * (ch + 1))
            assert same(buf[j], u1[0]), (key, step, ch)
        logs = np.log(buf[:4]).tolist()
        coss = np.cos(buf[5:9]).tolist()
        out = [9.0] * 5
        randomization.step_normals(out, 0, logs, 0, coss, 0, *levels)
        out_k = np.full(5, 9.0)
        kv._step_normals(out_k, 0, np.array(logs), 0, np.array(coss), 0, *levels)
        assert out[2] == 0.0 and all(same(a, b) for a, b in zip(out, out_k.tolist(), strict=True))


def test_ring_slots_compiled_equal_python() -> None:
    """Python's modulo (never negative) in both, counters below the lag included."""
    kv = _kernels()
    for length in (2, 3, 7):
        for step in range(-3, 20):
            assert kv._ring_slot(step, length) == actuators.ring_slot(step, length) == step % length
            for lag in range(length - 1):
                want = actuators.ring_read_slots(step, lag, length)
                assert kv._ring_read_slots(step, lag, length) == want
                cols = actuators.ring_read_slots(step, np.array([lag, lag]), length)
                assert [int(c[0]) for c in cols] == list(want)


def test_actuator_helpers_have_their_float_forms_compiled() -> None:
    """The actuator step's two helpers that differ between floats and columns (``actuators.SCALAR_FORMS``) have float
    forms that the kernel lists (its fingerprint) and compiles in their place; the sort of columns gives each row the
    float sort's values, ties included (the piece boundaries are never -0.0 or NaN: ramp times from ``|u| / rate``
    and ``fmod`` of a delay >= 0)."""
    from amigo_gym.sim import layout_v1

    for form in actuators.SCALAR_FORMS.values():
        assert form in layout_v1.SHARED
    g = np.random.default_rng(4)
    cols = [g.choice([0.0, 0.05, 0.1, 0.07, 0.1 / 3.0], 64) for _ in range(9)]
    ws: list[Any] = [0.0, *cols]
    actuators.sort_knots(ws, 1, 9)
    for i in range(64):
        row = [0.0, *(float(c[i]) for c in cols)]
        actuators.sort_knots(row, 1, 9)
        assert row[1:] == [float(c[i]) for c in ws[1:]]
