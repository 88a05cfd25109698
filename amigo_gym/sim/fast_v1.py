"""When the compiled step runs (:func:`use_kernel`, :func:`compiled_path`) and its vectors; numba-free until
:func:`kernels`. The kernel compiles the reference's scalar functions and agrees with it to 1e-9, not bit for bit."""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Callable, Sequence
from functools import lru_cache, partial
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model import fresnel, randomization
from amigo_gym.paths import CirclePath, ManoeuvrePath, families
from amigo_gym.paths.classic import PathPose
from amigo_gym.paths.clothoid import ClothoidPath, PathLoops, use_compiled_rows
from amigo_gym.sim import layout_v1
from amigo_gym.sim.layout import kernel_cache
from amigo_gym.task import v1 as tracking

Array = NDArray[np.float64]


#: environment variable that selects the step's implementation: ``auto`` (default), ``numba``, ``numpy``
KERNEL_ENV = "AMIGO_GYM_KERNEL"

#: the values of every env's ``kernel`` keyword (the vector envs also take ``"numba-parallel"``)
KERNELS: tuple[str, ...] = ("auto", "numpy", "numba")


def choices(values: Sequence[str]) -> str:
    """``"'a', 'b' or 'c'"``: allowed values for a one-line error message."""
    quoted = [repr(v) for v in values]
    return quoted[0] if len(quoted) == 1 else ", ".join(quoted[:-1]) + " or " + quoted[-1]


@lru_cache(maxsize=1)
def numba_available() -> bool:
    """Whether numba can be imported (checked without importing it)."""
    return importlib.util.find_spec("numba") is not None


def use_fast_path(requested: bool | None = None) -> bool:
    """Whether to run the compiled kernel: ``requested`` ``True`` requires it, ``False`` refuses it, ``None`` follows
    :data:`KERNEL_ENV` (else ``ValueError``). ``ImportError`` where it is required but numba is missing."""
    if requested is None:
        mode = os.environ.get(KERNEL_ENV, "auto").strip().lower() or "auto"
        if mode not in KERNELS:
            raise ValueError(f"{KERNEL_ENV} must be 'auto', 'numba' or 'numpy', got {mode!r}")
        requested = None if mode == "auto" else mode == "numba"
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


def wait_passively() -> None:
    """Unless the user set ``OMP_WAIT_POLICY``: ``PASSIVE`` and ``GOMP_SPINCOUNT=1000`` (unless set): numba's OpenMP
    (libgomp) threads spin 1,000 pauses after a parallel loop (tens of µs; libgomp's own count where threads outnumber
    cores), then sleep; libgomp's default spins 300,000, ``PASSIVE`` alone none (docs/performance.md, "Threads on a
    busy machine"). Call it before they start (the first parallel call or ``numba.set_num_threads``)."""
    if "OMP_WAIT_POLICY" not in os.environ:
        os.environ["OMP_WAIT_POLICY"] = "PASSIVE"
        os.environ.setdefault("GOMP_SPINCOUNT", "1000")


def set_threads(n: int) -> None:
    """``numba.set_num_threads(n)`` after :func:`wait_passively` (it starts numba's threads)."""
    wait_passively()
    import numba

    numba.set_num_threads(n)


#: the one line printed (stderr) when numba starts compiling a kernel of this package in this process
COMPILE_NOTICE = (
    "amigo_gym: compiling the numba step (once per install, up to about 20 s; "
    "later runs load it from numba's cache; AMIGO_GYM_KERNEL=numpy skips it)"
)


@lru_cache(maxsize=1)
def announce_compilation() -> None:
    """Print :data:`COMPILE_NOTICE` once to stderr when numba compiles (not loads from its cache) a kernel of
    ``amigo_gym``: when stderr is a terminal, or ``AMIGO_GYM_COMPILE_NOTICE=1`` (``0`` silences it)."""
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


def direct_call(dispatcher: Any, *args: Any) -> Any:
    """The compiled entry of the numba function ``dispatcher`` for the types of ``args`` (compiled or loaded now),
    callable without numba's dispatch (about 0.1 us per argument): only for arguments of exactly these types at every
    call. Returns ``dispatcher`` itself where numba gives no such entry."""
    import numba

    sig = tuple(numba.typeof(a) for a in args)  # type: ignore[no-untyped-call]
    dispatcher.compile(sig)
    try:
        return dispatcher.get_overload(sig)
    except (AttributeError, KeyError):  # pragma: no cover  (numba's API moved)
        return dispatcher


