"""The optional compiled fast path (numba) of ``AmigoBot-v0``'s step, and which path runs when.

Two implementations of one step exist:

* the **reference**, AmigoBot-v1's step with AmigoBot-v0's settings (:func:`amigo_gym.task.v1.step_columns` with
  ideal actuators and :func:`amigo_gym.task.v1.reset_columns` of :func:`amigo_gym.task.v1.v0_configuration`; numpy,
  always available: ``kernel="numpy"``, Python floats in the single environment, ``(N,)`` arrays in the vector one);
* the **fast path**, :func:`step_rows`: AmigoBot-v0's step in three compiled passes over the robots
  (:mod:`amigo_gym.sim._kernels`, numba, a core dependency where it ships wheels) around numpy's own ``tan`` ufunc
  (its ``exp`` the reference's, in plain arithmetic: :func:`amigo_gym.model.kinematics.col_exp`), writing into
  preallocated arrays. ``tests/test_kernels.py`` checks that it gives the reference's results
  (to 1e-12, and bit for bit on this machine).

:func:`use_fast_path` decides: ``AMIGO_GYM_KERNEL=numpy`` forces the reference, ``=numba`` requires
the fast path (an ``ImportError`` if numba is missing), unset or ``auto`` uses numba when it can be
imported. numba is imported only on the first call of :func:`kernels` (never by ``import amigo_gym``);
its compiled code is cached on disk, so a later process loads it instead of compiling.
"""

from __future__ import annotations

import ctypes
import importlib.util
import os
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import lru_cache, partial
from types import ModuleType
from typing import Any, Literal, NamedTuple, SupportsIndex

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.params import HEADING_LIMIT
from amigo_gym.paths import CirclePath, ManoeuvrePath
from amigo_gym.sim.layout import twin
from amigo_gym.sim.numpy_loops import numpy_loops
from amigo_gym.task.v0 import TaskConstants, _path_start, bound_angle, initial_wheel_rates, obs_dim, record_info

__all__ = [
    "twin",
    "SingleStep",
    "KERNEL_ENV",
    "kernel_mode",
    "numba_available",
    "KERNELS",
    "choices",
    "use_fast_path",
    "kernels",
    "COMPILE_NOTICE",
    "announce_compilation",
    "kernel_constants",
    "Workspace",
    "workspace",
    "step_rows",
    "start_constants",
    "GeneratorTable",
    "StepReport",
    "step_rows_unchecked",
    "EnvStep",
    "step_env_rows",
    "direct_call",
    "same_bits_as_numpy",
]

Array = NDArray[np.float64]

#: environment variable that selects the step's implementation: ``auto`` (default), ``numba``, ``numpy``
KERNEL_ENV = "AMIGO_GYM_KERNEL"

KernelMode = Literal["auto", "numba", "numpy"]


#: the values of every env's ``kernel`` keyword (the vector envs also take ``"numba-parallel"``)
KERNELS: tuple[str, ...] = ("auto", "numpy", "numba")


def choices(values: Sequence[str]) -> str:
    """``"'a', 'b' or 'c'"``: allowed values for a one-line error message."""
    quoted = [repr(v) for v in values]
    return quoted[0] if len(quoted) == 1 else ", ".join(quoted[:-1]) + " or " + quoted[-1]


def kernel_mode() -> KernelMode:
    """The mode set by :data:`KERNEL_ENV` (``ValueError`` on another value)."""
    mode = os.environ.get(KERNEL_ENV, "auto").strip().lower() or "auto"
    if mode == "auto":
        return "auto"
    if mode == "numba":
        return "numba"
    if mode == "numpy":
        return "numpy"
    raise ValueError(f"{KERNEL_ENV} must be 'auto', 'numba' or 'numpy', got {mode!r}")


@lru_cache(maxsize=1)
def numba_available() -> bool:
    """Whether numba can be imported (checked without importing it)."""
    return importlib.util.find_spec("numba") is not None


def use_fast_path(requested: bool | None = None) -> bool:
    """Whether to run the compiled kernel.

    Args:
        requested: ``True`` requires it, ``False`` refuses it, ``None`` follows :data:`KERNEL_ENV`.

    Raises:
        ImportError: the fast path is required (argument or ``AMIGO_GYM_KERNEL=numba``) but numba is missing.
    """
    if requested is None:
        mode = kernel_mode()
        if mode == "numpy":
            return False
        requested = True if mode == "numba" else None
    if requested is False:
        return False
    if numba_available():
        return True
    if requested:
        raise ImportError(
            "the fast path needs numba, which amigo-gym installs where numba ships wheels: "
            'pip install "amigo-gym[fast]" (from a clone: pip install -e ".[fast]"; or set AMIGO_GYM_KERNEL=numpy)'
        )
    return False


