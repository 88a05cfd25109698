"""AmigoBot-v0's reference step for the tests, on AmigoBot-v0's state columns.

The reference is the route ``gym.make("AmigoBot-v0", kernel="numpy")`` runs: AmigoBot-v1's column step with ideal
actuators (:func:`amigo_gym.task.v1.step_columns`) and its start evaluation (:func:`amigo_gym.task.v1.reset_columns`)
with v0's settings (:func:`amigo_gym.task.v1.v0_configuration`), on the nominal robot's episode. :class:`Reference`
holds the state as AmigoBot-v0's 8 columns ``x, y, beta, alpha1, alpha2, alpha3, rate1, rate2``
(:data:`amigo_gym.sim._kernels.STATE_FIELDS`, the compiled step's rows): ``(N, 8)`` rows give ``(N,)`` columns,
one ``(8,)`` row gives Python floats (the single env's float route). The castor angle, which AmigoBot-v1's state
does not hold, is integrated as the vector env's reference route integrates it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import body_velocity_columns, castor_rate_columns
from amigo_gym.model.params import EnvParams
from amigo_gym.task import v1 as tracking

Array = NDArray[np.float64]


def nominal_episode(k: tracking.Constants) -> tracking.Episode:
    """The episode of v0's settings (the nominal robot, no randomisation; Python floats)."""
    return tracking.begin_episode(np.random.default_rng(0), k).episode


def start_pose(params: EnvParams, u: ArrayLike) -> Array:
    """The start pose ``(..., 3)`` ``(x_A, y_A, beta)`` of uniform draws ``u (..., 3)`` in [-1, 1]
    (:func:`amigo_gym.task.v1.start_state`: H at the path's start plus ``u[:2] * init_position_noise``, heading
    ``theta(0) + u[2] * init_heading_noise``, A ``l3`` behind H)."""
    k = tracking.constants(tracking.v0_configuration(params))
    uu = np.asarray(u, dtype=np.float64)
    st = tracking.start_state(k, k.params.path, nominal_episode(k), (uu[..., 0], uu[..., 1], uu[..., 2]))
    out = np.empty(uu.shape)
    out[..., 0], out[..., 1], out[..., 2] = st.x, st.y, st.beta
    return out


class Reference:
    """AmigoBot-v0's reference step (module docstring) from the state ``state``: ``(N, 8)`` rows or one ``(8,)``
    row of AmigoBot-v0's columns."""

    def __init__(self, params: EnvParams, state: ArrayLike) -> None:
        rows = np.asarray(state, dtype=np.float64)
        self.k = tracking.constants(tracking.v0_configuration(params))
        self.path = self.k.params.path
        self.dt = self.k.params.dt
        ep = nominal_episode(self.k)
        c: list[Any]
        if rows.ndim == 1:  # one robot: Python floats
            self.n = 0
            self.ep = ep
            self.ring = np.zeros((self.k.ring_length, 2))
            c = rows.tolist()
            z: Any = 0.0
            steps: Any = 0
        else:
            self.n = len(rows)
            self.ep = tracking.Episode(*(np.full(self.n, v) for v in ep))
            self.ring = np.zeros((self.n, self.k.ring_length, 2))
            c = [rows[:, j].copy() for j in range(8)]
            z = np.zeros(self.n)
            steps = np.zeros(self.n, dtype=np.int64)
        self.st = tracking.State(c[0], c[1], c[2], c[6], c[7], c[3], c[4], z, z, z, steps)
        self.castor: Any = c[5]

    def step(self, actions: ArrayLike) -> tuple[Array, Array, tracking.Outcome]:
        """One step with ``actions`` (``(N, 2)``, or ``(2,)`` for one robot, normalised): ``(state rows, record
        rows, outcome)`` (rows as :meth:`rows` and :meth:`record`)."""
        a = np.asarray(actions, dtype=np.float64)
        a1, a2 = (a[0].item(), a[1].item()) if self.n == 0 else (a[:, 0], a[:, 1])
        st, out, _ = tracking.step_columns(self.k, self.path, self.st, self.ep, self.ring, 0, a1, a2)
        self.st = st if self.n == 0 else tracking.State(*(np.asarray(col) for col in st))
        v, bdot = body_velocity_columns(self.st.w1, self.st.w2, self.k.nominal)
        self.castor = self.castor + castor_rate_columns(v, bdot, self.k.nominal) * self.dt
        return self.rows(), self.record(out), out

    def start(self) -> tuple[Array, tracking.Outcome]:
        """The evaluation of the state as a start state: ``(record rows, outcome)``."""
        out = tracking.reset_columns(self.k, self.path, self.st, self.ep, tracking.NO_NOISE)
        return self.record(out), out

    def _stack(self, cols: list[Any]) -> Array:
        if self.n == 0:
            return np.array([float(c) for c in cols])
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=np.float64), (self.n,)) for c in cols])

    def rows(self) -> Array:
        """The state as AmigoBot-v0's 8 columns: ``(N, 8)``, or ``(8,)`` for one robot."""
        s = self.st
        return self._stack([s.x, s.y, s.beta, s.alpha1, s.alpha2, self.castor, s.w1, s.w2])

    def record(self, out: tracking.Outcome) -> Array:
        """The 16 columns of the compiled step's record (:data:`amigo_gym.sim._kernels.RECORD_FIELDS`) of ``out``."""
        s = self.st
        cols: list[Any] = [s.x, s.y, s.beta, out.h_x, out.h_y, out.error, s.w1, s.w2, s.alpha1, s.alpha2, self.castor]
        return self._stack([*cols, *out.terms, out.reward])

    def obs(self, out: tracking.Outcome) -> Array:
        """The observation of ``out`` as float64 rows: ``(N, obs_dim)``, or ``(obs_dim,)`` for one robot."""
        return self._stack(list(out.obs))
