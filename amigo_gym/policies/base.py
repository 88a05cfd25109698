"""What every policy shares: the observation adapter :class:`Fields` and SB3's ``predict`` (:class:`Policy`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.task.v1 import TrackingParams, obs_fields

Array = NDArray[np.float64]


class Fields:
    """The observation layout of ``params`` (a ``TrackingParams``: AmigoBot-v0's layout or v1's; ``v1_only``: v1's),
    read by field name; ``owner`` (the policy's name) starts every error message."""

    def __init__(self, owner: str, params: Any, v1_only: bool = False) -> None:
        if not isinstance(params, TrackingParams) or (v1_only and params.observation != "v1"):
            want = "TrackingParams with observation='v1'" if v1_only else "TrackingParams"
            got = f"observation={params.observation!r}" if isinstance(params, TrackingParams) else type(params).__name__
            raise ValueError(f"{owner}.params must be {want}, got {got}")
        self.owner, self.params, self.robot = owner, params, params.robot
        self.names = obs_fields(params)
        self.dim = len(self.names)
        self.index = {n: i for i, n in enumerate(self.names)}

    def check(self, obs: ArrayLike) -> tuple[Array, bool]:
        """Observations as float64 ``(N, dim)`` (shape and finiteness checked) and whether one ``(dim,)`` was given."""
        o = np.asarray(obs, dtype=np.float64)
        if o.ndim not in (1, 2) or o.shape[-1] != self.dim:
            raise ValueError(
                f"{self.owner}: observation must have shape ({self.dim},) or (N, {self.dim}), got {o.shape}"
            )
        if not np.all(np.isfinite(o)):
            raise ValueError(f"{self.owner}: observation must be finite; got NaN or infinite values")
        single = o.ndim == 1
        return (o[None, :] if single else o), single

    def __call__(self, o: Array, name: str) -> Array:
        """The column ``name`` of observations ``(N, dim)``, ``(N,)``."""
        return o[:, self.index[name]]


class Policy:
    """SB3's ``predict`` over :meth:`_act`, with a per-row recurrent state; ``self._fields`` is set by the subclass."""

    _fields: Fields
    _state: Array | None = None

    def reset(self) -> None:
        """Forget the internal state (used when ``predict`` gets no ``state``)."""
        self._state = None

    def _rows(self, n: int, state: Any, episode_start: Any, width: int) -> tuple[Array, NDArray[np.bool_]]:
        """The state ``(n, width)`` (a copy of ``state``, or the internal state: zeros when new or resized) and the
        rows that start an episode: ``episode_start`` (a scalar is broadcast), None: every row of a new or all-zero
        state."""
        if state is None:
            if fresh := self._state is None or self._state.shape[0] != n:
                self._state = np.zeros((n, width))
            assert self._state is not None
            s = self._state
        else:
            s = np.asarray(state, dtype=np.float64)
            if s.size != n * width:
                raise ValueError(f"{self._fields.owner}: state must have shape ({n}, {width}), got {s.shape}")
            s, fresh = s.reshape(n, width).copy(), not np.any(s)
        if episode_start is None:
            return s, np.full(n, fresh)
        return s, np.broadcast_to(np.asarray(episode_start, dtype=bool).reshape(-1), (n,)).copy()

    def _keep(self, state: Any, new: Array) -> Array:
        """``new`` as the internal state if ``predict`` got no ``state``; a copy of it (what ``predict`` returns)."""
        if state is None:
            self._state = new
        return new.copy()

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, Any]:
        """``(actions (N, 2) in [-1, 1], new state)`` for checked observations ``(N, d)``."""
        raise NotImplementedError

    def predict(
        self, observation: ArrayLike, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[NDArray[np.float32], Any]:
        """SB3-style ``(actions, state)``: actions ``(2,)`` or ``(N, 2)`` float32 in [-1, 1] for observations ``(d,)``
        or ``(N, d)``; ``state`` ``(N, k)`` or None (the internal state); ``episode_start``: rows to reset;
        ``deterministic``: the mean action (the classical controllers ignore it)."""
        o, single = self._fields.check(observation)
        act, new_state = self._act(o, state, episode_start, deterministic)
        a32 = np.asarray(act).astype(np.float32)
        return (a32[0] if single else a32), new_state