#: the one line printed (stderr) when numba starts compiling a kernel of this package in this process
COMPILE_NOTICE = (
    "amigo_gym: compiling the numba step (once per install, up to about 20 s; "
    "later runs load it from numba's cache; AMIGO_GYM_KERNEL=numpy skips it)"
)
_notice_installed = False


def announce_compilation() -> None:
    """Print :data:`COMPILE_NOTICE` once to stderr when numba really compiles a kernel of ``amigo_gym``.

    A listener of numba's ``numba:compile`` event, which numba fires only on a compilation, not when it loads the
    compiled code from its disk cache: a process that finds the cache warm prints nothing. Only for a person: when
    stderr is a terminal, or when the environment sets ``AMIGO_GYM_COMPILE_NOTICE=1`` (``0`` silences it); a
    script's captured stderr stays as it was. Installed by the first call of :func:`kernels` (here and in
    :mod:`amigo_gym.sim.fast_v1`); cheap afterwards.
    """
    global _notice_installed
    if _notice_installed:
        return
    _notice_installed = True
    wanted = os.environ.get("AMIGO_GYM_COMPILE_NOTICE")
    if wanted == "0" or (wanted != "1" and not (sys.stderr is not None and sys.stderr.isatty())):
        return
    from numba.core import event

    class _Notice(event.Listener):
        done = False

        def on_start(self, ev: Any) -> None:
            dispatcher = ev.data.get("dispatcher") if isinstance(ev.data, dict) else None
            module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
            if not self.done and module.startswith("amigo_gym"):
                self.done = True
                print(COMPILE_NOTICE, file=sys.stderr, flush=True)

        def on_end(self, ev: Any) -> None:
            pass

    event.register("numba:compile", _Notice())  # type: ignore[no-untyped-call]


def kernels() -> ModuleType:
    """The compiled kernels, :mod:`amigo_gym.sim._kernels` (imports numba on the first call)."""
    announce_compilation()
    from amigo_gym.sim.layout import kernel_cache

    with kernel_cache():
        import amigo_gym.sim._kernels as k

    return k


def direct_call(dispatcher: Any, *args: Any) -> Any:
    """The compiled code of the numba function ``dispatcher`` for the types of ``args``, called without numba's
    dispatch.

    A call of a numba function first finds the type of each argument and the compiled code for them (about 0.1 us per
    argument: more than one robot's step); this returns that code, compiled or loaded from numba's disk cache now as
    the first call would, so that a step pays for it once. The same machine code runs, so the results are the same
    bits. Only for arguments of exactly these types at every call (the same dtypes, dimensions, C-contiguity and
    writeability; numbers of the same kind): the callers pass their own buffers, allocated once, of the types
    ``args`` have. Returns ``dispatcher`` itself where numba gives no such entry (another numba version).
    """
    import numba

    sig = tuple(numba.typeof(a) for a in args)  # type: ignore[no-untyped-call]
    dispatcher.compile(sig)
    try:
        return dispatcher.get_overload(sig)
    except (AttributeError, KeyError):  # pragma: no cover  (numba's API moved)
        return dispatcher


def same_bits_as_numpy(compiled: Any, x: NDArray[np.float64], f0: Any, f1: Any) -> bool:
    """Whether ``compiled(x, y0, y1)``, a kernel's elementwise loop of two C library functions, writes numpy's
    ``f0(x)`` and ``f1(x)`` bit for bit (overflows to ``inf`` compared as bits, without numpy's warning): the check
    behind :func:`amigo_gym.sim.fast_v1.libm_matches_numpy`."""
    y0, y1 = np.empty_like(x), np.empty_like(x)
    compiled(x, y0, y1)
    with np.errstate(all="ignore"):
        same0 = np.array_equal(y0.view(np.int64), f0(x).view(np.int64))
        return bool(same0 and np.array_equal(y1.view(np.int64), f1(x).view(np.int64)))


