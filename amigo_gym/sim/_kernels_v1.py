r"""The compiled step for one robot and its batch loops (numba): :func:`step` is
:func:`amigo_gym.task.v1.step_columns` on floats, :func:`evaluate` :func:`amigo_gym.task.v1.reset_columns`, the
reference's scalar functions compiled as they are (float forms for those that take columns). They agree with the
reference to 1e-9, not bit for bit (``sin``, ``cos``, ``tan``, ``exp`` and ``log`` are the C library's here).

Layouts (float64, C-contiguous; index constants in :mod:`amigo_gym.sim.layout_v1`, ``L`` here):

* ``consts``: ``CONSTANT_FIELDS``, the ``n_preview`` preview distances [m], their observation bounds, the actuator
  quadrature's nodes and weights on [0, 1] (``10 n_sub`` each, then its smaller rules: ``fresnel.step_table``), the
  path quadrature's (10 each);
* ``path``: a clothoid path's flat vector; empty for a circle or manoeuvre (closed forms in ``consts``);
* ``ring (L, 2)``: the command ring [rad/s], updated in place;
* ``ws (len(Rows._fields), N)``: the robots' state and episode, one named row ``(N,)`` each (``layout_v1.Rows``);
  the per-robot functions take the block and a robot's index ``i``;
* ``obs``: the observation (float32 or float64), ``rec``: the info record (``layout_v1.R_*``), written.
"""

from __future__ import annotations

import inspect
import math
import types
from collections.abc import Callable
from typing import Any, cast

import numba
import numpy as np
from llvmlite import ir as llvm_ir
from numba.core import cgutils
from numba.extending import intrinsic, overload, register_jitable
from numba.np import numpy_support
from numpy.typing import NDArray

from amigo_gym.model import actuators, fresnel, kinematics, numeric, randomization
from amigo_gym.model.actuators import PIECES
from amigo_gym.paths import classic, clothoid, families
from amigo_gym.sim import layout_v1 as L
from amigo_gym.sim.layout import twin as _twin
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking

F64 = NDArray[np.float64]

_jit = numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
_jit_inline = numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False, inline="always")

#: the modules whose functions the kernel compiles as they are: each registered with numba (``register_jitable``:
#: compiled code may call it), the node loops inlined (small loops LLVM would leave as calls)
_SHARED_MODULES = (actuators, fresnel, kinematics, randomization, classic, clothoid, families, task, tracking)
_INLINE = (fresnel.advance_nodes, fresnel.node_phases, fresnel.node_sums, fresnel.unit_speed_phases,
           fresnel.unit_speed_sums, fresnel.unit_speed_nodes)  # fmt: skip
#: functions that dispatch on floats or columns, and the float form compiled in their place
_FLOAT_FORMS: dict[Callable[..., Any], Callable[..., Any]] = {
    numeric.where: numeric.where_float,
    actuators.sort_knots: actuators.sort_knots_float,
    actuators.advance_pieces: fresnel.advance_nodes,
    classic.angle_of: classic.atan2_float,
    fresnel.tier: fresnel.tier_float,
}
_OVERLOADED: set[Any] = {*_FLOAT_FORMS, fresnel.cos_sin_nodes, randomization._uint64}


def _register() -> None:
    for module in (*_SHARED_MODULES, numeric):
        for fn in vars(module).values():
            if isinstance(fn, types.FunctionType) and fn.__module__ == module.__name__ and fn not in _OVERLOADED:
                register_jitable(inline="always" if fn in _INLINE else "never", error_model="numpy")(fn)
    for poly, scalar in _FLOAT_FORMS.items():
        typer = lambda *args, _s=scalar: _s  # noqa: E731
        typer.__signature__ = inspect.signature(scalar)  # type: ignore[attr-defined]
        overload(poly, jit_options={"error_model": "numpy"})(typer)


_register()


@overload(fresnel.cos_sin_nodes, jit_options={"error_model": "numpy"}, inline="always")
def _cos_sin_nodes(buf: F64, b: int, n: int, m: int) -> Callable[[F64, int, int, int], None]:
    """:func:`amigo_gym.model.fresnel.cos_sin_nodes`: ``cos``/``sin`` of the first phase ``p0``, each node's by the
    angle sum with ``d = p - p0`` and Taylor polynomials of ``cos d``, ``sin d`` when every ``|d| <= 0.5`` (terms left
    out < 1e-16), else ``math.cos``/``math.sin`` of each."""

    def impl(buf: F64, b: int, n: int, m: int) -> None:
        if n == 0:
            return
        p0 = buf[b]
        near = True
        for i in range(b, b + n):
            near = near & (abs(buf[i] - p0) <= 0.5)
        if not near:
            for i in range(b, b + n):
                phase = buf[i]  # one load: LLVM fuses the cosine and sine into one sincos call
                buf[m + i] = math.cos(phase)
                buf[2 * m + i] = math.sin(phase)
            return
        c0 = math.cos(p0)
        s0 = math.sin(p0)
        for i in range(b, b + n):
            d = buf[i] - p0
            d2 = d * d
            cd = 1.0 + d2 * (-_C2 + d2 * (_C4 + d2 * (-_C6 + d2 * (_C8 + d2 * (-_C10 + d2 * (_C12 - d2 * _C14))))))
            sd = d * (1.0 + d2 * (-_C3 + d2 * (_C5 + d2 * (-_C7 + d2 * (_C9 + d2 * (-_C11 + d2 * _C13))))))
            buf[m + i] = c0 * cd - s0 * sd
            buf[2 * m + i] = s0 * cd + c0 * sd

    return impl


_C2, _C3, _C4, _C5, _C6, _C7, _C8, _C9, _C10, _C11, _C12, _C13, _C14 = (1.0 / math.factorial(k) for k in range(2, 15))


#: entries of the path pose's node buffer (stride ``NODES + 1``), of the actuator step's (one sub-interval per piece;
#: more sub-intervals allocate theirs) and of its scratch, on the stack
_POSE_NODES = 3 * (L.PATH_NODES + 1)
_STEP_NODES = 3 * PIECES * L.PATH_NODES
_TIERS = 2 * sum(fresnel.TIER_NODES)  # the smaller rules' nodes and weights after the 10-node one (step_table)
_ACT_SCRATCH = actuators.SCRATCH
_RECORD = L.RECORD_WIDTH


def _stack_ptr_typing(typingctx: Any, n: Any) -> Any:
    if not isinstance(n, numba.types.IntegerLiteral):
        return None
    size = n.literal_value

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        ptr = _alloca_once(builder, llvm_ir.ArrayType(llvm_ir.DoubleType(), size))
        return builder.bitcast(ptr, llvm_ir.DoubleType().as_pointer())

    return _cpointer(numba.types.float64)(n), codegen


_alloca_once: Any = cgutils.alloca_once
_cpointer: Any = numba.types.CPointer
_carray: Any = numpy_support.carray


def _data_ptr_typing(typingctx: Any, arr: Any) -> Any:
    if not isinstance(arr, numba.types.Array):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return context.make_array(signature.args[0])(context, builder, args[0]).data

    return _cpointer(arr.dtype)(arr), codegen