def use_kernel(owner: str, kernel: object) -> bool:
    """Whether ``kernel=`` (one of :data:`KERNELS`, else ``ValueError``) selects the compiled step: ``"numba"``
    requires it, ``"numpy"`` refuses it, ``"auto"`` follows :data:`KERNEL_ENV` (:func:`use_fast_path`)."""
    return use_fast_path(None if check_kernel(owner, kernel) == "auto" else kernel == "numba")


def check_kernel(owner: str, kernel: object, allowed: Sequence[str] = KERNELS) -> str:
    """``kernel`` if it is one of ``allowed``; else ``ValueError`` naming them."""
    if not isinstance(kernel, str) or kernel not in allowed:
        raise ValueError(f"{owner}.kernel must be {choices(allowed)}, got {kernel!r}")
    return kernel


def compiled_path(path: Any, p: tracking.TrackingParams) -> bool:
    """Whether the compiled step runs on ``path``: a :class:`ClothoidPath`, or AmigoBot-v0's circle or manoeuvre
    (closed forms) with ``observation="v0"`` (whose preview is the curvature alone)."""
    return type(path) is ClothoidPath or (type(path) in (CirclePath, ManoeuvrePath) and p.observation == "v0")


@lru_cache(maxsize=1)
def path_loops() -> PathLoops:
    """The compiled path-building loops (:class:`amigo_gym.paths.clothoid.PathLoops`), their node tables bound; also
    installed for the column projection and pose (:func:`amigo_gym.paths.clothoid.use_compiled_rows`)."""
    kv = kernels()
    nodes, run_nodes = node_tables()
    loops = PathLoops(
        family=partial(kv.build_family, run_nodes),
        flat=partial(kv.build_flat, nodes),
        samples=partial(kv.build_samples, nodes),
        locate=partial(kv.rows_locate, nodes),
        pose=partial(kv.rows_pose, nodes),
    )
    use_compiled_rows(loops)
    return loops


@lru_cache(maxsize=1)
def node_tables() -> tuple[Array, Array]:
    """The path quadrature's node table (:func:`amigo_gym.model.fresnel.node_table` of 1) and
    :data:`amigo_gym.paths.families.RUN_NODES`, as arrays."""
    return np.array(fresnel.node_table(1), dtype=np.float64), np.array(families.RUN_NODES, dtype=np.float64)


@lru_cache(maxsize=1)
def kernels() -> ModuleType:
    """The compiled kernels, :mod:`amigo_gym.sim._kernels_v1` (imports numba on the first call)."""
    announce_compilation()
    with kernel_cache():
        import amigo_gym.sim._kernels_v1 as kv

    return kv


def kernel_constants(k: tracking.Constants) -> Array:
    """The ``consts`` vector of :mod:`amigo_gym.sim._kernels_v1` for the constants ``k``, with the closed forms of a
    :class:`CirclePath` or :class:`ManoeuvrePath` ``k.params.path``."""
    p = k.params
    path = p.path
    kind, circle, straight = layout_v1.PATH_CLOTHOID, CirclePath(), 0.0
    if type(path) is CirclePath:
        kind, circle = layout_v1.PATH_CIRCLE, path
    elif type(path) is ManoeuvrePath:
        kind, circle, straight = layout_v1.PATH_MANOEUVRE, path.circle, path.straight_length
    cx, cy, r0x, r0y = circle._frame
    n = k.nominal
    act = p.actuators
    rz = p.randomize
    head = [  # in the order of layout_v1.CONSTANT_FIELDS, line by line
        p.dt, k.w_max, n.r1, n.r2, n.l1, 2.0 * n.l1,
        act.acceleration, act.deceleration, act.rot_acceleration, act.rot_deceleration,
        k.l3, p.error_scale, k.e_max, p.termination_distance, p.preview_scale, k.v_max,
        p.sigma_track, p.sigma_speed, k.smooth_scale_sq,
        1.0 if p.speed_profile == "trapezoid" else 0.0, p.profile_accel, p.profile_decel,
        k.window, tracking.SPEED_LOOKAHEAD, float(len(p.preview)), float(fresnel.NODES * k.n_sub),
        rz.position_noise, rz.heading_noise, rz.wheel_rate_noise,
        1.0 if p.ideal_actuators else 0.0, 1.0 if p.observation == "v0" else 0.0, 1.0 if p.reward == "v0" else 0.0,
        n.l5, n.r3,
        kind,
        cx, cy, r0x, r0y, float(circle.direction), circle.radius, straight,
    ]  # fmt: skip
    tail = [*p.preview, *k.preview_bounds, *fresnel.step_table(k.n_sub), *fresnel.node_table(1)]
    return np.array(head + tail, dtype=np.float64)


_NO_PATH: Array = np.zeros(0)


