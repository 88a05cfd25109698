r"""Compiled step of ``AmigoBot-v0`` (numba): three compiled passes over the robots, no temporaries.

The fast path (numba, a core dependency where it ships wheels). It computes AmigoBot-v0's reference step
(AmigoBot-v1's ideal step with v0's settings: clip and scale the action, exact arc step of pose and
wheel angles, projection of H on the circle or the manoeuvre path, observation, reward terms,
termination) in the same order of operations, writing into preallocated arrays: the scalar pieces are the
reference's own functions compiled as they are (:data:`SHARED`; docs/architecture.md, "The compiled step"): the
projection on the circle and on the manoeuvre path (``paths/classic.py``'s ``circle_foot``, ``manoeuvre_foot``,
``manoeuvre_curvature``, which the paths run on floats), the observation (``task/v0.py``'s ``observe_head``,
``curvature_feature``, ``observe_rates``, ``observe_reference``, which ``observe_columns`` calls, clips included),
the reward's terms and the arguments of its exponentials (``reward_arguments``, which ``reward_term_columns`` calls)
and the termination (``off_path``). Written here: the loops, the reading and writing of the rows, the row's glue
between the shared functions (once, in the pieces :func:`_moved`, :func:`_projected`, :func:`_terms`,
:func:`_preview_feature`), and what is computed once per call instead of per row (the steady heading of the two
curvatures a row can have, the observed reference speed). ``tests/test_kernels.py`` checks it
against the reference the environments run with ``kernel="numpy"``, AmigoBot-v1's ideal step with v0's settings
(:func:`amigo_gym.task.v1.step_columns`), and the compiled pieces against themselves run as Python.

Why three passes and not one: the transcendental functions of a step (two ``tan``, three ``exp``) are
evaluated by numpy's own vectorised ufuncs between the loops (``np.tan(tans, out=tans)``,
``np.exp(exps, out=exps)``, :func:`amigo_gym.sim.fast.step_rows`): they are several times faster than the
C library's scalar functions that a numba loop calls (SIMD), and they are the very functions the
reference calls, so the results are **bit-identical** to the reference's (the single env's step runs in one call
instead, :func:`single_step`, which calls numpy's own loops of the two functions inside: the same bits).
Everything else (about a
hundred additions, multiplications, divisions, comparisons and square roots per robot, which numpy
would run as as many passes over temporary arrays) is compiled into the passes:

1. :func:`move_arguments`: the arguments of the two tangents of the arc step, ``0.5 h`` and
   ``0.5 (beta + h)``, into ``tans (N, 2)``;
2. :func:`evaluate`: the arc step from the tangents (state updated in place), H, its projection,
   the observation, the heading term, the termination, and the arguments of the three exponentials
   into ``exps (N, 3)``;
3. :func:`finish`: the track, speed and smoothness terms from the exponentials and the reward.

The evaluate pass is where a step's divisions and square roots are (about thirteen and two per robot), and a scalar
division takes the divider several cycles, so it runs in a form that LLVM vectorises: by blocks of :data:`BLOCK`
rows (:func:`_evaluate_block`), each in stages, loops over the block's rows that call the pieces above and keep what
they hand on in the block's columns of a scratch (:data:`SCRATCH_FIELDS`, contiguous and at fixed distances, so that
LLVM can tell its loads and stores apart; the rows' arrays are read through flat views, their row lengths known), the
restart rows and the path's branches selected rather than branched to. SIMD divisions and square roots are correctly
rounded as the scalar ones are: the same bits. The manoeuvre path's projection stage stays scalar (it calls the C
library's ``atan2`` and ``hypot``). The single env evaluates its one row by :func:`evaluate_rows`, the same pieces
called in turn without the stages (for one row the stages cost more than they save).

The manoeuvre path's ``np.arctan2`` and ``np.hypot`` (its arc length on the circle and the distance to the straight
part, in :func:`amigo_gym.paths.classic.manoeuvre_foot`) are compiled by numba to the C library's ``atan2`` and
``hypot``, which numpy's float64 ufuncs call where numpy does not vectorise them (``tests/test_kernels.py`` compares
the compiled function with the Python one); where a build vectorises ``arctan2`` (numpy's AVX-512 SVML loops) they may
differ in the last bit of the arc length, which only decides whether a preview point lies before the end of the
straight part. The observation's clips (:func:`amigo_gym.model.numeric.clip_real`, which dispatches on the type) are
compiled as :func:`amigo_gym.model.numeric.clip_float`, what ``clip_real`` runs on a float
(:data:`amigo_gym.model.numeric.SCALAR_FORMS`, registered by :func:`amigo_gym.sim.layout.shared_compiler`).

Layouts (all C-contiguous, one row per robot):

* ``consts`` float64: :data:`CONSTANT_FIELDS` (:func:`amigo_gym.sim.fast.kernel_constants`);
* ``state (N, 8)`` float64, updated in place: the columns :data:`STATE_FIELDS`,
  ``x, y, beta, alpha1, alpha2, alpha3, rate1, rate2``;
* ``actions (N, 2)`` float64: the validated, normalised action (clipped to [-1, 1] here);
* ``restart (N,)`` bool: rows whose ``state`` has just been set to a start state; they do not move
  and are evaluated as :func:`amigo_gym.task.v1.reset_columns` evaluates them (no smoothness loss); their
  ``tans`` row must hold ``(np.cos(beta), np.sin(beta))`` when :func:`evaluate` runs;
* ``turn (N,)`` float64 scratch: the turn rate ``bdot`` of each row's action, written by
  :func:`move_arguments` and read by :func:`evaluate` (one division per row instead of two);
* outputs ``obs (N, obs_dim)`` float32 or float64, ``reward (N,)`` float64, ``terminated (N,)`` bool
  and ``record (N, 16)`` float64 with the columns :data:`RECORD_FIELDS` (the new state and what the
  infos report about it);
* ``cols`` float64 scratch of :func:`evaluate`: a whole number of slots of :data:`BLOCK_WIDTH` floats (block ``b``
  of the rows works in slot ``b % slots``): one slot for :func:`evaluate`, :func:`scratch_size` for
  :func:`evaluate_parallel` (a slot per block, which its threads never share).

Start states of restarting rows (:func:`draw_starts`, :func:`place_starts`): the native vector env's
``NEXT_STEP`` autoreset draws each restarting robot's start perturbation from that robot's own numpy
generator inside the compiled loop, by calling the generator's C function ``next_double`` through the
address of its ``bitgen_t`` (:func:`_next_double`; the call ``Generator.random`` makes per number), so
the numbers and the generators' states afterwards are those of ``Generator.random(3)`` per robot. The
start pose is :func:`amigo_gym.task.v1.start_state`'s arithmetic in its order, with numpy's ``cos`` and
``sin`` of the headings evaluated between the two loops (:func:`amigo_gym.sim.fast.step_rows`).

This module imports numba at import time; :mod:`amigo_gym.sim.fast` imports it only when the fast path
is first used, so ``import amigo_gym`` never loads numba. Compiled code is cached on disk
(``cache=True``, in ``__pycache__`` or ``NUMBA_CACHE_DIR``), so only the first process compiles. The
``*_parallel`` variants run their loop on numba's threads (``prange``; ``numba.set_num_threads`` or
``NUMBA_NUM_THREADS`` set their number); each row is computed the same way, so the results do not
depend on the number of threads.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numba
import numpy as np
from llvmlite import ir
from numba.core import types as nb_types
from numba.core.typing.templates import Signature
from numba.extending import intrinsic
from numpy.typing import NDArray

from amigo_gym.model import kinematics, numeric
from amigo_gym.paths import classic
from amigo_gym.sim import numpy_loops
from amigo_gym.sim.layout import shared_compiler
from amigo_gym.sim.layout import twin as _twin
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking

__all__ = [
    "RECORD_FIELDS",
    "STATE_FIELDS",
    "CONSTANT_FIELDS",
    "move_arguments",
    "move_arguments_parallel",
    "evaluate",
    "evaluate_parallel",
    "evaluate_rows",
    "BLOCK",
    "BLOCK_WIDTH",
    "SCRATCH_FIELDS",
    "scratch_size",
    "ROWS_BELOW",
    "finish",
    "finish_parallel",
    "START_FIELDS",
    "draw_starts",
    "place_starts",
    "count_steps",
    "single_move",
    "single_evaluate",
    "single_finish",
    "single_step",
]

#: columns of the ``state`` array: pose [m, m, rad], wheel angles [rad], wheel rates of the last step [rad/s]
STATE_FIELDS: tuple[str, ...] = ("x", "y", "beta", "alpha1", "alpha2", "alpha3", "rate1", "rate2")

#: columns of the ``record`` array
RECORD_FIELDS: tuple[str, ...] = (
    "x",
    "y",
    "beta",
    "h_x",
    "h_y",
    "cross_track_error",
    "rate1",
    "rate2",
    "alpha1",
    "alpha2",
    "alpha3",
    "track",
    "speed",
    "heading",
    "smooth",
    "reward",
)

#: entries of the ``consts`` vector (built by :func:`amigo_gym.sim.fast.kernel_constants`)
CONSTANT_FIELDS: tuple[str, ...] = (
    "dt",
    "w_max",
    "r1",
    "r2",
    "two_l1",
    "l3",
    "l5",
    "r3",
    "speed",
    "max_speed",
    "error_scale",
    "e_max",
    "termination_distance",
    "sigma_track",
    "sigma_speed",
    "smooth_scale_sq",
    "smooth_weight",
    "manoeuvre",
    "direction",
    "radius",
    "cx",
    "cy",
    "r0x",
    "r0y",
    "straight_length",
    "curvature",
    "heading_limit",
)

#: entries of the ``start`` vector of :func:`draw_starts` and :func:`place_starts`
#: (:func:`amigo_gym.sim.fast.start_constants`): the path's start point and tangent angle, the noise scales of
#: the start pose (:func:`amigo_gym.task.v1.start_state`), ``l3``, and the initial wheel rates
START_FIELDS: tuple[str, ...] = (
    "x0",
    "y0",
    "theta0",
    "position_noise",
    "heading_noise",
    "l3",
    "rate1",
    "rate2",
)

_S = {name: i for i, name in enumerate(START_FIELDS)}
S_X0, S_Y0, S_THETA0, S_POS_NOISE, S_HEADING_NOISE, S_L3, S_RATE1, S_RATE2 = (_S[n] for n in START_FIELDS)

_C = {name: i for i, name in enumerate(CONSTANT_FIELDS)}
DT, W_MAX, R1, R2, TWO_L1, L3, L5, R3 = (_C[n] for n in CONSTANT_FIELDS[:8])
SPEED, MAX_SPEED, ERROR_SCALE, E_MAX, TERM = (_C[n] for n in CONSTANT_FIELDS[8:13])
SIG_T, SIG_V, SMOOTH_SQ, SMOOTH_W = (_C[n] for n in CONSTANT_FIELDS[13:17])
MANOEUVRE, DIRECTION, RADIUS, CX, CY, R0X, R0Y, STRAIGHT, CURV = (_C[n] for n in CONSTANT_FIELDS[17:26])
HEADING_LIM = _C["heading_limit"]


F64 = NDArray[np.float64]

#: the reference's scalar functions this module compiles as they are (``numba.njit`` of the function itself, called
#: by the loops below): the one source of each piece of the step (docs/architecture.md, "The compiled step")
SHARED: tuple[Callable[..., Any], ...] = (
    *numeric.SCALAR_FORMS.values(),
    tracking.action_commands,
    task.heading_error,
    task.heading_term,
    task.steady_heading_float,
    task.smooth_term,
    task.reward_product,
    task.reward_arguments,
    task.off_path,
    task.observe_head,
    task.curvature_feature,
    task.observe_rates,
    task.observe_reference,
    kinematics.body_velocity_of,
    kinematics.arc_from_tangents,
    kinematics.castor_rate_float,
    kinematics.advance_angle,
    kinematics.h_from_a,
    kinematics.a_from_h,
    kinematics.half_tan_cos_sin,
    kinematics.col_exp,
    numeric.pow2_typing,
    classic.circle_foot,
    classic.circle_arc,
    classic.manoeuvre_foot,
    classic.manoeuvre_curvature,
    numpy_loops.numpy_loop_in_place,
    numpy_loops.loop_call_typing,
)

_jit = numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)


_shared = shared_compiler(
    "amigo_gym.sim._kernels",
    SHARED,
    _jit,
    inline=(kinematics.col_exp,),
    scalar_forms=numeric.SCALAR_FORMS,
    intrinsics={numpy_loops.call_loop: numpy_loops.loop_call_typing, numeric.pow2_real: numeric.pow2_typing},
)


_action_commands = cast(Callable[..., tuple[float, float, float, float]], _shared(tracking.action_commands))
#: numpy's own inner loop of a unary ufunc called in place (:func:`amigo_gym.sim.numpy_loops.numpy_loop_in_place`),
#: compiled on its own (the single step calls the shared function itself; tests call this)
numpy_loop_in_place = _shared(numpy_loops.numpy_loop_in_place)
_heading_error = _shared(task.heading_error)
_heading_term = _shared(task.heading_term)
_steady_heading = _shared(task.steady_heading_float)
_smooth_term = _shared(task.smooth_term)
_reward_product = _shared(task.reward_product)
_body_velocity = _shared(kinematics.body_velocity_of)
_arc = _shared(kinematics.arc_from_tangents)
_advance_angle = _shared(kinematics.advance_angle)
_castor_rate = _shared(kinematics.castor_rate_float)
_h_from_a = _shared(kinematics.h_from_a)
_a_from_h = _shared(kinematics.a_from_h)
_circle_foot = _shared(classic.circle_foot)
_manoeuvre_foot = _shared(classic.manoeuvre_foot)
_manoeuvre_curvature = _shared(classic.manoeuvre_curvature)
_reward_arguments = _shared(task.reward_arguments)
_off_path = _shared(task.off_path)
_observe_head = _shared(task.observe_head)
_curvature_feature = _shared(task.curvature_feature)
_observe_rates = _shared(task.observe_rates)
_observe_reference = _shared(task.observe_reference)


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _motion(c: F64, a1: float, a2: float) -> tuple[float, float, float, float, float]:
    # the reference's motion (task.v1._ideal_step) up to the arc step: (w1, w2, v, bdot, db)
    w1, w2 = _action_commands(a1, a2, c[W_MAX])[2:]
    v, bdot = _body_velocity(w1, w2, c[R1], c[R2], c[TWO_L1])
    return w1, w2, v, bdot, bdot * c[DT]


def _move_arguments(c: F64, state: F64, actions: F64, restart: NDArray[np.bool_], tans: F64, turn: F64) -> None:
    """Pass 1: ``tans[i] = (0.5 h, 0.5 (beta + h))`` of the arc step (zeros where ``restart``), and the
    turn rate ``bdot`` into ``turn[i]`` (for :func:`evaluate`, which would divide again)."""
    for i in numba.prange(state.shape[0]):
        if restart[i]:
            tans[i, 0] = 0.0
            tans[i, 1] = 0.0
            continue
        bdot, db = _motion(c, actions[i, 0], actions[i, 1])[3:]
        turn[i] = bdot
        h = 0.5 * db
        tans[i, 0] = 0.5 * h
        tans[i, 1] = 0.5 * (state[i, 2] + h)


#: rows per block of :func:`evaluate`: its stages run over one block at a time, in the block's columns of the scratch
#: ``cols`` (:func:`scratch_size`)
BLOCK = 128

#: the columns of a block of :func:`evaluate`'s scratch (one float per row of the block each)
SCRATCH_FIELDS: tuple[str, ...] = (
    "x",
    "y",
    "beta",
    "alpha1",
    "alpha2",
    "alpha3",
    "w1",
    "w2",
    "cos_beta",
    "sin_beta",
    "abs_dv",
    "change_sq",
    "rate1_obs",
    "rate2_obs",
    "speed_obs",
    "h_x",
    "h_y",
    "e",
    "cos_theta",
    "sin_theta",
    "s",
    "on_line",
    "error_obs",
    "sin_psi",
    "cos_psi",
    "curvature_obs",
    "heading",
)
_K = {name: i * BLOCK for i, name in enumerate(SCRATCH_FIELDS)}
K_X, K_Y, K_BETA, K_AL1, K_AL2, K_AL3, K_W1, K_W2, K_COS, K_SIN = (_K[n] for n in SCRATCH_FIELDS[:10])
K_ADV, K_CHG, K_OR1, K_OR2, K_OR3, K_HX, K_HY, K_E, K_CT, K_ST = (_K[n] for n in SCRATCH_FIELDS[10:20])
K_S, K_LINE, K_OE, K_SPSI, K_CPSI, K_OK, K_HEAD = (_K[n] for n in SCRATCH_FIELDS[20:])
#: floats of one block's scratch
BLOCK_WIDTH = BLOCK * len(SCRATCH_FIELDS)


#: below this many rows the row loop (:func:`evaluate_rows`, the same bits) is faster than :func:`evaluate`'s stages
#: (their fixed cost per call, about 0.5 us here, against their gain per row; :func:`amigo_gym.sim.fast.step_rows`)
ROWS_BELOW = 48


def scratch_size(n: int) -> int:
    """The length of :func:`evaluate_parallel`'s scratch ``cols`` for ``n`` rows: one slot (:data:`BLOCK_WIDTH`
    floats) per block, so that the threads never share one; :func:`evaluate` needs one slot."""
    return -(-n // BLOCK) * BLOCK_WIDTH


# The row's code of pass 2 in four pieces (the constants ``q`` of :func:`_row_constants`), called by the two drivers:
# :func:`evaluate`'s stages (one loop per piece over a block's rows) and :func:`_evaluate_rows` (the single env's row).
@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _row_constants(c: F64) -> tuple[float, ...]:
    # the constants of pass 2 as a tuple of locals (LLVM cannot tell that the rows' stores leave ``c`` alone: read in
    # a loop, they are loaded again per row, and what depends on them alone, is recomputed per row); with
    # task.steady_heading of the only two curvatures a row can have (the path's; 0 on the straight part of the
    # manoeuvre), computed once with the same operations instead of a square root per row
    l3 = c[L3]
    cos_ss_curve, sin_ss_curve = _steady_heading(c[CURV], l3)
    cos_ss_line, sin_ss_line = _steady_heading(0.0, l3)
    return (c[DT], c[W_MAX], c[R1], c[R2], c[TWO_L1], c[L5], c[R3], l3, c[CX], c[CY], c[R0X], c[R0Y], c[DIRECTION],
            c[RADIUS], c[STRAIGHT], c[CURV], c[SPEED], c[MAX_SPEED], c[ERROR_SCALE], c[E_MAX], c[TERM], c[SIG_T],
            c[SIG_V], c[SMOOTH_SQ], cos_ss_curve, sin_ss_curve, cos_ss_line, sin_ss_line)  # fmt: skip


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _moved(
    q: tuple[float, ...], start: bool, x: float, y: float, beta: float, al1: float, al2: float, al3: float,
    prev1: float, prev2: float, a1: float, a2: float, bdot: float, t0: float, t1: float,
) -> tuple[Any, ...]:  # fmt: skip
    # task.v1._ideal_step: kinematics.arc_step from the two tangents t0, t1, the wheel angles, bdot from pass 1; a
    # start state (task.v1.reset_columns, ``start``) as it is, t0, t1 np.cos and np.sin of its heading, its speed.
    # Selects, not branches (the stages vectorise). Returns the new state, cos and sin of its heading, the reward's
    # speed and smoothness inputs and task.v0.observe_columns' rates.
    dt, w_max, r1, r2, two_l1, l5, r3 = q[0], q[1], q[2], q[3], q[4], q[5], q[6]
    speed, v_max = q[16], q[17]
    w1, w2 = _action_commands(a1, a2, w_max)[2:]
    w1 = prev1 if start else w1
    w2 = prev2 if start else w2
    v = _body_velocity(w1, w2, r1, r2, two_l1)[0]
    db = bdot * dt
    h = 0.5 * db
    x1, y1, cos1, sin1 = _arc(x, y, v, dt, h, t0, t1)
    castor = _castor_rate(v, bdot, l5, r3)
    dw1 = w1 - prev1
    dw2 = w2 - prev2
    o0, o1, o2 = _observe_rates(w1, w2, v, speed, w_max, v_max)
    return (
        x if start else x1,
        y if start else y1,
        beta if start else beta + db,
        al1 if start else _advance_angle(al1, w1, dt),
        al2 if start else _advance_angle(al2, w2, dt),
        al3 if start else _advance_angle(al3, castor, dt),
        w1,
        w2,
        t0 if start else cos1,
        t1 if start else sin1,
        abs(v - speed),
        dw1 * dw1 + dw2 * dw2,
        o0,
        o1,
        o2,
    )


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _projected(
    q: tuple[float, ...], manoeuvre: bool, x: float, y: float, cos_beta: float, sin_beta: float
) -> tuple[float, float, float, float, float, float, bool]:
    # task.v1.evaluate_columns: H, its projection on the path (paths.classic's project_xy on floats):
    # (h_x, h_y, e, cos theta, sin theta, s, on_line)
    l3, cx, cy, r0x, r0y, d, r, big_l = q[7], q[8], q[9], q[10], q[11], q[12], q[13], q[14]
    hx, hy = _h_from_a(x, y, cos_beta, sin_beta, l3)
    if manoeuvre:
        e, cos_theta, sin_theta, s, _, on_line = _manoeuvre_foot(hx, hy, cx, cy, r0x, r0y, d, r, big_l)
        return hx, hy, e, cos_theta, sin_theta, s, on_line  # type: ignore[return-value]  # floats here
    e, cos_theta, sin_theta, _, _ = _circle_foot(hx, hy, cx, cy, r0x, r0y, d, r)
    return hx, hy, e, cos_theta, sin_theta, 0.0, False  # type: ignore[return-value]  # floats here


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _terms(
    q: tuple[float, ...], on_line: bool, e: float, cos_beta: float, sin_beta: float, cos_theta: float,
    sin_theta: float, abs_dv: float, change_sq: float,
) -> tuple[Any, ...]:  # fmt: skip
    # task.v0.observe_columns' head, task.v0.reward_term_columns (steady_heading): the heading term and the
    # arguments of the exponentials, the termination
    l3, curv = q[7], q[15]
    error_scale, e_max, term, sigma_t, sigma_v, smooth_sq = q[18], q[19], q[20], q[21], q[22], q[23]
    curvature = 0.0 if on_line else curv  # the straight part's, else the circle's
    cos_psi, sin_psi = _heading_error(cos_beta, sin_beta, cos_theta, sin_theta)
    abs_e = abs(e)
    o0, o1, o2, o3 = _observe_head(e, sin_psi, cos_psi, curvature, l3, error_scale, e_max)
    cos_ss = q[26] if on_line else q[24]
    sin_ss = q[27] if on_line else q[25]
    ex0, ex1, ex2 = _reward_arguments(abs_e, abs_dv, change_sq, sigma_t, sigma_v, smooth_sq)
    heading = _heading_term(cos_psi, sin_psi, cos_ss, sin_ss)
    return o0, o1, o2, o3, heading, ex0, ex1, ex2, _off_path(abs_e, term)


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _preview_feature(q: tuple[float, ...], manoeuvre: bool, s: float, ahead: float) -> Any:
    # the curvature field of the preview point ``ahead`` of the foot at the arc length s (task.v0.observe_columns)
    l3, big_l, curv = q[7], q[14], q[15]
    return _curvature_feature(_manoeuvre_curvature(s + ahead, big_l, curv) if manoeuvre else curv, l3)


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _stored(
    st: F64, rc: F64, so: int, ro: int, x: float, y: float, beta: float, al1: float, al2: float, al3: float,
    w1: float, w2: float, hx: float, hy: float, e: float, heading: float,
) -> None:  # fmt: skip
    # a row's new state into st[so : so + 8] (STATE_FIELDS) and its record's columns into rc[ro : ro + 16]
    # (RECORD_FIELDS; the reward terms and the reward by finish)
    st[so] = rc[ro] = x
    st[so + 1] = rc[ro + 1] = y
    st[so + 2] = rc[ro + 2] = beta
    st[so + 3] = rc[ro + 8] = al1
    st[so + 4] = rc[ro + 9] = al2
    st[so + 5] = rc[ro + 10] = al3
    st[so + 6] = rc[ro + 6] = w1
    st[so + 7] = rc[ro + 7] = w2
    rc[ro + 3] = hx
    rc[ro + 4] = hy
    rc[ro + 5] = e
    rc[ro + 13] = heading


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _observed(
    obs: NDArray[np.floating], i: int, m: int, o0: float, o1: float, o2: float, o3: float, r0: float, r1: float,
    r2: float, reference: Any,
) -> None:  # fmt: skip
    # row i's observation but the preview's curvatures (task.v0.observe_columns): its head, its tail from column m
    obs[i, 0] = o0
    obs[i, 1] = o1
    obs[i, 2] = o2
    obs[i, 3] = o3
    obs[i, m] = r0
    obs[i, m + 1] = r1
    obs[i, m + 2] = r2
    obs[i, m + 3] = reference


def _evaluate(
    c: F64,
    preview: F64,
    state: F64,
    actions: F64,
    restart: NDArray[np.bool_],
    tans: F64,
    turn: F64,
    obs: NDArray[np.floating],
    terminated: NDArray[np.bool_],
    record: F64,
    exps: F64,
    cols: F64,
) -> None:
    """Pass 2: with ``tans`` the tangents (or, where ``restart``, ``cos beta, sin beta``): move, observe.

    By blocks of :data:`BLOCK` rows (:func:`_evaluate_block`); block ``b`` works in the slot ``b % slots`` of the
    scratch ``cols`` (``slots`` of :data:`BLOCK_WIDTH` floats: one for the serial loop, one per block for the
    parallel one, whose threads must not share a slot). C-contiguous arrays.
    """
    q = _row_constants(c)
    manoeuvre = c[MANOEUVRE] != 0.0
    reference_obs = _observe_reference(c[SPEED], c[MAX_SPEED])  # observe_tail's last field: the same for every row
    n = state.shape[0]
    # the rows' arrays as flat views: their rows at a distance LLVM knows (8, 2, 2, 3, 16), so that it can tell the
    # loops' loads and stores apart (a row length read from the array hides it)
    st = state.reshape(n * 8)
    ac = actions.reshape(n * 2)
    tn = tans.reshape(n * 2)
    ex = exps.reshape(n * 3)
    rc = record.reshape(n * 16)
    slots = cols.shape[0] // BLOCK_WIDTH
    for b in numba.prange((n + BLOCK - 1) // BLOCK):
        lo = b * BLOCK
        o = (b % slots) * BLOCK_WIDTH
        hi = min(lo + BLOCK, n)
        _evaluate_block(q, manoeuvre, reference_obs, preview, hi - lo, st[8 * lo : 8 * hi], ac[2 * lo : 2 * hi],
                        restart[lo:hi], tn[2 * lo : 2 * hi], turn[lo:hi], obs[lo:hi], terminated[lo:hi],
                        ex[3 * lo : 3 * hi], rc[16 * lo : 16 * hi], cols[o : o + BLOCK_WIDTH])  # fmt: skip


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def _evaluate_block(
    q: tuple[float, ...],
    manoeuvre: bool,
    reference_obs: Any,
    preview: F64,
    count: int,
    st: F64,
    ac: F64,
    restart: NDArray[np.bool_],
    tn: F64,
    turn: F64,
    obs: NDArray[np.floating],
    terminated: NDArray[np.bool_],
    ex: F64,
    rc: F64,
    k: F64,
) -> None:
    """:func:`evaluate` of a block of ``count`` rows (``st, ac, tn, ex, rc``: flat views of its rows of the state,
    actions, tans, exps and record; the other arrays, views of its rows), in stages: loops over the block's rows that
    read and write its columns in ``k`` (:data:`SCRATCH_FIELDS`, at fixed distances), so that LLVM vectorises them
    (SIMD divisions and square roots: the scalar ones' bits); restart rows are selected in them, not branched to.

    A function of its own, not the body of :func:`evaluate`'s loop, so that the parallel loop's body is compiled as
    the serial one's; indexed from the block's first row (LLVM sees that no index is negative)."""
    m = 4 + preview.shape[0]
    for j in range(count):  # 1. the motion
        (k[K_X + j], k[K_Y + j], k[K_BETA + j], k[K_AL1 + j], k[K_AL2 + j], k[K_AL3 + j], k[K_W1 + j],
         k[K_W2 + j], k[K_COS + j], k[K_SIN + j], k[K_ADV + j], k[K_CHG + j], k[K_OR1 + j], k[K_OR2 + j],
         k[K_OR3 + j]) = _moved(q, restart[j], st[8 * j], st[8 * j + 1], st[8 * j + 2], st[8 * j + 3],
                                st[8 * j + 4], st[8 * j + 5], st[8 * j + 6], st[8 * j + 7], ac[2 * j],
                                ac[2 * j + 1], turn[j], tn[2 * j], tn[2 * j + 1])  # fmt: skip
    # 2. the projection: the circle's loop vectorises, the manoeuvre's calls the C library's atan2 and hypot
    if manoeuvre:
        for j in range(count):
            (k[K_HX + j], k[K_HY + j], k[K_E + j], k[K_CT + j], k[K_ST + j], k[K_S + j],
             on_line) = _projected(q, True, k[K_X + j], k[K_Y + j], k[K_COS + j], k[K_SIN + j])  # fmt: skip
            k[K_LINE + j] = 1.0 if on_line else 0.0
    else:
        for j in range(count):
            (k[K_HX + j], k[K_HY + j], k[K_E + j], k[K_CT + j], k[K_ST + j], k[K_S + j],
             on_line) = _projected(q, False, k[K_X + j], k[K_Y + j], k[K_COS + j], k[K_SIN + j])  # fmt: skip
            k[K_LINE + j] = 1.0 if on_line else 0.0
    for j in range(count):  # 3. the observation's head, the heading term, the exponentials' arguments, termination
        (k[K_OE + j], k[K_SPSI + j], k[K_CPSI + j], k[K_OK + j], k[K_HEAD + j], ex[3 * j], ex[3 * j + 1],
         ex[3 * j + 2], terminated[j]) = _terms(q, k[K_LINE + j] != 0.0, k[K_E + j], k[K_COS + j], k[K_SIN + j],
                                                k[K_CT + j], k[K_ST + j], k[K_ADV + j], k[K_CHG + j])  # fmt: skip
    for j in range(count):  # 4. the new state and the record
        _stored(st, rc, 8 * j, 16 * j, k[K_X + j], k[K_Y + j], k[K_BETA + j], k[K_AL1 + j], k[K_AL2 + j],
                k[K_AL3 + j], k[K_W1 + j], k[K_W2 + j], k[K_HX + j], k[K_HY + j], k[K_E + j],
                k[K_HEAD + j])  # fmt: skip
    for j in range(count):  # 5. the observation: its head, its tail
        _observed(obs, j, m, k[K_OE + j], k[K_SPSI + j], k[K_CPSI + j], k[K_OK + j], k[K_OR1 + j], k[K_OR2 + j],
                  k[K_OR3 + j], reference_obs)  # fmt: skip
    for p in range(preview.shape[0]):  # the preview's curvatures
        ahead = preview[p]
        for j in range(count):
            obs[j, 4 + p] = _preview_feature(q, manoeuvre, k[K_S + j], ahead)


def _evaluate_rows(
    c: F64,
    preview: F64,
    state: F64,
    actions: F64,
    restart: NDArray[np.bool_],
    tans: F64,
    turn: F64,
    obs: NDArray[np.floating],
    terminated: NDArray[np.bool_],
    record: F64,
    exps: F64,
) -> None:
    """Pass 2 row by row, the pieces of :func:`evaluate` called in turn per row, without scratch (arrays of any
    layout): the same bits. The single env's, and the vector step's below :data:`ROWS_BELOW` rows, where
    :func:`evaluate`'s stages cost more than they save."""
    q = _row_constants(c)
    manoeuvre = c[MANOEUVRE] != 0.0
    m = 4 + preview.shape[0]
    reference_obs = _observe_reference(c[SPEED], c[MAX_SPEED])
    for i in range(state.shape[0]):
        (x, y, beta, al1, al2, al3, w1, w2, cos_beta, sin_beta, abs_dv, change_sq, r0, r1, r2) = _moved(
            q, restart[i], state[i, 0], state[i, 1], state[i, 2], state[i, 3], state[i, 4], state[i, 5],
            state[i, 6], state[i, 7], actions[i, 0], actions[i, 1], turn[i], tans[i, 0], tans[i, 1]
        )  # fmt: skip
        hx, hy, e, cos_theta, sin_theta, s, on_line = _projected(q, manoeuvre, x, y, cos_beta, sin_beta)
        o0, o1, o2, o3, heading, ex0, ex1, ex2, off = _terms(
            q, on_line, e, cos_beta, sin_beta, cos_theta, sin_theta, abs_dv, change_sq
        )
        _stored(state[i], record[i], 0, 0, x, y, beta, al1, al2, al3, w1, w2, hx, hy, e, heading)
        exps[i, 0] = ex0
        exps[i, 1] = ex1
        exps[i, 2] = ex2
        terminated[i] = off
        _observed(obs, i, m, o0, o1, o2, o3, r0, r1, r2, reference_obs)
        for p in range(preview.shape[0]):
            obs[i, 4 + p] = _preview_feature(q, manoeuvre, s, preview[p])


def _finish(c: F64, reward: F64, record: F64, exps: F64) -> int:
    """Pass 3: the exponentials of ``exps`` (their arguments, :func:`amigo_gym.model.kinematics.col_exp` in place),
    then the track, speed and smoothness terms and the reward.

    Returns the number of rows whose heading (``record[i, 2]``) lies past ``heading_limit`` in absolute
    value (the rows :func:`amigo_gym.task.v0.bound_angle` changes; NaN is not past it).
    """
    flat = exps.reshape(3 * reward.shape[0])
    for j in numba.prange(flat.shape[0]):  # in a loop of their own, over a flat view: LLVM vectorises it
        flat[j] = kinematics.col_exp(flat[j])
    limit = c[HEADING_LIM]
    past = 0
    for i in numba.prange(reward.shape[0]):
        if abs(record[i, 2]) > limit:
            past += 1
        # task.v0.reward_term_columns and reward_product, from exps = exp(arguments)
        track = exps[i, 0]
        speed = exps[i, 1]
        smooth = _smooth_term(exps[i, 2], c[SMOOTH_W])
        rew = _reward_product(track, speed, record[i, 13], smooth)
        record[i, 11] = track
        record[i, 12] = speed
        record[i, 14] = smooth
        record[i, 15] = rew
        reward[i] = rew
    return past


# Each loop is written once, with ``prange``: compiled without ``parallel`` it is a plain serial loop.
# The row's code is the loop's own or that of the pieces (functions of floats, which LLVM inlines): a per-row call
# with a dozen array arguments cost twice the time. The evaluate pass calls a function per block (_evaluate_block).
_serial = numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
_parallel = numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False, parallel=True)
move_arguments = _serial(_twin(_move_arguments, "move_arguments"))
move_arguments_parallel = _parallel(_twin(_move_arguments, "move_arguments_parallel"))
evaluate = _serial(_twin(_evaluate, "evaluate"))
evaluate_parallel = _parallel(_twin(_evaluate, "evaluate_parallel"))
evaluate_rows = _serial(_evaluate_rows)
finish = _serial(_twin(_finish, "finish"))
finish_parallel = _parallel(_twin(_finish, "finish_parallel"))