#: ``_data_ptr(a)``: the data pointer of ``a``; ``_carray(_data_ptr(a), n)`` is a view of its first ``n`` elements
#: without a reference count (no atomic operations per call; used while ``a`` lives)
_data_ptr: Any = intrinsic(_data_ptr_typing)


@_jit_inline
def _bare(a: Any) -> Any:
    # ``a`` (C-contiguous) without a reference count: its views and slices take none either (no atomic operations
    # per row in the loops below)
    return _carray(_data_ptr(a), a.shape)


@_jit_inline
def _rows(ws: F64) -> L.Rows:
    # the named rows of the block ``ws`` (:data:`amigo_gym.sim.layout_v1.Rows`), without reference counts; whole rows,
    # not ``_rows_in(ws, 0, n)``: that form measured slower in the general row step (v1 vector step +5 to +25 %)
    w = _bare(ws)
    return L.Rows(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], w[8], w[9], w[10], w[11], w[12], w[13], w[14],
                  w[15], w[16], w[17], w[18], w[19], w[20], w[21])  # fmt: skip


@_jit_inline
def _rows_in(ws: F64, i0: int, i1: int) -> L.Rows:
    # the named rows of the columns i0:i1 of the block ``ws``, indexed from 0, without reference counts
    w = _bare(ws)
    return L.Rows(w[0, i0:i1], w[1, i0:i1], w[2, i0:i1], w[3, i0:i1], w[4, i0:i1], w[5, i0:i1], w[6, i0:i1],
                  w[7, i0:i1], w[8, i0:i1], w[9, i0:i1], w[10, i0:i1], w[11, i0:i1], w[12, i0:i1], w[13, i0:i1],
                  w[14, i0:i1], w[15, i0:i1], w[16, i0:i1], w[17, i0:i1], w[18, i0:i1], w[19, i0:i1],
                  w[20, i0:i1], w[21, i0:i1])  # fmt: skip


#: ``_stack_ptr(n)``: ``n`` float64 (a compile-time constant) on the caller's stack, no allocation per call
_stack_ptr: Any = intrinsic(_stack_ptr_typing)


#: the functions of floats or columns that the kernel calls, typed as their float forms
_command_change = cast(Callable[..., tuple[float, float]], tracking.command_change)
_action_commands = cast(Callable[..., tuple[float, float, float, float]], tracking.action_commands)
_measurements = cast(Callable[..., tuple[float, float, float, float, float]], tracking.measurements)
_arc_from_tangents = cast(Callable[..., tuple[float, float, float, float]], kinematics.arc_from_tangents)
_reference_speed_of = cast(Callable[..., float], tracking.reference_speed_of)


@overload(randomization._uint64, jit_options={"error_model": "numpy"})
def _uint64_of(n: int) -> Callable[[int], np.uint64]:
    """``np.uint64(n)``: the counter generator's wrapping ``uint64`` arithmetic."""

    def impl(n: int) -> np.uint64:
        return np.uint64(n)

    return impl


@_jit
def _actuator_step(c: F64, ws: F64, i: int, o1: float, o2: float, n1: float, n2: float, s1: float, s2: float) -> float:
    """:func:`amigo_gym.model.actuators.actuator_step_ws` of the state of row ``i``, updated in place; returns the true
    speed of A at the end of the step [m/s]."""
    r = _rows(ws)
    nn = int(c[L.C_N_NODES])
    base = L.C_TAIL + 2 * int(c[L.C_N_PREVIEW])
    size = 3 * PIECES * nn
    # on the stack for n_sub = 1 (dt = 0.1 s), else allocated
    nodes = _carray(_stack_ptr(_STEP_NODES), _STEP_NODES) if size <= _STEP_NODES else np.empty(size)
    scratch = _carray(_stack_ptr(_ACT_SCRATCH), _ACT_SCRATCH)
    x, y, beta, w1n, w2n, da1, da2, _dist, v_true, _w_true = actuators.actuator_step_ws(
        scratch, 0, nodes, 0, c, base, nn,
        r.x[i], r.y[i], r.beta[i], r.w1[i], r.w2[i], o1, o2, n1, n2, r.t_switch[i], c[L.C_DT],
        c[L.C_W_MAX], c[L.C_L1], c[L.C_R1], c[L.C_R2], c[L.C_TWO_L1],
        c[L.C_ACC], c[L.C_DEC], c[L.C_RACC], c[L.C_RDEC],
        r.r1[i], r.r2[i], r.l1[i], s1, s2,
    )  # fmt: skip
    r.x[i] = x
    r.y[i] = y
    r.beta[i] = beta
    r.w1[i] = w1n
    r.w2[i] = w2n
    r.alpha1[i] = r.alpha1[i] + da1
    r.alpha2[i] = r.alpha2[i] + da2
    return v_true  # type: ignore[return-value]  # a float here


@_jit
def _path_nodes(c: F64) -> int:
    nodes: int = L.C_TAIL + 2 * int(c[L.C_N_PREVIEW]) + 2 * int(c[L.C_N_NODES]) + _TIERS
    return nodes


@_jit_inline
def pose(c: F64, pv: F64, s: float) -> tuple[float, float, float, float, float, float, float]:
    """:func:`amigo_gym.paths.clothoid.pose_flat`: ``(x, y, theta, kappa, curvature_rate, cos theta, sin theta)`` at
    the arc length ``s`` [m]."""
    buf = _carray(_stack_ptr(_POSE_NODES), _POSE_NODES)
    return clothoid.pose_flat(buf, c, _path_nodes(c), pv, s)


@_jit
def _locate(
    c: F64, pv: F64, x: float, y: float, sp: float, scan: bool = True
) -> tuple[float, float, float, float, float, int]:
    """H's projection ``(progress, curvature, cross_track_error, cos_theta, sin_theta, status)`` from the hint ``sp``:
    ``path.locate`` with the window ``c[L.C_WINDOW]`` ahead and behind (``scan=False``: Newton from ``sp``, the foot
    of a point within a sample spacing); a circle's or manoeuvre's closed form (the circle's lap nearest ``sp``),
    status 0."""
    kind = c[L.C_PATH_KIND]
    if kind != L.PATH_CLOTHOID:
        d = c[L.C_DIRECTION]
        r = c[L.C_RADIUS]
        cx, cy, r0x, r0y = c[L.C_CX], c[L.C_CY], c[L.C_R0X], c[L.C_R0Y]
        if kind == L.PATH_CIRCLE:
            e, ct, st, ux, uy = classic.circle_foot(x, y, cx, cy, r0x, r0y, d, r)
            s = classic.circle_arc(ux, uy, r0x, r0y, d, r)
            lap = task.TWO_PI * r
            return s + lap * task.round_half_even((sp - s) / lap), d / r, e, ct, st, 0  # type: ignore[return-value]
        e, ct, st, s, _s_circ, on_line = classic.manoeuvre_foot(x, y, cx, cy, r0x, r0y, d, r, c[L.C_STRAIGHT])
        return s, 0.0 if on_line else d / r, e, ct, st, 0  # type: ignore[return-value]
    window = c[L.C_WINDOW]
    buf = _carray(_stack_ptr(_POSE_NODES), _POSE_NODES)
    s, _px, _py, _th, kappa, _cr, e, ct, st, _dist, status = clothoid.locate_flat(
        clothoid.pose_flat, buf, c, _path_nodes(c), pv, x, y, sp, window, window, scan
    )
    return s, kappa, e, ct, st, status