def kernel_constants(k: TaskConstants, path: CirclePath | ManoeuvrePath) -> NDArray[np.float64]:
    """The ``consts`` vector of the kernels (:data:`amigo_gym.sim._kernels.CONSTANT_FIELDS`).

    Every entry is computed as the reference computes it (``2.0 * l1``, ``direction / radius``), so the kernel's
    arithmetic is the reference's.
    """
    robot = k.robot
    if isinstance(path, CirclePath):
        circle, manoeuvre, straight = path, 0.0, 0.0
    else:
        circle, manoeuvre, straight = path.circle, 1.0, path.straight_length
    cx, cy, r0x, r0y = circle._frame
    values = {
        "dt": k.dt,
        "w_max": k.w_max,
        "r1": robot.r1,
        "r2": robot.r2,
        "two_l1": 2.0 * robot.l1,
        "l3": k.l3,
        "l5": robot.l5,
        "r3": robot.r3,
        "speed": k.speed,
        "max_speed": k.max_speed,
        "error_scale": k.error_scale,
        "e_max": k.e_max,
        "termination_distance": k.termination_distance,
        "sigma_track": k.sigma_track,
        "sigma_speed": k.sigma_speed,
        "smooth_scale_sq": k.smooth_scale_sq,
        "smooth_weight": k.smooth_weight,
        "manoeuvre": manoeuvre,
        "direction": float(circle.direction),
        "radius": circle.radius,
        "cx": cx,
        "cy": cy,
        "r0x": r0x,
        "r0y": r0y,
        "straight_length": straight,
        "curvature": circle.direction / circle.radius,
        "heading_limit": HEADING_LIMIT,
    }
    fields: tuple[str, ...] = kernels().CONSTANT_FIELDS
    return np.array([values[name] for name in fields], dtype=np.float64)


@dataclass(frozen=True)
class Workspace:
    """What the kernels need besides the state: the constants and scratch arrays for ``n`` rows.

    Attributes:
        consts: :func:`kernel_constants`.
        preview: the preview distances [m].
        tans: ``(n, 2)`` scratch: arguments, then values, of the two tangents of the arc step.
        turn: ``(n,)`` scratch: the turn rates of the actions (pass 1, read by pass 2).
        exps: ``(n, 3)`` scratch: arguments, then values, of the three exponentials of the reward.
        obs_dim: length of an observation.
        start: :func:`start_constants`, for start states drawn in :func:`step_rows`.
        rows, beta, cos_beta, sin_beta: ``(n,)`` scratch of those draws: the restarting rows, their
            headings and numpy's cosines and sines of them.
        block_cols: the serial evaluate pass's scratch: one block's columns
            (:data:`amigo_gym.sim._kernels.BLOCK_WIDTH` floats), reused by every block of rows (they stay in the L1
            cache).
        parallel_cols: the parallel evaluate pass's scratch, a slot per block of rows
            (:func:`amigo_gym.sim._kernels.scratch_size`), allocated by its first call (empty until then).
    """

    consts: Array
    preview: Array
    tans: Array
    turn: Array
    exps: Array
    obs_dim: int
    start: Array
    rows: NDArray[np.intp]
    beta: Array
    cos_beta: Array
    sin_beta: Array
    block_cols: Array
    parallel_cols: list[Array]


def workspace(k: TaskConstants, path: CirclePath | ManoeuvrePath, n: int) -> Workspace:
    """A :class:`Workspace` for ``n`` robots with the settings ``k`` on ``path``."""
    return Workspace(
        kernel_constants(k, path),
        np.array(k.preview, dtype=np.float64),
        np.zeros((n, 2)),
        np.zeros(n),
        np.zeros((n, 3)),
        obs_dim(k.params),
        start_constants(k, path),
        np.zeros(n, dtype=np.intp),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(kernels().BLOCK_WIDTH),
        [],
    )


def start_constants(k: TaskConstants, path: CirclePath | ManoeuvrePath) -> Array:
    """The ``start`` vector of the start-state kernels (:data:`amigo_gym.sim._kernels.START_FIELDS`).

    The numbers of the start state (:func:`amigo_gym.task.v1.start_state` with v0's settings): the path's start
    point and tangent angle, ``init_position_noise``, ``init_heading_noise``, the robot's ``l3``, and the initial
    wheel rates (:func:`amigo_gym.task.v0.initial_wheel_rates`).
    """
    p = k.params
    x0, y0, theta0 = _path_start(path)
    rate1, rate2 = initial_wheel_rates(p).tolist()
    values = {
        "x0": x0,
        "y0": y0,
        "theta0": theta0,
        "position_noise": p.init_position_noise,
        "heading_noise": p.init_heading_noise,
        "l3": p.robot.l3,
        "rate1": rate1,
        "rate2": rate2,
    }
    fields: tuple[str, ...] = kernels().START_FIELDS
    return np.array([values[name] for name in fields], dtype=np.float64)