# ---------------------------------------------------------------------------------------------- start states
def _next_double_typing(typingctx: object, bitgen: nb_types.Type) -> tuple[Signature, Callable[..., ir.Value]] | None:
    """``bitgen->next_double(bitgen->state)`` for ``bitgen`` the address (an integer) of a numpy ``bitgen_t``.

    numpy's C API (``numpy/random/bitgen.h``): ``bitgen_t`` is ``{void *state; uint64_t (*next_uint64)(void *);
    uint32_t (*next_uint32)(void *); double (*next_double)(void *); uint64_t (*next_raw)(void *);}``, and
    ``Generator.random`` fills its output with exactly this call, one per number. The address is an
    argument, never a constant of the compiled code, so the on-disk cache holds nothing of one process.
    """
    if not isinstance(bitgen, nb_types.Integer):
        return None

    def codegen(context: object, builder: ir.IRBuilder, signature: Signature, args: list[ir.Value]) -> ir.Value:
        void_p = ir.IntType(8).as_pointer()
        next_double = ir.FunctionType(ir.DoubleType(), [void_p]).as_pointer()
        bitgen_t = ir.LiteralStructType([void_p, void_p, void_p, next_double, void_p])
        ptr = builder.inttoptr(args[0], bitgen_t.as_pointer())
        zero, i32 = ir.Constant(ir.IntType(32), 0), ir.IntType(32)
        state = builder.load(builder.gep(ptr, [zero, ir.Constant(i32, 0)], inbounds=True))
        fn = builder.load(builder.gep(ptr, [zero, ir.Constant(i32, 3)], inbounds=True))
        return builder.call(fn, [state])

    return nb_types.float64(bitgen), codegen


