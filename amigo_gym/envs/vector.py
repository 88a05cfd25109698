"""Native numpy-batched vector environment of ``AmigoBot-v0``.

``gym.make_vec("AmigoBot-v0", num_envs=N)`` (or ``vectorization_mode="vector_entry_point"``)
builds :class:`AmigoBotVectorEnv`: ``N`` robots stepped together by the same pure, batched
functions of :mod:`amigo_gym.task.v0` that the single environment calls, with no Python loop over
the environments on the step path. Restarting robots draw their start perturbations from their own
generators: with the compiled kernel, inside it (:func:`amigo_gym.sim.fast.step_rows` with the table of
generators, :class:`amigo_gym.sim.fast.GeneratorTable`); otherwise (the numpy path, or a generator that is
not ``PCG64``) by a Python loop of ``Generator.random`` over them. The two give the same numbers and
leave the generators in the same states.

For the same seed it reproduces ``gym.make_vec(..., vectorization_mode="sync")`` bit for bit:
observations, rewards, terminations, truncations and infos (in the vector format with ``_key``
masks), across autoresets and truncations, in the ``NEXT_STEP`` (default), ``SAME_STEP`` and
``DISABLED`` autoreset modes. Sub-environment ``i`` reset with ``seed`` uses the generator
``gymnasium.utils.seeding.np_random(seed + i)``, exactly as ``Env.reset(seed=seed + i)`` seeds
``np_random``, and draws its start perturbation ``u ~ U[-1, 1]^3`` from it in the same order.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from amigo_gym.envs.amigobot import (
    TRAIL_LENGTH,
    ObsArray,
    check_reset_options,
    make_env_params,
    make_spaces,
    parse_pose_option,
)
from amigo_gym.envs.spec import JsonSpecMixin
from amigo_gym.model.kinematics import h_position, pack
from amigo_gym.model.params import EnvParams, RobotParams, show_value
from amigo_gym.paths import CirclePath, ManoeuvrePath, make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task

__all__ = [
    "AmigoBotVectorEnv",
    "assign_rows",
    "check_reset_mask",
    "check_vector_args",
    "info_row",
    "parse_seeds",
    "scatter_infos",
    "take_rows",
]

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _parse_autoreset_mode(mode: str | AutoresetMode) -> AutoresetMode:
    try:
        return mode if isinstance(mode, AutoresetMode) else AutoresetMode(mode)
    except ValueError:
        allowed = [m.value for m in AutoresetMode]
        raise ValueError(f"autoreset_mode must be one of {allowed}, got {mode!r}") from None


class AmigoBotVectorEnv(JsonSpecMixin, VectorEnv[ObsArray, NDArray[np.floating[Any]], NDArray[Any]]):
    """``N`` AmigoBot tracking tasks stepped as numpy batches (see :class:`amigo_gym.envs.AmigoBotEnv`).

    Args:
        num_envs: number of robots ``N`` >= 1.
        max_episode_steps: truncation after this many steps (``None``: never); ``gym.make_vec``
            passes the registration's 400 unless given.
        render_mode: ``None`` or ``"rgb_array"`` (``render()`` returns one frame per robot).
        autoreset_mode: ``"NextStep"`` (default), ``"SameStep"`` or ``"Disabled"``
            (:class:`gymnasium.vector.AutoresetMode`), as in ``SyncVectorEnv``.
        kernel: the step's implementation (:mod:`amigo_gym.sim.fast`): ``"auto"`` (default: the compiled
            kernel when numba is installed, unless ``AMIGO_GYM_KERNEL=numpy``; else numpy), ``"numpy"`` (the
            reference column functions of :mod:`amigo_gym.task.v0`), ``"numba"`` (the compiled kernel, the
            same results bit for bit; needs the extra ``amigo_gym[fast]``), or ``"numba-parallel"`` (the
            kernel's loops on numba's threads).
        params, robot, **settings: the task settings, exactly as for ``gym.make("AmigoBot-v0", ...)``.

    Spaces: ``single_action_space = Box(-1, 1, (2,), float32)``, ``action_space`` its batch
    ``(N, 2)``; ``single_observation_space`` as the single env's, ``observation_space`` ``(N, obs_dim)``.
    ``step`` accepts actions of shape ``(N, 2)`` (float64 applied exactly; NaN/inf or a wrong
    shape raise ``ValueError``) and returns rewards ``(N,)`` float64, terminations and truncations
    ``(N,)`` bool, and infos with the single env's keys as ``(N, ...)`` arrays plus ``_key`` masks.
    ``reset`` accepts ``seed`` (``None``, an int ``s`` for seeds ``s + i``, or a list of ``N``) and
    ``options`` with ``"pose"`` (``(3,)`` for all or ``(N, 3)``) and ``"reset_mask"`` (``(N,)`` bool).

    Rendering keeps the last ``trail_length`` (1000) positions of H per robot in a ring buffer, so memory
    stays flat however many steps are rendered. The environment pickles and deep-copies (also after
    ``render()``: the renderers are dropped and recreated when next used).
    """

    #: positions of H kept per robot for the rendered trail (a fixed-size ring buffer)
    trail_length: int = TRAIL_LENGTH

    metadata: dict[str, Any] = {  # noqa: RUF012  (gymnasium declares metadata as a plain attribute)
        "render_modes": ["rgb_array"],
        "render_fps": 10.0,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        kernel: str = "auto",
        *,
        params: EnvParams | Mapping[str, Any] | None = None,
        robot: RobotParams | Mapping[str, Any] | None = None,
        **settings: Any,
    ) -> None:
        owner = type(self).__name__
        check_vector_args(owner, num_envs, max_episode_steps, render_mode)
        self.params: EnvParams = make_env_params(owner, params, robot, **settings)
        p = self.params
        self.path: CirclePath | ManoeuvrePath = make_path(p)
        self.num_envs = int(num_envs)
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        self.render_mode = render_mode
        self.autoreset_mode = _parse_autoreset_mode(autoreset_mode)
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / p.dt, "autoreset_mode": self.autoreset_mode}

        n = self.num_envs
        self.single_action_space, self.single_observation_space = make_spaces(p)
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)

        self._k = task.task_constants(p)
        self._initial_rates = task.initial_wheel_rates(p)
        # the generators, with the addresses of their C bit generators for the kernel's draws
        self._rngs = fast.GeneratorTable([None] * n)
        self._seeds: list[int | None] = [None] * n
        # the state as (N,) columns, stepped by the same column functions as the single env; with the
        # compiled kernel, the columns are views of one (N, 8) array that the kernel updates in place
        rate1, rate2 = self._initial_rates.tolist()
        self._ws = _kernel_workspace(owner, kernel, self._k, self.path, n)
        self._parallel = kernel == "numba-parallel"
        self._rows = np.zeros((n, 8))
        self._rows[:, 6] = rate1
        self._rows[:, 7] = rate2
        if self._ws is not None:
            self._state = task.State(*(self._rows[:, j] for j in range(8)))
        else:
            z = [np.zeros(n) for _ in range(6)]
            self._state = task.State(z[0], z[1], z[2], z[3], z[4], z[5], np.full(n, rate1), np.full(n, rate2))
        self._steps = np.zeros(n, dtype=np.int64)
        self._autoreset: BoolArray = np.zeros(n, dtype=np.bool_)
        self._no_restart: BoolArray = np.zeros(n, dtype=np.bool_)  # the kernel's restart mask when none restarts
        self._no_rows: NDArray[np.intp] = np.zeros(0, dtype=np.intp)
        self._obs: ObsArray = np.zeros((n, task.obs_dim(p)), dtype=np.float32)
        self._trail: Array | None = None  # ring buffer (trail_length, N, 2), allocated when first used
        self._trail_count = 0  # positions written so far
        self._trail_start = np.zeros(n, dtype=np.int64)
        self._renderers: list[Any] = []
        self._was_reset = False

    # ------------------------------------------------------------------ seeding
    @property
    def np_random_seed(self) -> tuple[int, ...]:  # type: ignore[override]
        """Seeds of the sub-environments' generators (as ``SyncVectorEnv.np_random_seed``).

        Before the first reset, as ``Env.np_random_seed``: each generator is made from a random seed
        on first use, and that seed is reported (and used by a ``reset()`` without a seed).
        """
        for i in range(self.num_envs):
            self._rng(i)
        return tuple(int(s) for s in self._seeds if s is not None)

    @property
    def np_randoms(self) -> tuple[np.random.Generator | None, ...]:
        """The sub-environments' generators (``None`` before the first reset)."""
        return tuple(self._rngs)

    def _rng(self, i: int) -> np.random.Generator:
        g = self._rngs[i]
        if g is None:  # as Env.np_random: a random seed on first use
            g, self._seeds[i] = seeding.np_random()
            self._rngs[i] = g
        return g

    # ------------------------------------------------------------------ reset
    def reset(
        self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsArray, dict[str, Any]]:
        """Reset all robots, or those of ``options["reset_mask"]`` (see the class docstring).

        Raises:
            TypeError: a ``reset_mask`` that is not a bool numpy array (as ``SyncVectorEnv``).
            ValueError: bad seed list, unknown option, bad pose, a mask of the wrong shape or all False.
        """
        n = self.num_envs
        check_reset_options(options, extra=("reset_mask",))
        seeds = parse_seeds(seed, n)
        mask: BoolArray = np.ones(n, dtype=np.bool_)
        if options is not None and "reset_mask" in options:
            mask = check_reset_mask(options["reset_mask"], n)
        pose_opt = None
        if options is not None and "pose" in options:
            pose_opt = np.broadcast_to(parse_pose_option(options["pose"], (n,)), (n, 3))
        if not mask.all() and not self._was_reset:
            raise gym.error.ResetNeeded('reset all robots (no "reset_mask") before a partial reset')
        self._was_reset = True
        idx = np.flatnonzero(mask)
        for i in idx:
            if seeds[i] is not None:
                self._rngs[i], self._seeds[i] = seeding.np_random(seeds[i])
        self._autoreset[idx] = False
        obs, infos = self._reset_rows(idx, pose_opt)
        self._obs = self._obs.copy()  # the last step returned it
        self._obs[idx] = obs
        if self.render_mode is not None:
            self._append_trail()
        return self._obs.copy(), self._scatter(infos, mask)

    def _start_states(self, idx: NDArray[np.intp], pose_opt: Array | None = None) -> task.State:
        """Start states of the robots ``idx`` (compact columns): a drawn pose (or ``pose_opt``'s rows),
        wheel angles 0, the initial rates.

        The Python loop here is the reference of the draws that :func:`amigo_gym.sim.fast.step_rows` makes
        in the kernel for ``NEXT_STEP`` restarts (:func:`amigo_gym.sim._kernels.draw_starts`): the same
        numbers, start states and generator states afterwards (``tests/test_kernel_draws.py``).
        """
        m = len(idx)
        if pose_opt is not None:
            pose = pose_opt[idx]
        else:
            # u ~ U[-1, 1]^3 from each robot's own generator, as the single env draws it:
            # Generator.uniform(-1, 1, 3) is -1 + 2 * Generator.random(3) (the same stream and rounding)
            u = np.empty((m, 3))
            rngs = self._rngs
            for j, i in enumerate(idx.tolist()):
                g = rngs[i]
                (self._rng(i) if g is None else g).random(out=u[j])
            pose = task.start_pose(-1.0 + 2.0 * u, self.params, self.path)
        rate1, rate2 = self._initial_rates.tolist()
        zeros = np.zeros(m)
        return task.State(
            pose[:, 0].copy(),
            pose[:, 1].copy(),
            pose[:, 2].copy(),
            zeros,
            zeros,
            zeros,
            np.full(m, rate1),
            np.full(m, rate2),
        )

    def _reset_rows(self, idx: NDArray[np.intp], pose_opt: Array | None = None) -> tuple[ObsArray, dict[str, Any]]:
        """Start new episodes for the robots ``idx``; return their observations and (compact) infos."""
        state = self._start_states(idx, pose_opt)
        _set_rows(self._state, state, idx)
        self._steps[idx] = 0
        out = task.reset_columns(self._k, self.path, state, minimal=True)
        if self.render_mode is not None:
            self._trail_start[idx] = self._trail_count
        m = len(idx)
        return self._obs_array(out, m), self._info(state, out, np.zeros(m, dtype=np.int64))

    # ------------------------------------------------------------------ step
    def step(
        self, actions: NDArray[np.floating[Any]]
    ) -> tuple[ObsArray, NDArray[Any], NDArray[Any], NDArray[Any], dict[str, Any]]:
        """Step every robot; autoreset finished ones according to ``autoreset_mode``.

        Raises:
            TypeError: a scalar (not iterable) action, as ``SyncVectorEnv``.
            ValueError: actions not of shape ``(N, 2)`` or with NaN/inf entries.
            RuntimeError: in ``Disabled`` mode, stepping a robot whose episode ended (reset it first).
        """
        n = self.num_envs
        if not self._was_reset:
            raise gym.error.ResetNeeded("call reset() before step() on AmigoBotVectorEnv")
        if _is_scalar(actions):  # TypeError as SyncVectorEnv, which iterates over the actions
            kind = "a string" if isinstance(actions, str | bytes) else f"a scalar {type(actions).__name__} object"
            raise TypeError(
                f"Unable to iterate over the following elements: {actions} "
                f"(actions must be an array of shape ({n}, 2), got {kind})"
            )
        a = task.validate_action(actions, (n,))
        mode = self.autoreset_mode
        if mode == AutoresetMode.DISABLED and self._autoreset.any():
            raise RuntimeError(
                f"robots {np.flatnonzero(self._autoreset).tolist()} finished their episodes; "
                "reset them (options={'reset_mask': ...}) before stepping in Disabled autoreset mode"
            )
        if self._ws is not None:
            return self._step_kernel(self._ws, a, mode)
        k = self._k
        motion = task.move_columns(k, self._state, a[:, 0], a[:, 1])
        state = motion.state
        cos_beta, sin_beta, v = (np.asarray(c) for c in motion[1:])
        prev1, prev2 = self._state.rate1, self._state.rate2
        self._steps += 1
        idx = None
        if mode == AutoresetMode.NEXT_STEP and self._autoreset.any():
            # robots whose episode ended at the last step start a new one instead of this step: their
            # start states replace their rows and are evaluated with the others, with the inputs that
            # task.reset_columns gives them (so the same values as a separate reset)
            idx = np.flatnonzero(self._autoreset)
            start = self._start_states(idx)
            _set_rows(state, start, idx)
            begin = task.start_motion(k, start)
            cos_beta[idx] = begin.cos_beta
            sin_beta[idx] = begin.sin_beta
            v[idx] = begin.v
            prev1, prev2 = np.array(prev1), np.array(prev2)
            prev1[idx] = start.rate1
            prev2[idx] = start.rate2
            self._steps[idx] = 0
            if self.render_mode is not None:
                self._trail_start[idx] = self._trail_count
        out = task.outcome_columns(k, self.path, state, cos_beta, sin_beta, v, prev1, prev2, minimal=True)
        self._state = task.bound_heading(state)
        obs = self._obs_array(out, n)
        reward = _column(out.reward, n)
        terminated: BoolArray = np.asarray(out.terminated)
        truncated = (
            self._steps >= self.max_episode_steps if self.max_episode_steps is not None else np.zeros(n, np.bool_)
        )
        infos = self._info(state, out, self._steps)
        return self._finish_step(obs, reward, terminated, truncated, infos, idx)

    def _step_kernel(
        self, ws: fast.Workspace, a: Array, mode: AutoresetMode
    ) -> tuple[ObsArray, NDArray[Any], NDArray[Any], NDArray[Any], dict[str, Any]]:
        """:meth:`step` by the compiled kernel (:func:`amigo_gym.sim.fast.step_rows`); the same results.

        Restarting robots (``NEXT_STEP``) get their start states inside the kernel's step, drawn from
        their generators' C bit generators (:attr:`amigo_gym.sim.fast.GeneratorTable.bitgens`), when every
        generator is a ``PCG64``; otherwise from :meth:`_start_states` (the Python loop). Both give the
        numpy path's numbers and leave the generators in the same states.
        """
        n = self.num_envs
        restart = self._no_restart
        bitgens = None
        idx = None
        if mode == AutoresetMode.NEXT_STEP and self._autoreset.any():
            # as in the numpy path: the start states replace these rows, evaluated without moving
            restart = self._autoreset  # a new array at every step (_finish_step), not changed before then
            if self._rngs.drawable:
                bitgens = self._rngs.bitgens
            else:
                idx = np.flatnonzero(restart)
                _set_rows(self._state, self._start_states(idx), idx)
        obs: ObsArray = np.empty((n, ws.obs_dim), dtype=np.float32)
        reward = np.empty(n)
        terminated: BoolArray = np.empty(n, dtype=np.bool_)
        record = np.empty((n, 16))
        a = np.ascontiguousarray(a)
        # the env's own arrays, of the workspace's shapes and dtypes (validated actions): no checks per step
        report = fast.step_rows_unchecked(
            ws, self._rows, a, restart, obs, reward, terminated, record, self._parallel, bitgens
        )
        if bitgens is not None:
            idx = ws.rows[: report.drawn].copy()  # the rows restarted in the kernel (ws.rows is its scratch)
        # steps += 1, 0 for the restarted rows; truncated = steps >= max_episode_steps; time = steps * dt
        truncated: BoolArray = np.empty(n, dtype=np.bool_)
        time = np.empty(n)
        limit = -1 if self.max_episode_steps is None else self.max_episode_steps
        fast.kernels().count_steps(
            self._steps, self._no_rows if idx is None else idx, limit, self._k.dt, truncated, time
        )
        if idx is not None and self.render_mode is not None:
            self._trail_start[idx] = self._trail_count
        if report.past_limit:
            # as the numpy path: headings past the limit reduced by whole turns (task.bound_heading), in the
            # state and in the info's pose
            bounded = np.asarray(task.bound_heading(self._state).beta)
            self._rows[:, 2] = bounded
            record[:, 2] = bounded
        # the infos are views of the record, a new array at every step (the single env's keys)
        infos = {
            "pose": record[:, 0:3],
            "h_position": record[:, 3:5],
            "cross_track_error": record[:, 5],
            "wheel_rates": record[:, 6:8],
            "wheel_angles": record[:, 8:10],
            "castor_angle": record[:, 10],
            "reward_terms": {name: record[:, 11 + j] for j, name in enumerate(task.REWARD_TERMS)},
            "time": time,
        }
        return self._finish_step(obs, reward, terminated, truncated, infos, idx)

    def _finish_step(
        self,
        obs: ObsArray,
        reward: Array,
        terminated: BoolArray,
        truncated: BoolArray,
        infos: dict[str, Any],
        idx: NDArray[np.intp] | None,
    ) -> tuple[ObsArray, NDArray[Any], NDArray[Any], NDArray[Any], dict[str, Any]]:
        """Autoreset bookkeeping of a step (both implementations); ``idx`` the robots that started a new
        episode at this step instead of stepping (``NEXT_STEP``)."""
        n = self.num_envs
        mode = self.autoreset_mode
        if idx is not None:
            reward[idx] = 0.0
            terminated[idx] = False
            truncated[idx] = False
        elif mode == AutoresetMode.SAME_STEP:
            done = terminated | truncated
            if done.any():
                idx = np.flatnonzero(done)
                final_obs = np.full(n, None, dtype=object)
                for i in idx:
                    final_obs[i] = obs[i].copy()
                final_info = self._scatter(take_rows(infos, idx), done)
                obs_r, info_r = self._reset_rows(idx)
                obs[idx] = obs_r
                assign_rows(infos, info_r, idx)
                infos = {
                    "final_obs": final_obs,
                    "_final_obs": done.copy(),
                    "final_info": final_info,
                    "_final_info": done.copy(),
                    **infos,
                }
        self._autoreset = terminated | truncated
        self._obs = obs  # returned as is: reset() copies it before changing rows
        if self.render_mode is not None:
            self._append_trail()
        return obs, reward, terminated, truncated, self._scatter(infos, None)

    # ------------------------------------------------------------------ infos
    def _obs_array(self, out: task.Outcome, m: int) -> ObsArray:
        """The float32 observations ``(m, obs_dim)`` of an outcome, filled column by column."""
        obs = np.empty((m, len(out.obs)), dtype=np.float32)
        for j, col in enumerate(out.obs):
            obs[:, j] = col
        return obs

    def _info(self, state: task.State, out: task.Outcome, steps: NDArray[np.int64]) -> dict[str, Any]:
        """Compact infos (rows of the robots concerned, no masks); keys as the single env's.

        The arrays of ``out`` are new at every step and not kept, so they are handed out without a copy.
        """
        m = len(steps)
        cols = task.info_columns(state, out, steps * self._k.dt)
        return {key: _batched(kind, cols[key], m) for key, kind in task.INFO_KEYS.items()}

    def _pose(self) -> Array:
        """The poses ``(N, 3)``."""
        return pack(self._state.x, self._state.y, self._state.beta)

    def _scatter(self, infos: dict[str, Any], mask: BoolArray | None) -> dict[str, Any]:
        """Vector-format infos (:func:`scatter_infos`)."""
        return scatter_infos(infos, mask, self.num_envs)

    # ------------------------------------------------------------------ rendering
    def _append_trail(self) -> None:
        """Write the robots' H into the trail's ring buffer."""
        length = max(1, int(self.trail_length))
        if self._trail is None or self._trail.shape[0] != length:
            self._trail = np.zeros((length, self.num_envs, 2))
            self._trail_count = 0
            self._trail_start[:] = 0
        self._trail[self._trail_count % length] = h_position(self._pose(), self.params.robot)
        self._trail_count += 1

    def _trail_of(self, i: int) -> list[tuple[float, float]]:
        """H's positions of robot ``i`` since its episode started (at most ``trail_length``), oldest first."""
        return trail_of(self._trail, self._trail_start, self._trail_count, i)

    def __getstate__(self) -> dict[str, Any]:
        """Pickle and deep-copy without the renderers (pygame surfaces); they are recreated when next used.

        The generators are copied with their table, which computes the copies' addresses anew
        (:class:`amigo_gym.sim.fast.GeneratorTable`): a copy draws from its own generators only.
        """
        state = self.__dict__.copy()
        state["_renderers"] = []
        return state

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        """One ``(H, W, 3)`` uint8 frame per robot for ``render_mode="rgb_array"``; ``None`` otherwise.

        Raises:
            gymnasium.error.ResetNeeded: before the first ``reset()``.
        """
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gym.make_vec")
            return None
        if not self._was_reset:
            raise gym.error.ResetNeeded("call reset() before render() on AmigoBotVectorEnv")
        from amigo_gym.envs.rendering import Renderer

        while len(self._renderers) < self.num_envs:
            self._renderers.append(Renderer(self.params, self.path, "rgb_array"))
        frames = []
        pose = self._pose()
        st = self._state
        for i, r in enumerate(self._renderers):
            trail = self._trail_of(i)
            frames.append(
                r.draw(
                    pose[i],
                    trail,
                    wheel_angles=np.array((np.asarray(st.alpha1)[i], np.asarray(st.alpha2)[i])),
                    time=float(self._steps[i] * self.params.dt),
                )
            )
        return tuple(frames)

    def close_extras(self, **kwargs: Any) -> None:
        """Close the renderers."""
        for r in self._renderers:
            r.close()
        self._renderers = []