class StepReport(NamedTuple):
    """What :func:`step_rows` reports besides its outputs."""

    #: the number ``m`` of start states drawn from ``bitgens`` (their rows are ``ws.rows[:m]``, in increasing
    #: order, until the next call); 0 without ``bitgens``
    drawn: int
    #: the number of rows whose new heading lies past :data:`amigo_gym.model.params.HEADING_LIMIT` in absolute
    #: value (those :func:`amigo_gym.task.v0.bound_angle` reduces; the kernel leaves them as they are)
    past_limit: int


class SingleStep:
    """One robot's step by the compiled kernel: the single env's fast path (``AmigoBotEnv(kernel=...)``).

    The three passes of :func:`step_rows` (:func:`amigo_gym.sim._kernels.single_move`, ``single_evaluate``,
    ``single_finish``: the vector kernel's own loops on a one-row view) with numpy's ``tan`` between the first
    two, on one preallocated buffer: the same operations as a row of the vector env, so the single env
    and the vector env give the same bits, and both those of the reference, AmigoBot-v1's ideal step
    (``tests/test_kernels.py``), on buffers allocated once. One compiled call per step
    (:func:`amigo_gym.sim._kernels.single_step`), which calls numpy's own ``tan`` loop between the passes
    (:func:`amigo_gym.sim.numpy_loops.numpy_loops`: the same bits); where it is not found, three compiled
    calls with ``np.tan`` between the first two.

    Attributes:
        buf: ``(1, SINGLE_WIDTH)`` float64: state, action, scratch, reward and record
            (:data:`amigo_gym.sim._kernels.SINGLE_STATE` and the other column offsets).
        flags: ``(1, 2)`` bool: the restart mask (False) and ``terminated``.
        obs: ``(1, obs_dim)`` float32: the observation of the last step; ``obs_row`` its row (a view).
        record: ``(16,)`` view of the buffer's record (:data:`amigo_gym.sim._kernels.RECORD_FIELDS`); ``head`` its
            first 10 columns (the state's and H's entries of the info).
    """

    def __init__(self, k: TaskConstants, path: CirclePath | ManoeuvrePath) -> None:
        kk = kernels()
        self.consts = kernel_constants(k, path)
        self.preview = np.array(k.preview, dtype=np.float64)
        self.buf = np.zeros((1, kk.SINGLE_WIDTH))
        self.flags = np.zeros((1, 2), dtype=np.bool_)
        self.obs = np.zeros((1, obs_dim(k.params)), dtype=np.float32)
        self.past_limit = 0
        self._bind()

    def _bind(self) -> None:
        """The compiled functions and the buffer's views (again after unpickling)."""
        kk = kernels()
        b = self.buf
        # the compiled passes for exactly these buffers' types (direct_call: no dispatch per call)
        self._move = direct_call(kk.single_move, self.consts, b, self.flags, 0.0, 0.0)
        self._evaluate = direct_call(kk.single_evaluate, self.consts, self.preview, b, self.flags, self.obs)
        self._finish = direct_call(kk.single_finish, self.consts, b)
        # the whole step in one call, numpy's own tan loop called inside (numpy_loops: its address and data pointer,
        # and a scratch); where it is not found, the three passes with np.tan between the first two
        self._whole: Any = None
        self._loops: tuple[Any, ...] | None = None
        loops = numpy_loops()
        if loops is not None:
            self._loops = (loops.tan.address, loops.tan.data, np.zeros(5, np.int64))
            args = (self.consts, self.preview, b, self.flags, self.obs, 0.0, 0.0, *self._loops)
            self._whole = direct_call(kk.single_step, *args)
        self._tans = b[:, kk.SINGLE_TANS : kk.SINGLE_TURN]
        self._state = b[0, kk.SINGLE_STATE : kk.SINGLE_ACTION]
        self.record = b[0, kk.SINGLE_RECORD : kk.SINGLE_WIDTH]
        self.obs_row = self.obs[0]
        self.head = self.record[:10]

    def __getstate__(self) -> dict[str, object]:
        return {name: getattr(self, name) for name in ("consts", "preview", "buf", "flags", "obs", "past_limit")}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._bind()

    def set_state(self, values: Sequence[Any]) -> None:
        """Set the state (the 8 columns :data:`amigo_gym.sim._kernels.STATE_FIELDS`)."""
        self._state[:] = values

    def state(self) -> list[float]:
        """The state's 8 columns as Python floats."""
        out: list[float] = self._state.tolist()
        return out

    def step(self, a1: float, a2: float) -> list[float]:
        """Step the robot with the validated action ``(a1, a2)``; return the record's 16 columns as floats
        (:data:`amigo_gym.sim._kernels.RECORD_FIELDS`: the new state, H, the error, the reward terms and the
        reward). The observation is in :attr:`obs`, ``terminated`` in ``flags[0, 1]``. A heading past
        :data:`amigo_gym.model.params.HEADING_LIMIT` is left as it is and counted in :attr:`past_limit` (1, else 0):
        the caller reduces it by :func:`amigo_gym.task.v0.bound_angle`."""
        b = self.buf
        c = self.consts
        loops = self._loops
        if loops is not None:
            tan, tan_data, meta = loops
            self.past_limit = self._whole(c, self.preview, b, self.flags, self.obs, a1, a2, tan, tan_data, meta)
        else:
            tans = self._tans
            self._move(c, b, self.flags, a1, a2)
            _np_tan(tans, tans)  # out= positionally: numpy parses no keywords
            self._evaluate(c, self.preview, b, self.flags, self.obs)
            self.past_limit = self._finish(c, b)
        rec: list[float] = self.record.tolist()
        return rec

    def env_step(self, a1: float, a2: float, time: float) -> tuple[NDArray[np.float32], float, bool, dict[str, Any]]:
        """The single env's step of AmigoBot-v0's task (AmigoBot-v0, and AmigoBot-v1 with v0's settings):
        :meth:`step`, a heading past the limit reduced by whole turns in the state and the record
        (:func:`amigo_gym.task.v0.bound_angle`, as the reference), then the observation (a new array), the reward,
        ``terminated`` and the info (:func:`amigo_gym.task.v0.record_info`; ``time`` since the reset [s])."""
        rec = self.step(a1, a2)
        if self.past_limit:
            beta = float(bound_angle(float(self._state[2])))
            rec[2] = self.record[2] = self._state[2] = beta
        # the four info arrays are views of one new array
        return self.obs_row.copy(), rec[15], bool(self.flags[0, 1]), record_info(self.head.copy(), rec, time)


