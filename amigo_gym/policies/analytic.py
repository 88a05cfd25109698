r"""The analytic inverse solution as a state-feedback policy: the law of both envs, and ``AmigoBot-v0``'s policy.

From either env's observation (by field name): ``e = cross_track_error * error_scale`` [m] (positive left),
``psi = atan2(sin_heading_error, cos_heading_error)`` [rad], ``kappa = curvature / l3`` [1/m], ``v_ref =
reference_speed * max_speed`` [m/s]. H = A + l3 (cos beta, sin beta) moves along the path's tangent and normal as

.. math::
    \begin{pmatrix} \dot H \cdot t \\ \dot H \cdot n \end{pmatrix}
    = \begin{pmatrix} \cos\psi & -l_3 \sin\psi \\ \sin\psi & l_3\cos\psi \end{pmatrix}
      \begin{pmatrix} v_A \\ \dot\beta \end{pmatrix},

``speed_reference="A"`` (default, the paper's eqs 11-12; ``k = 0``: its inverse ODE in closed loop) imposes
``v_A = v_ref`` and ``edot = -k e``: :math:`\dot\beta = (-k e - v_{ref}\sin\psi) / (l_3\cos\psi)`.
``speed_reference="H"`` imposes ``(v_A, betadot) = M(psi)^{-1} (v_ref / cos delta_ss, -k e)``, ``sin delta_ss =
kappa l3``. The wheel rates ``r1 w1 = v_A + l1 betadot``, ``r2 w2 = v_A - l1 betadot``, the action ``clip(w /
max_wheel_rate, -1, 1)``; ``cos psi`` floored at :data:`COS_MIN`."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import wheel_rates
from amigo_gym.model.params import check_real
from amigo_gym.policies.base import Fields, Policy
from amigo_gym.task.v1 import TrackingParams

Array = NDArray[np.float64]

#: default feedback gain k [1/s] on H's cross-track error
DEFAULT_GAIN = 3.0
#: floor of cos(psi) in the denominators [-]
COS_MIN = 0.2

SpeedReference = Literal["A", "H"]


def analytic_tracking_command(
    e: ArrayLike,
    sin_psi: ArrayLike,
    cos_psi: ArrayLike,
    kappa: ArrayLike,
    v_ref: ArrayLike,
    c: ArrayLike,
    l3: float,
    dt: float,
    feedforward: bool = True,
) -> tuple[Array, Array]:
    r"""``(v [m/s], omega [rad/s])``, columns ``(N,)``, of the analytic law for H's normal speed ``c`` [m/s]:

    .. math::
        \dot s = \frac{v - c\sin\psi}{\cos\psi}, \quad \omega_0 = \frac{c - v\sin\psi}{l_3\cos\psi}, \quad
        \omega = \omega_0 - \frac{\dot s}{l_3\cos\psi}\Bigl(\omega_0 - \frac{\kappa\dot s}{1 - \kappa e}\Bigr)
        \frac{dt}{2}\ \text{(feedforward)},

    with ``v = v_ref``, ``cos psi`` floored at :data:`COS_MIN` and ``1 - kappa e`` at 0.5."""
    e_a, sp, v, c_a = (np.asarray(a, dtype=np.float64) for a in (e, sin_psi, v_ref, c))
    cp = np.maximum(np.asarray(cos_psi, dtype=np.float64), COS_MIN)
    omega = (c_a - v * sp) / (l3 * cp)
    if feedforward:
        sdot = (v - c_a * sp) / cp
        k = np.asarray(kappa, dtype=np.float64)
        psidot = omega - k * sdot / np.maximum(1.0 - k * e_a, 0.5)
        omega = omega - sdot / (l3 * cp) * psidot * (0.5 * dt)
    return v + 0.0 * omega, omega


def _body_velocity(f: Fields, o: Array, gain: float, speed_reference: str) -> tuple[Array, Array]:
    p, l3 = f.params, f.robot.l3
    e = f(o, "cross_track_error") * p.error_scale
    psi = np.arctan2(f(o, "sin_heading_error"), f(o, "cos_heading_error"))
    v_ref = f(o, "reference_speed") * f.robot.max_speed
    if speed_reference == "A":
        return analytic_tracking_command(e, np.sin(psi), np.cos(psi), 0.0, v_ref, -gain * e, l3, p.dt, False)
    if speed_reference == "H":
        s, c = np.sin(psi), np.maximum(np.cos(psi), COS_MIN)
        u_n = -gain * e
        kl3 = np.clip(f(o, "curvature"), -1.0 + 1e-9, 1.0 - 1e-9)
        u_t = v_ref / np.sqrt(1.0 - kl3 * kl3)
        return c * u_t + s * u_n, (-s * u_t + c * u_n) / l3
    raise ValueError(f"speed_reference must be 'A' or 'H', got {speed_reference!r}")


def analytic_body_velocity(
    obs: ArrayLike, params: TrackingParams, gain: float = DEFAULT_GAIN, speed_reference: SpeedReference = "A"
) -> tuple[Array, Array]:
    """Commanded ``(v_A [m/s], betadot [rad/s])``, each ``()`` or ``(N,)``, of the law (module docstring) with gain
    ``k`` [1/s] >= 0 for observations ``(d,)`` or ``(N, d)`` made with ``params`` (v0's or v1's)."""
    f = Fields("analytic_body_velocity", params)
    o, single = f.check(obs)
    v, bd = _body_velocity(f, o, gain, speed_reference)
    return (v[0], bd[0]) if single else (v, bd)


def analytic_wheel_rates(
    obs: ArrayLike, params: TrackingParams, gain: float = DEFAULT_GAIN, speed_reference: SpeedReference = "A"
) -> Array:
    """Wheel rates ``(..., 2)`` [rad/s] of the analytic law, unclipped (``r1 w1 = v_A + l1 betadot``, ...)."""
    v, bd = analytic_body_velocity(obs, params, gain, speed_reference)
    return wheel_rates(v, bd, params.robot)


class AnalyticPolicy(Policy):
    """The analytic law (module docstring) for AmigoBot-v0's or v1's ``TrackingParams``, gain ``k`` [1/s] in [0, 1/dt]
    (``feedforward_only``: ``k = 0``); ``predict`` is stateless."""

    def __init__(
        self,
        params: TrackingParams,
        gain: float = DEFAULT_GAIN,
        feedforward_only: bool = False,
        speed_reference: SpeedReference = "A",
    ) -> None:
        self._fields, self.params = Fields("AnalyticPolicy", params), params
        self.gain = 0.0 if feedforward_only else check_real("AnalyticPolicy", "gain", gain, 0.0, 1.0 / params.dt)
        self.feedforward_only = bool(feedforward_only)
        if speed_reference not in ("A", "H"):
            raise ValueError(f"AnalyticPolicy.speed_reference must be 'A' or 'H', got {speed_reference!r}")
        self.speed_reference: SpeedReference = speed_reference

    @property
    def name(self) -> str:
        """Short label: ``analytic`` or ``analytic_ff``."""
        return "analytic_ff" if self.feedforward_only else "analytic"

    def wheel_rates(self, obs: ArrayLike) -> Array:
        """Unclipped commanded wheel rates ``(..., 2)`` [rad/s] for observations ``(..., obs_dim)``."""
        return analytic_wheel_rates(obs, self.params, self.gain, self.speed_reference)

    def action(self, obs: ArrayLike) -> NDArray[np.float32]:
        """Normalised action ``clip(w / max_wheel_rate, -1, 1)``, float32, shape ``(2,)`` or ``(N, 2)``."""
        return self.predict(obs)[0]

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, None]:
        v, bd = _body_velocity(self._fields, obs, self.gain, self.speed_reference)
        return np.clip(wheel_rates(v, bd, self.params.robot) / self.params.robot.max_wheel_rate, -1.0, 1.0), None

    def __repr__(self) -> str:
        return (
            f"AnalyticPolicy(gain={self.gain:g}, feedforward_only={self.feedforward_only}, "
            f"speed_reference={self.speed_reference!r})"
        )