#: :func:`_next_double_typing` as numba's intrinsic: ``_next_double(address) -> float`` in compiled code
_next_double = cast(Callable[[int], float], intrinsic(_next_double_typing))


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def draw_starts(
    bitgens: NDArray[np.uintp],
    restart: NDArray[np.bool_],
    start: F64,
    state: F64,
    rows: NDArray[np.intp],
    beta: F64,
) -> int:
    """Draw the start states of the rows where ``restart`` is set, in row order; return their number ``m``.

    Row ``i`` draws three numbers ``r`` from the generator whose ``bitgen_t`` lies at ``bitgens[i]``
    (what ``Generator.random(3)`` draws; :class:`amigo_gym.envs.AmigoBotEnv` draws ``uniform(-1, 1, 3)``,
    which is ``-1 + 2 r``) and sets ``state[i]`` to the start pose of ``u = -1 + 2 r`` (``task.v1.start_state``)
    with wheel angles 0 and the initial rates, except that ``x, y`` hold H's position until
    :func:`place_starts` moves them to A (it needs ``cos beta, sin beta``). ``rows[:m]`` receives the
    rows, ``beta[:m]`` their headings. Returns ``-1`` (and draws nothing more) at a zero address.
    """
    x0 = start[S_X0]
    y0 = start[S_Y0]
    theta0 = start[S_THETA0]
    pos_noise = start[S_POS_NOISE]
    heading_noise = start[S_HEADING_NOISE]
    rate1 = start[S_RATE1]
    rate2 = start[S_RATE2]
    m = 0
    for i in range(restart.shape[0]):
        if not restart[i]:
            continue
        g = bitgens[i]
        if g == 0:
            return -1
        u0 = -1.0 + 2.0 * _next_double(g)  # three calls in order, as Generator.random(3)
        u1 = -1.0 + 2.0 * _next_double(g)
        u2 = -1.0 + 2.0 * _next_double(g)
        b = theta0 + u2 * heading_noise
        state[i, 0] = x0 + u0 * pos_noise
        state[i, 1] = y0 + u1 * pos_noise
        state[i, 2] = b
        state[i, 3] = 0.0
        state[i, 4] = 0.0
        state[i, 5] = 0.0
        state[i, 6] = rate1
        state[i, 7] = rate2
        rows[m] = i
        beta[m] = b
        m += 1
    return m


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def place_starts(
    start: F64,
    rows: NDArray[np.intp],
    cos_beta: F64,
    sin_beta: F64,
    state: F64,
    tans: F64,
) -> None:
    """Finish :func:`draw_starts`' rows with ``cos_beta, sin_beta`` of their headings (numpy's ``cos``, ``sin``).

    A lies ``l3`` behind H (:func:`amigo_gym.model.kinematics.a_from_h`): ``x = x_H - l3 cos beta``, ``y = y_H -
    l3 sin beta``; the row's ``tans`` receive ``(cos beta, sin beta)``, as :func:`evaluate` wants them.
    """
    l3 = start[S_L3]
    for j in range(rows.shape[0]):
        i = rows[j]
        c = cos_beta[j]
        s = sin_beta[j]
        state[i, 0], state[i, 1] = _a_from_h(state[i, 0], state[i, 1], c, s, l3)
        tans[i, 0] = c
        tans[i, 1] = s


