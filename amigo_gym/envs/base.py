"""What every AmigoBot environment shares, whatever its task version: the Gymnasium machinery, written once.

:class:`AmigoBotBase` (one robot) and :class:`AmigoBotVectorBase` (``N`` robots) hold the argument checks, the
reset options, seeding, the order of calls (no step before reset, the warning when a terminated episode is
stepped), autoreset in the three :class:`gymnasium.vector.AutoresetMode` modes with infos in the vector format,
the rendered trail of H, rendering and pickling. A task version supplies only what really differs, through a
few hooks: ``AmigoBot-v1``'s classes (:mod:`amigo_gym.envs.amigobot_v1`, :mod:`amigo_gym.envs.vector_v1`) over
:mod:`amigo_gym.task.v1`, of which ``AmigoBot-v0`` is a configuration (:mod:`amigo_gym.envs.amigobot`).

Hooks of the single env: ``_begin(pose) -> (obs, info)`` starts an episode (``pose``: the ``options["pose"]`` of
``reset`` or ``None``), ``_advance(a1, a2) -> (obs, reward, terminated, info)`` steps it, ``_render_state()``
gives what :meth:`amigo_gym.envs.rendering.Renderer.draw` draws. Hooks of the vector env: ``_reset_rows(idx,
pose) -> (obs, infos)`` starts the robots ``idx``, ``_step(actions, mode)`` steps them all and ends with
:meth:`AmigoBotVectorBase._finish_step`, ``_h_positions()`` gives H for the trail and ``_path_of(i)`` a robot's
path. Both infos keep the single env's keys (``info["h_position"]`` is what the trail records).

This module may import numpy, gymnasium, :mod:`amigo_gym.envs.spec`, :mod:`amigo_gym.model.params`,
:mod:`amigo_gym.task.v0` (the checks of actions and poses) and :mod:`amigo_gym.sim.fast_v1` (the kernel choices).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from numpy.typing import NDArray

from amigo_gym.envs.spec import JsonSpecMixin
from amigo_gym.model.params import HEADING_LIMIT, POSE_LIMIT, show_value
from amigo_gym.sim import fast_v1
from amigo_gym.task import v0 as task

Array = NDArray[np.float64]
ObsArray = NDArray[np.float32]
BoolArray = NDArray[np.bool_]
StepResult = tuple[ObsArray, NDArray[Any], NDArray[Any], NDArray[Any], dict[str, Any]]

#: keys accepted in ``reset(options=...)`` (the vector envs also take ``"reset_mask"``)
RESET_OPTIONS: tuple[str, ...] = ("pose",)

RENDER_MODES: tuple[str, ...] = ("human", "rgb_array")

#: points of H's trail kept for rendering (the most recent ones; memory stays flat however long the run)
TRAIL_LENGTH = 1000

#: the values of the vector envs' ``kernel`` keyword
VECTOR_KERNELS: tuple[str, ...] = (*fast_v1.KERNELS, "numba-parallel")


# ---------------------------------------------------------------------------------------------------- checks
def parse_pose_option(value: Any, batch_shape: tuple[int, ...] = ()) -> Array:
    """Validate ``options["pose"]``: ``(x_A [m], y_A [m], beta [rad])`` as finite numbers.

    The coordinates must lie within ``POSE_LIMIT`` (1e6 m) and the heading within ``HEADING_LIMIT``
    (1e6 rad) of zero, where float64 still resolves a step (:mod:`amigo_gym.model.params`).

    Args:
        value: the option's value; shape ``(3,)``, or ``batch_shape + (3,)`` when ``batch_shape`` is given.
        batch_shape: leading axes a vector environment also accepts.

    Raises:
        ValueError: not real numbers (strings, bools, complex numbers, objects), a ragged sequence, a
            wrong shape, NaN/inf, or a value out of range.
    """
    try:
        pose = task.real_array(value, 'options["pose"]').copy()
    except TypeError as exc:  # reset options are refused with ValueError, whatever is wrong
        raise ValueError(str(exc)) from None
    if pose.shape != (3,) and pose.shape != (*batch_shape, 3):
        want = "(3,)" if not batch_shape else f"(3,) or {(*batch_shape, 3)}"
        raise ValueError(f'options["pose"] must have shape {want} (x_A, y_A, beta), got shape {pose.shape}')
    if not np.all(np.isfinite(pose)):
        raise ValueError(f'options["pose"] must be finite, got {show_value(value)}')
    if np.abs(pose[..., :2]).max() > POSE_LIMIT or np.abs(pose[..., 2]).max() > HEADING_LIMIT:
        raise ValueError(
            f'options["pose"] must have x_A, y_A in [-{POSE_LIMIT:g}, {POSE_LIMIT:g}] m and beta in '
            f"[-{HEADING_LIMIT:g}, {HEADING_LIMIT:g}] rad, got {show_value(value)}"
        )
    return pose


def check_reset_options(options: Mapping[str, Any] | None, extra: tuple[str, ...] = ()) -> None:
    """Refuse unknown ``reset`` option keys (``ValueError`` naming the allowed ones)."""
    if options is None:
        return
    if not isinstance(options, Mapping):
        raise ValueError(f"options must be a dict or None, got {type(options).__name__}")
    allowed = (*RESET_OPTIONS, *extra)
    unknown = sorted(str(k) for k in options if k not in allowed)
    if unknown:
        raise ValueError(f"unknown reset option(s) {unknown}; allowed: {list(allowed)}")


def check_render_mode(render_mode: str | None) -> str | None:
    """Refuse a render mode other than ``None``, ``"human"`` and ``"rgb_array"`` (``ValueError``)."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(f"render_mode must be one of {list(RENDER_MODES)} or None, got {render_mode!r}")
    return render_mode


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