def check_reset_mask(mask: Any, n: int) -> BoolArray:
    """``options["reset_mask"]`` checked as ``SyncVectorEnv.reset`` checks it (same exception types and messages)."""
    if not isinstance(mask, np.ndarray):
        raise TypeError(f"`options['reset_mask']` must be a numpy array, got {type(mask)}")
    if mask.shape != (n,):
        raise ValueError(f"`options['reset_mask']` must have shape `({n},)`, got {mask.shape}")
    if mask.dtype != np.bool_:
        raise TypeError(f"`options['reset_mask']` must have `dtype=np.bool_`, got {mask.dtype}")
    if not np.any(mask):
        raise ValueError(
            f"`options['reset_mask']` must contain a boolean array with at least one True value, got reset_mask={mask}"
        )
    out: BoolArray = mask.copy()
    return out


def _is_scalar(x: Any) -> bool:
    """Whether ``x`` is not a sequence of per-robot actions (strings count as scalars)."""
    if isinstance(x, str | bytes):
        return True
    if isinstance(x, np.ndarray):
        return x.ndim == 0
    try:
        iter(x)
    except TypeError:
        return True
    return False


def _kernel_workspace(
    owner: str, kernel: str, k: task.TaskConstants, path: CirclePath | ManoeuvrePath, n: int
) -> fast.Workspace | None:
    """The kernel's workspace for ``kernel="numba"`` (or ``"auto"`` with numba), ``None`` for numpy."""
    if kernel not in ("numpy", "numba", "numba-parallel", "auto"):
        raise ValueError(f"{owner}.kernel must be 'numpy', 'numba', 'numba-parallel' or 'auto', got {kernel!r}")
    if not fast.use_fast_path(None if kernel == "auto" else kernel != "numpy"):
        return None
    return fast.workspace(k, path, n)