_np_tan = np.tan


def step_rows(
    ws: Workspace,
    state: Array,
    actions: Array,
    restart: NDArray[np.bool_],
    obs: NDArray[np.floating],
    reward: Array,
    terminated: NDArray[np.bool_],
    record: Array,
    parallel: bool = False,
    bitgens: NDArray[np.uintp] | None = None,
    *,
    check: bool = True,
) -> StepReport:
    """One step of every row of ``state`` (in place), the outputs written into the arrays given.

    The three passes of :mod:`amigo_gym.sim._kernels` with numpy's ``tan`` between the first two; rows
    where ``restart`` is set (their ``state`` a start state) are evaluated without moving, as
    :func:`amigo_gym.task.v1.reset_columns` evaluates a start state. Layouts: :mod:`amigo_gym.sim._kernels`.
    ``parallel`` runs the loops on numba's threads (the same results).

    ``bitgens`` (:attr:`GeneratorTable.bitgens`, one address per row) makes the step draw the start
    states of the ``restart`` rows itself, each from its row's generator, before evaluating them
    (:func:`amigo_gym.sim._kernels.draw_starts`, numpy's ``cos`` and ``sin`` of the headings,
    :func:`amigo_gym.sim._kernels.place_starts`). The reference is the vector env's loop over the rows of
    :func:`amigo_gym.task.v1.begin_episode`: the start states agree bit for bit, and the generators advance as that
    loop advances them (``tests/test_kernel_draws.py``).
    Without ``bitgens`` the caller has set the start states.

    ``check=False`` skips the checks of the arguments, for a caller that built them for ``ws`` itself (the vector
    env: its own state, buffers it has just allocated, validated actions, its generator table;
    :func:`step_rows_unchecked`): wrong shapes, dtypes or layouts then make numba read or write out of bounds.

    Returns:
        :class:`StepReport`: how many start states were drawn, how many headings are past the limit.

    Raises:
        ValueError: arrays of the wrong shape, dtype or layout for ``ws`` (numba would read past them),
            or a zero address in ``bitgens`` for a restarting row.
    """
    if check:
        _check(ws, state, actions, restart, obs, reward, terminated, record)
        if bitgens is not None and (bitgens.shape != restart.shape or bitgens.dtype != np.uintp):
            msg = f"bitgens must be a uintp array of shape {restart.shape}, got {bitgens.dtype} {bitgens.shape}"
            raise ValueError(msg)
    return _step_rows(_dispatched(parallel), ws, state, actions, restart, obs, reward, terminated, record, bitgens)