def box_spaces(bounds: tuple[Array, Array]) -> tuple[spaces.Box, spaces.Box]:
    """The action space ``Box(-1, 1, (2,), float32)`` and the observation space ``Box(low, high)`` (float32) of
    one robot, from the observation's bounds ``(low, high)``."""
    low, high = bounds
    return spaces.Box(-1.0, 1.0, (2,), np.float32), spaces.Box(
        low.astype(np.float32), high.astype(np.float32), dtype=np.float32
    )


def check_kernel(owner: str, kernel: Any, allowed: tuple[str, ...]) -> str:
    """``kernel`` if it is one of ``allowed``; else ``ValueError`` naming them."""
    if not isinstance(kernel, str) or kernel not in allowed:
        raise ValueError(f"{owner}.kernel must be {fast_v1.choices(allowed)}, got {kernel!r}")
    return kernel


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


# ---------------------------------------------------------------------------------------------------- vector infos
def scatter_infos(infos: dict[str, Any], mask: BoolArray | None, n: int) -> dict[str, Any]:
    """Vector-format infos of ``n`` robots: ``(n, ...)`` arrays (zeros outside ``mask``) and ``_key`` masks.

    ``mask=None`` means that ``infos`` already holds full ``(n, ...)`` rows for every robot. Shared by the
    native vector envs of AmigoBot-v0 and -v1. Every ``_key`` mask is an array of its own, as in
    ``SyncVectorEnv``'s infos (the rows of one ``(keys, n)`` array, filled at once, after one walk over ``infos``
    that leaves a place for each).
    """
    slots: list[tuple[dict[str, Any], str]] = []
    out = _scatter_into(infos, mask, n, slots)
    masks = np.empty((len(slots), n), dtype=np.bool_)
    masks[...] = True if mask is None else mask
    for (d, name), row in zip(slots, masks, strict=True):
        d[name] = row
    return out


#: the ``_key`` mask's name of each info key (``""``: a key passed on without a mask), memoised (a step's hot path)
_MASK_NAMES: dict[str, str] = {}


