"""AmigoBot-v0's reference step for the tests, on AmigoBot-v0's state columns.

The reference is the route ``gym.make("AmigoBot-v0", kernel="numpy")`` runs: AmigoBot-v1's column step with ideal
actuators (:func:`amigo_gym.task.v1.step_columns`) and its start evaluation (:func:`amigo_gym.task.v1.reset_columns`)
with v0's settings (:func:`amigo_gym.task.v1.v0_configuration`), on the nominal robot's episode:
:class:`amigo_gym.task.v1.V0Reference` (here :class:`Reference`), which holds the state as AmigoBot-v0's 8 columns
``x, y, beta, alpha1, alpha2, alpha3, rate1, rate2`` (:data:`amigo_gym.sim._kernels.STATE_FIELDS`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.params import EnvParams
from amigo_gym.task import v1 as tracking
from amigo_gym.task.v1 import V0Reference as Reference

__all__ = ["Reference", "start_pose"]

Array = NDArray[np.float64]


def start_pose(params: EnvParams, u: ArrayLike) -> Array:
    """The start pose ``(..., 3)`` ``(x_A, y_A, beta)`` of uniform draws ``u (..., 3)`` in [-1, 1]
    (:func:`amigo_gym.task.v1.start_state`: H at the path's start plus ``u[:2] * init_position_noise``, heading
    ``theta(0) + u[2] * init_heading_noise``, A ``l3`` behind H)."""
    ref = Reference(params, np.zeros(8))
    uu = np.asarray(u, dtype=np.float64)
    st = tracking.start_state(ref.k, ref.path, ref.ep, (uu[..., 0], uu[..., 1], uu[..., 2]))
    out = np.empty(uu.shape)
    out[..., 0], out[..., 1], out[..., 2] = st.x, st.y, st.beta
    return out