def _set_rows(full: task.State, rows: task.State, idx: NDArray[np.intp]) -> None:
    """Write the compact columns ``rows`` into the rows ``idx`` of the ``(N,)`` columns ``full``."""
    for f, r in zip(full, rows, strict=True):
        np.asarray(f)[idx] = r


def _batched(kind: str, value: Any, m: int) -> Any:
    """One info entry of :func:`amigo_gym.task.v0.info_columns` as ``(m, ...)`` arrays (new ones: never the state's)."""
    if kind == "columns":
        return pack(*value)
    if kind == "terms":
        return {name: _column(v, m) for name, v in value.items()}
    if isinstance(value, np.ndarray) and value.shape == (m,):
        return np.array(value, dtype=np.float64)
    return np.full(m, value, dtype=np.float64)


def _column(x: Any, m: int) -> Array:
    """``x`` as a float64 array of shape ``(m,)`` (a new one if ``x`` is not already such an array)."""
    if isinstance(x, np.ndarray) and x.shape == (m,) and x.dtype == np.float64:
        return x
    return np.full(m, x, dtype=np.float64)


def check_vector_args(owner: str, num_envs: Any, max_episode_steps: Any, render_mode: Any) -> None:
    """Refuse a bad ``num_envs`` (an integer >= 1), ``max_episode_steps`` (>= 1 or None) or ``render_mode``."""
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"{owner}.num_envs must be an integer >= 1, got {num_envs!r}")
    if max_episode_steps is not None and (
        isinstance(max_episode_steps, bool)
        or not isinstance(max_episode_steps, int | np.integer)
        or max_episode_steps < 1
    ):
        raise ValueError(f"{owner}.max_episode_steps must be an integer >= 1 or None, got {max_episode_steps!r}")
    if render_mode is not None and render_mode != "rgb_array":
        raise ValueError(f"{owner}.render_mode must be 'rgb_array' or None, got {render_mode!r}")