def _mask_name(k: str) -> str:
    """``"_" + k``, or ``""`` for a key that gets no mask (a mask itself, ``final_obs``, ``final_info``)."""
    name = _MASK_NAMES.get(k)
    if name is None:
        name = "" if k.startswith("_") or k in ("final_obs", "final_info") else f"_{k}"
        if len(_MASK_NAMES) < 4096:  # the envs' few keys; a bound for other callers' ones
            _MASK_NAMES[k] = name
    return name


def _scatter_into(
    infos: dict[str, Any], mask: BoolArray | None, n: int, slots: list[tuple[dict[str, Any], str]]
) -> dict[str, Any]:
    """:func:`scatter_infos` without the masks: each ``_key`` entry is a place (``None``) recorded in ``slots``, in
    the order of the masks' rows."""
    out: dict[str, Any] = {}
    for k, v in infos.items():
        name = _MASK_NAMES.get(k) or _mask_name(k)
        if not name:
            out[k] = v
            continue
        if isinstance(v, dict):
            out[k] = _scatter_into(v, mask, n, slots)
        elif mask is None:
            out[k] = v
        else:
            full = np.zeros((n, *v.shape[1:]), dtype=v.dtype)
            full[mask] = v
            out[k] = full
        out[name] = None  # a mask of its own per key, set by scatter_infos
        slots.append((out, name))
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
    """The rows ``idx`` of compact infos (copies; nested dicts recurse)."""
    return {k: (take_rows(v, idx) if isinstance(v, dict) else v[idx].copy()) for k, v in infos.items()}


def assign_rows(infos: dict[str, Any], rows: dict[str, Any], idx: NDArray[np.intp]) -> None:
    """Write the compact infos ``rows`` into the rows ``idx`` of ``infos`` (nested dicts recurse)."""
    for k, v in rows.items():
        if isinstance(v, dict):
            assign_rows(infos[k], v, idx)
        else:
            infos[k][idx] = v