@_jit
def _draws(c: F64, steps: float, slip_max: float, key: np.uint64) -> tuple[float, ...]:
    # randomization.step_noise of the step counter: (slip1, slip2, the five normals), the normals by Box-Muller
    position = c[L.C_POS_NOISE]
    heading = c[L.C_HEAD_NOISE]
    rate = c[L.C_RATE_NOISE]
    u = _carray(_stack_ptr(15), 15)  # u1, 2 pi u2, the normals: 5 each
    s1, s2, on = randomization.step_uniforms(u, 0, 5, key, int(steps), slip_max, position, heading, rate)
    for j in range(on):
        u[j] = math.log(u[j])
        u[5 + j] = math.cos(u[5 + j])
    randomization.step_normals(u, 10, u, 0, u, 5, position, heading, rate)
    return s1, s2, u[10], u[11], u[12], u[13], u[14]  # type: ignore[return-value]  # floats here


_NO_DRAWS = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


# The path-building loops (clothoid.PathLoops), their scratch on the stack; ``nodes``: the quadrature's node table.
_RUN_NODES = families.RUN_SCRATCH


@_jit
def build_flat(
    nodes: F64, pv: F64, segs: F64, n_segs: int, n: int, m: int, total: float, spacing: float, x: float, y: float,
    th: float, closed: bool,
) -> tuple[float, float]:  # fmt: skip
    """:func:`amigo_gym.paths.clothoid.build_flat` and its :func:`~amigo_gym.paths.clothoid.sample_points`."""
    buf = _carray(_stack_ptr(_POSE_NODES), _POSE_NODES)
    gap = clothoid.build_flat(pv, segs, n_segs, n, m, total, spacing, x, y, th, closed, buf, nodes)
    clothoid.sample_points(buf, nodes, pv, clothoid.P_TAIL + 6 * n, m, spacing)
    return gap


@_jit
def rows_locate(
    nodes: F64, out: F64, flat: F64, start: NDArray[np.int64], x: F64, y: F64, sp: F64, ahead: float, behind: float,
    on: bool,
) -> None:  # fmt: skip
    """:func:`amigo_gym.paths.clothoid.locate_rows`: the column projection, row by row, into ``out``."""
    buf = _carray(_stack_ptr(_POSE_NODES), _POSE_NODES)
    clothoid.locate_rows(clothoid.pose_flat, out, buf, nodes, flat, start, x, y, sp, ahead, behind, on)


@_jit
def rows_pose(nodes: F64, out: F64, flat: F64, start: NDArray[np.int64], s: F64) -> None:
    """:func:`amigo_gym.paths.clothoid.pose_rows`: the column pose, row by row, into ``out``."""
    buf = _carray(_stack_ptr(_POSE_NODES), _POSE_NODES)
    clothoid.pose_rows(out, buf, nodes, flat, start, s)


@_jit
def build_samples(nodes: F64, pv: F64, o: int, count: int, spacing: float) -> None:
    """:func:`amigo_gym.paths.clothoid.sample_points`: the coarse samples written into ``pv``."""
    buf = _carray(_stack_ptr(_POSE_NODES), _POSE_NODES)
    clothoid.sample_points(buf, nodes, pv, o, count, spacing)


@_jit
def build_family(nodes: F64, kind: int, a: float, b: float, c: float) -> F64:
    """:func:`amigo_gym.paths.families.family_segments`: the segments, their number last."""
    buf = _carray(_stack_ptr(_RUN_NODES), _RUN_NODES)
    out = np.empty(3 * families.FAMILY_SEGMENTS + 1)
    out[-1] = families.family_segments(buf, nodes, out, kind, a, b, c)
    return out


