"""AmigoBot-v0's reference step for the tests, on AmigoBot-v0's state columns.

The reference is the route ``gym.make("AmigoBot-v0", kernel="numpy")`` runs: AmigoBot-v1's column step with ideal
actuators (:func:`amigo_gym.task.v1.step_columns`) and its start evaluation (:func:`amigo_gym.task.v1.reset_columns`)
with v0's settings (:meth:`amigo_gym.task.v1.TrackingParams.v0`), on the nominal robot's episode:
:class:`Reference`, which holds the state as AmigoBot-v0's 8 columns
``x, y, beta, alpha1, alpha2, alpha3, rate1, rate2``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import body_velocity_columns, castor_rate_columns
from amigo_gym.task import v1 as tracking
from amigo_gym.task.v1 import (
    NO_NOISE,
    Episode,
    Outcome,
    State,
    TrackingParams,
    begin_episode,
    constants,
    reset_columns,
    step_columns,
)

__all__ = ["Reference", "start_pose"]

Array = NDArray[np.float64]


class Reference:
    """AmigoBot-v0's reference step, what ``gym.make("AmigoBot-v0", kernel="numpy")`` runs: :func:`step_columns` (and
    :func:`reset_columns` for a start state) with AmigoBot-v0's settings ``params`` on the nominal robot's episode.

    The state is AmigoBot-v0's 8 columns ``x, y, beta, alpha1, alpha2, alpha3, rate1, rate2`` [m, m, rad, rad, rad, rad,
    rad/s, rad/s] : ``(N, 8)`` rows give
    ``(N,)`` columns (``n = N``), one ``(8,)`` row Python floats (``n = 0``, the single env's float route). The castor
    angle ``alpha3``, which :class:`State` (``st``) does not hold, is integrated as the vector env's reference route
    does: ``alpha3 += castor_rate(v_A, betadot) dt`` [rad] with the new wheel rates (``castor``;
    :func:`~amigo_gym.model.kinematics.castor_rate`). ``k``, ``path``, ``dt`` [s], ``ep``: v0's constants, path, step
    and episode; ``ring``: the (unread) command ring.
    """

    def __init__(self, params: TrackingParams, state: Any) -> None:
        rows = np.asarray(state, dtype=np.float64)
        self.k = k = constants(params)
        self.path, self.dt, self.n = k.params.path, k.params.dt, 0 if rows.ndim == 1 else len(rows)
        ep = begin_episode(np.random.default_rng(0), k).episode  # v0's settings draw nothing that matters
        self.ep = ep if self.n == 0 else Episode(*(np.full(self.n, v) for v in ep))
        self.ring = np.zeros((*rows.shape[:-1], k.ring_length, 2))
        c: list[Any] = rows.tolist() if self.n == 0 else [rows[:, j].copy() for j in range(8)]
        z: Any = 0.0 if self.n == 0 else np.zeros(self.n)
        steps: Any = 0 if self.n == 0 else np.zeros(self.n, dtype=np.int64)
        self.st = State(c[0], c[1], c[2], c[6], c[7], c[3], c[4], z, z, z, steps)
        self.castor: Any = c[5]

    def step(self, actions: Any) -> tuple[NDArray[np.float64], NDArray[np.float64], Outcome]:
        """One step with the normalised ``actions`` ``(N, 2)`` (``(2,)`` for one robot), the state advanced:
        ``(state rows, record rows, outcome)`` (:meth:`rows`, :meth:`record`)."""
        a = np.asarray(actions, dtype=np.float64)
        a1, a2 = (a[0].item(), a[1].item()) if self.n == 0 else (a[:, 0], a[:, 1])
        st, out, _ = step_columns(self.k, self.path, self.st, self.ep, self.ring, 0, a1, a2)
        self.st = st if self.n == 0 else State(*(np.asarray(col) for col in st))
        v, bdot = body_velocity_columns(self.st.w1, self.st.w2, self.k.nominal)
        self.castor = self.castor + castor_rate_columns(v, bdot, self.k.nominal) * self.dt
        return self.rows(), self.record(out), out

    def start(self) -> tuple[NDArray[np.float64], Outcome]:
        """The evaluation of the state as a start state: ``(record rows, outcome)``."""
        out = reset_columns(self.k, self.path, self.st, self.ep, NO_NOISE)
        return self.record(out), out

    def _stack(self, cols: list[Any]) -> NDArray[np.float64]:
        if self.n == 0:
            return np.array([float(c) for c in cols])
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=np.float64), (self.n,)) for c in cols])

    def rows(self) -> NDArray[np.float64]:
        """The state as AmigoBot-v0's 8 columns: ``(N, 8)``, or ``(8,)`` for one robot."""
        s = self.st
        return self._stack([s.x, s.y, s.beta, s.alpha1, s.alpha2, self.castor, s.w1, s.w2])

    def record(self, out: Outcome) -> NDArray[np.float64]:
        """The 16 columns ``x, y, beta, h_x, h_y, e, rate1, rate2, alpha1, alpha2, alpha3``, the 4 terms, the reward:
        ``(N, 16)``, or ``(16,)`` for one robot."""
        s = self.st
        cols: list[Any] = [s.x, s.y, s.beta, out.h_x, out.h_y, out.error, s.w1, s.w2, s.alpha1, s.alpha2, self.castor]
        return self._stack([*cols, *out.terms, out.reward])

    def obs(self, out: Outcome) -> NDArray[np.float64]:
        """The observation of ``out`` as float64 rows: ``(N, obs_dim)``, or ``(obs_dim,)`` for one robot."""
        return self._stack(list(out.obs))


def start_pose(params: TrackingParams, u: ArrayLike) -> Array:
    """The start pose ``(..., 3)`` ``(x_A, y_A, beta)`` of uniform draws ``u (..., 3)`` in [-1, 1]
    (:func:`amigo_gym.task.v1.start_state`: H at the path's start plus ``u[:2] * init_position_noise``, heading
    ``theta(0) + u[2] * init_heading_noise``, A ``l3`` behind H)."""
    ref = Reference(params, np.zeros(8))
    uu = np.asarray(u, dtype=np.float64)
    st = tracking.start_state(ref.k, ref.path, ref.ep, (uu[..., 0], uu[..., 1], uu[..., 2]))
    out = np.empty(uu.shape)
    out[..., 0], out[..., 1], out[..., 2] = st.x, st.y, st.beta
    return out