class _Passes(NamedTuple):
    """The compiled functions of a step (:mod:`amigo_gym.sim._kernels`): numba's dispatchers, or their
    :func:`direct_call` entries for the types :func:`step_env_rows` passes."""

    move: Any
    evaluate: Any
    finish: Any
    draw_starts: Any
    place_starts: Any
    count_steps: Any
    #: the evaluate pass's row loop (:func:`amigo_gym.sim._kernels.evaluate_rows`), for fewer rows than ``rows_below``
    evaluate_rows: Any
    rows_below: int
    #: whether the passes run on numba's threads (the evaluate pass then needs a scratch slot per block)
    parallel: bool


def _dispatched(parallel: bool) -> _Passes:
    """The kernels' dispatchers (any argument types numba accepts)."""
    k = kernels()
    if parallel:
        return _Passes(k.move_arguments_parallel, k.evaluate_parallel, k.finish_parallel, k.draw_starts,
                       k.place_starts, k.count_steps, k.evaluate_rows, k.ROWS_BELOW, True)  # fmt: skip
    return _Passes(k.move_arguments, k.evaluate, k.finish, k.draw_starts, k.place_starts, k.count_steps,
                   k.evaluate_rows, k.ROWS_BELOW, False)  # fmt: skip


@lru_cache(maxsize=2)
def _direct(parallel: bool) -> _Passes:
    """:func:`_dispatched`'s functions as :func:`direct_call` entries for the argument types of :func:`step_env_rows`:
    C-contiguous float64 constants, state, actions, scratch, record and times, bool masks, a float32 observation,
    int64 step counters, intp rows and the read-only uintp addresses of :attr:`GeneratorTable.bitgens`."""
    d = _dispatched(parallel)
    k = kernels()
    c = np.zeros(len(k.CONSTANT_FIELDS))
    f1, f2, f3, f8, f16 = np.zeros(1), np.zeros((1, 2)), np.zeros((1, 3)), np.zeros((1, 8)), np.zeros((1, 16))
    mask, obs = np.zeros(1, dtype=np.bool_), np.zeros((1, 1), dtype=np.float32)
    rows, steps = np.zeros(1, dtype=np.intp), np.zeros(1, dtype=np.int64)
    bitgens = np.zeros(1, dtype=np.uintp)
    bitgens.flags.writeable = False
    return _Passes(
        direct_call(d.move, c, f8, f2, mask, f2, f1),
        direct_call(d.evaluate, c, f1, f8, f2, mask, f2, f1, obs, mask, f16, f3, f1),
        direct_call(d.finish, c, f1, f16, f3),
        direct_call(d.draw_starts, bitgens, mask, f1, f8, rows, f1),
        direct_call(d.place_starts, f1, rows, f1, f1, f8, f2),
        direct_call(d.count_steps, steps, rows, 0, 0.0, mask, f1),
        direct_call(d.evaluate_rows, c, f1, f8, f2, mask, f2, f1, obs, mask, f16, f3),
        d.rows_below,
        parallel,
    )


_np_count_nonzero = np.count_nonzero


def _step_rows(
    p: _Passes,
    ws: Workspace,
    state: Array,
    actions: Array,
    restart: NDArray[np.bool_],
    obs: NDArray[np.floating],
    reward: Array,
    terminated: NDArray[np.bool_],
    record: Array,
    bitgens: NDArray[np.uintp] | None,
) -> StepReport:
    """:func:`step_rows` (unchecked) with the compiled functions ``p``."""
    c, tans, exps = ws.consts, ws.tans, ws.exps
    p.move(c, state, actions, restart, tans, ws.turn)
    np.tan(tans, out=tans)
    m = 0
    if bitgens is not None:
        m = p.draw_starts(bitgens, restart, ws.start, state, ws.rows, ws.beta)
        if m < 0:
            raise ValueError("bitgens has no generator for a restarting row (address 0)")
        # numpy's cos and sin of the (m,) headings, as task.v1.start_state calls them on its (m,) column
        beta, cos_beta, sin_beta = ws.beta[:m], ws.cos_beta[:m], ws.sin_beta[:m]
        np.cos(beta, out=cos_beta)
        np.sin(beta, out=sin_beta)
        p.place_starts(ws.start, ws.rows[:m], cos_beta, sin_beta, state, tans)
    elif _np_count_nonzero(restart):
        idx = np.flatnonzero(restart)
        beta = state[idx, 2]
        tans[idx, 0] = np.cos(beta)
        tans[idx, 1] = np.sin(beta)
    if state.shape[0] < p.rows_below:  # the row loop: faster for a few rows, the same bits
        p.evaluate_rows(c, ws.preview, state, actions, restart, tans, ws.turn, obs, terminated, record, exps)
    else:
        cols = ws.block_cols
        if p.parallel:  # a slot per block: the threads never share one
            if not ws.parallel_cols:
                ws.parallel_cols.append(np.zeros(kernels().scratch_size(state.shape[0])))
            cols = ws.parallel_cols[0]
        p.evaluate(c, ws.preview, state, actions, restart, tans, ws.turn, obs, terminated, record, exps, cols)
    past = p.finish(c, reward, record, exps)
    return StepReport(int(m), int(past))


