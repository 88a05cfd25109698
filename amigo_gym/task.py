r"""The tracking task as pure, batched functions: actions, observation, reward, start, end.

Both :class:`amigo_gym.envs.AmigoBotEnv` and :class:`amigo_gym.envs.AmigoBotVectorEnv` (and the
agents) call these functions; nothing here keeps state. Shapes: a leading batch axis is optional
everywhere, ``pose (..., 3)``, ``rates (..., 2)``, ``action (..., 2)``, ``obs (..., obs_dim)``.

Observation (all dimensionless, ``psi = wrap(beta - theta)`` is the heading error against the path
tangent ``theta`` at H's closest point, ``e`` H's signed cross-track error, positive left):

====  ==============================  ==========================================
idx   component                       bounds
====  ==============================  ==========================================
0     ``e / error_scale``             +-2 termination_distance / error_scale (clipped)
1     ``sin(psi)``                    [-1, 1]
2     ``cos(psi)``                    [-1, 1]
3     ``kappa(s_H) l3``               [-1, 1]  (curvature at H's closest point)
4..   ``kappa(s_H + d_i) l3``         [-1, 1]  (one per ``preview`` distance d_i)
-4    ``alpha1dot / w_max``           [-1, 1]  (applied rate of wheel 1, right)
-3    ``alpha2dot / w_max``           [-1, 1]  (applied rate of wheel 2, left)
-2    ``(v_A - v_ref) / v_max``       [-2, 2]
-1    ``v_ref / v_max``               [0, 1]
====  ==============================  ==========================================

Reward: the product of four named terms, each in [0, 1], so the reward lies in [0, 1] per step:

.. math::
    r = \underbrace{e^{-|e|/\sigma_e}}_{\text{track}}
        \cdot \underbrace{e^{-|v_A - v_{ref}|/\sigma_v}}_{\text{speed}}
        \cdot \underbrace{\tfrac{1}{2}\left(1 + \cos(\psi - \psi_{ss})\right)}_{\text{heading}}
        \cdot \underbrace{\left(1 - w_s\left(1 - e^{-(\|\Delta a\|/\sigma_a)^2}\right)\right)}_{\text{smooth}}

with ``psi_ss = -asin(kappa l3)`` the steady heading error of the exact inverse solution on the
local curvature and ``Delta a`` the change of the normalised wheel-rate command. A product (rather
than a sum) makes every term necessary: standing still or spinning in place loses the speed term,
driving the path the wrong way loses the heading term, leaving the path loses the tracking term.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.kinematics import body_velocity, h_position, step_pose, step_wheel_angles
from amigo_gym.params import EnvParams
from amigo_gym.paths import CirclePath, ManoeuvrePath, Projection, wrap_angle

__all__ = [
    "REWARD_TERMS",
    "obs_dim",
    "obs_bounds",
    "obs_names",
    "validate_action",
    "action_to_wheel_rates",
    "initial_wheel_rates",
    "start_pose",
    "heading_error",
    "observe",
    "reward_terms",
    "combine_reward",
    "Evaluation",
    "evaluate",
    "Transition",
    "transition",
]

Array = NDArray[np.float64]
AnyPath = CirclePath | ManoeuvrePath

REWARD_TERMS: tuple[str, ...] = ("track", "speed", "heading", "smooth")


def obs_dim(params: EnvParams) -> int:
    """Length of the observation vector: ``8 + len(params.preview)``."""
    return 8 + len(params.preview)


def obs_names(params: EnvParams) -> list[str]:
    """Names of the observation components, in order."""
    return (
        ["cross_track_error", "sin_heading_error", "cos_heading_error", "curvature"]
        + [f"curvature_ahead_{d:g}m" for d in params.preview]
        + ["wheel_rate_1", "wheel_rate_2", "speed_error", "reference_speed"]
    )


def obs_bounds(params: EnvParams) -> tuple[Array, Array]:
    """Finite ``(low, high)`` bounds of the observation (see the module table)."""
    e_max = 2.0 * params.termination_distance / params.error_scale
    high = np.array([e_max, 1.0, 1.0] + [1.0] * (1 + len(params.preview)) + [1.0, 1.0, 2.0, 1.0])
    low = -high
    low[-1] = 0.0
    return low, high


def validate_action(action: ArrayLike, batch_shape: tuple[int, ...] = ()) -> Array:
    """Check a normalised action: shape ``batch_shape + (2,)`` and all values finite.

    Raises:
        ValueError: on a wrong shape, or on NaN or infinite entries (never silently clipped).
    """
    a = np.asarray(action, dtype=np.float64)
    want = (*batch_shape, 2)
    if a.shape != want:
        raise ValueError(f"action must have shape {want} (wheel 1, wheel 2), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"action must be finite; got NaN or infinite values: {np.asarray(action)!r}")
    return a


def action_to_wheel_rates(action: ArrayLike, params: EnvParams) -> Array:
    """Applied wheel rates [rad/s] from a normalised action: ``clip(a, -1, 1) * w_max``.

    ``w_max = robot.max_wheel_rate`` (15 rad/s: 0.75 m/s over a 0.05 m wheel). Values outside
    [-1, 1] are clipped; call :func:`validate_action` first to refuse NaN and infinities.
    """
    return np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0) * params.robot.max_wheel_rate


def initial_wheel_rates(params: EnvParams) -> Array:
    """Wheel rates at the start: rolling straight at the reference speed, ``(v/r1, v/r2)`` [rad/s]."""
    return np.array([params.speed / params.robot.r1, params.speed / params.robot.r2])


def start_pose(u: ArrayLike, params: EnvParams, path: AnyPath) -> Array:
    """Start pose from uniform draws ``u`` in [-1, 1], shape ``(..., 3)``.

    H starts at the path's start point (arc length 0) shifted by ``u[..., :2] *
    init_position_noise`` [m] per axis, with heading ``theta(0) + u[..., 2] * init_heading_noise``;
    A is placed ``l3`` behind H. ``u = 0`` gives the paper's start: H at the origin, ``beta = 0``.

    Returns:
        pose ``(..., 3)`` as ``(x_A, y_A, beta)``.
    """
    u = np.asarray(u, dtype=np.float64)
    p0 = path.point(0.0)
    beta = path.tangent_angle(0.0) + u[..., 2] * params.init_heading_noise
    hx = p0[0] + u[..., 0] * params.init_position_noise
    hy = p0[1] + u[..., 1] * params.init_position_noise
    l3 = params.robot.l3
    return np.stack((hx - l3 * np.cos(beta), hy - l3 * np.sin(beta), beta), axis=-1)


def heading_error(pose: ArrayLike, proj: Projection) -> Array:
    """``psi = wrap(beta - theta)`` [rad], the heading minus the path tangent at H's closest point."""
    return wrap_angle(np.asarray(pose, dtype=np.float64)[..., 2] - proj.tangent_angle)


