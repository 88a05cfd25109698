r"""The tracking task as pure, batched functions (no state): actions, observation, reward, start, end.

Shapes: a leading batch axis is optional, ``pose (..., 3)``, ``rates (..., 2)``, ``action (..., 2)``,
``obs (..., obs_dim)``. Observation and reward: AmigoBot-v0's env card (docs/env_card.md), ``e`` H's signed
cross-track error (positive left), ``psi = wrap(beta - theta)`` the heading error against the path tangent at H,
``psi_ss = -asin(kappa l3)`` the steady one. Without angles: ``cos(psi) = u . t``, ``sin(psi) = t x u`` of the unit
heading ``u`` and tangent ``t``, ``(||Delta a|| / sigma_a)^2 = (Delta w_1^2 + Delta w_2^2) / (w_max sigma_a)^2``.
The contracts readers use: the field names (:func:`obs_names`) and the info's keys (:data:`INFO_KEYS`).
"""

from __future__ import annotations

import math
import numbers
import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import Real, circle_steady_state, col_sqrt
from amigo_gym.model.numeric import clip
from amigo_gym.model.params import HEADING_LIMIT, MIN_SPEED, RobotParams, check_real, show_value
from amigo_gym.paths import CirclePath, ManoeuvrePath

Array = NDArray[np.float64]

REWARD_TERMS: tuple[str, ...] = ("track", "speed", "heading", "smooth")
TWO_PI = 2.0 * math.pi

#: the observation's fields before the preview (named in :func:`obs_names`)
OBS_HEAD: tuple[str, ...] = ("cross_track_error", "sin_heading_error", "cos_heading_error", "curvature")
#: the observation's fields after the preview
OBS_TAIL: tuple[str, ...] = ("wheel_rate_1", "wheel_rate_2", "speed_error", "reference_speed")

#: the info dict's keys (every ``reset`` and ``step`` of both environments), and what each holds:
#: ``"columns"`` a float64 vector of columns, ``"scalar"`` one float, ``"terms"`` a dict of the reward terms
INFO_KEYS: dict[str, str] = {
    "pose": "columns",
    "h_position": "columns",
    "cross_track_error": "scalar",
    "wheel_rates": "columns",
    "wheel_angles": "columns",
    "castor_angle": "scalar",
    "reward_terms": "terms",
    "time": "scalar",
}


#: AmigoBot-v0's settings: every keyword of ``gym.make("AmigoBot-v0", ...)`` and its default (:func:`check_v0`)
V0_DEFAULTS: dict[str, Any] = {
    "robot": RobotParams(),
    "dt": 0.1,
    "radius": 1.0,
    "speed": 0.2,
    "direction": 1,
    "path": "circle",
    "straight_length": 1.0,
    "termination_distance": 0.25,
    "init_position_noise": 0.02,
    "init_heading_noise": 0.1,
    "error_scale": 0.05,
    "preview": (0.2, 0.4),
    "sigma_track": 0.02,
    "sigma_speed": 0.05,
    "sigma_smooth": 0.1,
    "smooth_weight": 0.2,
}