@numba.njit(cache=True, nogil=True, error_model="numpy", boundscheck=False)
def count_steps(
    steps: NDArray[np.int64],
    rows: NDArray[np.intp],
    max_steps: int,
    dt: float,
    truncated: NDArray[np.bool_],
    time: F64,
) -> None:
    """The vector env's step counters in one pass: what ``steps += 1; steps[rows] = 0; truncated = steps >=
    max_steps`` (all False for ``max_steps < 0``, i.e. no limit) ``; time = steps * dt`` compute with numpy
    (``steps * dt`` converts the count to float64, then multiplies, as numpy does)."""
    for i in range(steps.shape[0]):
        steps[i] += 1
    for j in range(rows.shape[0]):
        steps[rows[j]] = 0
    for i in range(steps.shape[0]):
        s = steps[i]
        truncated[i] = max_steps >= 0 and s >= max_steps
        time[i] = float(s) * dt


# ---------------------------------------------------------------------------------------------- one robot
# The single env's step (:class:`amigo_gym.sim.fast.SingleStep`): the same three passes on a one-row view of one
# buffer, so that a call from Python hands over three arrays instead of a dozen (numba's dispatch costs about
# 0.1 us per array argument; a step's passes at N = 1 cost less than that). Columns of the ``(1, SINGLE_WIDTH)``
# float64 buffer ``buf``:
#: the state (:data:`STATE_FIELDS`)
SINGLE_STATE = 0
#: the validated action (two columns)
SINGLE_ACTION = 8
#: the tangents' arguments, then values (two columns)
SINGLE_TANS = 10
#: the turn rate of pass 1
SINGLE_TURN = 12
#: the exponentials' arguments, then values (three columns)
SINGLE_EXPS = 13
#: the reward
SINGLE_REWARD = 16
#: the record (:data:`RECORD_FIELDS`, 16 columns)
SINGLE_RECORD = 17
SINGLE_WIDTH = 33
# ``flags`` ``(1, 2)`` bool: column 0 the restart mask (always False for a step), column 1 ``terminated``.