def observe(pose: ArrayLike, rates: ArrayLike, params: EnvParams, path: AnyPath, proj: Projection) -> Array:
    """Observation ``(..., obs_dim)`` (float64; the environments cast to float32), module table.

    Args:
        pose: ``(..., 3)`` robot pose.
        rates: ``(..., 2)`` applied wheel rates [rad/s].
        params: task settings.
        path: the path of H.
        proj: ``path.project(h_position(pose))``, passed in so that it is computed once.
    """
    robot = params.robot
    pose = np.asarray(pose, dtype=np.float64)
    rates = np.asarray(rates, dtype=np.float64)
    psi = heading_error(pose, proj)
    v, _ = body_velocity(rates, robot)
    e_max = 2.0 * params.termination_distance / params.error_scale  # obs_bounds(params)[1][0]
    # filled column by column (the leading axes of pose and rates broadcast): no stacking copies
    out = np.empty((*np.broadcast_shapes(np.shape(psi), np.shape(v)), 8 + len(params.preview)))
    out[..., 0] = np.clip(proj.cross_track_error / params.error_scale, -e_max, e_max)
    out[..., 1] = np.sin(psi)
    out[..., 2] = np.cos(psi)
    out[..., 3] = proj.curvature * robot.l3
    for i, d in enumerate(params.preview):
        out[..., 4 + i] = path.curvature(proj.s + d) * robot.l3
    wmax = robot.max_wheel_rate
    out[..., -4] = rates[..., 0] / wmax
    out[..., -3] = rates[..., 1] / wmax
    out[..., -2] = (v - params.speed) / robot.max_speed
    out[..., -1] = params.speed / robot.max_speed
    return out


