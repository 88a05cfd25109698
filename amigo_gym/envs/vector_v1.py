"""Native vector environment of ``AmigoBot-v1`` (``gym.make_vec("AmigoBot-v1", num_envs=N)``): ``N`` robots, each
with its own path, speed, true robot, slip, delay and noise. For the same seeds it reproduces
``vectorization_mode="sync"`` in the three autoreset modes (to 1e-9 between the compiled step and the reference)."""

from __future__ import annotations

import ctypes
import os
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from amigo_gym.envs.amigobot_v1 import record_info, reference_record, v0_record_info
from amigo_gym.envs.base import (
    TRAIL_LENGTH,
    VECTOR_KERNELS,
    Array,
    BoolArray,
    ObsArray,
    StepResult,
    assign_rows,
    box_spaces,
    check_reset_mask,
    check_reset_options,
    check_vector_args,
    parse_pose_option,
    parse_seeds,
    scatter_infos,
    take_rows,
)
from amigo_gym.envs.spec import JsonSpecMixin
from amigo_gym.model.kinematics import advance_angle, body_velocity_columns, castor_rate_columns
from amigo_gym.model.randomization import EpisodeDraw
from amigo_gym.paths.batch import PathBatch
from amigo_gym.paths.clothoid import P_CLOSED, P_LENGTH, locate_columns, pose_columns_of
from amigo_gym.paths.families import make_family_path, segment_params
from amigo_gym.sim import fast_v1, fast_v1_batch, layout_v1
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking

_EPISODE_FIELDS = tracking.Episode._fields
_STATE_FIELDS = tracking.State._fields
_INT_FIELDS = {"lag": np.int64, "key": np.uint64, "steps": np.int64}  # of Episode and State (the others float64)
_U3 = [(-1.0, 1.0)] * 3  # draw_episode's u
_R_COMMAND, _R_SLIP, _R_HX, _R_HY = layout_v1.R_COMMAND, layout_v1.R_SLIP, layout_v1.R_HX, layout_v1.R_HY
_R_END, _R_TERM, _R_REWARD = layout_v1.R_END, layout_v1.R_TERM, layout_v1.R_REWARD


_np_count_nonzero = np.count_nonzero  # any() of a bool mask, faster than ndarray.any for a few robots
#: ``(BitGenerator.capsule, b"BitGenerator") -> int``: its ``bitgen_t`` address (as ``.ctypes.bit_generator``, faster)
_capsule_pointer = ctypes.pythonapi.PyCapsule_GetPointer
_capsule_pointer.restype, _capsule_pointer.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]

#: bytes per robot besides the command ring, the trail and the paths
ROW_BYTES = 3200


def memory_needed(n: int, p: tracking.TrackingParams, render_mode: str | None = None) -> int:
    """An estimate of the memory of ``n`` robots [bytes]: :data:`ROW_BYTES` each, the command ring, the render trail
    and, for drawn paths, a drawn path in the compiled step's arena (a random one also as a Python object; a family
    path's is built only when :attr:`AmigoBotV1VectorEnv.paths` is read)."""
    per = ROW_BYTES + 16 * tracking.command_ring_length(p)
    if render_mode is not None:
        per += 16 * TRAIL_LENGTH
    if tracking.fixed_path(p) is None:
        per += 2 * tracking.path_nbytes(tracking.random_pool_path(p, 0)) if p.path == "random" else 25_000
    return n * per


def check_memory(owner: str, n: int, p: tracking.TrackingParams, render_mode: str | None = None) -> None:
    """``ValueError`` when ``n`` robots need more memory than the machine has (:func:`memory_needed`)."""
    try:
        total: int | None = int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        total = None
    need = memory_needed(n, p, render_mode)
    if total is not None and need > total:
        raise ValueError(
            f"{owner}.num_envs={n} needs about {need:,} bytes ({need // n:,} per robot), more than this machine's "
            f"memory of {total:,} bytes; use fewer robots"
        )