@_serial
def single_move(c: F64, buf: F64, flags: NDArray[np.bool_], a1: float, a2: float) -> None:
    """The action ``(a1, a2)`` into ``buf``, then pass 1 (:func:`move_arguments`) of the robot in ``buf``."""
    buf[0, SINGLE_ACTION] = a1
    buf[0, SINGLE_ACTION + 1] = a2
    move_arguments(
        c,
        buf[:, SINGLE_STATE:SINGLE_ACTION],
        buf[:, SINGLE_ACTION:SINGLE_TANS],
        flags[:, 0],
        buf[:, SINGLE_TANS:SINGLE_TURN],
        buf[:, SINGLE_TURN],
    )


@_serial
def single_evaluate(c: F64, preview: F64, buf: F64, flags: NDArray[np.bool_], obs: NDArray[np.floating]) -> None:
    """Pass 2 (:func:`evaluate_rows`) of the robot in ``buf``, its observation into ``obs (1, obs_dim)``."""
    evaluate_rows(
        c,
        preview,
        buf[:, SINGLE_STATE:SINGLE_ACTION],
        buf[:, SINGLE_ACTION:SINGLE_TANS],
        flags[:, 0],
        buf[:, SINGLE_TANS:SINGLE_TURN],
        buf[:, SINGLE_TURN],
        obs,
        flags[:, 1],
        buf[:, SINGLE_RECORD:SINGLE_WIDTH],
        buf[:, SINGLE_EXPS:SINGLE_REWARD],
    )


