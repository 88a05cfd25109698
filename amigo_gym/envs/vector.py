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

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from numpy.typing import NDArray

from amigo_gym.envs.amigobot import make_env_params, make_spaces
from amigo_gym.envs.base import (
    VECTOR_KERNELS,
    AmigoBotVectorBase,
    Array,
    BoolArray,
    ObsArray,
    StepResult,
    assign_rows,
    check_kernel,
    check_reset_mask,
    check_vector_args,
    info_row,
    parse_seeds,
    scatter_infos,
    take_rows,
)
from amigo_gym.model.kinematics import h_position, pack
from amigo_gym.model.params import EnvParams, RobotParams
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


class AmigoBotVectorEnv(AmigoBotVectorBase):
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
        check_kernel(owner, kernel, VECTOR_KERNELS)
        self.params: EnvParams = make_env_params(owner, params, robot, **settings)
        p = self.params
        self.path: CirclePath | ManoeuvrePath = make_path(p)
        n = self._init_base(num_envs, max_episode_steps, render_mode, autoreset_mode, p.dt, make_spaces(p))
        self._k = task.task_constants(p)
        self._initial_rates = task.initial_wheel_rates(p)
        # the state as (N,) columns, stepped by the same column functions as the single env; with the
        # compiled kernel, the columns are views of one (N, 8) array that the kernel updates in place
        rate1, rate2 = self._initial_rates.tolist()
        self._ws: fast.Workspace | None = None
        if fast.use_fast_path(None if kernel == "auto" else kernel != "numpy"):
            self._ws = fast.workspace(self._k, self.path, n)
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
        self._no_restart: BoolArray = np.zeros(n, dtype=np.bool_)  # the kernel's restart mask when none restarts

    # ------------------------------------------------------------------ the task's hooks (AmigoBotVectorBase)
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

    def _step(self, a: Array, mode: AutoresetMode) -> StepResult:
        """Step every robot (actions ``a`` validated, ``(N, 2)``); restart those that ended at the last step."""
        n = self.num_envs
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
        truncated = self._truncated(self._steps)
        infos = self._info(state, out, self._steps)
        return self._finish_step(obs, reward, terminated, truncated, infos, idx)

    def _step_kernel(self, ws: fast.Workspace, a: Array, mode: AutoresetMode) -> StepResult:
        """:meth:`step` by the compiled kernel (:func:`amigo_gym.sim.fast.step_rows`); the same results.

        Restarting robots (``NEXT_STEP``) get their start states inside the kernel's step, drawn from
        their generators' C bit generators (:attr:`amigo_gym.sim.fast.GeneratorTable.bitgens`), when every
        generator is a ``PCG64``; otherwise from :meth:`_start_states` (the Python loop). Both give the
        numpy path's numbers and leave the generators in the same states.
        """
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
        # the env's own arrays, of the workspace's shapes and dtypes (validated actions): no checks per step
        dt, limit = self._k.dt, self.max_episode_steps
        r = fast.step_env_rows(ws, self._rows, a, restart, bitgens, self._parallel, self._steps, idx, limit, dt)
        obs, reward, terminated, truncated, infos, idx = r
        if idx is not None and self.render_mode is not None:
            self._trail_start[idx] = self._trail_count
        return self._finish_step(obs, reward, terminated, truncated, infos, idx)

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

    def _step_counts(self) -> NDArray[np.int64]:
        return self._steps

    def _h_positions(self) -> Array:
        return h_position(self._pose(), self.params.robot)

    def _path_of(self, i: int) -> CirclePath | ManoeuvrePath:
        return self.path


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