def parse_seeds(seed: Any, n: int) -> list[int | None]:
    """``reset(seed=...)`` of a vector env: ``None``, an int ``s >= 0`` (seeds ``s + i``) or a list/tuple of ``n``
    ints ``>= 0``/None, as ``SyncVectorEnv`` takes them (numpy integers accepted too; bools refused).

    Raises:
        TypeError: a seed of another type (a float, a string, ...), naming it and the accepted types.
        ValueError: a negative seed, or a list of the wrong length.
    """
    accepted = f"None, an int >= 0, or a list of num_envs={n} ints >= 0 / None"
    if seed is None:
        return [None] * n
    if _is_int(seed):
        if seed < 0:
            raise ValueError(f"seed must be {accepted}; got {seed!r}")
        return [int(seed) + i for i in range(n)]
    if not isinstance(seed, list | tuple):
        raise TypeError(f"seed must be {accepted}; got {show_value(seed)}")
    if len(seed) != n:
        raise ValueError(f"seed list must have length num_envs={n}, got length {len(seed)}")
    for i, s in enumerate(seed):
        if s is None:
            continue
        if not _is_int(s):
            raise TypeError(f"seed[{i}] must be an int >= 0 or None; got {show_value(s)}")
        if s < 0:
            raise ValueError(f"seed[{i}] must be an int >= 0 or None; got {s!r}")
    return [None if s is None else int(s) for s in seed]


