r"""The analytic inverse solution as a state-feedback policy for ``AmigoBot-v0``.

The policy reads only the observation, by the field names of :func:`amigo_gym.task.v0.obs_names` (never
by raw positions), and the constant task settings :class:`~amigo_gym.model.params.EnvParams`. It takes

* ``e = cross_track_error * error_scale``: signed cross-track error of H [m], positive left of the path;
* ``psi = atan2(sin_heading_error, cos_heading_error)``: heading error ``beta - theta`` [rad];
* ``kappa = curvature / l3``: signed path curvature at H's closest point [1/m];
* ``v_ref = reference_speed * max_speed``: reference speed of A [m/s].

Velocity of H in the path frame
-------------------------------
With ``t = (cos theta, sin theta)`` the path tangent and ``n = (-sin theta, cos theta)`` the left
normal at H's closest point, H = A + l3 (cos beta, sin beta) moves with

.. math::
    \begin{pmatrix} \dot H \cdot t \\ \dot H \cdot n \end{pmatrix}
    = \begin{pmatrix} \cos\psi & -l_3 \sin\psi \\ \sin\psi & l_3\cos\psi \end{pmatrix}
      \begin{pmatrix} v_A \\ \dot\beta \end{pmatrix},
    \qquad \det = l_3 \ne 0,

and the cross-track error obeys ``edot = Hdot . n`` (for the circle exactly; for any smooth path at
the closest point). The map is invertible everywhere, which is why the look-ahead point H (rather
than A) can be steered directly.

Control law (``speed_reference="A"``, the default)
--------------------------------------------------
The paper's inverse problem prescribes the speed of A, ``v_A = v_ref`` (eqs 11-12), and asks H to
stay on the path. Asking instead for ``Hdot . n = -k e`` (first-order decay of the error) and
solving the second row of the map for the turn rate gives

.. math::
    v_A = v_{ref}, \qquad
    \dot\beta = \frac{-k\,e - v_{ref}\sin\psi}{l_3\cos\psi}.

With ``k = 0`` (``feedforward_only=True``) this is exactly the paper's inverse ODE (docs/model.md)
``betadot = v_A tan(theta - beta) / l3`` evaluated on the measured heading error, i.e. the open-loop
inverse solution run in closed loop: it keeps ``Hdot . n = 0``, so H keeps whatever offset it
starts with, while the heading converges to the steady lag (rate ``v_A / l3``). The feedback term
adds the exponential decay ``e(t) = e0 exp(-k t)`` in continuous time.

Alternative (``speed_reference="H"``): the look-ahead law with a constant tangential speed of H,
the steady value ``v_ref R / R_A = v_ref / cos(delta_ss)`` with ``sin(delta_ss) = kappa l3``:

.. math::
    \begin{pmatrix} v_A \\ \dot\beta \end{pmatrix}
    = \begin{pmatrix} \cos\psi & \sin\psi \\ -\sin\psi / l_3 & \cos\psi / l_3 \end{pmatrix}
      \begin{pmatrix} v_{ref}/\cos\delta_{ss} \\ -k\,e \end{pmatrix}.

Both laws have the same steady state on a circle of radius ``R``: ``e = 0``, ``psi = -delta_ss``,
``v_A = v_ref``, ``betadot = v_ref / R_A`` (:func:`amigo_gym.model.kinematics.circle_steady_state`); they
differ only in transients (the "A" law never changes the speed of A, which the reward's speed term
asks for, and needs no curvature: the path enters through ``psi``).

Wheel rates follow from the rolling relations (:func:`amigo_gym.model.kinematics.wheel_rates`)
``r1 w1 = v_A + l1 betadot``, ``r2 w2 = v_A - l1 betadot``, and the action is
``clip(w / max_wheel_rate, -1, 1)``.

Discrete time and the gain
--------------------------
The environment holds the command over ``dt`` (0.1 s). Started on the steady state, the held
command is the exact steady arc, so H stays on the circle to rounding. Away from it, the error
decays roughly like ``(1 - k dt)^n`` while ``k dt`` is small; the zero-order hold adds an error of
order ``dt`` (the closed loop tends to ``e0 exp(-k t)`` as ``dt -> 0``, tested). The heading mode
(rate ``v_A / l3`` = 2.5 1/s) bounds the achievable rate: measured halving times of the error on
the env's perturbed starts over t in [1, 4] s are 0.71, 0.41, 0.33, 0.30 s for k = 1, 2, 3, 5 1/s
(``docs/baselines.md``). The default ``k = 3 1/s`` gets most of the speed without overshoot and
keeps the commands of the env's perturbed starts far from the wheel-rate limit.

Singularity: the law divides by ``cos psi``, like the paper's ODE (singular at ``|psi| = pi/2``). The
denominator is floored at ``cos_min`` (0.2) so that commands stay finite when the robot faces
across the path; the clipped action then turns the robot at the largest rate the wheels allow.
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import wheel_rates
from amigo_gym.model.params import EnvParams, check_range
from amigo_gym.task.v0 import obs_dim, obs_index

__all__ = ["DEFAULT_GAIN", "AnalyticPolicy", "analytic_body_velocity", "analytic_wheel_rates"]

Array = NDArray[np.float64]

#: default feedback gain k [1/s] on H's cross-track error
DEFAULT_GAIN = 3.0
#: floor of cos(psi) in the denominators [-]
COS_MIN = 0.2

SpeedReference = Literal["A", "H"]


def _check_obs(obs: ArrayLike, params: EnvParams) -> Array:
    o = np.asarray(obs, dtype=np.float64)
    n = obs_dim(params)
    if o.ndim not in (1, 2) or o.shape[-1] != n:
        raise ValueError(f"obs must have shape ({n},) or (N, {n}) for these EnvParams, got {o.shape}")
    if not np.all(np.isfinite(o)):
        raise ValueError("obs must be finite; got NaN or infinite values")
    return o


def analytic_body_velocity(
    obs: ArrayLike,
    params: EnvParams,
    gain: float = DEFAULT_GAIN,
    speed_reference: SpeedReference = "A",
) -> tuple[Array, Array]:
    r"""Commanded ``(v_A [m/s], betadot [rad/s])`` of the analytic law (module docstring) from observations.

    ``speed_reference="A"``: ``v_A = v_ref``, ``betadot = (-k e - v_ref sin psi) / (l3 cos psi)``.
    ``speed_reference="H"``: ``(v_A, betadot) = M(psi)^{-1} (v_ref / cos delta_ss, -k e)`` with
    ``sin delta_ss = kappa l3``. ``cos psi`` is floored at ``COS_MIN``.

    Args:
        obs: observations ``(obs_dim,)`` or ``(N, obs_dim)`` (layout of :mod:`amigo_gym.task.v0`).
        params: the task settings the observations were made with.
        gain: feedback gain ``k`` >= 0 [1/s]; 0 gives the paper's inverse ODE.
        speed_reference: ``"A"`` or ``"H"`` (module docstring).

    Returns:
        ``(v_A, betadot)``, each of shape ``()`` or ``(N,)``.
    """
    o = _check_obs(obs, params)
    i = obs_index(params)
    robot = params.robot
    l3 = robot.l3
    e = o[..., i["cross_track_error"]] * params.error_scale
    psi = np.arctan2(o[..., i["sin_heading_error"]], o[..., i["cos_heading_error"]])
    s, c = np.sin(psi), np.maximum(np.cos(psi), COS_MIN)
    v_ref = o[..., i["reference_speed"]] * robot.max_speed
    u_n = -gain * e
    if speed_reference == "A":
        return v_ref, (u_n - v_ref * s) / (l3 * c)
    if speed_reference == "H":
        kl3 = np.clip(o[..., i["curvature"]], -1.0 + 1e-9, 1.0 - 1e-9)
        u_t = v_ref / np.sqrt(1.0 - kl3 * kl3)
        return c * u_t + s * u_n, (-s * u_t + c * u_n) / l3
    raise ValueError(f"speed_reference must be 'A' or 'H', got {speed_reference!r}")


def analytic_wheel_rates(
    obs: ArrayLike,
    params: EnvParams,
    gain: float = DEFAULT_GAIN,
    speed_reference: SpeedReference = "A",
) -> Array:
    """Wheel rates ``(..., 2)`` [rad/s] of the analytic law, unclipped (``r1 w1 = v_A + l1 betadot``, ...)."""
    v, bd = analytic_body_velocity(obs, params, gain, speed_reference)
    return wheel_rates(v, bd, params.robot)


class AnalyticPolicy:
    """The analytic inverse solution with look-ahead feedback, with an SB3-like ``predict``.

    Args:
        params: task settings (geometry, ``error_scale``, ``preview`` for the observation length).
        gain: feedback gain ``k`` on H's cross-track error [1/s], in [0, 1/dt]; default 3.
        feedforward_only: use ``k = 0``: the paper's inverse ODE in closed loop (no error feedback).
        speed_reference: ``"A"`` (``v_A = v_ref``, default) or ``"H"`` (constant tangential speed of H).
    """

    def __init__(
        self,
        params: EnvParams,
        gain: float = DEFAULT_GAIN,
        feedforward_only: bool = False,
        speed_reference: SpeedReference = "A",
    ) -> None:
        if not isinstance(params, EnvParams):
            raise ValueError(f"AnalyticPolicy.params must be an EnvParams, got {type(params).__name__}")
        self.params = params
        self.gain = 0.0 if feedforward_only else check_range("AnalyticPolicy", "gain", gain, 0.0, 1.0 / params.dt)
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
        w = self.wheel_rates(obs)
        return np.clip(w / self.params.robot.max_wheel_rate, -1.0, 1.0).astype(np.float32)

    def predict(
        self,
        observation: ArrayLike,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.float32], None]:
        """SB3-style prediction: ``(action, None)`` for one observation or a batch (the policy is stateless)."""
        return self.action(observation), None

    def __repr__(self) -> str:
        return (
            f"AnalyticPolicy(gain={self.gain:g}, feedforward_only={self.feedforward_only}, "
            f"speed_reference={self.speed_reference!r})"
        )


def steady_lag(params: EnvParams) -> float:
    """Steady heading error ``psi_ss = -asin(kappa l3)`` on the task's circle [rad] (``-delta_ss``)."""
    return -params.direction * math.asin(params.robot.l3 / params.radius)