def reward_terms(
    pose: ArrayLike, rates: ArrayLike, prev_rates: ArrayLike, params: EnvParams, proj: Projection
) -> dict[str, Array]:
    """The named reward terms, each in [0, 1] with shape ``(...)`` (formula in the module docstring).

    Args:
        pose: pose after the step ``(..., 3)``.
        rates: wheel rates applied during the step ``(..., 2)`` [rad/s].
        prev_rates: wheel rates of the step before ``(..., 2)`` [rad/s].
        params: task settings.
        proj: projection of H (after the step) onto the path.
    """
    robot = params.robot
    rates = np.asarray(rates, dtype=np.float64)
    v, _ = body_velocity(rates, robot)
    psi = heading_error(pose, proj)
    psi_ss = -np.arcsin(np.clip(proj.curvature * robot.l3, -1.0, 1.0))
    da = np.linalg.norm((rates - np.asarray(prev_rates, dtype=np.float64)) / robot.max_wheel_rate, axis=-1)
    return {
        "track": np.exp(-np.abs(proj.cross_track_error) / params.sigma_track),
        "speed": np.exp(-np.abs(v - params.speed) / params.sigma_speed),
        "heading": 0.5 * (1.0 + np.cos(psi - psi_ss)),
        "smooth": 1.0 - params.smooth_weight * (1.0 - np.exp(-((da / params.sigma_smooth) ** 2))),
    }


def combine_reward(terms: dict[str, Array]) -> Array:
    """The reward: the product of the named terms, in [0, 1]."""
    out = np.ones_like(terms[REWARD_TERMS[0]])
    for k in REWARD_TERMS:
        out = out * terms[k]
    return out


class Evaluation(NamedTuple):
    """Everything the environment reports about a state (leading axes as the pose)."""

    obs: Array
    projection: Projection
    h: Array
    terminated: NDArray[np.bool_]


def evaluate(pose: ArrayLike, rates: ArrayLike, params: EnvParams, path: AnyPath) -> Evaluation:
    """Observation, projection of H, H itself and the termination flag of a state.

    Terminated when ``|e| > termination_distance``.
    """
    h = h_position(pose, params.robot)
    proj = path.project(h)
    obs = observe(pose, rates, params, path, proj)
    return Evaluation(obs, proj, h, np.abs(proj.cross_track_error) > params.termination_distance)


class Transition(NamedTuple):
    """Result of :func:`transition` (leading axes as the inputs)."""

    pose: Array
    wheel_angles: Array
    rates: Array
    reward: Array
    terms: dict[str, Array]
    evaluation: Evaluation


def transition(
    pose: ArrayLike,
    wheel_angles: ArrayLike,
    prev_rates: ArrayLike,
    action: ArrayLike,
    params: EnvParams,
    path: AnyPath,
) -> Transition:
    """One environment step: clip and scale the action, step exactly, observe and reward.

    The action must already be validated (:func:`validate_action`). The pose and the wheel angles
    advance by the closed-form solution for rates held over ``params.dt`` (no Euler step).
    """
    rates = action_to_wheel_rates(action, params)
    new_pose = step_pose(pose, rates, params.dt, params.robot)
    angles = step_wheel_angles(wheel_angles, rates, params.dt, params.robot)
    ev = evaluate(new_pose, rates, params, path)
    terms = reward_terms(new_pose, rates, prev_rates, params, ev.projection)
    return Transition(new_pose, angles, rates, combine_reward(terms), terms, ev)


def max_return(n_steps: int) -> float:
    """Largest possible return of ``n_steps`` steps (each term at most 1)."""
    return float(n_steps)