def _is_int(x: Any) -> bool:
    """A Python or numpy integer, not a bool."""
    return isinstance(x, int | np.integer) and not isinstance(x, bool | np.bool_)


def scatter_infos(infos: dict[str, Any], mask: BoolArray | None, n: int) -> dict[str, Any]:
    """Vector-format infos of ``n`` robots: ``(n, ...)`` arrays (zeros outside ``mask``) and ``_key`` masks.

    ``mask=None`` means that ``infos`` already holds full ``(n, ...)`` rows for every robot. Shared by the
    native vector envs of AmigoBot-v0 and -v1. Every ``_key`` mask is an array of its own, as in
    ``SyncVectorEnv``'s infos (the rows of one ``(keys, n)`` array, filled at once).
    """
    masks = np.empty((_mask_count(infos), n), dtype=np.bool_)
    masks[...] = True if mask is None else mask
    return _scatter_into(infos, mask, n, iter(masks))


def _mask_count(infos: dict[str, Any]) -> int:
    """How many ``_key`` masks :func:`scatter_infos` gives ``infos`` (nested dicts included)."""
    count = 0
    for k, v in infos.items():
        if k.startswith("_") or k in ("final_obs", "final_info"):
            continue
        count += 1 + (_mask_count(v) if isinstance(v, dict) else 0)
    return count