def flat_path(path: Any) -> Array:
    """The ``path`` vector of :mod:`amigo_gym.sim._kernels_v1`: a :class:`ClothoidPath`'s own flat vector (read
    only), else empty."""
    if type(path) is not ClothoidPath:
        return _NO_PATH
    flat: Array = path._t.flat
    return flat


def load_rows(ws: Array, rows: Any, st: tracking.State, ep: tracking.Episode, l3_differs: Any) -> None:
    """The states ``st`` and episodes ``ep`` (floats, or columns of ``rows``) into the columns ``rows`` of the block
    ``ws`` (:data:`amigo_gym.sim.layout_v1.Rows`), the castor's angle 0."""
    values = {**ep._asdict(), **st._asdict(), "castor": 0.0, "l3_differs": l3_differs}
    if isinstance(rows, int):  # one robot's floats: one store
        ws[:, rows] = [values[name] for name in layout_v1.Rows._fields]
        return
    for name, row in zip(layout_v1.Rows._fields, ws, strict=True):
        row[rows] = values[name]


class StepKernel:
    """The compiled step of one robot: constants :attr:`consts`, the path's vector :attr:`path`, the block :attr:`ws`
    ``(len(Rows._fields), 1)`` (the episode and its state between steps; :attr:`rows` names its rows), the observation
    :attr:`obs`, the info record :attr:`record` and the command ring :attr:`ring`. A step:
    ``run_record(ring_step, a1, a2, *args)``."""

    def __init__(self, k: tracking.Constants) -> None:
        self.consts: Array = kernel_constants(k)
        self.ws: Array = np.zeros((len(layout_v1.Rows._fields), 1))
        self.obs: NDArray[np.float32] = np.zeros(len(tracking.obs_bounds(k.params)[0]), dtype=np.float32)
        self.record: Array = np.zeros(layout_v1.RECORD_WIDTH)
        self.ring: Array = np.zeros((k.ring_length, 2))
        self.smooth_weight = float(k.params.smooth_weight)
        self.path: Array = np.zeros(0)
        self.key = np.uint64(0)
        rz = k.params.randomize
        self.n_normal = randomization.channels_on(rz.position_noise, rz.heading_noise, rz.wheel_rate_noise)
        self.window = k.window
        self._bind()

    def _bind(self) -> None:
        kv = kernels()
        self.rows = layout_v1.Rows(*self.ws)
        self.evaluate: Any = kv.evaluate
        self.locate_progress: Callable[..., float] = kv.progress
        self.path_pose: Any = kv.pose
        self._args()
        self.run_record: Any = direct_call(kv.step_record, 0, 0.0, 0.0, *self.args)
        self._fill: Any = direct_call(kv.fill_record, self.record, 0.0)
        self.scalars: Array = self.record[layout_v1.R_ERROR :]

    def __getstate__(self) -> dict[str, Any]:
        bound = ("rows", "evaluate", "locate_progress", "path_pose", "scalars", "args", "run_record", "_fill")
        return {k: v for k, v in self.__dict__.items() if k not in bound}  # _bind remakes them

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind()

    def _args(self) -> None:
        self.args = (self.consts, self.path, self.ring, self.ws, self.obs, self.record, self.smooth_weight, self.key)

    def progress(self, path: Any, x: float, y: float, hint: float) -> float:
        """H's progress [m] at ``(x, y)`` from ``hint`` (:data:`amigo_gym.task.v1.ProgressFn`)."""
        if type(path) is ClothoidPath:
            return self.locate_progress(self.consts, flat_path(path), x, y, hint)
        got: float = path.locate(x, y, hint, self.window, self.window).progress
        return got

    def pose(self, path: Any, s: float) -> PathPose:
        """The path's pose at the arc length ``s`` [m] (:data:`amigo_gym.task.v1.PoseFn`)."""
        if type(path) is ClothoidPath:
            return PathPose(*self.path_pose(self.consts, flat_path(path), s))
        got: PathPose = path.pose_columns(s)
        return got

    def load(self, path: Any, st: tracking.State, ep: tracking.Episode, l3_differs: bool) -> None:
        """Start an episode: the path's vector, the state and the episode into the block."""
        self.path = flat_path(path)
        load_rows(self.ws, 0, st, ep, l3_differs)
        self.key = np.uint64(ep.key)
        self._args()

    def fill(self) -> None:
        """The info record's exponentials, terms and reward (after :attr:`evaluate`)."""
        self._fill(self.record, self.smooth_weight)

    def state(self, steps: int) -> tracking.State:
        """The state in the block as a :class:`tracking.State` of floats, ``steps`` given."""
        return tracking.State._make(
            [*(float(getattr(self.rows, name)[0]) for name in tracking.State._fields[:-1]), steps]
        )