@_jit
def family_rows(
    run_nodes: F64, kinds: NDArray[np.int64], params: F64, sample_spacing: float, segs: F64, lay: F64
) -> None:
    """Each row's family path of :func:`amigo_gym.paths.families.family_segments` (``kinds (m,)``, ``params (m,
    3)``): its segments into ``segs (m, 4 FAMILY_SEGMENTS)`` and :func:`amigo_gym.paths.clothoid.path_layout` into
    ``lay (m, 6)``: ``n_segs, n, m, length, max |kappa|, spacing``; a row's ``n_segs < 0`` on an error."""
    buf = _carray(_stack_ptr(_RUN_NODES), _RUN_NODES)
    out = np.empty(3 * families.FAMILY_SEGMENTS)
    for i in range(len(kinds)):
        g = families.family_segments(buf, run_nodes, out, kinds[i], params[i, 0], params[i, 1], params[i, 2])
        lay[i, 0] = g
        if g < 0:
            continue
        for j in range(3 * g):  # (length, curvature, rate) of segment j // 3 into segs[i, 4 (j // 3) + j % 3]
            segs[i, j + j // 3] = out[j]
        closed = families.family_start(kinds[i], params[i, 0])[3]
        n, m, total, kmax, spacing = clothoid.path_layout(segs[i], g, sample_spacing, closed)
        lay[i, 1], lay[i, 2], lay[i, 3], lay[i, 4], lay[i, 5] = n, m, total, kmax, spacing


def _family_fill(
    nodes: F64, flat: F64, starts: NDArray[np.int64], kinds: NDArray[np.int64], params: F64, segs: F64, lay: F64
) -> None:
    """The flat vectors of :func:`family_rows`' paths into ``flat[starts[i]:]`` (:func:`build_flat`)."""
    for i in numba.prange(len(kinds)):
        x, y, th, closed = families.family_start(kinds[i], params[i, 0])
        n, m = int(lay[i, 1]), int(lay[i, 2])
        build_flat(nodes, flat[starts[i] :], segs[i], int(lay[i, 0]), n, m, lay[i, 3], lay[i, 5], x, y, th, closed)


@_jit
def _curvature_at(c: F64, pv: F64, s: float) -> float:
    # the path's curvature [1/m] at the arc length s [m]
    kind = c[L.C_PATH_KIND]
    if kind == L.PATH_CLOTHOID:
        k: float = pose(c, pv, s)[3]
        return k
    curvature: float = c[L.C_DIRECTION] / c[L.C_RADIUS]
    if kind == L.PATH_CIRCLE:
        return curvature
    k_s: float = classic.manoeuvre_curvature(s, c[L.C_STRAIGHT], curvature)
    return k_s


@_jit
def progress(c: F64, pv: F64, x: float, y: float, s_prev: float) -> float:
    """H's progress [m]: ``path.locate(x, y, s_prev, window, window).progress``."""
    s: float = _locate(c, pv, x, y, s_prev)[0]
    return s


@_jit
def _reference_speed(c: F64, v_cruise: float, t_brake: float, t: float) -> float:
    return _reference_speed_of(c[L.C_TRAPEZOID] != 0.0, v_cruise, c[L.C_PACC], c[L.C_PDEC], t_brake, t)


@_jit
def _evaluate(
    c: F64, pv: F64, ws: F64, i: int, obs: NDArray[np.floating], rec: F64, v_true: float, cb: float, sb: float,
    da1: float, da2: float, t: float, nx: float, ny: float, nbeta: float, nr1: float, nr2: float,
) -> None:  # fmt: skip
    """:func:`amigo_gym.task.v1.evaluate_columns` of the state of row ``i`` with the heading's ``cos``, ``sin`` (``cb``,
    ``sb``), the command's change ``(da1, da2)`` and the noise ``(nx, ny, nbeta, nr1, nr2)``: H's progress into the
    row, the observation into ``obs``, the record but its command and slips into ``rec`` (the exponentials'
    arguments in their place)."""
    r = _rows(ws)
    l3 = c[L.C_L3]
    x = r.x[i]
    y = r.y[i]
    beta = r.beta[i]
    hx, hy = kinematics.h_from_a(x, y, cb, sb, r.l3[i])
    s_h, kappa, e, ct, st, status = _locate(c, pv, hx, hy, r.progress[i])
    cos_psi, sin_psi = task.heading_error(cb, sb, ct, st)
    v_ref = _reference_speed(c, r.v_cruise[i], r.t_brake[i], t)
    cos_ss, sin_ss = task.steady_heading_float(kappa, l3)
    rec[L.R_TRACK], rec[L.R_SPEED], rec[L.R_SMOOTH_EXP] = task.reward_arguments(
        abs(e), abs(v_true - v_ref), da1 * da1 + da2 * da2, c[L.C_SIG_T], c[L.C_SIG_V], c[L.C_SMOOTH_SQ]
    )
    rec[L.R_HEADING] = task.heading_term(cos_psi, sin_psi, cos_ss, sin_ss)
    closed = pv[clothoid.P_CLOSED] if c[L.C_PATH_KIND] == L.PATH_CLOTHOID else 1.0
    terminated, at_end = tracking.end_flags(e, c[L.C_TERM], closed, status)
    mx, my, mb, mw1, mw2 = _measurements(x, y, beta, r.w1[i], r.w2[i], nx, ny, nbeta, nr1, nr2)
    if tracking.measured_differs(c[L.C_POS_NOISE], c[L.C_HEAD_NOISE], r.l3_differs[i] != 0.0):
        mcb = math.cos(mb)
        msb = math.sin(mb)
        mhx, mhy = kinematics.h_from_a(mx, my, mcb, msb, l3)
        # Newton from H's foot (no coarse search) where it is a well-conditioned interior foot within a sample
        # spacing: the same foot (to 1e-12 m: tests/test_kernel_v1.py)
        near = len(pv) > 0 and status == clothoid.STATUS_INTERIOR and abs(kappa * e) <= 0.5
        near = near and (mhx - hx) ** 2 + (mhy - hy) ** 2 <= pv[clothoid.P_SPACING] ** 2
        m_s, m_k, m_e, m_ct, m_st, _ = _locate(c, pv, mhx, mhy, s_h, not near)
    else:
        mcb = cb
        msb = sb
        m_s, m_k, m_e, m_ct, m_st = s_h, kappa, e, ct, st
    m_cos_psi, m_sin_psi = task.heading_error(mcb, msb, m_ct, m_st)
    obs[0], obs[1], obs[2], obs[3] = task.observe_head(
        m_e, m_sin_psi, m_cos_psi, m_k, l3, c[L.C_ERROR_SCALE], c[L.C_E_MAX]
    )
    n_prev = int(c[L.C_N_PREVIEW])
    v_meas = kinematics.body_velocity_of(mw1, mw2, c[L.C_R1], c[L.C_R2], c[L.C_TWO_L1])[0]
    if c[L.C_OBS_V0] != 0.0:  # task.v0.observe_columns
        for j in range(n_prev):
            obs[4 + j] = task.curvature_feature(_curvature_at(c, pv, m_s + c[L.C_TAIL + j]), l3)
        obs[4 + n_prev], obs[5 + n_prev], obs[6 + n_prev] = task.observe_rates(
            mw1, mw2, v_meas, v_ref, c[L.C_W_MAX], c[L.C_V_MAX]
        )
        obs[7 + n_prev] = task.observe_reference(v_ref, c[L.C_V_MAX])
    else:
        scale = c[L.C_PREVIEW_SCALE]
        for j in range(n_prev):
            qx, qy, _th, qk, _cr, _ct, _st = pose(c, pv, m_s + c[L.C_TAIL + j])
            obs[4 + 3 * j], obs[5 + 3 * j], obs[6 + 3 * j] = tracking.preview_entry(
                mcb, msb, mx, my, qx, qy, qk, l3, scale, c[L.C_TAIL + n_prev + j]
            )
        v_ahead = _reference_speed(c, r.v_cruise[i], r.t_brake[i], t + c[L.C_LOOKAHEAD])
        k = 4 + 3 * n_prev
        obs[k], obs[k + 1], obs[k + 2], obs[k + 3], obs[k + 4] = tracking.speed_observations(
            v_ref, v_ahead, v_meas, mw1, mw2, c[L.C_V_MAX], c[L.C_W_MAX]
        )
        obs[k + 5] = r.a1[i]
        obs[k + 6] = r.a2[i]
    r.progress[i] = s_h
    rec[L.R_X] = x
    rec[L.R_Y] = y
    rec[L.R_BETA] = beta
    rec[L.R_HX] = hx
    rec[L.R_HY] = hy
    rec[L.R_W1] = r.w1[i]
    rec[L.R_W2] = r.w2[i]
    rec[L.R_AL1] = r.alpha1[i]
    rec[L.R_AL2] = r.alpha2[i]
    rec[L.R_MX] = mx
    rec[L.R_MY] = my
    rec[L.R_MB] = mb
    rec[L.R_ERROR] = e
    rec[L.R_PROGRESS] = s_h
    rec[L.R_VT] = v_true
    rec[L.R_VREF] = v_ref
    rec[L.R_END] = 1.0 if at_end else 0.0
    rec[L.R_TERM] = 1.0 if terminated else 0.0
    rec[L.R_CASTOR] = r.castor[i]


@_jit
def evaluate(
    c: F64, pv: F64, ws: F64, i: int, obs: NDArray[np.floating], rec: F64, v_true: float, t: float
) -> None:  # fmt: skip
    """:func:`amigo_gym.task.v1.reset_columns` of the state of row ``i`` (no noise, no command change) at the true
    speed ``v_true`` [m/s] and time ``t`` [s]: the observation into ``obs``, the record but its command and slips into
    ``rec`` (the exponentials' arguments in their place: :func:`fill_record`); the progress is kept."""
    r = _rows(ws)
    progress = r.progress[i]
    beta = r.beta[i]
    _evaluate(c, pv, ws, i, obs, rec, v_true, math.cos(beta), math.sin(beta), 0.0, 0.0, t, 0.0, 0.0, 0.0, 0.0, 0.0)
    r.progress[i] = progress
    rec[L.R_PROGRESS] = progress


@_jit
def step(
    c: F64, pv: F64, ring: F64, ws: F64, i: int, obs: NDArray[np.floating], rec: F64, ring_step: int, a1: float,
    a2: float, key: np.uint64,
) -> None:  # fmt: skip
    """:func:`amigo_gym.task.v1.step_columns` of the state of row ``i``, updated in place, for the finite action
    ``(a1, a2)`` [-] (clipped here); ``ring_step`` is the ring's counter. This step's draws (the episode's ``key``)
    when the row's ``slip_max`` or a noise level is above 0, else zeros. The observation into ``obs``, the record into
    ``rec`` (the exponentials' arguments in their place: :func:`fill_record`)."""
    r = _rows(ws)
    on = randomization.channels_on(c[L.C_POS_NOISE], c[L.C_HEAD_NOISE], c[L.C_RATE_NOISE])
    dr = _draws(c, r.steps[i], r.slip_max[i], key) if r.slip_max[i] > 0.0 or on > 0 else _NO_DRAWS
    c1, c2, cmd1, cmd2 = _action_commands(a1, a2, c[L.C_W_MAX])
    if c[L.C_IDEAL] != 0.0:
        v, bdot, h, arg_h, arg_m = _ideal_motion(c, r.beta[i], cmd1, cmd2)
        _ideal_move(c, pv, ws, i, obs, rec, dr, c1, c2, cmd1, cmd2, v, bdot, h, math.tan(arg_h), math.tan(arg_m))
        return
    length = ring.shape[0]
    slot = actuators.ring_slot(ring_step, length)
    ring[slot, 0] = cmd1
    ring[slot, 1] = cmd2
    i_old, i_new = actuators.ring_read_slots(ring_step, int(r.lag[i]), length)
    o1 = ring[i_old, 0]
    o2 = ring[i_old, 1]
    w1_old = r.w1[i]
    w2_old = r.w2[i]
    v_true = _actuator_step(c, ws, i, o1, o2, ring[i_new, 0], ring[i_new, 1], dr[0], dr[1])
    da1, da2 = _command_change(c[L.C_REWARD_V0] != 0.0, r.w1[i], r.w2[i], w1_old, w2_old, c1, c2, r.a1[i], r.a2[i])
    beta = r.beta[i]
    _finish(c, pv, ws, i, obs, rec, dr, v_true, math.cos(beta), math.sin(beta), da1, da2, c1, c2, cmd1, cmd2)


@_jit
def _finish(
    c: F64, pv: F64, ws: F64, i: int, obs: NDArray[np.floating], rec: F64, dr: tuple[float, ...], v_true: float,
    cb: float, sb: float, da1: float, da2: float, c1: float, c2: float, cmd1: float, cmd2: float,
) -> None:  # fmt: skip
    # the step's command and counter into the row, its commands and slips into rec, then the evaluation
    r = _rows(ws)
    steps = r.steps[i] + 1.0
    r.a1[i] = c1
    r.a2[i] = c2
    r.steps[i] = steps
    rec[L.R_CMD1] = cmd1
    rec[L.R_CMD2] = cmd2
    rec[L.R_SLIP1] = dr[0]
    rec[L.R_SLIP2] = dr[1]
    t = steps * c[L.C_DT]
    _evaluate(c, pv, ws, i, obs, rec, v_true, cb, sb, da1, da2, t, dr[2], dr[3], dr[4], dr[5], dr[6])


@_jit
def _ideal_motion(c: F64, beta: float, w1: float, w2: float) -> tuple[float, float, float, float, float]:
    # (v_A [m/s], betadot [rad/s], h = betadot dt / 2, the tangents' arguments h / 2, (beta + h) / 2 [rad])
    v, bdot = kinematics.body_velocity_of(w1, w2, c[L.C_R1], c[L.C_R2], c[L.C_TWO_L1])
    h = 0.5 * (bdot * c[L.C_DT])
    return v, bdot, h, 0.5 * h, 0.5 * (beta + h)


@_jit
def _ideal_arc(
    c: F64, x: float, y: float, beta: float, w1: float, w2: float, v: float, bdot: float, h: float, t_h: float,
    t_m: float, al1: float, al2: float, castor: float,
) -> tuple[float, float, float, float, float, float, float, float]:  # fmt: skip
    # the exact arc step over dt at the wheel rates (w1, w2): (x, y, beta, cos, sin, alpha1, alpha2, castor)
    dt = c[L.C_DT]
    x1, y1, cb, sb = _arc_from_tangents(x, y, v, dt, h, t_h, t_m)
    castor_rate = kinematics.castor_rate_float(v, bdot, c[L.C_L5], c[L.C_R3])
    return (x1, y1, task.bound_angle_float(beta + bdot * dt), cb, sb, kinematics.advance_angle(al1, w1, dt),
            kinematics.advance_angle(al2, w2, dt), kinematics.advance_angle(castor, castor_rate, dt))  # fmt: skip


@_jit
def _ideal_move(
    c: F64, pv: F64, ws: F64, i: int, obs: NDArray[np.floating], rec: F64, dr: tuple[float, ...], c1: float,
    c2: float, w1: float, w2: float, v: float, bdot: float, h: float, t_h: float, t_m: float,
) -> None:  # fmt: skip
    """The ideal step of row ``i``: the wheel rates are the commands ``(w1, w2)`` [rad/s] over dt, the exact
    arc step with ``t_h = tan(h / 2)``, ``t_m = tan((beta + h) / 2)``, then the evaluation with the draws ``dr``."""
    r = _rows(ws)
    x1, y1, b1, cb, sb, al1, al2, castor = _ideal_arc(
        c, r.x[i], r.y[i], r.beta[i], w1, w2, v, bdot, h, t_h, t_m, r.alpha1[i], r.alpha2[i], r.castor[i]
    )
    da1, da2 = _command_change(c[L.C_REWARD_V0] != 0.0, w1, w2, r.w1[i], r.w2[i], c1, c2, r.a1[i], r.a2[i])
    r.x[i] = x1
    r.y[i] = y1
    r.beta[i] = b1
    r.w1[i] = w1
    r.w2[i] = w2
    r.alpha1[i] = al1
    r.alpha2[i] = al2
    r.castor[i] = castor
    _finish(c, pv, ws, i, obs, rec, dr, v, cb, sb, da1, da2, c1, c2, w1, w2)


#: rows per block of :func:`_ideal_block`, and its scratch: columns of ``_BLOCK`` floats each, on the stack (``K_O``:
#: the observation's four head and four tail fields)
_BLOCK = 128
K_X, K_Y, K_B, K_CB, K_SB, K_AL1, K_AL2, K_CAS, K_C1, K_C2, K_W1, K_W2 = (i * _BLOCK for i in range(12))
K_V, K_STEPS, K_VREF, K_CHG, K_HX, K_HY, K_S, K_K, K_E, K_CT, K_ST = (i * _BLOCK for i in range(12, 23))
K_AT, K_AV, K_AS, K_HEAD, K_TERM, K_O = (i * _BLOCK for i in range(23, 29))
_K_SIZE = K_O + 8 * _BLOCK


@_jit
def _ideal_block(
    c: F64, pv: F64, ws: F64, obs: NDArray[np.floating], a1: F64, a2: F64, tans: F64, i0: int, i1: int, rec: F64
) -> None:
    """:func:`_ideal_move` of the rows ``i0:i1`` (at most :data:`_BLOCK`) on a circle or manoeuvre path with the v0
    observation, no draws and the nominal ``l3``, in stages over the block (each a short loop over the block's
    columns of a scratch, the same functions in the same order: the same bits): the arc step; H's projection; the
    evaluation; the stores into the rows of ``ws`` and of :func:`_ideal_rows`' field-major ``rec`` (contiguous
    columns) and into ``obs``. The stages without calls to the C library vectorise: they index views of the
    block's columns from 0 (no negative index to wrap, so contiguous loads and stores, not gathers and scatters)."""
    k = _carray(_stack_ptr(_K_SIZE), _K_SIZE)
    r = _rows_in(ws, i0, i1)
    a1, a2, t_h, t_m, obs = a1[i0:i1], a2[i0:i1], tans[0, i0:i1], tans[1, i0:i1], obs[i0:i1]
    m = i1 - i0
    dt, l3 = c[L.C_DT], c[L.C_L3]
    for j in range(m):  # the arc step
        c1, c2, w1, w2 = _action_commands(a1[j], a2[j], c[L.C_W_MAX])
        v, bdot, h = _ideal_motion(c, r.beta[j], w1, w2)[:3]
        x1, y1, b1, cb, sb, al1, al2, castor = _ideal_arc(
            c, r.x[j], r.y[j], r.beta[j], w1, w2, v, bdot, h, t_h[j], t_m[j], r.alpha1[j], r.alpha2[j], r.castor[j]
        )
        da1, da2 = _command_change(c[L.C_REWARD_V0] != 0.0, w1, w2, r.w1[j], r.w2[j], c1, c2, r.a1[j], r.a2[j])
        steps = r.steps[j] + 1.0
        k[K_X + j], k[K_Y + j], k[K_B + j], k[K_CB + j], k[K_SB + j] = x1, y1, b1, cb, sb
        k[K_AL1 + j], k[K_AL2 + j], k[K_CAS + j], k[K_C1 + j], k[K_C2 + j] = al1, al2, castor, c1, c2
        k[K_W1 + j], k[K_W2 + j], k[K_V + j], k[K_STEPS + j] = w1, w2, v, steps
        k[K_VREF + j] = _reference_speed(c, r.v_cruise[j], r.t_brake[j], steps * dt)
        k[K_CHG + j] = da1 * da1 + da2 * da2
        k[K_HX + j], k[K_HY + j] = kinematics.h_from_a(x1, y1, cb, sb, r.l3[j])
    if c[L.C_PATH_KIND] == L.PATH_CIRCLE:  # H's projection: _locate's closed form, atan2's loop on its own
        d, rad, cx, cy, r0x, r0y = c[L.C_DIRECTION], c[L.C_RADIUS], c[L.C_CX], c[L.C_CY], c[L.C_R0X], c[L.C_R0Y]
        for j in range(m):  # the foot; u = (x, y) - centre into the columns of s and kappa
            k[K_E + j], k[K_CT + j], k[K_ST + j], k[K_S + j], k[K_K + j] = classic.circle_foot(
                k[K_HX + j], k[K_HY + j], cx, cy, r0x, r0y, d, rad
            )
        for j in range(m):
            k[K_S + j] = classic.circle_arc(k[K_S + j], k[K_K + j], r0x, r0y, d, rad)
        lap = task.TWO_PI * rad
        for j in range(m):  # the lap nearest the progress before
            s = k[K_S + j]
            k[K_S + j] = s + lap * task.round_half_even((r.progress[j] - s) / lap)
            k[K_K + j] = d / rad
    else:
        for j in range(m):
            s, kappa, e, ct, st, _ = _locate(c, pv, k[K_HX + j], k[K_HY + j], r.progress[j])
            k[K_S + j], k[K_K + j], k[K_E + j], k[K_CT + j], k[K_ST + j] = s, kappa, e, ct, st
    for j in range(m):  # _evaluate's terms and observation
        e, kappa, v_ref, w1, w2 = k[K_E + j], k[K_K + j], k[K_VREF + j], k[K_W1 + j], k[K_W2 + j]
        cos_psi, sin_psi = task.heading_error(k[K_CB + j], k[K_SB + j], k[K_CT + j], k[K_ST + j])
        cos_ss, sin_ss = task.steady_heading_float(kappa, l3)
        k[K_AT + j], k[K_AV + j], k[K_AS + j] = task.reward_arguments(
            abs(e), abs(k[K_V + j] - v_ref), k[K_CHG + j], c[L.C_SIG_T], c[L.C_SIG_V], c[L.C_SMOOTH_SQ]
        )
        k[K_HEAD + j] = task.heading_term(cos_psi, sin_psi, cos_ss, sin_ss)
        k[K_TERM + j] = 1.0 if tracking.end_flags(e, c[L.C_TERM], 1.0, 0)[0] else 0.0
        o = task.observe_head(e, sin_psi, cos_psi, kappa, l3, c[L.C_ERROR_SCALE], c[L.C_E_MAX])
        v_meas = kinematics.body_velocity_of(w1, w2, c[L.C_R1], c[L.C_R2], c[L.C_TWO_L1])[0]
        q = task.observe_rates(w1, w2, v_meas, v_ref, c[L.C_W_MAX], c[L.C_V_MAX])
        k[K_O + j], k[K_O + _BLOCK + j], k[K_O + 2 * _BLOCK + j], k[K_O + 3 * _BLOCK + j] = o
        k[K_O + 4 * _BLOCK + j], k[K_O + 5 * _BLOCK + j], k[K_O + 6 * _BLOCK + j] = q
        k[K_O + 7 * _BLOCK + j] = task.observe_reference(v_ref, c[L.C_V_MAX])
    for f, col in ((K_X, r.x), (K_Y, r.y), (K_B, r.beta), (K_W1, r.w1), (K_W2, r.w2), (K_AL1, r.alpha1),
                   (K_AL2, r.alpha2), (K_CAS, r.castor), (K_C1, r.a1), (K_C2, r.a2), (K_STEPS, r.steps),
                   (K_S, r.progress), (K_X, rec[L.R_X, i0:i1]), (K_Y, rec[L.R_Y, i0:i1]),
                   (K_B, rec[L.R_BETA, i0:i1]), (K_HX, rec[L.R_HX, i0:i1]), (K_HY, rec[L.R_HY, i0:i1]),
                   (K_W1, rec[L.R_W1, i0:i1]), (K_W2, rec[L.R_W2, i0:i1]), (K_W1, rec[L.R_CMD1, i0:i1]),
                   (K_W2, rec[L.R_CMD2, i0:i1]), (K_AL1, rec[L.R_AL1, i0:i1]), (K_AL2, rec[L.R_AL2, i0:i1]),
                   (K_E, rec[L.R_ERROR, i0:i1]), (K_S, rec[L.R_PROGRESS, i0:i1]), (K_V, rec[L.R_VT, i0:i1]),
                   (K_VREF, rec[L.R_VREF, i0:i1]), (K_HEAD, rec[L.R_HEADING, i0:i1]),
                   (K_TERM, rec[L.R_TERM, i0:i1]), (K_CAS, rec[L.R_CASTOR, i0:i1]),
                   (K_AT, rec[L.R_TRACK, i0:i1]), (K_AV, rec[L.R_SPEED, i0:i1]),
                   (K_AS, rec[L.R_SMOOTH_EXP, i0:i1])):  # fmt: skip
        for j in range(m):  # the stores of the rows, the records and the exponentials' arguments
            col[j] = k[f + j]
    mx, my, mb = rec[L.R_MX, i0:i1], rec[L.R_MY, i0:i1], rec[L.R_MB, i0:i1]
    slip1, slip2, end = rec[L.R_SLIP1, i0:i1], rec[L.R_SLIP2, i0:i1], rec[L.R_END, i0:i1]
    for j in range(m):
        mx[j], my[j], mb[j] = _measurements(
            k[K_X + j], k[K_Y + j], k[K_B + j], k[K_W1 + j], k[K_W2 + j], 0.0, 0.0, 0.0, 0.0, 0.0
        )[:3]
        slip1[j] = slip2[j] = end[j] = 0.0
    n_prev = int(c[L.C_N_PREVIEW])
    for j in range(m):  # the observations' stores
        for f in range(4):
            obs[j, f] = k[K_O + f * _BLOCK + j]
            obs[j, 4 + n_prev + f] = k[K_O + (4 + f) * _BLOCK + j]
    curvature, straight = c[L.C_DIRECTION] / c[L.C_RADIUS], c[L.C_STRAIGHT]
    circle = c[L.C_PATH_KIND] == L.PATH_CIRCLE
    for p in range(n_prev):  # the previews' curvature fields (_curvature_at)
        ahead = c[L.C_TAIL + p]
        for j in range(m):
            kp = curvature if circle else classic.manoeuvre_curvature(k[K_S + j] + ahead, straight, curvature)
            obs[j, 4 + p] = task.curvature_feature(kp, l3)


@_jit
def fill_record(rec: F64, smooth_weight: float) -> None:
    """The info record ``rec (RECORD_WIDTH,)``: the exponentials of the arguments in their place, terms and reward."""
    rec[L.R_TRACK] = math.exp(rec[L.R_TRACK])
    rec[L.R_SPEED] = math.exp(rec[L.R_SPEED])
    rec[L.R_SMOOTH_EXP] = math.exp(rec[L.R_SMOOTH_EXP])
    record_terms(rec, smooth_weight)


@_jit
def record_terms(rec: F64, smooth_weight: float) -> None:
    """The smoothness term and the reward of ``rec`` from its exponentials and heading term."""
    smooth = task.smooth_term(rec[L.R_SMOOTH_EXP], smooth_weight)
    rec[L.R_SMOOTH] = smooth
    rec[L.R_REWARD] = task.reward_product(rec[L.R_TRACK], rec[L.R_SPEED], rec[L.R_HEADING], smooth)


@_jit
def step_record(
    ring_step: int, a1: float, a2: float, c: F64, pv: F64, ring: F64, ws: F64, obs: NDArray[np.floating], rec: F64,
    smooth_weight: float, key: np.uint64,
) -> None:  # fmt: skip
    """:func:`step` of the one row of ``ws``, then :func:`fill_record` (the arguments after ``a2``:
    :attr:`fast_v1.StepKernel.args`)."""
    c, pv, ws, obs, rec = _bare(c), _bare(pv), _bare(ws), _bare(obs), _bare(rec)
    step(c, pv, _bare(ring), ws, 0, obs, rec, ring_step, a1, a2, key)
    fill_record(rec, smooth_weight)


# The batch: each row loop is written once with ``prange`` and compiled twice (serial, and ``parallel=True`` under
# another name).


def _step_rows(
    c: F64, flat: F64, starts: NDArray[np.int64], stops: NDArray[np.int64], rings: F64, ws: F64,
    obs: NDArray[np.floating], ring_step: int, a1: F64, a2: F64, keys: NDArray[np.uint64], rec: F64,
    smooth_weight: float,
) -> None:  # fmt: skip
    """:func:`step` and :func:`fill_record` of every row ``i``: its path ``flat[starts[i]:stops[i]]``, ring
    ``rings[i]``, observation ``obs[i]``, action ``(a1[i], a2[i])``, record ``rec[i]`` and key ``keys[i]``."""
    c, flat, rings, ws, obs, rec = _bare(c), _bare(flat), _bare(rings), _bare(ws), _bare(obs), _bare(rec)
    for i in numba.prange(ws.shape[1]):
        step(c, flat[starts[i] : stops[i]], rings[i], ws, i, obs[i], rec[i], ring_step, a1[i], a2[i], keys[i])
        fill_record(rec[i], smooth_weight)


def _ideal_tangent_rows(c: F64, ws: F64, a1: F64, a2: F64, tans: F64, take: bool) -> None:
    """Pass 1 of the ideal step (no per-step draws): the tangents of every row into ``tans (2, N)`` if ``take``, else
    their arguments, whose ``np.tan`` the caller takes."""
    c = _bare(c)
    beta = _rows(ws).beta
    for i in numba.prange(beta.shape[0]):
        w1, w2 = _action_commands(a1[i], a2[i], c[L.C_W_MAX])[2:]
        arg_h, arg_m = _ideal_motion(c, beta[i], w1, w2)[3:]
        tans[0, i] = arg_h
        tans[1, i] = arg_m
    if take:  # a loop of its own: within the one above, LLVM takes the tangents whatever ``take``
        for i in numba.prange(beta.shape[0]):
            tans[0, i] = math.tan(tans[0, i])
            tans[1, i] = math.tan(tans[1, i])


def _ideal_rows(
    c: F64, flat: F64, starts: NDArray[np.int64], stops: NDArray[np.int64], ws: F64, obs: NDArray[np.floating],
    a1: F64, a2: F64, tans: F64, rec: F64,
) -> None:  # fmt: skip
    """Pass 2: :func:`_ideal_move` of every row with the tangents ``tans (2, N)``; the records, field-major, into the
    columns of ``rec (RECORD_WIDTH, N)`` (the reward's exponential arguments in their place). By blocks of
    :data:`_BLOCK` rows: on a circle or manoeuvre with the v0 observation and the nominal ``l3``,
    :func:`_ideal_block`'s stages, else row by row."""
    c, flat, ws, obs, rec = _bare(c), _bare(flat), _bare(ws), _bare(obs), _bare(rec)
    r = _rows(ws)
    beta, l3_differs = r.beta, r.l3_differs  # arrays: the parallel loop takes no named tuple
    n = ws.shape[1]
    staged = c[L.C_PATH_KIND] != L.PATH_CLOTHOID and c[L.C_OBS_V0] != 0.0
    staged = staged and not tracking.measured_differs(c[L.C_POS_NOISE], c[L.C_HEAD_NOISE], False)
    for b in numba.prange((n + _BLOCK - 1) // _BLOCK):
        i0 = b * _BLOCK
        i1 = min(i0 + _BLOCK, n)
        if staged and not l3_differs[i0:i1].any():
            _ideal_block(c, flat[0:0], ws, obs, a1, a2, tans, i0, i1, rec)
            continue
        one = _carray(_stack_ptr(_RECORD), _RECORD)  # a row's record
        for i in range(i0, i1):
            c1, c2, w1, w2 = _action_commands(a1[i], a2[i], c[L.C_W_MAX])
            v, bdot, h = _ideal_motion(c, beta[i], w1, w2)[:3]
            pv = flat[starts[i] : stops[i]]
            _ideal_move(c, pv, ws, i, obs[i], one, _NO_DRAWS, c1, c2, w1, w2, v, bdot, h, tans[0, i], tans[1, i])
            for f in range(_RECORD):
                rec[f, i] = one[f]


def _record_rows(rec: F64, smooth_weight: float, take: bool) -> None:
    """Pass 3: the smoothness terms and rewards of the field-major records ``rec (RECORD_WIDTH, N)``, the three
    exponentials taken here if ``take``, else in place (``np.exp`` taken by the caller)."""
    rec = _bare(rec)
    if take:
        for i in numba.prange(rec.shape[1]):
            for f in range(L.R_TRACK, L.R_SMOOTH_EXP + 1):
                rec[f, i] = math.exp(rec[f, i])
    for i in numba.prange(rec.shape[1]):
        s = task.smooth_term(rec[L.R_SMOOTH_EXP, i], smooth_weight)
        rec[L.R_SMOOTH, i] = s
        rec[L.R_REWARD, i] = task.reward_product(rec[L.R_TRACK, i], rec[L.R_SPEED, i], rec[L.R_HEADING, i], s)


def _start_rows(
    c: F64, flat: F64, starts: NDArray[np.int64], stops: NDArray[np.int64], ws: F64, obs: NDArray[np.floating],
    rec: F64, rows: NDArray[np.int64], v_true: F64, t: F64, smooth_weight: float,
) -> None:  # fmt: skip
    """:func:`evaluate` and :func:`fill_record` of the rows ``rows (m,)`` of ``ws``, at the start speeds ``v_true``
    [m/s] and times ``t`` [s]: observations into ``obs (m, D)``, records into ``rec (m, RECORD_WIDTH)``."""
    c, flat, ws, obs, rec = _bare(c), _bare(flat), _bare(ws), _bare(obs), _bare(rec)
    for j in numba.prange(rows.shape[0]):
        i = rows[j]
        evaluate(c, flat[starts[i] : stops[i]], ws, i, obs[j], rec[j], v_true[j], t[j])
        fill_record(rec[j], smooth_weight)


def _restart_rows(
    c: F64, flat: F64, starts: NDArray[np.int64], stops: NDArray[np.int64], ws: F64, obs: NDArray[np.floating],
    rec: F64, rows: NDArray[np.int64], template: F64, start: F64, u: F64, smooth_weight: float,
) -> None:  # fmt: skip
    """:func:`amigo_gym.task.v1.start_state`, then :func:`start_rows`, of the rows ``rows (m,)`` with one episode:
    their columns of ``ws`` from the column ``template`` (the episode and the start state but its pose and progress);
    ``start``: the path's start ``(x, y, theta)`` [m, rad], the initial position and heading noise [m, rad] and the
    start speed of A [m/s]; ``u (m, 3)``: the draws in [-1, 1]."""
    c, flat, ws, obs, rec = _bare(c), _bare(flat), _bare(ws), _bare(obs), _bare(rec)
    r = _rows(ws)
    x, y, b, l3, s = r.x, r.y, r.beta, r.l3, r.progress  # arrays: the parallel loop takes no named tuple
    for j in numba.prange(rows.shape[0]):
        i = rows[j]
        pv = flat[starts[i] : stops[i]]
        ws[:, i] = template
        uj = (u[j, 0], u[j, 1], u[j, 2])
        hx, hy, beta = tracking.start_offsets(start[0], start[1], start[2], uj, start[3], start[4])
        x[i], y[i] = kinematics.a_from_h(hx, hy, math.cos(beta), math.sin(beta), l3[i])
        b[i] = beta
        s[i] = progress(c, pv, float(hx), float(hy), 0.0)
        evaluate(c, pv, ws, i, obs[j], rec[j], start[5], 0.0)
        fill_record(rec[j], smooth_weight)


def _bitgen_call(slot: int, ret: Any, ret_ir: Any) -> Any:
    # f(bitgen): the function in ``slot`` of numpy's ``bitgen_t`` (state, next_uint64, next_uint32, next_double) at
    # the address ``bitgen`` (int64: the pointer of ``BitGenerator.capsule``), called on its state
    def typing(typingctx: Any, bitgen: Any) -> Any:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            void_p = llvm_ir.IntType(8).as_pointer()
            fn_t = llvm_ir.FunctionType(ret_ir, [void_p])
            base = builder.inttoptr(args[0], void_p.as_pointer())
            fn = builder.bitcast(builder.load(builder.gep(base, [llvm_ir.IntType(32)(slot)])), fn_t.as_pointer())
            return builder.call(fn, [builder.load(base)])

        return ret(bitgen), codegen

    return intrinsic(typing)


_next_uint64: Any = _bitgen_call(1, numba.types.uint64, llvm_ir.IntType(64))
_next_uint32: Any = _bitgen_call(2, numba.types.uint32, llvm_ir.IntType(32))
_next_double: Any = _bitgen_call(3, numba.types.float64, llvm_ir.DoubleType())


def _draw_uniforms(bitgens: NDArray[np.int64], intervals: F64, out: F64, keys: NDArray[np.uint64]) -> None:
    """Row ``j``'s draws from the bit generator at ``bitgens[j]``, numpy's numbers and states: ``out[j, q] =
    U(intervals[q])`` (``lo + (hi - lo) next_double``; ``lo`` undrawn where ``lo == hi``), then ``keys[j]`` (if not
    empty) as ``draw_key`` (``Generator.integers``' Lemire bits: ``next_uint64 >> 1``, ``next_uint32 >> 31``)."""
    one = np.uint64(1)
    for j in numba.prange(out.shape[0]):
        for q in range(out.shape[1]):
            lo, hi = intervals[q, 0], intervals[q, 1]
            out[j, q] = lo if lo == hi else lo + (hi - lo) * _next_double(bitgens[j])
        if keys.shape[0]:
            keys[j] = ((_next_uint64(bitgens[j]) >> one) << one) + np.uint64(_next_uint32(bitgens[j]) >> np.uint32(31))


_jit_parallel = numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False, parallel=True)
step_rows = _jit(_twin(_step_rows, "step_rows"))
step_rows_parallel = _jit_parallel(_twin(_step_rows, "step_rows_parallel"))
ideal_tangent_rows = _jit(_twin(_ideal_tangent_rows, "ideal_tangent_rows"))
ideal_tangent_rows_parallel = _jit_parallel(_twin(_ideal_tangent_rows, "ideal_tangent_rows_parallel"))
ideal_rows = _jit(_twin(_ideal_rows, "ideal_rows"))
ideal_rows_parallel = _jit_parallel(_twin(_ideal_rows, "ideal_rows_parallel"))
record_rows = _jit(_twin(_record_rows, "record_rows"))
record_rows_parallel = _jit_parallel(_twin(_record_rows, "record_rows_parallel"))
family_fill = _jit(_twin(_family_fill, "family_fill"))
family_fill_parallel = _jit_parallel(_twin(_family_fill, "family_fill_parallel"))
start_rows = _jit(_twin(_start_rows, "start_rows"))
start_rows_parallel = _jit_parallel(_twin(_start_rows, "start_rows_parallel"))
restart_rows = _jit(_twin(_restart_rows, "restart_rows"))
restart_rows_parallel = _jit_parallel(_twin(_restart_rows, "restart_rows_parallel"))
draw_uniforms = _jit(_twin(_draw_uniforms, "draw_uniforms"))
draw_uniforms_parallel = _jit_parallel(_twin(_draw_uniforms, "draw_uniforms_parallel"))