@_serial
def single_finish(c: F64, buf: F64) -> int:
    """Pass 3 (:func:`finish`) of the robot in ``buf``: the number of headings past the limit (0 or 1)."""
    exps = buf[0, SINGLE_EXPS:SINGLE_REWARD].reshape((1, 3))  # contiguous, as finish reshapes it
    past = finish(c, buf[:, SINGLE_REWARD], buf[:, SINGLE_RECORD:SINGLE_WIDTH], exps)
    return int(past)


@_serial
def single_step(c: F64, preview: F64, buf: F64, flags: NDArray[np.bool_], obs: NDArray[np.floating], a1: float,
                a2: float, tan: int, tan_data: int, meta: NDArray[np.int64]) -> int:  # fmt: skip
    """The single env's whole step in one call: :func:`single_move`, the two tangents, :func:`single_evaluate` and
    :func:`single_finish` (the exponentials), the tangents by numpy's own float64 loop at the address ``tan``
    (:func:`amigo_gym.sim.numpy_loops.numpy_loop_in_place`): the passes' bits with ``np.tan`` between them, on every
    CPU. Returns what :func:`single_finish` returns."""
    single_move(c, buf, flags, a1, a2)
    numpy_loops.numpy_loop_in_place(tan, tan_data, buf[0, SINGLE_TANS:SINGLE_TURN], meta)
    single_evaluate(c, preview, buf, flags, obs)
    return single_finish(c, buf)