# ---------------------------------------------------------------------------------------------------- single env
class AmigoBotBase(JsonSpecMixin, gym.Env[ObsArray, NDArray[np.floating[Any]]]):
    """One robot: the Gymnasium machinery of every task version (module docstring); a version sets
    ``params`` and ``path`` and implements ``_begin``, ``_advance`` and ``_render_state``."""

    metadata: dict[str, Any] = {"render_modes": list(RENDER_MODES), "render_fps": 10.0}  # noqa: RUF012

    #: points of H kept for the rendered trail (the most recent ones)
    trail_length: int = TRAIL_LENGTH

    params: Any
    path: Any

    def _init_base(self, render_mode: str | None, dt: float, spaces: tuple[spaces.Space[Any], ...]) -> None:
        """The shared state: render mode (checked), ``render_fps = 1 / dt``, spaces, trail, order of calls."""
        self.render_mode = check_render_mode(render_mode)
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / dt}
        self.action_space, self.observation_space = spaces
        self._trail: deque[tuple[float, float]] = deque(maxlen=self.trail_length)
        self._renderer: Any = None
        # order of calls (Gymnasium's classic-control convention): no step before reset; a warning
        # when a terminated episode is stepped
        self._needs_reset = True
        self._ended: bool | None = False  # None: terminated and warned

    def _begin(self, pose: Array | None) -> tuple[ObsArray, dict[str, Any]]:
        raise NotImplementedError

    def _advance(self, a1: float, a2: float) -> tuple[ObsArray, SupportsFloat, bool, dict[str, Any]]:
        raise NotImplementedError

    def _render_state(self) -> dict[str, Any]:
        """The keywords of :meth:`amigo_gym.envs.rendering.Renderer.draw` besides the trail (``pose`` included)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ gym API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsArray, dict[str, Any]]:
        """Start an episode (see the class docstring, *Starting State*).

        Args:
            seed: seeds ``self.np_random`` (as every Gymnasium env).
            options: ``None`` or ``{"pose": (x_A, y_A, beta)}`` for an exact start pose.

        Raises:
            ValueError: unknown option key or a bad pose.
        """
        check_reset_options(options)  # refuse bad options before touching the state or the generator
        pose = parse_pose_option(options["pose"]) if options is not None and "pose" in options else None
        super().reset(seed=seed)
        obs, info = self._begin(pose)
        self._needs_reset = False
        self._ended = False
        self._trail.clear()
        hx, hy = info["h_position"].tolist()
        self._trail.append((hx, hy))
        if self.render_mode == "human":
            self.render()
        return obs, info

    def step(self, action: NDArray[np.floating[Any]]) -> tuple[ObsArray, SupportsFloat, bool, bool, dict[str, Any]]:
        """Hold the wheel-rate commands ``clip(action, -1, 1) * w_max`` for ``dt`` and report the new state.

        Raises:
            gymnasium.error.ResetNeeded: before the first ``reset()``.
            TypeError: an action that is not real numbers (:func:`amigo_gym.task.v0.validate_action`).
            ValueError: action of a wrong shape or with NaN/inf entries.

        Stepping a terminated episode warns once per episode, as Gymnasium's classic-control
        environments do, and goes on integrating. (Truncation belongs to the ``TimeLimit`` wrapper of
        ``gym.make``, outside this environment; the vector environment truncates itself and autoresets,
        or refuses to step a finished robot in ``Disabled`` mode.)
        """
        if self._needs_reset:
            raise gym.error.ResetNeeded(f"{type(self).__name__}: call reset() before step()")
        a1, a2 = task.action_pair(action)
        if self._ended:
            gym.logger.warn(
                f"{type(self).__name__}: step() called after the episode was terminated (the environment has already "
                "returned terminated = True); call reset() to start a new one (the steps go on integrating, outside "
                "the task)"
            )
            self._ended = None  # warned: once per episode
        obs, reward, terminated, info = self._advance(a1, a2)
        if self.render_mode is not None:
            hx, hy = info["h_position"].tolist()
            self._trail.append((hx, hy))
            if self.render_mode == "human":
                self.render()
        if terminated and self._ended is False:
            self._ended = True
        return obs, reward, terminated, False, info

    # ------------------------------------------------------------------ rendering
    def render(self) -> NDArray[np.uint8] | None:
        """Draw the robot to scale, the path and H's trail (see :mod:`amigo_gym.envs.rendering`).

        Returns:
            ``(H, W, 3)`` uint8 frame for ``render_mode="rgb_array"``; ``None`` otherwise.
        """
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; pass render_mode='rgb_array' or 'human' to gym.make"
            )
            return None
        if self._needs_reset:
            raise gym.error.ResetNeeded(f"{type(self).__name__}: call reset() before render()")
        from amigo_gym.envs.rendering import Renderer

        if self._renderer is None or self._renderer.path is not self.path:  # a new episode may have a new path
            if self._renderer is not None:
                self._renderer.close()
            self._renderer = Renderer(self.params, self.path, self.render_mode)
        frame: NDArray[np.uint8] | None = self._renderer.draw(trail=self._trail, **self._render_state())
        return frame

    def close(self) -> None:
        """Close the render window, if any."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __getstate__(self) -> dict[str, Any]:
        """Pickle and deep-copy without the renderer (pygame surfaces); it is recreated when next used."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        return state


# ---------------------------------------------------------------------------------------------------- vector env
class AmigoBotVectorBase(JsonSpecMixin, VectorEnv[ObsArray, NDArray[np.floating[Any]], NDArray[Any]]):
    """``N`` robots: the Gymnasium machinery of every task version's native vector env (module docstring); a
    version sets ``params``, ``_state`` (columns with fields ``x``, ``y``, ``beta``, ``alpha1``, ``alpha2``) and
    implements ``_reset_rows``, ``_step``, ``_step_counts``, ``_h_positions`` and ``_path_of``."""

    #: positions of H kept per robot for the rendered trail (a fixed-size ring buffer)
    trail_length: int = TRAIL_LENGTH

    metadata: dict[str, Any] = {  # noqa: RUF012  (gymnasium declares metadata as a plain attribute)
        "render_modes": ["rgb_array"],
        "render_fps": 10.0,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    params: Any
    _state: Any

    def _init_base(
        self,
        num_envs: int,
        max_episode_steps: int | None,
        render_mode: str | None,
        autoreset_mode: str | AutoresetMode,
        dt: float,
        single_spaces: tuple[spaces.Space[Any], spaces.Space[Any]],
    ) -> int:
        """The shared state (arguments checked before by :func:`check_vector_args`); returns ``N``."""
        n = self.num_envs = int(num_envs)
        self.max_episode_steps = None if max_episode_steps is None else int(max_episode_steps)
        self.render_mode = render_mode
        try:
            self.autoreset_mode = AutoresetMode(autoreset_mode)
        except ValueError:
            allowed = [m.value for m in AutoresetMode]
            raise ValueError(f"autoreset_mode must be one of {allowed}, got {autoreset_mode!r}") from None
        self.metadata = {**type(self).metadata, "render_fps": 1.0 / dt, "autoreset_mode": self.autoreset_mode}
        self.single_action_space, self.single_observation_space = single_spaces
        self.action_space = batch_space(self.single_action_space, n)
        self.observation_space = batch_space(self.single_observation_space, n)
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._seeds: list[int | None] = [None] * n
        self._autoreset: BoolArray = np.zeros(n, dtype=np.bool_)
        obs_dim = self.single_observation_space.shape[0]  # type: ignore[index]
        self._obs: ObsArray = np.zeros((n, obs_dim), dtype=np.float32)
        # the rendered trail of H: a ring (trail_length, N, 2), allocated when first written (render_mode set)
        self._trail: Array | None = None
        self._trail_count = 0  # positions written so far
        self._trail_start = np.zeros(n, dtype=np.int64)  # the count at which each robot's episode started
        self._renderers: list[Any] = [None] * n
        self._was_reset = False
        return n

    # the hooks (module docstring): new episodes for the robots idx (observations (m, D), compact infos); a step;
    # steps taken (N,); each robot's H (N, 2) [m]; robot i's path; amend the compact infos of the robots idx that
    # restarted within a step; amend the final_info of a SAME_STEP autoreset
    def _reset_rows(self, idx: NDArray[np.intp], pose_opt: Array | None = None) -> tuple[ObsArray, dict[str, Any]]:
        raise NotImplementedError

    def _step(self, a: Array, mode: AutoresetMode) -> StepResult:
        raise NotImplementedError

    def _step_counts(self) -> NDArray[np.int64]:
        raise NotImplementedError

    def _h_positions(self) -> Array:
        raise NotImplementedError

    def _path_of(self, i: int) -> Any:
        raise NotImplementedError

    def _mark_restarted(self, infos: dict[str, Any], idx: NDArray[np.intp]) -> None:
        raise NotImplementedError

    def _mark_final(self, final_info: dict[str, Any], done: BoolArray) -> None:
        raise NotImplementedError

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

    # ------------------------------------------------------------------ reset and step
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
        for i in idx.tolist():
            if seeds[i] is not None:
                self._rngs[i], self._seeds[i] = seeding.np_random(seeds[i])
        self._autoreset[idx] = False
        obs, infos = self._reset_rows(idx, pose_opt)
        self._obs = self._obs.copy()  # the last step returned it
        self._obs[idx] = obs
        if self.render_mode is not None:
            self._append_trail()
        return self._obs.copy(), scatter_infos(infos, mask, self.num_envs)

    def step(self, actions: NDArray[np.floating[Any]]) -> StepResult:
        """Step every robot; autoreset finished ones according to ``autoreset_mode``.

        Raises:
            TypeError: a scalar (not iterable) action, as ``SyncVectorEnv``; actions that are not real numbers.
            ValueError: actions not of shape ``(N, 2)`` or with NaN/inf entries.
            RuntimeError: in ``Disabled`` mode, stepping a robot whose episode ended (reset it first).
        """
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
        return self._step(a, mode)

    def _finish_step(
        self,
        obs: ObsArray,
        reward: Array,
        terminated: BoolArray,
        truncated: BoolArray,
        infos: dict[str, Any],
        idx: NDArray[np.intp] | None,
    ) -> StepResult:
        """Autoreset bookkeeping of a step (every implementation); ``idx`` the robots that started a new
        episode at this step instead of stepping (``NEXT_STEP``), their infos already those of the start."""
        n = self.num_envs
        if idx is not None:
            reward[idx] = 0.0
            terminated[idx] = False
            truncated[idx] = False
            self._mark_restarted(infos, idx)
        elif self.autoreset_mode == AutoresetMode.SAME_STEP:
            done = terminated | truncated
            if np.count_nonzero(done):
                idx = np.flatnonzero(done)
                final_obs = np.full(n, None, dtype=object)
                for i in idx.tolist():
                    final_obs[i] = obs[i].copy()
                final_info = scatter_infos(take_rows(infos, idx), done, n)
                self._mark_final(final_info, done)
                obs_r, info_r = self._reset_rows(idx)
                obs[idx] = obs_r
                assign_rows(infos, info_r, idx)
                self._mark_restarted(infos, idx)
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
        return obs, reward, terminated, truncated, scatter_infos(infos, None, n)

    def _truncated(self, steps: NDArray[np.int64]) -> BoolArray:
        """``steps >= max_episode_steps`` (all False without a limit)."""
        if self.max_episode_steps is None:
            return np.zeros(self.num_envs, dtype=np.bool_)
        out: BoolArray = steps >= self.max_episode_steps
        return out

    # ------------------------------------------------------------------ rendering
    def _append_trail(self) -> None:
        """Write the robots' H (:meth:`_h_positions`) into the trail's ring buffer."""
        length = max(1, int(self.trail_length))
        if self._trail is None or self._trail.shape[0] != length:
            self._trail = np.zeros((length, self.num_envs, 2))
            self._trail_count = 0
            self._trail_start[:] = 0
        self._trail[self._trail_count % length] = self._h_positions()
        self._trail_count += 1

    def _trail_of(self, i: int) -> list[tuple[float, float]]:
        """H's positions of robot ``i`` since its episode started (at most ``trail_length``), oldest first."""
        if self._trail is None:
            return []
        length = self._trail.shape[0]
        rows = np.arange(max(int(self._trail_start[i]), self._trail_count - length), self._trail_count) % length
        return [(float(x), float(y)) for x, y in self._trail[rows, i].tolist()]

    def render(self) -> tuple[NDArray[np.uint8], ...] | None:
        """One ``(H, W, 3)`` uint8 frame per robot for ``render_mode="rgb_array"``; ``None`` otherwise.

        Raises:
            gymnasium.error.ResetNeeded: before the first ``reset()``.
        """
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode='rgb_array' to gym.make_vec")
            return None
        if not self._was_reset:
            raise gym.error.ResetNeeded(f"call reset() before render() on {type(self).__name__}")
        from amigo_gym.envs.rendering import Renderer

        st = self._state
        x, y, beta, alpha1, alpha2 = (np.asarray(c) for c in (st.x, st.y, st.beta, st.alpha1, st.alpha2))
        steps = self._step_counts()
        frames = []
        for i in range(self.num_envs):
            path = self._path_of(i)
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
        """Pickle and deep-copy without the renderers (pygame surfaces); they are recreated when next used."""
        state = self.__dict__.copy()
        state["_renderers"] = [None] * self.num_envs
        return state