def check_v0(**settings: Any) -> dict[str, Any]:
    """The keywords of :class:`~amigo_gym.task.v1.TrackingParams` of AmigoBot-v0's settings (:data:`V0_DEFAULTS`
    where not given; ``path`` a :class:`~amigo_gym.paths.CirclePath` or :class:`~amigo_gym.paths.ManoeuvrePath`),
    with the checks ``TrackingParams`` does not make (it checks the rest, in v0's ranges).

    ``robot`` a :class:`~amigo_gym.model.params.RobotParams`; ``dt`` in [1e-6, 2] s; ``radius`` of the circle H
    follows in (robot.l3, 1e3] m; ``speed`` of A in [1e-6, robot.max_speed] m/s; ``direction`` +1 (left, eq. 6) or
    -1; ``path`` ``"circle"`` (through the origin, tangent to x0) or ``"manoeuvre"`` (``straight_length`` in
    [0, 1e3] m along x0, then the circle); ``termination_distance`` in [1e-3, 10] m; ``init_position_noise`` in
    [0, termination_distance / 2] m per axis; ``init_heading_noise`` in [0, pi/4] rad; ``error_scale`` in
    [1e-6, 10] m; each ``preview`` distance in [0, 10] m; ``sigma_track`` [m], ``sigma_speed`` [m/s],
    ``sigma_smooth`` in [1e-6, 1e6]; ``smooth_weight`` in [0, 1). Drivable: the straight roll (``speed / r``) and
    the steady state (:func:`~amigo_gym.model.kinematics.circle_steady_state`) within ``robot.max_wheel_rate``.
    ``TypeError`` for an unknown setting; a one-line ``ValueError`` names ``TrackingParams.v0.<setting>``, the range
    and the value, or the wheel rate a task needs and the limit.
    """
    o = "TrackingParams.v0"
    unknown = sorted(set(settings) - set(V0_DEFAULTS))
    if unknown:
        raise TypeError(f"{o} got unexpected keyword argument(s) {unknown}; allowed: {', '.join(V0_DEFAULTS)}")
    s = {**V0_DEFAULTS, **settings}
    robot = s["robot"]
    if not isinstance(robot, RobotParams):
        raise ValueError(f"{o}.robot must be a RobotParams, got {show_value(robot)}")
    s["speed"] = check_real(o, "speed", s["speed"], MIN_SPEED, robot.max_speed)
    s["radius"] = check_real(o, "radius", s["radius"], robot.l3, 1e3, low_open=True)
    s["straight_length"] = check_real(o, "straight_length", s["straight_length"], 0.0, 1e3)
    s["termination_distance"] = check_real(o, "termination_distance", s["termination_distance"], 1e-3, 10.0)
    d = s["direction"]
    if isinstance(d, bool) or not isinstance(d, numbers.Integral) or d not in (1, -1):
        raise ValueError(f"{o}.direction must be +1 (left turn) or -1 (right), got {show_value(d)}")
    s["direction"] = d = int(d)
    if not isinstance(s["path"], str) or s["path"] not in ("circle", "manoeuvre"):
        raise ValueError(f"{o}.path must be 'circle' or 'manoeuvre', got {show_value(s['path'])}")
    # drivable: the straight roll at the start, the exact steady state on the circle; the rates are linear in the
    # speed, so at most speed * w_max / need fits
    v, radius = s["speed"], s["radius"]
    w_max = robot.max_wheel_rate
    limit = f"the limit {w_max:.3g} rad/s (robot.max_speed / max(r1, r2))"
    r_min = min(robot.r1, robot.r2)
    need = v / r_min
    if need > w_max:
        raise ValueError(
            f"{o}: speed {v:g} m/s rolling straight needs {need:.3g} rad/s on the smaller wheel "
            f"(r = {r_min:g} m), over {limit}; at most {v * w_max / need:.3g} m/s fits"
        )
    rates = circle_steady_state(radius, v, robot, d).wheel_rates.tolist()
    need = max(abs(rates[0]), abs(rates[1]))
    if not need <= w_max:
        raise ValueError(
            f"{o}: speed {v:g} m/s on a {radius:g} m circle needs {need:.3g} rad/s on the outer "
            f"wheel, over {limit}; at most {v * w_max / need:.3g} m/s fits this circle"
        )
    straight = s.pop("straight_length")
    s["path"] = CirclePath(radius, direction=d) if s["path"] == "circle" else ManoeuvrePath(radius, straight, d)
    return s


def obs_names(params: Any) -> list[str]:
    """Names of the observation components of AmigoBot-v0's settings ``params`` (a ``TrackingParams``), in order (the
    module table): the contract every reader uses."""
    return [*OBS_HEAD, *(f"curvature_ahead_{i + 1}" for i in range(len(params.preview))), *OBS_TAIL]


def obs_index(params: Any) -> dict[str, int]:
    """``{name: index}`` of the observation components (:func:`obs_names`)."""
    return {name: i for i, name in enumerate(obs_names(params))}


def error_bound(termination_distance: float, error_scale: float) -> float:
    """The bound of the observed cross-track error ``e / error_scale`` [-]: ``2 termination_distance / error_scale``
    (AmigoBot-v0 and -v1; the observation clips to it)."""
    return 2.0 * termination_distance / error_scale


def obs_bounds_of(termination_distance: float, error_scale: float, n_preview: int) -> tuple[Array, Array]:
    """The observation's finite ``(low, high)`` bounds (the module table) from ``termination_distance``, ``error_scale``
    [m] and the number of preview distances."""
    e_max = error_bound(termination_distance, error_scale)
    high = np.array([e_max, 1.0, 1.0] + [1.0] * (1 + n_preview) + [1.0, 1.0, 2.0, 1.0])
    low = -high
    low[-1] = 0.0
    return low, high