#: :func:`step_rows` without the checks of its arguments (``check=False``)
step_rows_unchecked = partial(step_rows, check=False)


class EnvStep(NamedTuple):
    """What :func:`step_env_rows` returns: a vector env's step of AmigoBot-v0's task, before its autoreset
    bookkeeping."""

    obs: NDArray[np.float32]
    reward: Array
    terminated: NDArray[np.bool_]
    truncated: NDArray[np.bool_]
    #: AmigoBot-v0's infos (:func:`amigo_gym.task.v0.record_info`): views of the step's record
    infos: dict[str, Any]
    #: the rows that started an episode at this step (``reset_rows``, or those drawn with ``bitgens``), or None
    restarted: NDArray[np.intp] | None


_NO_ROWS: NDArray[np.intp] = np.zeros(0, dtype=np.intp)


def step_env_rows(
    ws: Workspace,
    rows: Array,
    actions: Array,
    restart: NDArray[np.bool_],
    bitgens: NDArray[np.uintp] | None,
    parallel: bool,
    steps: NDArray[np.int64],
    reset_rows: NDArray[np.intp] | None,
    max_steps: int | None,
    dt: float,
) -> EnvStep:
    """The vector env's step of AmigoBot-v0's task by the compiled kernel (AmigoBot-v0, and AmigoBot-v1 with v0's
    settings): :func:`step_rows` (unchecked) of the state ``rows (N, 8)`` (in place) with the new output arrays, then
    the step counters (``steps += 1``, 0 for the restarted rows; ``truncated = steps >= max_steps``, never for
    ``None``; ``time = steps * dt`` [s]), the headings past the limit reduced by whole turns in the state and the
    record (:func:`amigo_gym.task.v0.bound_angle`, as the numpy path) and the infos.

    The compiled functions are called without numba's dispatch (:func:`direct_call`), for the types of the vector
    env's own arrays: ``rows`` C-contiguous float64 ``(N, 8)``, ``restart`` C-contiguous bool ``(N,)``, ``steps``
    C-contiguous int64 ``(N,)``, ``bitgens`` :attr:`GeneratorTable.bitgens`; ``actions`` is made C-contiguous float64.

    Args:
        reset_rows: rows the caller set to start states before the step (``restart`` set there), or None.
        ws, actions, restart, bitgens, parallel: as :func:`step_rows` (the caller's own arrays).
    """
    n = rows.shape[0]
    p = _direct(parallel)
    obs = np.empty((n, ws.obs_dim), dtype=np.float32)
    reward = np.empty(n)
    terminated = np.empty(n, dtype=np.bool_)
    record = np.empty((n, 16))
    a = np.ascontiguousarray(actions, dtype=np.float64)  # the type of _direct's entries
    report = _step_rows(p, ws, rows, a, restart, obs, reward, terminated, record, bitgens)
    if bitgens is not None:
        reset_rows = ws.rows[: report.drawn].copy()  # the rows restarted in the step (ws.rows is its scratch)
    truncated = np.empty(n, dtype=np.bool_)
    time = np.empty(n)
    limit = -1 if max_steps is None else max_steps
    p.count_steps(steps, _NO_ROWS if reset_rows is None else reset_rows, limit, float(dt), truncated, time)
    if report.past_limit:
        rows[:, 2] = record[:, 2] = bound_angle(rows[:, 2])
    return EnvStep(obs, reward, terminated, truncated, record_info(record, record.T, time), reset_rows)


