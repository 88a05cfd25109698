"""The optional compiled step of the single ``AmigoBot-v1`` environment (numba), and when it runs.

Two implementations of one robot's step exist:

* the **reference**, :func:`amigo_gym.task.v1.step_columns` / :func:`amigo_gym.task.v1.evaluate_columns`
  on Python floats (numpy, always available, any path object);
* the **kernel**, :class:`StepKernel`: one compiled call per step (:mod:`amigo_gym.sim._kernels_v1`, numba, a
  core dependency where it ships wheels) on a :class:`~amigo_gym.paths.ClothoidPath` (every built-in path family). The
  logarithms of the per-step noise (between a small compiled call that draws the uniforms and the step) and
  the three reward exponentials (after the step) are numpy's, as in the reference, since numpy's ``log`` and
  ``exp`` are not the C library's. The results are the reference's bit for bit (``tests/test_kernel_v1.py``).
  A path object of another class runs the reference.

This module is numba-free: it holds the layouts of the kernel's vectors (the index constants below, used by
the kernel and by :class:`amigo_gym.envs.AmigoBotV1Env`), builds the constants, hands out the paths' flat vectors
and loads the kernel.

:func:`use_kernel` decides from ``kernel="auto" | "numpy" | "numba"`` with the semantics of the v0 vector
env's keyword (:func:`amigo_gym.sim.fast.use_fast_path`: ``"auto"`` follows ``AMIGO_GYM_KERNEL`` and uses numba when
it can be imported). numba is imported only when a :class:`StepKernel` is first built (never by
``import amigo_gym``); its compiled code is cached on disk, so a later process loads it instead of compiling.
"""

from __future__ import annotations

from functools import lru_cache, partial
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model import fresnel, randomization
from amigo_gym.paths import families
from amigo_gym.paths.classic import PathPose
from amigo_gym.paths.clothoid import ClothoidPath, PathLoops, use_compiled_rows
from amigo_gym.sim import fast, layout_v1
from amigo_gym.task import v1 as tracking

__all__ = [
    "KERNELS",
    "use_kernel",
    "libm_matches_numpy",
    "kernels",
    "kernel_constants",
    "flat_path",
    "path_loops",
    "StepKernel",
]

Array = NDArray[np.float64]