def _has_bool(value: Any, depth: int = 0) -> bool:
    """Whether a (nested) list or tuple holds a ``bool`` or ``numpy.bool_``."""
    if isinstance(value, bool | np.bool_):
        return True
    return depth < 3 and isinstance(value, list | tuple) and any(_has_bool(v, depth + 1) for v in value)


def real_array(value: Any, what: str) -> Array:
    """``value`` (numbers, nested sequences, integer or floating arrays) as a float64 array. Raises a one-line
    ``TypeError`` for strings, bools, complex numbers, ``None``, other objects; ``ValueError`` for ragged ones."""
    if isinstance(value, str | bytes):
        raise TypeError(f"{what} must be real numbers, got a string: {show_value(value)}")
    if isinstance(value, list | tuple) and _has_bool(value):  # numpy would read True as 1.0
        raise TypeError(f"{what} must be real numbers (float or int), got bool values: {show_value(value)}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # e.g. numpy's ComplexWarning: never drop a part silently
            arr = np.asarray(value)
    except (ValueError, TypeError, Warning):
        raise ValueError(f"{what} must be a rectangular array of real numbers, got {show_value(value)}") from None
    kind = arr.dtype.kind
    if kind not in ("f", "i", "u"):
        names = {"b": "bool", "c": "complex", "U": "str", "S": "bytes", "O": "object", "V": "void", "M": "datetime"}
        got = names.get(kind, str(arr.dtype))
        raise TypeError(f"{what} must be real numbers (float or int), got {got} values: {show_value(value)}")
    return arr.astype(np.float64, copy=False)


def validate_action(action: ArrayLike, batch_shape: tuple[int, ...] = ()) -> Array:
    """A normalised action as float64 of shape ``batch_shape + (2,)``, checked finite. Raises ``TypeError`` (not
    real numbers, :func:`real_array`) or ``ValueError`` (ragged, wrong shape, NaN or infinite: never clipped)."""
    if type(action) is np.ndarray and action.dtype.kind == "f":  # the common case, checked quickly
        a = action.astype(np.float64, copy=False)
    else:
        a = real_array(action, "action")
    want = (*batch_shape, 2)
    if a.shape != want:
        raise ValueError(f"action must have shape {want} (wheel 1, wheel 2), got shape {a.shape}")
    # a few values (one robot) are checked faster one by one than by a numpy reduction
    if not (all(map(math.isfinite, a.ravel().tolist())) if a.size <= 8 else np.isfinite(a).all()):
        raise ValueError(f"action must be finite; got NaN or infinite values: {show_value(action)}")
    return a


def action_pair(action: ArrayLike) -> tuple[float, float]:
    """:func:`validate_action` of one robot's action, as two Python floats (the same checks and errors); a float32
    or float64 ``(2,)`` array is checked directly (``a - a == 0`` holds exactly for finite ``a`` only)."""
    if type(action) is np.ndarray and action.shape == (2,) and action.dtype.char in ("f", "d"):
        a1, a2 = action.tolist()
        if a1 - a1 == 0.0 and a2 - a2 == 0.0:
            return a1, a2
    b1, b2 = validate_action(action).tolist()
    return b1, b2


def bound_angle(b: Real) -> Real:
    """A heading ``b`` [rad] (float or column), unwrapped, reduced to ``b - 2 pi round(b / 2 pi)`` where ``|b| >
    HEADING_LIMIT`` (1e6 rad) so float64 keeps resolving a step's turn; ``b`` itself when nothing is reduced."""
    if isinstance(b, np.ndarray):
        big = np.abs(b) > HEADING_LIMIT
        return np.where(big, b - TWO_PI * np.round(b / TWO_PI), b) if big.any() else b
    return bound_angle_float(b)


def round_half_even(x: float) -> float:
    """``x`` rounded to the nearest integer, ties to even (Python's ``round`` and ``np.round``), as a float."""
    r = float(math.floor(x + 0.5))
    if r - x == 0.5 and r - 2.0 * math.floor(0.5 * r) != 0.0:
        r -= 1.0
    return r


def bound_angle_float(b: float) -> float:
    """:func:`bound_angle` of one float (a no-op within ``[-HEADING_LIMIT, HEADING_LIMIT]``; compiled)."""
    if -HEADING_LIMIT <= b <= HEADING_LIMIT:
        return b
    return b - TWO_PI * round_half_even(b / TWO_PI)


def heading_error(cos_beta: Real, sin_beta: Real, cos_theta: Real, sin_theta: Real) -> tuple[Real, Real]:
    """``(cos(psi), sin(psi))`` of ``psi = beta - theta`` from the unit vectors: ``u . t`` and ``t x u``."""
    return cos_beta * cos_theta + sin_beta * sin_theta, sin_beta * cos_theta - cos_beta * sin_theta


def heading_term(cos_psi: Real, sin_psi: Real, cos_ss: Real, sin_ss: Real) -> Real:
    r"""The heading reward term ``(1 + cos(psi - psi_ss)) / 2`` [-]:
    :math:`\tfrac12(1 + (\cos\psi\cos\psi_{ss} + \sin\psi\sin\psi_{ss}))`."""
    return 0.5 * (1.0 + (cos_psi * cos_ss + sin_psi * sin_ss))


def steady_heading_float(curvature: float, l3: float) -> tuple[float, float]:
    """``(cos psi_ss, sin psi_ss)`` of the steady heading error ``psi_ss = -asin(kappa l3)`` for floats
    (``kappa l3`` clipped to [-1, 1]; :func:`steady_heading`)."""
    sin_ss = -min(max(curvature * l3, -1.0), 1.0)
    return math.sqrt(1.0 - sin_ss * sin_ss), sin_ss


def observe_head(
    e: Real, sin_psi: Real, cos_psi: Real, curvature: Real, l3: float, error_scale: float, e_max: float
) -> tuple[Real, Real, Real, Real]:
    """The fields :data:`OBS_HEAD`, ``(clip(e / error_scale, +-e_max), sin psi, cos psi, clip(kappa l3, +-1))``, of
    H's cross-track error ``e`` [m] and curvature ``kappa`` [1/m] (``l3``, ``error_scale`` [m]); floats or columns."""
    return clip(e / error_scale, -e_max, e_max), sin_psi, cos_psi, curvature_feature(curvature, l3)


def curvature_feature(curvature: Real, l3: float) -> Real:
    """A curvature field of the observation (at H, and at each preview point): ``clip(kappa l3, -1, 1)`` [-] of the
    curvature ``kappa`` [1/m] and ``l3`` [m]. Floats or columns."""
    return clip(curvature * l3, -1.0, 1.0)


def observe_rates(w1: Real, w2: Real, v: Real, v_ref: Real, w_max: float, v_max: float) -> tuple[Real, Real, Real]:
    """``(clip(w1 / w_max, +-1), clip(w2 / w_max, +-1), clip((v - v_ref) / v_max, +-2))`` of the wheel rates [rad/s]
    and the speeds of A and the reference [m/s]; floats or columns."""
    return (clip(w1 / w_max, -1.0, 1.0), clip(w2 / w_max, -1.0, 1.0), clip((v - v_ref) / v_max, -2.0, 2.0))


def observe_reference(v_ref: Real, v_max: float) -> Real:
    """The observed reference speed ``v_ref / v_max`` [-] (``v_ref``, ``v_max`` [m/s]). Floats or columns."""
    return v_ref / v_max


def observe_columns(
    path: Any,
    preview: tuple[float, ...],
    l3: float,
    error_scale: float,
    e_max: float,
    w_max: float,
    v_max: float,
    e: Real,
    sin_psi: Real,
    cos_psi: Real,
    curvature: Real,
    s: Real,
    w1: Real,
    w2: Real,
    v: Real,
    v_ref: Real,
) -> tuple[Real, ...]:
    """AmigoBot-v0's observation (also AmigoBot-v1's ``observation="v0"``): :func:`observe_head`, the curvature
    fields at ``s + preview`` [m] on ``path`` (``s`` H's arc length), :func:`observe_rates`,
    :func:`observe_reference`; each clipped to its bound (:func:`obs_bounds_of`)."""
    if type(path) in (CirclePath, ManoeuvrePath):  # AmigoBot-v0's paths: the curvature alone (the same number)
        ahead = [curvature_feature(path.curvature_columns(s + d), l3) for d in preview]
    else:
        ahead = [curvature_feature(path.pose_columns(s + d).curvature, l3) for d in preview]
    return (
        *observe_head(e, sin_psi, cos_psi, curvature, l3, error_scale, e_max),
        *ahead,
        *observe_rates(w1, w2, v, v_ref, w_max, v_max),
        observe_reference(v_ref, v_max),
    )


def reward_term_columns(
    abs_error: Real,
    abs_dv: Real,
    cos_psi: Real,
    sin_psi: Real,
    cos_ss: Real,
    sin_ss: Real,
    change_sq: Real,
    sigma_track: float,
    sigma_speed: float,
    smooth_weight: float,
    smooth_scale_sq: float,
) -> tuple[Real, Real, Real, Real]:
    r"""The four reward terms ``(track, speed, heading, smooth)``, each in [0, 1] (AmigoBot-v0 and -v1).

    .. math::
        e^{-|e|/\sigma_e},\quad e^{-|\Delta v|/\sigma_v},\quad \tfrac12(1 + \cos\psi\cos\psi_{ss}
        + \sin\psi\sin\psi_{ss}),\quad 1 - w_s\left(1 - e^{-c/s^2}\right)

    with ``|e|`` [m], ``|Delta v|`` [m/s], the heading error's and steady one's (:func:`steady_heading`) cosine and
    sine, and the squared command change ``c`` in the units of ``s^2 = smooth_scale_sq``.
    """
    arg_track, arg_speed, arg_smooth = reward_arguments(
        abs_error, abs_dv, change_sq, sigma_track, sigma_speed, smooth_scale_sq
    )
    return (
        np.exp(arg_track),
        np.exp(arg_speed),
        heading_term(cos_psi, sin_psi, cos_ss, sin_ss),
        smooth_term(np.exp(arg_smooth), smooth_weight),
    )


def reward_arguments(
    abs_error: Real, abs_dv: Real, change_sq: Real, sigma_track: float, sigma_speed: float, smooth_scale_sq: float
) -> tuple[Real, Real, Real]:
    r"""The arguments of the reward's three exponentials (:func:`reward_term_columns`),
    :math:`(-|e|/\sigma_e,\ -|\Delta v|/\sigma_v,\ -c/s^2)`, each a division by the negated scale; floats or columns."""
    return abs_error / -sigma_track, abs_dv / -sigma_speed, change_sq / -smooth_scale_sq


def off_path(abs_error: Real, termination_distance: float) -> Any:
    """The termination of AmigoBot-v0's task: H farther than ``termination_distance`` [m] from the path, ``|e| >
    termination_distance`` with ``abs_error = |e|`` [m] (NaN is not off the path). A bool, or a bool column."""
    return abs_error > termination_distance


def smooth_term(ex: Real, smooth_weight: float) -> Real:
    """The smoothness term ``1 - w_s (1 - ex)`` from ``ex = exp(-c / s^2)`` (:func:`reward_term_columns`)."""
    return 1.0 - smooth_weight * (1.0 - ex)


def reward_product(track: Real, speed: Real, heading: Real, smooth: Real) -> Real:
    """The reward, the product of the four terms in this order: ``((track * speed) * heading) * smooth``."""
    return ((track * speed) * heading) * smooth


def steady_heading(curvature: Real, l3: float) -> tuple[Real, Real]:
    """``(cos psi_ss, sin psi_ss)`` of the steady heading error ``psi_ss = -asin(kappa l3)`` (``kappa l3`` clipped to
    [-1, 1]): ``cos psi_ss = sqrt(1 - (kappa l3)^2)``, ``sin psi_ss = -kappa l3``; floats or columns."""
    sin_ss = -clip(curvature * l3, -1.0, 1.0)
    return col_sqrt(1.0 - sin_ss * sin_ss), sin_ss


def info_dict(
    pose: Any, h_position: Any, error: Any, rates: Any, angles: Any, castor: Any, terms: Any, time: Any
) -> dict[str, Any]:
    """The info dict keyed as :data:`INFO_KEYS`: ``pose`` ``(x, y, beta)`` [m, m, rad], ``h_position`` [m],
    ``error`` H's cross-track error [m], ``rates`` the wheel rates [rad/s], ``angles`` the wheel angles and
    ``castor`` the castor's [rad], ``terms`` the 4 reward terms (:data:`REWARD_TERMS` order), ``time`` [s]: any
    types, handed out as they are."""
    return {
        "pose": pose,
        "h_position": h_position,
        "cross_track_error": error,
        "wheel_rates": rates,
        "wheel_angles": angles,
        "castor_angle": castor,
        "reward_terms": dict(zip(REWARD_TERMS, terms, strict=True)),
        "time": time,
    }
