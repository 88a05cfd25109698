"""What the AmigoBot environments share: the checks of their arguments, reset options and seeds, their spaces,
and the vector format of infos (:func:`scatter_infos`, :func:`info_row`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from amigo_gym.model.params import HEADING_LIMIT, POSE_LIMIT, show_value
from amigo_gym.sim import fast_v1
from amigo_gym.task import v0 as task

Array = NDArray[np.float64]
ObsArray = NDArray[np.float32]
BoolArray = NDArray[np.bool_]
StepResult = tuple[ObsArray, NDArray[Any], NDArray[Any], NDArray[Any], dict[str, Any]]

RENDER_MODES: tuple[str, ...] = ("human", "rgb_array")

#: points of H's trail kept for rendering (the most recent ones)
TRAIL_LENGTH = 1000

#: the values of the vector envs' ``kernel`` keyword
VECTOR_KERNELS: tuple[str, ...] = (*fast_v1.KERNELS, "numba-parallel")


def parse_pose_option(value: Any, batch_shape: tuple[int, ...] = ()) -> Array:
    """``options["pose"]``, ``(x_A [m], y_A [m], beta [rad])`` of shape ``(3,)`` or ``batch_shape + (3,)``, checked
    finite, ``|x_A|, |y_A| <= POSE_LIMIT`` (1e6 m), ``|beta| <= HEADING_LIMIT`` (1e6 rad); else ``ValueError``."""
    try:
        pose = task.real_array(value, 'options["pose"]').copy()
    except TypeError as exc:  # reset options are refused with ValueError
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
    """Refuse ``reset`` option keys other than ``"pose"`` and ``extra`` (``ValueError`` naming the allowed ones)."""
    if options is None:
        return
    if not isinstance(options, Mapping):
        raise ValueError(f"options must be a dict or None, got {type(options).__name__}")
    allowed = ("pose", *extra)
    if unknown := sorted(str(k) for k in options if k not in allowed):
        raise ValueError(f"unknown reset option(s) {unknown}; allowed: {list(allowed)}")


def check_vector_args(owner: str, num_envs: Any, max_episode_steps: Any, render_mode: Any) -> None:
    """Refuse a bad ``num_envs`` (an integer >= 1), ``max_episode_steps`` (>= 1 or None) or ``render_mode``."""
    if not _is_int(num_envs) or num_envs < 1:
        raise ValueError(f"{owner}.num_envs must be an integer >= 1, got {num_envs!r}")
    if max_episode_steps is not None and (not _is_int(max_episode_steps) or max_episode_steps < 1):
        raise ValueError(f"{owner}.max_episode_steps must be an integer >= 1 or None, got {max_episode_steps!r}")
    if render_mode is not None and render_mode != "rgb_array":
        raise ValueError(f"{owner}.render_mode must be 'rgb_array' or None, got {render_mode!r}")


def box_spaces(bounds: tuple[Array, Array]) -> tuple[spaces.Box, spaces.Box]:
    """The action space ``Box(-1, 1, (2,), float32)`` and the observation space ``Box(low, high)`` (float32) of
    one robot, from the observation's bounds ``(low, high)``."""
    low, high = (b.astype(np.float32) for b in bounds)
    return spaces.Box(-1.0, 1.0, (2,), np.float32), spaces.Box(low, high, dtype=np.float32)


def check_reset_mask(mask: Any, n: int) -> BoolArray:
    """``options["reset_mask"]`` checked as ``SyncVectorEnv.reset`` checks it (same exceptions and messages)."""
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
    return mask.copy()


def parse_seeds(seed: Any, n: int) -> list[int | None]:
    """``reset(seed=...)`` of a vector env as ``SyncVectorEnv`` takes it: ``None``, an int ``s >= 0`` (seeds
    ``s + i``) or a list/tuple of ``n`` ints ``>= 0`` or None. ``TypeError`` for another type, ``ValueError`` for a
    negative seed or a list of the wrong length."""
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
    return isinstance(x, int | np.integer) and not isinstance(x, bool | np.bool_)


def scatter_infos(infos: dict[str, Any], mask: BoolArray | None, n: int) -> dict[str, Any]:
    """Vector-format infos of ``n`` robots: ``(n, ...)`` arrays (zeros outside ``mask``; ``mask=None``: ``infos``
    holds full rows already) and a ``_key`` mask array of its own per key, as in ``SyncVectorEnv``."""
    slots: list[tuple[dict[str, Any], str]] = []
    out = _scatter_into(infos, None if mask is None else np.flatnonzero(mask), n, slots)
    masks = np.empty((len(slots), n), dtype=np.bool_)
    masks[...] = True if mask is None else mask
    for (d, name), row in zip(slots, masks, strict=True):
        d[name] = row
    return out


#: the ``_key`` mask's name of each info key (``""``: no mask), memoised
_MASK_NAMES: dict[str, str] = {}


def _scatter_into(
    infos: dict[str, Any], rows: NDArray[np.intp] | None, n: int, slots: list[tuple[dict[str, Any], str]]
) -> dict[str, Any]:
    # scatter_infos without the masks (rows: the mask's indices, 5x faster to assign than the mask); each _key entry
    # is a place recorded in slots
    out: dict[str, Any] = {}
    for k, v in infos.items():
        name = _MASK_NAMES.get(k)
        if name is None:
            name = "" if k.startswith("_") or k in ("final_obs", "final_info") else f"_{k}"
            if len(_MASK_NAMES) < 4096:
                _MASK_NAMES[k] = name
        if not name:
            out[k] = v
            continue
        if isinstance(v, dict):
            out[k] = _scatter_into(v, rows, n, slots)
        elif rows is None:
            out[k] = v
        else:
            full = np.zeros((n, *v.shape[1:]), dtype=v.dtype)
            full[rows] = v
            out[k] = full
        out[name] = None
        slots.append((out, name))
    return out


def info_row(vinfo: dict[str, Any], i: int) -> dict[str, Any]:
    """Robot ``i``'s info from vector-format infos: ``(N,)`` columns as floats (object columns as they are),
    ``(N, k)`` rows as arrays; without the ``_key`` masks and ``final_obs``/``final_info``."""
    out: dict[str, Any] = {}
    for k, v in vinfo.items():
        if k.startswith("_") or k in ("final_obs", "final_info"):
            continue
        if isinstance(v, dict):
            out[k] = info_row(v, i)
        elif (a := np.asarray(v)).dtype == object:
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