def _columns(kind: Any, values: Any, m: int) -> Any:
    # floats or (m,) columns as the NamedTuple kind (Episode, State) of new (m,) arrays
    cols = zip(kind._fields, values, strict=True)
    return kind(*(np.broadcast_to(np.asarray(c, dtype=_INT_FIELDS.get(f, np.float64)), (m,)).copy() for f, c in cols))


def _is_scalar(x: Any) -> bool:
    try:  # (a 0-d array is not iterable)
        iter(x)
    except TypeError:
        return True
    return isinstance(x, str | bytes)


class AmigoBotV1VectorEnv(JsonSpecMixin, VectorEnv[ObsArray, NDArray[np.floating[Any]], NDArray[Any]]):
    """``N`` AmigoBot-v1 tasks stepped as numpy batches (see :class:`amigo_gym.envs.AmigoBotV1Env`).

    Args:
        num_envs: number of robots ``N`` >= 1.
        max_episode_steps: truncation after this many steps (``None``: never); ``gym.make_vec`` passes the
            registration's 600 unless given.
        render_mode: ``None`` or ``"rgb_array"`` (``render()`` returns one frame per robot).
        autoreset_mode: ``"NextStep"`` (default), ``"SameStep"`` or ``"Disabled"``, as in ``SyncVectorEnv``.
        kernel: ``"auto"``, ``"numpy"`` or ``"numba"`` as for :class:`amigo_gym.envs.AmigoBotV1Env`, or
            ``"numba-parallel"`` (the compiled loops on numba's threads, which sleep between steps after a short
            spin: :func:`amigo_gym.sim.fast_v1.wait_passively`, unless ``OMP_WAIT_POLICY`` was set before).
        params, **settings: the task settings, exactly as for ``gym.make("AmigoBot-v1", ...)``.

    Infos: the single env's numeric keys as ``(N, ...)`` arrays with ``_key`` masks; each robot's path description
    is in :attr:`path_infos`. Rendering keeps the last ``trail_length`` (1000) positions of H per robot.
    ``num_envs`` is refused when its robots would need more than the machine's memory (:func:`memory_needed`:
    about 3.3 KB per robot at dt = 0.1 s on a fixed path, 28 KB on mixed paths, 51 KB on random ones).
    """

    trail_length: int = TRAIL_LENGTH

    metadata: dict[str, Any] = {  # noqa: RUF012
        "render_modes": ["rgb_array"],
        "render_fps": 10.0,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    #: AmigoBot-v0's classes: the path without a feasibility report (check_v0 checked that it is drivable)
    _v0 = False

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        kernel: str = "auto",
        *,
        params: Any = None,
        **settings: Any,
    ) -> None:
        owner = type(self).__name__
        check_vector_args(owner, num_envs, max_episode_steps, render_mode)
        fast_v1.check_kernel(owner, kernel, VECTOR_KERNELS)
        self.params: tracking.TrackingParams = tracking.make_tracking_params(owner, params, **settings)
        p = self.params
        self._k = tracking.constants(p)
        check_memory(owner, int(num_envs), p, render_mode)
        #: the fixed path's feasibility report (None for drawn paths)
        fixed, self.feasibility = (p.path, None) if self._v0 else tracking.check_task(p)
        # on a fixed path, the episode every start draws but its offsets, and as columns of one row
        self._template = None if fixed is None else tracking.episode_template(p)
        self._template_row = None if self._template is None else _columns(tracking.Episode, self._template, 1)
        n = self.num_envs = int(num_envs)
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        self.render_mode = render_mode
        try:
            self.autoreset_mode = AutoresetMode(autoreset_mode)
        except ValueError:
            allowed = [m.value for m in AutoresetMode]
            raise ValueError(f"autoreset_mode must be one of {allowed}, got {autoreset_mode!r}") from None
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / p.dt, "autoreset_mode": self.autoreset_mode}
        self.single_action_space, obs_space = box_spaces(tracking.obs_bounds(p))
        self.single_observation_space = obs_space
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(obs_space, n)
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._seeds: list[int | None] = [None] * n
        #: each generator's ``bitgen_t`` address (0: not yet; :meth:`_draws`)
        self._draw_ptrs = np.zeros(n, dtype=np.int64)
        self._autoreset: BoolArray = np.zeros(n, dtype=np.bool_)
        self._obs: ObsArray = np.zeros((n, obs_space.shape[0]), dtype=np.float32)
        self._trail: Array | None = None  # H's trail: a ring (trail_length, N, 2), allocated when first written
        self._trail_count = 0
        self._trail_start = np.zeros(n, dtype=np.int64)  # the count at which each robot's episode started
        self._renderers: list[Any] = [None] * n
        self._was_reset = False
        placeholder = fixed if fixed is not None else tracking.random_pool_path(p, 0)
        self._paths = PathBatch([placeholder] * n)
        self._unbuilt: dict[int, Any] = {}  # row -> its drawn path or description, not yet in _paths
        self.path_infos: list[dict[str, Any]] = [{} for _ in range(n)]
        self._state = tracking.State._make([*(np.zeros(n) for _ in _STATE_FIELDS[:-1]), np.zeros(n, dtype=np.int64)])
        self._episode = _columns(tracking.Episode, [0] * len(_EPISODE_FIELDS), n)
        self._ring = np.zeros((n, self._k.ring_length, 2))
        self._batch: fast_v1_batch.BatchKernel | None = None
        compiled = fixed is None or fast_v1.compiled_path(fixed, p)  # drawn paths are built-in ones
        if fast_v1.use_kernel(owner, "numba" if kernel == "numba-parallel" else kernel) and compiled:
            self._batch = fast_v1_batch.BatchKernel(self._k, n, parallel=kernel == "numba-parallel")
            self._state, self._episode = self._block_views(self._state.steps)
        elif fast_v1.use_fast_path(None):
            fast_v1.path_loops()
        #: the AmigoBot-v0 task these settings are (:func:`amigo_gym.task.v1.v0_settings`), or None
        self.v0_params = tracking.v0_settings(p)
        self._castor = np.zeros(n)  # the castor's rolling angle [rad] (v0's info) on the reference route
        self._ring_step = 0
        self._goal = np.full((n, 2), np.nan)
        self._no_end = np.full(n, "", dtype=object)  # end_condition's template: copied, a quarter of np.full's time
        self._h_now: Array = np.zeros((n, 2)) if render_mode is not None else np.zeros((0, 2))

    @property
    def paths(self) -> PathBatch:
        """Each robot's path (:class:`amigo_gym.paths.PathBatch`). A drawn family path is built when first asked for
        here (the compiled step builds only its flat vector; the same path)."""
        if self._unbuilt:
            loops = fast_v1.path_loops()
            rows, got = np.fromiter(self._unbuilt, dtype=np.intp), list(self._unbuilt.values())
            self._unbuilt = {}
            built = [make_family_path(q["family"], loops=loops, **{k: v for k, v in q.items() if k != "family"})
                     if isinstance(q, dict) else q for q in got]  # fmt: skip
            self._paths.replace(rows, built)
        return self._paths

    @property
    def np_random_seed(self) -> tuple[int, ...]:  # type: ignore[override]
        """Seeds of the sub-environments' generators (as ``SyncVectorEnv.np_random_seed``; before the first reset,
        each generator is made from a random seed, which is reported)."""
        for i in range(self.num_envs):
            self._rng(i)
        return tuple(int(s) for s in self._seeds if s is not None)

    def _rng(self, i: int) -> np.random.Generator:
        g = self._rngs[i]
        if g is None:
            g, self._seeds[i] = seeding.np_random()
            self._rngs[i] = g
        return g

    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsArray, dict[str, Any]]:
        """Reset all robots, or those of ``options["reset_mask"]``. Raises ``TypeError`` for a ``reset_mask`` that is
        not a bool numpy array (as ``SyncVectorEnv``), ``ValueError`` for a bad seed list, option, pose or mask."""
        n = self.num_envs
        check_reset_options(options, extra=("reset_mask",))
        seeds = parse_seeds(seed, n)
        opts = {} if options is None else options
        mask = check_reset_mask(opts["reset_mask"], n) if "reset_mask" in opts else np.ones(n, dtype=np.bool_)
        pose_opt = np.broadcast_to(parse_pose_option(opts["pose"], (n,)), (n, 3)) if "pose" in opts else None
        if not mask.all() and not self._was_reset:
            raise gym.error.ResetNeeded('reset all robots (no "reset_mask") before a partial reset')
        self._was_reset = True
        idx = np.flatnonzero(mask)
        for i in idx.tolist():
            if seeds[i] is not None:
                self._rngs[i], self._seeds[i] = seeding.np_random(seeds[i])
                self._draw_ptrs[i] = 0
        self._autoreset[idx] = False
        obs, infos = self._reset_rows(idx, pose_opt)
        self._obs = self._obs.copy()
        self._obs[idx] = obs
        if self.render_mode is not None:
            self._append_trail()
        return self._obs.copy(), scatter_infos(infos, mask, self.num_envs)

    def step(self, actions: NDArray[np.floating[Any]]) -> StepResult:
        """Step every robot; autoreset finished ones according to ``autoreset_mode``. Raises ``TypeError`` for a
        scalar (as ``SyncVectorEnv``) or non-numeric action, ``ValueError`` for actions not of shape ``(N, 2)`` or
        NaN/inf, ``RuntimeError`` in ``Disabled`` mode on a robot whose episode ended (reset it first)."""
        n = self.num_envs
        if not self._was_reset:
            raise gym.error.ResetNeeded(f"call reset() before step() on {type(self).__name__}")
        if _is_scalar(actions):  # TypeError as SyncVectorEnv, which iterates over the actions
            kind = "a string" if isinstance(actions, str | bytes) else f"a scalar {type(actions).__name__} object"
            raise TypeError(
                f"Unable to iterate over the following elements: {actions} "
                f"(actions must be an array of shape ({n}, 2), got {kind})"
            )
        a = task.validate_action(actions, (n,))
        mode = self.autoreset_mode
        if mode == AutoresetMode.DISABLED and np.count_nonzero(self._autoreset):
            raise RuntimeError(
                f"robots {np.flatnonzero(self._autoreset).tolist()} finished their episodes; "
                "reset them (options={'reset_mask': ...}) before stepping in Disabled autoreset mode"
            )
        a1, a2 = a[:, 0].copy(), a[:, 1].copy()
        self._ring_step += 1
        obs, rec = self._step_kernel(a1, a2) if self._batch is not None else self._step_columns(a1, a2)
        restarted: NDArray[np.intp] | None = None
        if mode == AutoresetMode.NEXT_STEP and _np_count_nonzero(self._autoreset):
            # the new episodes' records replace the step's: no reward, not terminated
            restarted = np.flatnonzero(self._autoreset)
            obs[restarted], rec[restarted] = self._begin_rows(restarted)
            rec[restarted, _R_REWARD] = 0.0
            rec[restarted, _R_TERM] = 0.0
        infos, reward, terminated = self._record_infos(slice(None), rec)
        hx, hy = rec[:, _R_HX], rec[:, _R_HY]
        if self.render_mode is not None:
            self._h_now[:, 0] = hx
            self._h_now[:, 1] = hy
        if self.v0_params is None:
            terminated = self._end(terminated, infos, hx, hy, restarted)
        truncated: BoolArray = np.zeros(n, dtype=np.bool_)
        if self.max_episode_steps is not None:
            truncated = np.asarray(self._state.steps) >= self.max_episode_steps
            if restarted is not None:
                truncated[restarted] = False
        if mode == AutoresetMode.SAME_STEP and _np_count_nonzero(done := terminated | truncated):
            idx = np.flatnonzero(done)
            final_obs = np.full(n, None, dtype=object)
            for i in idx.tolist():
                final_obs[i] = obs[i].copy()
            final_info = scatter_infos(take_rows(infos, idx), done, n)
            if self.v0_params is None:
                final_info["end_condition"] = np.where(done, final_info["end_condition"], np.array(None))
            obs[idx], info_r = self._reset_rows(idx)
            assign_rows(infos, info_r, idx)
            self._mark_restarted(infos, idx)
            final = {"final_obs": final_obs, "_final_obs": done.copy(), "final_info": final_info}
            infos = {**final, "_final_info": done.copy(), **infos}
        self._autoreset = terminated | truncated
        self._obs = obs
        if self.render_mode is not None:
            self._append_trail()
        return obs, reward, terminated, truncated, scatter_infos(infos, None, n)

    def set_path_params(self, path_params: Any) -> None:
        """Draw the next episodes' paths with the family parameters ``path_params``, e.g.
        ``{"max_curvature": 3.0, "max_curvature_rate": 3.0}`` [1/m, 1/m^2] (``path="random"`` or ``"mixed"`` only).

        Checked as at construction before anything changes; episodes under way keep their paths, robots draw from
        the new pool at their next reset. No random number is drawn.
        """
        from dataclasses import replace

        owner = f"{type(self).__name__}.set_path_params"
        if not isinstance(self.params.path, str) or self.params.path not in ("random", "mixed"):
            raise ValueError(f"{owner}: only drawn paths (path='random' or 'mixed') take new parameters, got "
                             f"path={self.params.path!r}")  # fmt: skip
        p = replace(self.params, path_params=path_params)
        tracking.check_task(p)
        self.params = p
        self._k = tracking.constants(p)
        if self._batch is not None:
            self._batch._k = self._k

    def _reset_rows(self, idx: NDArray[np.intp], pose_opt: Array | None = None) -> tuple[ObsArray, dict[str, Any]]:
        """New episodes for the robots ``idx``: their observations ``(m, D)`` and compact infos."""
        obs, rec = self._begin_rows(idx, pose_opt)
        return obs, self._record_infos(idx, rec)[0]

    def _begin_rows(self, idx: NDArray[np.intp], pose_opt: Array | None = None) -> tuple[ObsArray, Array]:
        """New episodes for the robots ``idx``: their observations ``(m, D)`` and info records."""
        obs = np.empty((len(idx), self._obs.shape[1]), dtype=np.float32)
        begin = self._begin_rows_kernel if self._batch is not None else self._begin_rows_columns
        rec = begin(idx, pose_opt, obs)
        if self.render_mode is not None:  # the robots' trails start at the next position
            self._trail_start[idx] = self._trail_count
            self._h_now[idx, 0] = rec[:, _R_HX]
            self._h_now[idx, 1] = rec[:, _R_HY]
        return obs, rec

    def _begin_rows_columns(self, idx: NDArray[np.intp], pose_opt: Array | None, obs: ObsArray) -> Array:
        k = self._k
        recs, paths, states, episodes = [], [], [], []
        for j, i in enumerate(idx.tolist()):
            pose = None if pose_opt is None else tuple(pose_opt[i].tolist())
            b = tracking.begin_episode(self._rng(i), k, pose)
            paths.append(b.path)
            self.path_infos[i] = b.path_info
            states.append(b.state)
            episodes.append(b.episode)
            obs[j] = b.outcome.obs
            recs.append(reference_record(k.w_max, b.state, b.outcome, tracking.NO_NOISE, 0.0))
        st = tracking.State(*(np.array(c) for c in zip(*states, strict=True)))
        self._set_rows(idx, st, _columns(tracking.Episode, zip(*episodes, strict=True), len(idx)))
        self._paths.replace(idx, paths)
        self._castor[idx] = 0.0
        self._goal[idx] = [tracking.goal_point(self._k.params, path) for path in paths]
        return np.stack(recs)

    def _begin_rows_kernel(self, idx: NDArray[np.intp], pose_opt: Array | None, obs: ObsArray) -> Array:
        # each row draws from its own generator; the start states on the columns of all rows at once
        b = self._batch
        assert b is not None
        k = self._k
        rows = idx.tolist()
        m = len(rows)
        template = self._template
        path: Any = None if template is None else tracking.fixed_path(k.params)
        fns: tuple[Any, Any] = (None, None)  # start_state's progress and path_pose: the path's methods
        if template is not None:  # one path: the episodes differ in their start offsets alone
            assert self._template_row is not None
            paths: list[Any] = [path] * m
            if not self.path_infos[rows[0]]:  # the first reset, of every row: the path's description and goal
                self.path_infos = [tracking.draw_path(self._rng(0), k.params)[1] for _ in range(self.num_envs)]
                self._goal[:] = tracking.goal_point(k.params, path)
            u_all = self._draws(idx, _U3, False)[0]
            if pose_opt is None:  # the start states and their evaluation in one compiled call
                return self._started(idx, b.restart(rows, path, self._template_row, u_all, obs))
            ep_all = tracking.Episode(*(np.repeat(c, m) for c in self._template_row))
        else:  # each row draws its path and episode; the family paths built in the arena, the others held there
            held: list[tuple[int, Any]] = []
            built: list[tuple[int, tuple[int, float, float, float]]] = []
            drawn = k.params.path in ("random", "mixed")
            for i in rows:
                rng = self._rng(i)
                q, info = (None, tracking.draw_family(rng, k.params)) if drawn else tracking.draw_path(rng, k.params)
                self.path_infos[i] = info
                if info["family"] == "random":
                    q = tracking.random_pool_path(k.params, info["id"], fast_v1.path_loops())
                self._unbuilt[i] = info if q is None else q
                if q is None:
                    built.append((i, segment_params(info["family"], info)))
                else:
                    held.append((i, q))
            intervals, keyed = tracking.episode_draws(k.params)  # then each row's draw_episode
            draws, keys = self._draws(idx, [*intervals, *_U3], keyed)
            ep = tracking.episode_of(k.params, draws[:, 0], EpisodeDraw(*draws[:, 1:6].T), keys)
            ep_all = _columns(tracking.Episode, ep, m)
            u_all = draws[:, 6:]
            a = b.arena
            a.assign([i for i, _ in held], [q for _, q in held])
            if built:
                kinds = np.array([v[0] for _, v in built], dtype=np.int64)
                a.build([i for i, _ in built], kinds, np.array([v[1:] for _, v in built]))
            flat, at, w = a.flat, a.starts[idx], k.window  # the rows' poses and projections in one call each
            fns = (lambda _, x, y, s: locate_columns(flat, at, x, y, np.full(m, s), w, w).progress,
                   lambda _, s: pose_columns_of(flat, at, s))  # fmt: skip
        st = tracking.start_state(k, path, ep_all, tuple(u_all.T), *fns)
        if pose_opt is not None:
            st = tracking.placed_state(k, path, ep_all, st, tuple(pose_opt[idx].T), fns[0])
        st_all = _columns(tracking.State, st, m)
        if template is not None:
            return self._started(idx, b.start(rows, paths, st_all, ep_all, obs))
        if k.params.goal_tolerance > 0.0:  # the ends of the open paths (tracking.goal_point)
            ends = pose_columns_of(flat, at, flat[at + P_LENGTH])
            self._goal[idx] = np.where((flat[at + P_CLOSED] == 0.0)[:, None], np.c_[ends.x, ends.y], np.nan)
        return self._started(idx, b.start(rows, None, st_all, ep_all, obs))

    def _draws(self, idx: NDArray[np.intp], intervals: list[Any], keyed: bool) -> tuple[Array, NDArray[np.uint64]]:
        # each row's draws (m, q) of the intervals (lo, hi) and key (0 unless keyed), as numpy's: one compiled call
        ptrs = self._draw_ptrs
        for i in idx[ptrs[idx] == 0].tolist():  # the generators not yet drawn from
            ptrs[i] = _capsule_pointer(self._rng(i).bit_generator.capsule, b"BitGenerator") or 0
        out, keys = np.empty((len(idx), len(intervals))), np.zeros(len(idx), dtype=np.uint64)
        draw = fast_v1_batch.loop("draw_uniforms", self._batch is not None and self._batch.parallel)
        draw(ptrs[idx], np.array(intervals), out, keys[: len(keys) * keyed])
        return out, keys

    def _started(self, idx: NDArray[np.intp], rec: Array) -> Array:
        # the compiled step's rows began (their states and episodes are in its block): their step counts, command
        # rings and start records (the command being executed, no slip)
        np.asarray(self._state.steps)[idx] = 0
        self._start_rings(idx)
        rec[:, _R_COMMAND] = self._ring[idx, 0]  # (a1, a2) w_max
        rec[:, _R_SLIP] = 0.0
        return rec

    def _set_rows(self, idx: NDArray[np.intp], st: tracking.State, ep: tracking.Episode) -> None:
        # the reference route's rows began: their state and episode columns, command rings
        for name, col in zip(_STATE_FIELDS, st, strict=True):
            np.asarray(getattr(self._state, name))[idx] = col
        for name, col in zip(_EPISODE_FIELDS, ep, strict=True):
            np.asarray(getattr(self._episode, name))[idx] = col
        self._start_rings(idx)

    def _start_rings(self, idx: NDArray[np.intp]) -> None:
        # the command each robot was executing before its first step: its wheels' state (0 at rest)
        w_max = self._k.w_max
        self._ring[idx, :, 0] = (np.asarray(self._state.a1)[idx] * w_max)[:, None]
        self._ring[idx, :, 1] = (np.asarray(self._state.a2)[idx] * w_max)[:, None]

    def _mark_restarted(self, infos: dict[str, Any], idx: NDArray[np.intp]) -> None:
        if self.v0_params is not None:
            return
        infos["end_condition"] = infos["end_condition"].copy()
        infos["end_condition"][idx] = ""

    def _end(
        self, terminated: BoolArray, infos: dict[str, Any], hx: Array, hy: Array, restarted: NDArray[np.intp] | None
    ) -> BoolArray:
        # with the goals of open paths (goal_tolerance; not at the restarted rows' starts), which set end_of_path;
        # and infos["end_condition"]
        cond = self._no_end.copy()
        if self._k.params.goal_tolerance > 0.0:
            goal = tracking.goal_reached(self._k.params, hx, hy, self._goal[:, 0], self._goal[:, 1])
            if restarted is not None:
                goal[restarted] = False
            if _np_count_nonzero(goal):
                terminated = terminated | goal
                infos["end_of_path"] = np.where(goal, 1.0, infos["end_of_path"])
        else:
            goal = None
        if _np_count_nonzero(terminated):
            cond[terminated] = "off_path"
            cond[np.asarray(infos["end_of_path"]) != 0.0] = "end_of_path"
            if goal is not None:
                cond[goal] = "goal"
            if restarted is not None:
                cond[restarted] = ""
        infos["end_condition"] = cond
        return terminated

    def _step_columns(self, a1: Array, a2: Array) -> tuple[ObsArray, Array]:
        """Every robot's step: the observations and info records."""
        n = self.num_envs
        st, out, noise = tracking.step_columns(
            self._k, self.paths, self._state, self._episode, self._ring, self._ring_step, a1, a2
        )
        self._state = tracking.State(*(np.asarray(c) for c in st))
        if self.v0_params is not None:  # the castor angle of v0's info
            robot = self._k.nominal
            v, bdot = body_velocity_columns(self._state.w1, self._state.w2, robot)
            self._castor = advance_angle(self._castor, castor_rate_columns(v, bdot, robot), self.params.dt)
        obs = np.empty((n, self._obs.shape[1]), dtype=np.float32)
        for j, c in enumerate(out.obs):
            obs[:, j] = c
        return obs, reference_record(self._k.w_max, self._state, out, noise, self._castor).reshape(n, -1)

    def _step_kernel(self, a1: Array, a2: Array) -> tuple[ObsArray, Array]:
        b = self._batch
        assert b is not None
        obs = np.empty((self.num_envs, self._obs.shape[1]), dtype=np.float32)
        rec = b.step(self._ring, self._ring_step, a1, a2, obs)
        steps = self._state.steps
        np.add(steps, 1, out=steps)
        return obs, rec

    def _record_infos(self, rows: NDArray[np.intp] | slice, rec: Array) -> tuple[dict[str, Any], Array, BoolArray]:
        """The compact infos, rewards and ``terminated`` of ``rows`` from their info records ``rec``, a new array."""
        ep = self._episode
        dt = self.params.dt
        time = np.asarray(self._state.steps)[rows] * dt
        if self.v0_params is not None:
            infos = v0_record_info(rec, rec.T[layout_v1.R_ERROR :], time)
        else:
            true_robot = {name: np.array(np.asarray(getattr(ep, name))[rows]) for name in ("r1", "r2", "l1")}
            delay = np.asarray(ep.lag)[rows] * dt + np.asarray(ep.t_switch)[rows]
            infos = record_info(rec, rec.T[layout_v1.R_ERROR :], time, true_robot, delay, rec[:, _R_END])
        return infos, rec[:, _R_REWARD].copy(), rec[:, _R_TERM] != 0.0

    def _block_views(self, steps: NDArray[np.int64]) -> tuple[tracking.State, tracking.Episode]:
        # the state and episode columns as views of the compiled step's block (its keys for the episodes' key)
        assert self._batch is not None
        rows = self._batch.rows
        ep = tracking.Episode._make(self._batch.keys if f == "key" else getattr(rows, f) for f in _EPISODE_FIELDS)
        return tracking.State._make([*(getattr(rows, name) for name in _STATE_FIELDS[:-1]), steps]), ep

    def _append_trail(self) -> None:
        length = max(1, int(self.trail_length))
        if self._trail is None or self._trail.shape[0] != length:
            self._trail = np.zeros((length, self.num_envs, 2))
            self._trail_count = 0
            self._trail_start[:] = 0
        self._trail[self._trail_count % length] = self._h_now
        self._trail_count += 1

    def _trail_of(self, i: int) -> list[tuple[float, float]]:
        if self._trail is None:
            return []
        length = self._trail.shape[0]
        rows = np.arange(max(int(self._trail_start[i]), self._trail_count - length), self._trail_count) % length
        return [(float(x), float(y)) for x, y in self._trail[rows, i].tolist()]

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        """One ``(H, W, 3)`` uint8 frame per robot for ``render_mode="rgb_array"``, else ``None``; ``ResetNeeded``
        before the first ``reset()``."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gym.make_vec")
            return None
        if not self._was_reset:
            raise gym.error.ResetNeeded(f"call reset() before render() on {type(self).__name__}")
        from amigo_gym.envs.rendering import Renderer

        st = self._state
        x, y, beta, alpha1, alpha2 = (np.asarray(c) for c in (st.x, st.y, st.beta, st.alpha1, st.alpha2))
        steps = np.asarray(st.steps)
        frames = []
        for i in range(self.num_envs):
            path: Any = self.paths[i]
            r = self._renderers[i]
            if r is None or r.path is not path:
                r = self._renderers[i] = Renderer(self.params, path, "rgb_array")
            frames.append(
                r.draw(
                    np.array((x[i], y[i], beta[i])),
                    self._trail_of(i),
                    wheel_angles=np.array((alpha1[i], alpha2[i])),
                    time=float(steps[i] * self.params.dt),
                )
            )
        return tuple(frames)

    def close_extras(self, **kwargs: Any) -> None:
        """Close the renderers."""
        for r in self._renderers:
            if r is not None:
                r.close()
        self._renderers = [None] * self.num_envs

    def __getstate__(self) -> dict[str, Any]:
        """Pickle and deep-copy without the renderers (recreated when next used)."""
        state = self.__dict__.copy()
        state["_renderers"] = [None] * self.num_envs
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._draw_ptrs = np.zeros(self.num_envs, dtype=np.int64)  # the generators are new objects
        if self._batch is not None:  # the state columns are views of the block's rows again
            self._state, self._episode = self._block_views(np.asarray(self._state.steps))
        elif fast_v1.use_fast_path(None):
            fast_v1.path_loops()