def _scatter_into(infos: dict[str, Any], mask: BoolArray | None, n: int, masks: Iterator[BoolArray]) -> dict[str, Any]:
    """:func:`scatter_infos` with the ``_key`` masks taken from ``masks`` in order."""
    out: dict[str, Any] = {}
    for k, v in infos.items():
        if k.startswith("_") or k in ("final_obs", "final_info"):
            out[k] = v
            continue
        if isinstance(v, dict):
            out[k] = _scatter_into(v, mask, n, masks)
        elif mask is None:
            out[k] = v
        else:
            full = np.zeros((n, *v.shape[1:]), dtype=v.dtype)
            full[mask] = v
            out[k] = full
        out[f"_{k}"] = next(masks)  # a mask of its own per key
    return out


def info_row(vinfo: dict[str, Any], i: int) -> dict[str, Any]:
    """Robot ``i``'s info from vector-format infos: ``(N,)`` columns as floats (object columns as they are),
    ``(N, k)`` rows as arrays.

    The ``_key`` masks and ``final_obs``/``final_info`` are left out; nested dicts recurse.
    """
    out: dict[str, Any] = {}
    for k, v in vinfo.items():
        if k.startswith("_") or k in ("final_obs", "final_info"):
            continue
        if isinstance(v, dict):
            out[k] = info_row(v, i)
        else:
            a = np.asarray(v)
            if a.dtype == object:  # e.g. AmigoBot-v1's end_condition (str)
                out[k] = a[i]
            else:
                out[k] = float(a[i]) if a.ndim == 1 else a[i].copy()
    return out


def take_rows(infos: dict[str, Any], idx: NDArray[np.intp]) -> dict[str, Any]:
    return {k: (take_rows(v, idx) if isinstance(v, dict) else v[idx].copy()) for k, v in infos.items()}


def assign_rows(infos: dict[str, Any], rows: dict[str, Any], idx: NDArray[np.intp]) -> None:
    for k, v in rows.items():
        if isinstance(v, dict):
            assign_rows(infos[k], v, idx)
        else:
            infos[k][idx] = v


def trail_of(trail: Any, start: Any, count: int, i: int) -> list[tuple[float, float]]:
    """Robot ``i``'s rendered trail from a ring ``trail`` of shape ``(T, N, 2)`` [m] holding the last ``T`` of
    ``count`` positions written, ``start[i]`` being the count at which its episode began; oldest first.
    Shared by the v0 and v1 vector envs."""
    if trail is None:
        return []
    length = trail.shape[0]
    first = max(int(start[i]), count - length)
    rows = np.arange(first, count) % length
    return [(float(x), float(y)) for x, y in trail[rows, i].tolist()]