def __getattr__(name: str) -> Any:
    """The layouts' names (:mod:`amigo_gym.sim.layout_v1`), also read here: ``fast_v1.W_X``."""
    try:
        return getattr(layout_v1, name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


# ---------------------------------------------------------------------------- selection and data

#: values of the ``kernel=`` keyword of :class:`amigo_gym.envs.AmigoBotV1Env`
KERNELS: tuple[str, ...] = fast.KERNELS


def use_kernel(owner: str, kernel: object) -> bool:
    """Whether ``kernel=`` selects the compiled step (``"auto"``: when numba is importable and the platform's
    ``cos``/``sin`` give numpy's bits, :func:`libm_matches_numpy`).

    Raises:
        ValueError: not one of :data:`KERNELS`.
        ImportError: ``"numba"`` (or ``AMIGO_GYM_KERNEL=numba`` with ``"auto"``) without numba installed.
        RuntimeError: ``"numba"`` (or ``AMIGO_GYM_KERNEL=numba``) where the compiled step cannot give the
            reference's bits.
    """
    if not isinstance(kernel, str) or kernel not in KERNELS:
        raise ValueError(f"{owner}.kernel must be {fast.choices(KERNELS)}, got {kernel!r}")
    requested = None if kernel == "auto" else kernel == "numba"
    if not fast.use_fast_path(requested):
        return False
    if libm_matches_numpy():
        return True
    if requested or fast.kernel_mode() == "numba":
        raise RuntimeError(
            f"{owner}: the compiled step cannot reproduce the reference's bits on this platform (numba's cos/sin, "
            "the C library's, differ from numpy's); use kernel='numpy' (or 'auto')"
        )
    return False


@lru_cache(maxsize=1)
def libm_matches_numpy() -> bool:
    """Whether the kernel's ``math.cos``/``math.sin`` (the C library's) give numpy's float64 ``np.cos``/``np.sin``
    bits on a fixed sample of 4000 arguments (small ones, and headings of many laps): the premise of the
    kernel's bit-identity (:mod:`amigo_gym.sim._kernels_v1`). Checked once per process (a millisecond)."""
    g = np.random.default_rng(20240601)
    x = np.concatenate((g.uniform(-10.0, 10.0, 2000), g.uniform(-2000.0, 2000.0, 1000), g.normal(0.0, 1e-3, 1000)))
    return fast.same_bits_as_numpy(kernels().cos_sin, x, np.cos, np.sin)


@lru_cache(maxsize=1)
def path_loops() -> PathLoops | None:
    """The compiled path-building loops (:class:`amigo_gym.paths.clothoid.PathLoops`: the float route's
    :func:`~amigo_gym.paths.clothoid.chain_pieces`, :func:`~amigo_gym.paths.clothoid.sample_points`,
    :func:`~amigo_gym.paths.families.run_segments` and :func:`~amigo_gym.paths.families.lane_change_shape`, compiled
    by :mod:`amigo_gym.sim._kernels_v1` with their node tables bound), which the environments with the compiled step
    hand to the path constructors at resets; None where the C library's ``cos``/``sin`` do not give numpy's bits
    (:func:`libm_matches_numpy`: then the float route builds the paths). The same paths either way
    (``tests/test_path_loops.py``). Loads the kernels (numba) on the first call."""
    if not libm_matches_numpy():
        return None
    kv = kernels()
    nodes = np.array(fresnel.node_table(1), dtype=np.float64)
    run_nodes = np.array(families.RUN_NODES, dtype=np.float64)
    loops = PathLoops(
        chain=partial(kv.build_chain, nodes),
        samples=partial(kv.build_samples, nodes),
        run=partial(kv.build_run, run_nodes),
        lane=partial(kv.build_lane, run_nodes),
        locate=partial(kv.rows_locate, nodes),
        pose=partial(kv.rows_pose, nodes),
    )
    use_compiled_rows(loops)
    return loops


def kernels() -> ModuleType:
    """The compiled kernels, :mod:`amigo_gym.sim._kernels_v1` (imports numba on the first call)."""
    fast.announce_compilation()
    from amigo_gym.sim.layout import kernel_cache

    with kernel_cache():
        import amigo_gym.sim._kernels_v1 as kv

    return kv


def kernel_constants(k: tracking.Constants) -> Array:
    """The ``consts`` vector of :mod:`amigo_gym.sim._kernels_v1` for the constants ``k``.

    Every entry is computed as the reference computes it (``2.0 * l1``, the negated scales the reference
    divides by), the quadrature nodes are :mod:`amigo_gym.model.fresnel`'s own lists, so the kernel's arithmetic is
    the reference's.
    """
    p = k.params
    nominal = k.nominal
    act = p.actuators
    rz = p.randomize
    u, uw = fresnel._nodes(k.n_sub)
    values: dict[str, float] = {
        "dt": p.dt,
        "w_max": k.w_max,
        "r1": nominal.r1,
        "r2": nominal.r2,
        "l1": nominal.l1,
        "two_l1": 2.0 * nominal.l1,
        "accel": act.acceleration,
        "decel": act.deceleration,
        "rot_accel": act.rot_acceleration,
        "rot_decel": act.rot_deceleration,
        "l3": k.l3,
        "error_scale": p.error_scale,
        "e_max": k.e_max,
        "termination_distance": p.termination_distance,
        "preview_scale": p.preview_scale,
        "v_max": k.v_max,
        "sigma_track": p.sigma_track,
        "sigma_speed": p.sigma_speed,
        "smooth_scale_sq": k.smooth_scale_sq,
        "trapezoid": 1.0 if p.speed_profile == "trapezoid" else 0.0,
        "profile_accel": p.profile_accel,
        "profile_decel": p.profile_decel,
        "window": k.window,
        "speed_lookahead": tracking.SPEED_LOOKAHEAD,
        "n_preview": float(len(p.preview)),
        "n_nodes": float(len(u)),
        "position_noise": rz.position_noise,
        "heading_noise": rz.heading_noise,
        "wheel_rate_noise": rz.wheel_rate_noise,
    }
    head = [values[name] for name in layout_v1.CONSTANT_FIELDS]
    tail = [*p.preview, *k.preview_bounds, *u, *uw, *fresnel._U_LIST, *fresnel._UW_LIST]
    return np.array(head + tail, dtype=np.float64)


def flat_path(path: ClothoidPath) -> Array:
    """The ``path`` vector of :mod:`amigo_gym.sim._kernels_v1` for a :class:`ClothoidPath`: the path's own flat vector
    (``ClothoidPath._t.flat``, built with the path; the pieces' tables and the coarse samples the
    reference searches). Read only by the kernels."""
    flat: Array = path._t.flat
    return flat


class StepKernel:
    """The compiled step of one robot (:mod:`amigo_gym.sim._kernels_v1`): constants, flattened path, workspace.

    The state of an episode lives in :attr:`ws` between steps (:meth:`load` puts a :class:`tracking.State` and a
    :class:`tracking.Episode` there, :meth:`state` reads it back). :attr:`run_record` (a step: ``run_record(ring_step,
    a1, a2, *args)``) and :attr:`evaluate` are the compiled :func:`amigo_gym.sim._kernels_v1.step_record` and
    :func:`amigo_gym.sim._kernels_v1.evaluate` (dropped when pickled, loaded again when unpickled).

    Attributes:
        consts: :func:`kernel_constants`. path: :func:`flat_path` of the episode's path.
        ws: the workspace, ``len(layout_v1.WS_FIELDS) + layout_v1.WS_SCRATCH`` float64.
    """

    def __init__(self, k: tracking.Constants) -> None:
        self.consts: Array = kernel_constants(k)
        self.ws: Array = np.zeros(len(layout_v1.WS_FIELDS) + layout_v1.WS_SCRATCH)
        #: the single env's observation, written by each step (:attr:`run`; the env hands out a copy)
        self.obs: NDArray[np.float32] = np.zeros(len(tracking.obs_bounds(k.params)[0]), dtype=np.float32)
        #: the single env's info record (:data:`layout_v1.RECORD_WIDTH`, :func:`amigo_gym.sim._kernels_v1.fill_record`),
        #: written by :attr:`run_record` and :meth:`fill`
        self.record: Array = np.zeros(layout_v1.RECORD_WIDTH)
        #: the single env's delay ring of commands (:func:`amigo_gym.model.actuators.ring_write`), ``(L, 2)``
        self.ring: Array = np.zeros((k.ring_length, 2))
        self.smooth_weight = float(k.params.smooth_weight)
        self.path: Array = np.zeros(0)
        self.key = np.uint64(0)
        rz = k.params.randomize
        # normal draws per step
        self.n_normal = randomization.channels_on(rz.position_noise, rz.heading_noise, rz.wheel_rate_noise)
        self.window = k.window
        self.noise_on = False  # this episode draws per step (:meth:`draw` before :attr:`step`)
        self._bind()

    def _bind(self) -> None:
        kv = kernels()
        self.evaluate: Any = kv.evaluate
        self.noise_uniforms: Any = kv.noise_uniforms
        self.locate_progress: Any = kv.progress
        self.path_pose: Any = kv.pose
        # the step and the draws for exactly these types (fast.direct_call: no dispatch per call): the ring (L, 2) and
        # the observation (D,) float32 of the single env, the step counters Python ints
        self._uniforms: Any = fast.direct_call(kv.noise_uniforms, self.consts, self.ws, self.key, 0)
        self._args()
        #: the step and its info record in one call (:func:`amigo_gym.sim._kernels_v1.step_record`)
        self.run_record: Any = fast.direct_call(kv.step_record, 0, 0.0, 0.0, *self.args)
        self._fill: Any = fast.direct_call(kv.fill_record, self.ws, self.record, 0.0)
        #: the record's scalars (``record[R_ERROR:]``: a view, for their floats)
        self.scalars: Array = self.record[layout_v1.R_ERROR :]
        self.u1: Array = self.ws[layout_v1.S_U1 : layout_v1.S_U1 + self.n_normal]
        self.logs: Array = self.ws[layout_v1.S_LOG : layout_v1.S_LOG + self.n_normal]

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for name in (
            "evaluate",
            "noise_uniforms",
            "locate_progress",
            "path_pose",
            "scalars",
            "u1",
            "logs",
            "args",
            "_uniforms",
            "run_record",
            "_fill",
        ):
            del state[name]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._bind()

    def _args(self) -> None:
        #: :attr:`run_record`'s arguments after the step's own (the episode's path: set again by :meth:`load`)
        self.args = (self.consts, self.path, self.ring, self.ws, self.obs, self.record, self.smooth_weight)

    def progress(self, path: Any, x: float, y: float, hint: float) -> float:
        """H's progress [m] at ``(x, y)`` from ``hint`` (:data:`amigo_gym.task.v1.ProgressFn`): compiled on a
        :class:`ClothoidPath`, ``path.locate`` on any other path."""
        if type(path) is ClothoidPath:
            s: float = self.locate_progress(self.consts, flat_path(path), x, y, hint)
            return s
        got: float = path.locate(x, y, hint, self.window, self.window).progress
        return got

    def pose(self, path: Any, s: float) -> PathPose:
        """The path's pose at the arc length ``s`` [m] (:data:`amigo_gym.task.v1.PoseFn`): compiled on a
        :class:`ClothoidPath` (:func:`amigo_gym.paths.clothoid.pose_flat`, as its float path), ``path.pose_columns``
        on any other path."""
        if type(path) is ClothoidPath:
            return PathPose(*self.path_pose(self.consts, flat_path(path), s))
        got: PathPose = path.pose_columns(s)
        return got

    def load(self, path: ClothoidPath, st: tracking.State, ep: tracking.Episode, l3_differs: bool) -> None:
        """Start an episode: the path's vector, the state and the episode's constants into the workspace."""
        self.path = flat_path(path)
        self._args()
        ws = self.ws
        ws[layout_v1.W_X : layout_v1.W_STEPS + 1] = (
            st.x, st.y, st.beta, st.w1, st.w2, st.alpha1, st.alpha2, st.progress, st.a1, st.a2, float(st.steps),
        )  # fmt: skip
        ws[layout_v1.W_R1 : layout_v1.W_L3D + 1] = (
            ep.r1, ep.r2, ep.l1, ep.l3, float(ep.lag), ep.t_switch, ep.v_cruise, ep.t_brake, float(l3_differs),
        )  # fmt: skip
        ws[layout_v1.W_SLIP_MAX] = ep.slip_max
        # anything drawn per step (randomization._step_noise_float: slip when slip_max > 0, noise when a level is)
        self.noise_on = float(ep.slip_max) > 0.0 or self.n_normal > 0
        ws[layout_v1.W_NOISE_ON] = 1.0 if self.noise_on else 0.0
        self.key = np.uint64(ep.key)

    def fill(self) -> None:
        """The info record from the workspace as it is (a start state: after :attr:`evaluate`)."""
        self._fill(self.ws, self.record, self.smooth_weight)

    def draw(self, steps: int) -> None:
        """This step's draws into the workspace (:func:`amigo_gym.model.randomization.step_noise` of the step counter
        ``steps``): the uniforms by :func:`amigo_gym.sim._kernels_v1.noise_uniforms`, their logarithms by ``np.log``
        (as the reference); :func:`amigo_gym.sim._kernels_v1.step` completes the normals. Only when anything is drawn.
        """
        if self._uniforms(self.consts, self.ws, self.key, steps):
            np.log(self.u1, out=self.logs)

    def state(self, steps: int) -> tracking.State:
        """The state in the workspace as a :class:`tracking.State` of floats (``steps``, an int, given)."""
        x, y, beta, w1, w2, al1, al2, prog, a1, a2 = self.ws[layout_v1.W_X : layout_v1.W_A2 + 1].tolist()
        return tracking.State(x, y, beta, w1, w2, al1, al2, prog, a1, a2, steps)

    def outputs(self) -> list[float]:
        """The entries :data:`layout_v1.WS_FIELDS` of the workspace as Python floats."""
        out: list[float] = self.ws[: len(layout_v1.WS_FIELDS)].tolist()
        return out