def _check(
    ws: Workspace,
    state: Array,
    actions: Array,
    restart: NDArray[np.bool_],
    obs: NDArray[np.floating],
    reward: Array,
    terminated: NDArray[np.bool_],
    record: Array,
) -> None:
    n = ws.tans.shape[0]
    want: tuple[tuple[str, NDArray[np.generic], tuple[int, ...], tuple[type[np.generic], ...]], ...] = (
        ("state", state, (n, 8), (np.float64,)),
        ("actions", actions, (n, 2), (np.float64,)),
        ("restart", restart, (n,), (np.bool_,)),
        ("obs", obs, (n, ws.obs_dim), (np.float32, np.float64)),
        ("reward", reward, (n,), (np.float64,)),
        ("terminated", terminated, (n,), (np.bool_,)),
        ("record", record, (n, 16), (np.float64,)),
    )
    for name, a, shape, dtypes in want:
        if a.shape != shape or a.dtype.type not in dtypes or not a.flags.c_contiguous:
            raise ValueError(
                f"{name} must be a C-contiguous {'/'.join(d.__name__ for d in dtypes)} array of shape {shape}, "
                f"got {a.dtype} {a.shape}"
            )


# ---------------------------------------------------------------------------------------------- generators
_capsule_pointer = ctypes.PYFUNCTYPE(ctypes.c_void_p, ctypes.py_object, ctypes.c_char_p)(
    ("PyCapsule_GetPointer", ctypes.pythonapi)
)


def _bitgen_address(g: np.random.Generator | None) -> int:
    """Address of the C ``bitgen_t`` of ``g``'s bit generator when it is a ``PCG64``; 0 otherwise.

    It is the pointer in the bit generator's ``capsule`` (``numpy/random/bitgen.h``), the struct that
    ``Generator`` itself calls (``bitgen->next_double(bitgen->state)``); it lives inside the bit
    generator object, so it stays valid while ``g`` is referenced.
    """
    if g is None or type(g.bit_generator) is not np.random.PCG64:
        return 0
    address: int | None = _capsule_pointer(g.bit_generator.capsule, b"BitGenerator")
    return address or 0


class GeneratorTable:
    """The generators of ``n`` sub-environments (``None`` until set) and the addresses of their C bit generators.

    Indexing reads and sets generators like a list; setting one records its address in :attr:`bitgens`
    (0 for ``None`` or a bit generator other than ``PCG64``), and the table keeps a reference to every
    generator it holds, so each address stays valid as long as the table holds it. :attr:`drawable`
    says whether every row has an address, i.e. whether :func:`step_rows` may draw from
    :attr:`bitgens` (else the caller draws with ``Generator.random``). Pickling and deep copies copy the
    generators and compute the copies' addresses anew (an address is only good in its own process and
    for its own object).

    The compiled draws do not take a generator's lock (its methods do): do not draw from these
    generators in another thread while the environment steps.
    """

    __slots__ = ("_addresses", "_generators", "_missing", "bitgens")

    def __init__(self, generators: Sequence[np.random.Generator | None]) -> None:
        n = len(generators)
        self._generators: list[np.random.Generator | None] = [None] * n
        self._addresses: NDArray[np.uintp] = np.zeros(n, dtype=np.uintp)
        #: the addresses, one per row (0: none), a read-only view (only setting a generator changes them)
        self.bitgens: NDArray[np.uintp] = self._addresses.view()
        self.bitgens.flags.writeable = False
        self._missing = n
        for i, g in enumerate(generators):
            self[i] = g

    def __len__(self) -> int:
        return len(self._generators)

    def __getitem__(self, i: SupportsIndex) -> np.random.Generator | None:
        return self._generators[i]

    def __setitem__(self, i: SupportsIndex, g: np.random.Generator | None) -> None:
        address = _bitgen_address(g)
        self._missing += (address == 0) - (int(self._addresses[i]) == 0)
        self._generators[i] = g
        self._addresses[i] = address

    def __iter__(self) -> Iterator[np.random.Generator | None]:
        return iter(self._generators)

    @property
    def drawable(self) -> bool:
        """Whether every row has a ``PCG64`` generator, so that :func:`step_rows` can draw from :attr:`bitgens`."""
        return self._missing == 0

    def __reduce__(self) -> tuple[type[GeneratorTable], tuple[list[np.random.Generator | None]]]:
        # rebuilt from the (copied) generators: the addresses are computed for the new objects
        return (GeneratorTable, (self._generators,))
