r"""The AmigoBot-v1 task as pure functions of floats (one robot) or ``(N,)`` columns (a batch): settings, start,
step, observation, reward, end.

Observation (float32, :func:`obs_fields` order; "measured": from the noisy pose and wheel rates, nominal robot).
``e`` is H's signed cross-track error (positive left), ``psi`` the heading minus the path tangent at H's closest
point, ``kappa`` the path curvature, ``(x_i, y_i)`` the path point ``d_i`` ahead of H's closest point in the robot
frame (origin A, x along the heading), ``v_ref`` the reference speed of A:

==============================  =====================================  ===========================
field                           value                                  bounds
==============================  =====================================  ===========================
``cross_track_error``           ``e / error_scale`` (clipped)          ``+-2 d_term / error_scale``
``sin_heading_error``           ``sin psi``                            [-1, 1]
``cos_heading_error``           ``cos psi``                            [-1, 1]
``curvature``                   ``kappa l3`` (clipped)                 [-1, 1]
``preview_x_<d>``               ``x_i / preview_scale`` (clipped)      ``+-b_i``
``preview_y_<d>``               ``y_i / preview_scale`` (clipped)      ``+-b_i``
``preview_curvature_<d>``       ``kappa(s + d_i) l3`` (clipped)        [-1, 1]
``reference_speed``             ``v_ref(t) / v_max``                   [0, 1]
``reference_speed_ahead``       ``v_ref(t + 1 s) / v_max``             [0, 1]
``speed_error``                 ``(v_meas - v_ref) / v_max`` (clipped) [-2, 2]
``wheel_rate_1``, ``_2``        measured ``alphadot_i / w_max``        [-2, 2] (clipped)
``previous_command_1``, ``_2``  the previous action                    [-1, 1]
==============================  =====================================  ===========================

with ``b_i = (d_i + l3 + 2 d_term) / preview_scale``.

Reward (true state): the product of the terms ``track``, ``speed``, ``heading``, ``smooth``, each in [0, 1],

.. math::
    r = e^{-|e|/\sigma_e} \cdot e^{-|v_A - v_{ref}|/\sigma_v} \cdot \tfrac12(1 + \cos(\psi - \psi_{ss}))
        \cdot \left(1 - w_s (1 - e^{-(\|\Delta a\|/2\sigma_a)^2})\right)

with ``psi_ss = -asin(kappa l3)``, ``v_A`` the true speed of A at the step's end, ``Delta a`` the change of the
normalised command and ``sigma_a = sigma_smooth`` (``reward="v0"``: the wheel rates' change over
``w_max sigma_smooth``).

End: terminated when ``|e| > termination_distance`` (true H) or H reaches an open path's end; truncated by the
registration's time limit.
"""

from __future__ import annotations

import math
import os
import warnings
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from functools import lru_cache
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from amigo_gym.logs import load_robot_file
from amigo_gym.model import actuators, randomization
from amigo_gym.model.actuators import ActuatorParams
from amigo_gym.model.kinematics import (
    Real,
    a_from_h,
    advance_angle,
    arc_step,
    body_velocity_columns,
    body_velocity_of,
    col_cos,
    col_sin,
    h_from_a,
)
from amigo_gym.model.numeric import clip, where
from amigo_gym.model.params import RobotParams, check_pair, check_real, show_value
from amigo_gym.model.randomization import Randomization, StepNoise, draw_key, intervals, make_randomization, sample
from amigo_gym.paths import FAMILIES, CirclePath, ClothoidPath, ManoeuvrePath, check_path, make_family_path
from amigo_gym.paths.analysis import Feasibility, feasibility
from amigo_gym.paths.clothoid import STATUS_END, PathLoops
from amigo_gym.paths.families import RANDOM_RANGES
from amigo_gym.paths.points import cached_file_path, is_points_file
from amigo_gym.task.v0 import (
    OBS_HEAD,
    V0_DEFAULTS,
    bound_angle,
    check_v0,
    curvature_feature,
    error_bound,
    heading_error,
    obs_bounds_of,
    obs_names,
    observe_columns,
    observe_head,
    off_path,
    reward_product,
    reward_term_columns,
    steady_heading,
)

#: names accepted by ``path=`` (or pass a path object implementing :class:`amigo_gym.paths.PathSpec`)
PATH_FAMILIES: tuple[str, ...] = ("circle", "manoeuvre", "figure8", "lane_change", "random", "mixed")
#: the families ``"mixed"`` draws from, with equal probability
MIXED_FAMILIES: tuple[str, ...] = ("circle", "figure8", "lane_change", "random")
#: how far ahead the reference speed is also observed [s]
SPEED_LOOKAHEAD = 1.0
#: smallest control period [s]: the delay ring then keeps 501 commands per robot
MIN_DT = 1e-3

SpeedProfile = Literal["constant", "trapezoid"]
#: values of ``observation=`` and ``reward=``: AmigoBot-v1's own, or AmigoBot-v0's
LAYOUTS: tuple[str, ...] = ("v1", "v0")
#: values of ``feasibility=``: refuse an infeasible fixed path, warn and run it, or run it silently
FEASIBILITY_MODES: tuple[str, ...] = ("error", "warn", "off")


#: the settings that must be instances of a class: name, class, and the class as the error message names it
_TYPES: tuple[tuple[str, type, str], ...] = (
    ("robot", RobotParams, "a RobotParams"),
    ("true_robot", RobotParams, "a RobotParams or None"),
    ("actuators", ActuatorParams, "an ActuatorParams"),
    ("randomize", Randomization, "a Randomization"),
)
#: the settings that take one of a few values
_CHOICES: tuple[tuple[str, tuple[Any, ...]], ...] = (
    ("ideal_actuators", (True, False)),
    ("observation", LAYOUTS),
    ("reward", LAYOUTS),
    ("speed_profile", ("constant", "trapezoid")),
    ("start_at_rest", (True, False)),
    ("feasibility", FEASIBILITY_MODES),
)


@dataclass(frozen=True)
class TrackingParams:
    """Settings of ``AmigoBot-v1`` (every keyword argument of ``gym.make("AmigoBot-v1", ...)``).

    Attributes:
        robot: the nominal robot: what the action scale, the observation and every policy use.
        true_robot: the robot actually simulated (its ``r1``, ``r2``, ``l1``, ``l3`` matter); ``None``: the
            nominal one. ``gym.make`` takes a mapping of the fields that differ, or a robot file's path
            (:func:`make_tracking_params`).
        actuators: the firmware's ramps (0.3 / 0.75 m/s^2, 0.87 / 2.5 rad/s^2) and a fixed delay [s].
        randomize: ranges drawn per episode (wheel radii, track, slip, delay) and measurement noise;
            a preset name (``"none"``, ``"mild"``, ``"hard"``) or a mapping in ``gym.make``.
        dt: control period [s], in [MIN_DT = 0.001, 1] (the delay ring keeps at most 501 commands). Default 0.1.
            AmigoBot-v0's configuration (``ideal_actuators=True, observation="v0", reward="v0"``) keeps
            AmigoBot-v0's ranges: ``dt`` in [1e-6, 2] s, ``error_scale`` in [1e-6, 10] m, each ``preview`` in
            [0, 10] m, the sigmas in [1e-6, 1e6].
        path: a family name of :data:`PATH_FAMILIES`, a points file (``.csv`` or ``.json`` with columns ``x``,
            ``y`` [m]: :func:`amigo_gym.paths.from_file`), or a path object (:mod:`amigo_gym.paths.user`).
        radius: radius of ``"circle"`` and of the circular part of ``"manoeuvre"`` [m]; with
            ``path="mixed"`` circles draw their radius in [0.5, 3] m instead. Default 1.0.
        direction: +1 (left turn) or -1 (right) for circles and the manoeuvre. Default +1.
        path_params: further parameters of the family (e.g. ``{"size": 4.0}`` for ``"figure8"``), as sorted
            ``(name, value)`` pairs (``gym.make`` takes a mapping), checked against the family's ranges
            (:data:`amigo_gym.paths.FAMILIES`); unknown, out-of-range and unused parameters are refused (with
            ``path="mixed"`` only its random paths take them; ``radius``/``direction`` are keywords).
        random_pool: ``"random"`` paths are drawn from this many seeded paths (ids ``[0, pool)``), each built once
            per process and cached within :data:`PATH_CACHE_BYTES`. Default 1024.
        speed: reference speed of A [m/s]: a number in (0, robot.max_speed] or a pair ``(low, high)`` per episode.
        speed_profile: ``"constant"``, or ``"trapezoid"`` (start at 0, accelerate at ``profile_accel``,
            cruise at ``speed``, brake at ``profile_decel`` to stop at ``profile_duration``).
        profile_accel, profile_decel: the trapezoid's rates [m/s^2], within the robot's (``max_acceleration``
            0.3, ``max_deceleration`` 0.75).
        profile_duration: time at which the trapezoid stops [s].
        start_at_rest: the wheels start at rest (a real robot's start); else rolling straight at the reference speed.
        termination_distance: the episode terminates when H is farther than this from the path [m].
        init_position_noise: half-width of the uniform start offset of H per axis [m].
        init_heading_noise: half-width of the uniform start heading offset [rad].
        error_scale: the observation divides the cross-track error by this [m].
        preview: distances ahead of H's closest point at which the path is observed [m], each in (0, 5].
        preview_scale: the observation divides preview coordinates by this [m].
        sigma_track, sigma_speed, sigma_smooth, smooth_weight: reward scales (module docstring).
        feasibility: a fixed path the robot cannot track at the highest ``speed`` (:func:`check_feasible`):
            ``"error"`` refuses it, ``"warn"`` warns and runs it, ``"off"`` runs it; in every mode the report is the
            env's ``feasibility`` and ``info["feasibility"]`` at reset.
        goal_tolerance: an open path's episode terminates as a success when H is within this distance [m] of
            the path's end point (``info["end_condition"] == "goal"``), in [0, 10]; 0 (default): only when H
            passes the end (``"end_of_path"``).
        ideal_actuators: the wheels take the commanded rates ``a w_max`` at once and hold them over the step
            (AmigoBot-v0's; the exact arc), else the firmware's ramps. Requires no delay, slip, ``true_robot`` or
            randomised geometry.
        observation: the observation layout: ``"v1"`` (default, module table) or ``"v0"``, AmigoBot-v0's
            (:func:`amigo_gym.task.v0.obs_names`), from the measured state.
        reward: ``"v1"`` (default): the smoothness term's change is that of the normalised command over
            ``2 sigma_smooth``; ``"v0"``: AmigoBot-v0's, the change of the wheel rates over ``w_max sigma_smooth``.
    """

    robot: RobotParams = field(default_factory=RobotParams)
    true_robot: RobotParams | None = None
    actuators: ActuatorParams = field(default_factory=ActuatorParams)
    randomize: Randomization = field(default_factory=Randomization)
    dt: float = 0.1
    path: Any = "circle"
    radius: float = 1.0
    direction: int = 1
    path_params: tuple[tuple[str, float], ...] = ()
    random_pool: int = 1024
    speed: float | tuple[float, float] = 0.2
    speed_profile: SpeedProfile = "constant"
    profile_accel: float = 0.2
    profile_decel: float = 0.5
    profile_duration: float = 40.0
    start_at_rest: bool = True
    termination_distance: float = 0.25
    init_position_noise: float = 0.02
    init_heading_noise: float = 0.1
    error_scale: float = 0.05
    preview: tuple[float, ...] = (0.2, 0.5, 1.0)
    preview_scale: float = 1.0
    sigma_track: float = 0.02
    sigma_speed: float = 0.05
    sigma_smooth: float = 0.1
    smooth_weight: float = 0.2
    feasibility: str = "error"
    goal_tolerance: float = 0.0
    ideal_actuators: bool = False
    observation: str = "v1"
    reward: str = "v1"

    def __post_init__(self) -> None:
        o = "TrackingParams"
        s = object.__setattr__
        for name, cls, what in _TYPES:
            value = getattr(self, name)
            if not isinstance(value, cls) and not (name == "true_robot" and value is None):
                raise ValueError(f"{o}.{name} must be {what}, got {type(value).__name__}")
        for name, allowed in _CHOICES:
            value = getattr(self, name)
            if not isinstance(value, type(allowed[0])) or value not in allowed:
                what = "True or False" if allowed[0] is True else f"one of {list(allowed)}"
                raise ValueError(f"{o}.{name} must be {what}, got {value!r}")
        if isinstance(self.path, str) and self.path not in PATH_FAMILIES:
            if not is_points_file(self.path):
                raise ValueError(
                    f"{o}.path must be one of {list(PATH_FAMILIES)}, a points file (.csv, .json) or a path object, "
                    f"got {self.path!r}"
                )
            s(self, "path", cached_file_path(self.path))  # amigo_gym.paths.from_file, fitted once per file
        if not isinstance(self.path, str):  # a path object: checked, wrapped unless a ClothoidPath (paths.user)
            s(self, "path", check_path(self.path, "AmigoBot-v1"))
        # AmigoBot-v0's configuration (ideal actuators, v0's observation and reward) keeps AmigoBot-v0's ranges
        # (check_v0's): its steps need no delay ring, so dt in [1e-6, 2] s. (name, low, high, low end open)
        v0 = self.ideal_actuators and self.observation == "v0" and self.reward == "v0"
        r = self.robot
        ranges = (
            ("dt", *((1e-6, 2.0) if v0 else (MIN_DT, 1.0)), False),
            ("radius", r.l3, 1e3, True),
            ("profile_accel", 0.0, r.max_acceleration, True),
            ("profile_decel", 0.0, r.max_deceleration, True),
            ("profile_duration", 0.0, 1e5, True),
            ("termination_distance", 0.0, 10.0, True),
            ("init_heading_noise", 0.0, math.pi / 4, False),
            ("error_scale", 1e-6 if v0 else 1e-4, 10.0, False),
            ("preview_scale", 1e-2, 10.0, False),
            *((name, 1e-6, 1e6 if v0 else 10.0, False) for name in ("sigma_track", "sigma_speed", "sigma_smooth")),
            ("goal_tolerance", 0.0, 10.0, False),
        )
        for name, low, high, low_open in ranges:
            s(self, name, check_real(o, name, getattr(self, name), low, high, low_open=low_open))
        s(self, "smooth_weight", check_real(o, "smooth_weight", self.smooth_weight, 0.0, 1.0, high_open=True))
        high = self.termination_distance / 2
        s(self, "init_position_noise", check_real(o, "init_position_noise", self.init_position_noise, 0.0, high))
        if isinstance(self.direction, bool) or self.direction not in (1, -1):
            raise ValueError(f"{o}.direction must be +1 (left turn) or -1 (right), got {self.direction!r}")
        if isinstance(self.random_pool, bool) or not isinstance(self.random_pool, int) or self.random_pool < 1:
            raise ValueError(f"{o}.random_pool must be an integer >= 1, got {self.random_pool!r}")
        check = check_pair if isinstance(self.speed, tuple | list) else check_real  # a pair drawn per episode
        s(self, "speed", check(o, "speed", self.speed, 0.0, r.max_speed, low_open=True))
        pv = self.preview
        far, near_open = (10.0, False) if v0 else (5.0, True)  # v0's previews: [0, 10] m
        if isinstance(pv, str | bytes | Mapping) or not hasattr(pv, "__iter__") or getattr(pv, "ndim", 1) != 1:
            within = f"{'(' if near_open else '['}0, {far:g}]"
            raise ValueError(f"{o}.preview must be a sequence of distances in {within} m, got {show_value(pv)}")
        prev = (check_real(o, f"preview[{i}]", d, 0.0, far, low_open=near_open) for i, d in enumerate(self.preview))
        s(self, "preview", tuple(prev))
        s(self, "path_params", _path_params(o, self.path, self.path_params))
        _check_combined(o, self)

    @classmethod
    def v0(cls, **settings: Any) -> TrackingParams:
        """AmigoBot-v0's task: its settings (every keyword of ``gym.make("AmigoBot-v0", ...)``, checked by
        :func:`amigo_gym.task.v0.check_v0`) with ideal actuators, v0's observation and reward, no randomisation, the
        wheels rolling at the start, the circle or manoeuvre as a path object and ``feasibility="off"`` (``check_v0``
        checked that the robot can drive it)."""
        kw = check_v0(**settings) | {"ideal_actuators": True, "observation": "v0", "reward": "v0"}
        try:
            return cls(**kw, start_at_rest=False, feasibility="off")
        except ValueError as exc:  # the message names the keyword of v0's settings
            raise ValueError(str(exc).replace("TrackingParams", "TrackingParams.v0", 1)) from None

    @property
    def speed_range(self) -> tuple[float, float]:
        """``(low, high)`` of the reference cruise speed [m/s] (equal for a constant)."""
        sp = self.speed
        return sp if isinstance(sp, tuple) else (float(sp), float(sp))


def _path_params(owner: str, path: Any, value: Any) -> tuple[tuple[str, float], ...]:
    """``path_params`` (a mapping or ``(name, value)`` pairs) as sorted ``(name, float)`` pairs, checked against the
    family of ``path``: one-line ``ValueError`` for an unknown, out-of-range or unused parameter."""
    name = f"{owner}.path_params"
    if isinstance(value, Mapping):
        items = list(value.items())
    elif isinstance(value, (tuple, list)) and all(
        isinstance(kv, (tuple, list)) and len(kv) == 2 and isinstance(kv[0], str) for kv in value
    ):
        items = [(kv[0], kv[1]) for kv in value]
    else:
        raise ValueError(f"{name} must be a mapping of family parameters, got {show_value(value)}")
    keys = [k for k, _ in items]
    bad_keys = [k for k in keys if not isinstance(k, str)]
    if bad_keys:
        raise ValueError(f"{name} keys must be parameter names (strings), got {bad_keys[0]!r}")
    if len(set(keys)) != len(keys):
        raise ValueError(f"{name} names a parameter twice: {sorted(keys)}")
    if not items:
        return ()
    given = {k: v for k, v in items}
    if not isinstance(path, str):
        raise ValueError(
            f"{name} is unused with a path object ({type(path).__name__}): give the path its parameters instead, "
            f"got {given!r}"
        )
    if path == "mixed":
        unused = sorted(k for k in keys if k not in RANDOM_RANGES)
        if unused:
            raise ValueError(
                f"{name}[{unused[0]!r}] is unused with path='mixed' (only its random paths take parameters, "
                f"{sorted(RANDOM_RANGES)}; the other families' ranges are fixed: tracking.MIXED_RANGES); got {given!r}"
            )
    fam = FAMILIES["random" if path == "mixed" else path]
    keyword = {"radius", "direction"} if path in ("circle", "manoeuvre") else set()
    allowed = sorted(set(fam.params) - keyword)
    for k in keys:
        if k in keyword:
            raise ValueError(f"{name}[{k!r}] is not a path parameter of {path!r}: use the keyword {k}= instead")
        if k not in fam.params:
            raise ValueError(f"{name}: path {path!r} has no parameter {k!r}; it takes {allowed}")
    out = tuple(sorted((k, fam.params[k].check(name, k, v)) for k, v in items))
    if path in ("random", "mixed"):
        vals = {k: r.default for k, r in RANDOM_RANGES.items()} | dict(out)
        if vals["min_piece"] > vals["max_piece"]:
            raise ValueError(f"{name}: min_piece {vals['min_piece']:g} m must be <= max_piece {vals['max_piece']:g} m")
    return out


def _check_combined(owner: str, p: TrackingParams) -> None:
    """Refuse settings that are each in range but conflict together (never clipped silently): a total delay above
    ``MAX_DELAY``, a trapezoid too short to reach its speed, ``ideal_actuators`` with delay, slip or mismatch."""
    fixed = p.actuators.delay
    high = p.randomize.delay[1]
    if p.ideal_actuators:
        r = p.randomize
        nominal = {"wheel_radius": (1.0, 1.0), "track": (1.0, 1.0), "slip": (0.0, 0.0), "delay": (0.0, 0.0)}
        bad = [f"randomize.{k} {tuple(getattr(r, k))!r}" for k, v in nominal.items() if tuple(getattr(r, k)) != v]
        if fixed != 0.0:
            bad.insert(0, f"actuators.delay {fixed!r}")
        if p.true_robot is not None:
            bad.append("a true_robot")
        if bad:
            raise ValueError(
                f"{owner}.ideal_actuators needs the nominal robot without delay, slip or randomised geometry; got "
                + ", ".join(bad)
            )
    if fixed + high > actuators.MAX_DELAY:
        raise ValueError(
            f"{owner}: actuators.delay {fixed:g} s + randomize.delay high {high:g} s = {fixed + high:g} s exceeds "
            f"the largest delay supported, MAX_DELAY = {actuators.MAX_DELAY:g} s; lower one of them"
        )
    if p.speed_profile == "trapezoid":
        v = p.speed_range[1]
        need = v / p.profile_accel + v / p.profile_decel
        if need > p.profile_duration:
            raise ValueError(
                f"{owner}.profile_duration {p.profile_duration:g} s is too short for the trapezoid to reach speed "
                f"{v:g} m/s: accelerating and braking take {need:g} s (speed / profile_accel + speed / profile_decel)"
            )


def make_tracking_params(
    owner: str, params: TrackingParams | Mapping[str, Any] | None = None, **settings: Any
) -> TrackingParams:
    """Settings from the keywords of ``gym.make("AmigoBot-v1", ...)``: every field, mappings accepted.

    ``robot``, ``actuators``: an instance or a mapping of its fields; ``true_robot``: a mapping of the fields that
    differ from the nominal robot, a ``RobotParams``, or a robot file (``robot.json`` of ``amigo-gym identify``: its
    ``r1``, ``r2``, ``l1`` [m], and its ``delay`` [s] and ramps on ``actuators``, whose own fields win);
    ``randomize``: a preset name or a mapping; ``params``: a :class:`TrackingParams` or a mapping of its fields.
    Raises ``TypeError`` for an unknown keyword, ``ValueError`` for a bad value (naming field, value and range).
    """
    names = [f.name for f in fields(TrackingParams)]
    if isinstance(params, Mapping):
        settings = {**dict(params), **settings}
        params = None
    unknown = sorted(k for k in settings if k not in names)
    if unknown:
        raise TypeError(
            f"{owner} got unexpected keyword argument(s) {unknown}; allowed: {', '.join(['params', *names])}"
        )
    base = TrackingParams() if params is None else params
    if not isinstance(base, TrackingParams):
        raise TypeError(f"{owner}: params must be a TrackingParams or a mapping, got {type(base).__name__}")
    robot = settings.get("robot", base.robot)
    if isinstance(robot, Mapping):
        robot = _from_mapping(owner, "robot", RobotParams(), robot)
        settings["robot"] = robot
    tr = settings.get("true_robot")
    act_file: dict[str, float] = {}
    if isinstance(tr, str | os.PathLike):
        try:
            tr, act_file = load_robot_file(tr)
        except (FileNotFoundError, ValueError) as exc:
            raise type(exc)(f"{owner}: true_robot: {exc}") from None
    if isinstance(tr, Mapping):
        settings["true_robot"] = _from_mapping(owner, "true_robot", robot, tr)
    act = settings.get("actuators")
    if act_file or isinstance(act, Mapping):  # a mapping's fields win over the file's
        given = act if isinstance(act, Mapping) else {}
        start = ActuatorParams() if isinstance(act, Mapping) else base.actuators if act is None else act
        settings["actuators"] = _from_mapping(owner, "actuators", start, {**act_file, **given})
    if "randomize" in settings:
        settings["randomize"] = make_randomization(settings["randomize"])
    return replace(base, **settings) if settings else base


def _from_mapping(owner: str, name: str, base: Any, values: Mapping[str, Any]) -> Any:
    allowed = {f.name for f in fields(base)}
    bad = sorted(str(k) for k in values if k not in allowed)
    if bad:
        raise ValueError(f"{owner}: unknown {name} field(s) {bad}; allowed: {sorted(allowed)}")
    return replace(base, **{str(k): v for k, v in values.items()})


def obs_fields(p: TrackingParams) -> tuple[str, ...]:
    """Names of the observation's components, in order (module table; ``observation="v0"``: AmigoBot-v0's)."""
    if p.observation == "v0":
        return tuple(obs_names(p))
    preview = [f"preview_{c}_{d:g}m" for d in p.preview for c in ("x", "y", "curvature")]
    speeds = ("reference_speed", "reference_speed_ahead", "speed_error", "wheel_rate_1", "wheel_rate_2")
    return (*OBS_HEAD, *preview, *speeds, "previous_command_1", "previous_command_2")


def obs_bounds(p: TrackingParams) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Finite ``(low, high)`` bounds of the observation (module table; ``observation="v0"``: AmigoBot-v0's)."""
    if p.observation == "v0":
        return obs_bounds_of(p.termination_distance, p.error_scale, len(p.preview))
    e_max = error_bound(p.termination_distance, p.error_scale)
    preview = [v for b in constants(p).preview_bounds for v in (b, b, 1.0)]
    hi = np.array([e_max, 1.0, 1.0, 1.0, *preview, 1.0, 1.0, 2.0, 2.0, 2.0, 1.0, 1.0])
    lo = -hi
    lo[-7:-5] = 0.0  # the reference speeds
    return lo, hi


@dataclass(frozen=True)
class Constants:
    """Numbers a step needs, derived once from :class:`TrackingParams` (:func:`constants`)."""

    params: TrackingParams
    nominal: RobotParams
    w_max: float
    v_max: float
    l3: float
    e_max: float
    n_sub: int
    ring_length: int
    window: float
    preview_bounds: tuple[float, ...]  # the b_i of the module table
    smooth_scale_sq: float


def command_ring_length(p: TrackingParams) -> int:
    """Commands kept per robot in the delay ring: for delays up to ``MAX_DELAY``, or 2 with ``ideal_actuators``."""
    return actuators.ring_length(p.dt, 0.0 if p.ideal_actuators else actuators.MAX_DELAY)


def constants(p: TrackingParams) -> Constants:
    """The :class:`Constants` of ``p``."""
    robot = p.robot
    w_max = robot.max_wheel_rate
    # the projection window exceeds H's step (speed of H <= v + l3 |w|)
    h_speed = actuators.turn_rate_bound(robot) * robot.l3 + 1.25 * robot.max_speed
    window = max(0.25, 1.5 * h_speed * p.dt + 0.1)
    smooth = w_max * p.sigma_smooth
    return Constants(
        params=p,
        nominal=robot,
        w_max=w_max,
        v_max=robot.max_speed,
        l3=robot.l3,
        e_max=error_bound(p.termination_distance, p.error_scale),
        n_sub=actuators.step_subintervals(p.dt, robot),
        ring_length=command_ring_length(p),
        window=window,
        preview_bounds=tuple((d + robot.l3 + 2.0 * p.termination_distance) / p.preview_scale for d in p.preview),
        # (w_max sigma_smooth)^2 [rad^2/s^2] of the wheel rates' change (reward="v0"), else (2 sigma_smooth)^2
        smooth_scale_sq=smooth * smooth if p.reward == "v0" else 4.0 * p.sigma_smooth * p.sigma_smooth,
    )


def v0_settings(p: TrackingParams) -> dict[str, Any] | None:
    """AmigoBot-v0's settings that make ``p`` (``TrackingParams.v0(**v0_settings(p))`` is ``p`` with
    ``feasibility="off"``), or ``None`` when ``p`` is no AmigoBot-v0 task (:meth:`TrackingParams.v0`)."""
    path = p.path
    if type(path) not in (CirclePath, ManoeuvrePath) or not (p.ideal_actuators and p.observation == p.reward == "v0"):
        return None
    kind = "circle" if type(path) is CirclePath else "manoeuvre"
    of_path = {"radius": path.radius, "direction": path.direction, "path": kind}
    of_path["straight_length"] = getattr(path, "straight_length", 1.0)
    s = {k: of_path[k] if k in of_path else getattr(p, k) for k in V0_DEFAULTS}
    try:
        q = TrackingParams.v0(**s)
    except ValueError:  # e.g. a speed range
        return None
    same = ("path", "randomize", "start_at_rest", "speed_profile", "goal_tolerance")  # what v0's settings fix
    return s if all(getattr(q, k) == getattr(p, k) for k in same) else None


class Episode(NamedTuple):
    """What is drawn once per episode: the true geometry ``r1, r2, l1, l3`` [m], the slip bound ``slip_max`` [-], the
    delay ``lag dt + t_switch`` (whole steps, [s]), the ``key`` of the per-step draws (uint64), the cruise speed
    ``v_cruise`` [m/s] and the trapezoid's braking time ``t_brake`` [s] (``inf`` for a constant speed)."""

    r1: Real
    r2: Real
    l1: Real
    l3: Real
    slip_max: Real
    lag: Any
    t_switch: Real
    key: Any
    v_cruise: Real
    t_brake: Real


class State(NamedTuple):
    """The state: true pose of A ``x, y, beta`` [m, m, rad], wheel rates ``w1, w2`` [rad/s] and angles ``alpha1,
    alpha2`` [rad], H's arc length ``progress`` unwrapped over laps [m], the previous action ``a1, a2`` [-] and the
    ``steps`` taken (int)."""

    x: Real
    y: Real
    beta: Real
    w1: Real
    w2: Real
    alpha1: Real
    alpha2: Real
    progress: Real
    a1: Real
    a2: Real
    steps: Any


class Outcome(NamedTuple):
    """What the environments report about a state: the observation (:func:`obs_fields` order, float64), the reward
    ``terms`` (:data:`~amigo_gym.task.v0.REWARD_TERMS`) and their product, ``terminated``, true H ``h_x, h_y`` [m], its
    cross-track ``error`` [m], the true and reference speeds of A [m/s], the measured pose [m, m, rad] and wheel
    rates [rad/s], and ``end_of_path`` (H reached an open path's end: a success)."""

    obs: tuple[Real, ...]
    terms: tuple[Real, Real, Real, Real]
    reward: Real
    terminated: Any
    h_x: Real
    h_y: Real
    error: Real
    v_true: Real
    v_ref: Real
    meas_x: Real
    meas_y: Real
    meas_beta: Real
    meas_w1: Real
    meas_w2: Real
    end_of_path: Any = False


# The pieces below take floats or columns; the compiled step compiles them.


def reference_speed(p: TrackingParams, ep: Episode, t: Real) -> Real:
    """Reference speed of A [m/s] at episode time ``t`` [s] (:func:`reference_speed_of`)."""
    trapezoid = p.speed_profile == "trapezoid"
    return reference_speed_of(trapezoid, ep.v_cruise, p.profile_accel, p.profile_decel, ep.t_brake, t)


def reference_speed_of(trapezoid: bool, v: Real, accel: float, decel: float, t_brake: Real, t: Real) -> Real:
    r"""Reference speed [m/s]: the cruise speed ``v``, or when ``trapezoid``

    .. math:: v_{ref}(t) = \max\bigl(0, \min(a_{up} t,\; v,\; v - a_{down} (t - t_b))\bigr),
        \qquad t_b = T - v / a_{down}

    (``T = profile_duration``), the minima left to right."""
    out: Real = np.maximum(np.minimum(np.minimum(accel * t, v), v - decel * (t - t_brake)), 0.0) if trapezoid else v
    return out


def action_commands(a1: Real, a2: Real, w_max: float) -> tuple[Real, Real, Real, Real]:
    """The action clipped to [-1, 1] and its setpoints: ``(c1, c2, c1 w_max, c2 w_max)`` [-, -, rad/s, rad/s]."""
    c1 = clip(a1, -1.0, 1.0)
    c2 = clip(a2, -1.0, 1.0)
    return c1, c2, c1 * w_max, c2 * w_max


def measurements(
    x: Real, y: Real, beta: Real, w1: Real, w2: Real, nx: Real, ny: Real, nbeta: Real, nr1: Real, nr2: Real
) -> tuple[Real, Real, Real, Real, Real]:
    """The measured pose of A and wheel rates: the true ones plus the step's noise [m, m, rad, rad/s, rad/s]."""
    return x + nx, y + ny, beta + nbeta, w1 + nr1, w2 + nr2


def measured_differs(position_noise: float, heading_noise: float, l3_differs: bool) -> bool:
    """Whether the measured H is projected on its own: noise on the position [m] or heading [rad], or a true ``l3``
    other than the nominal."""
    return position_noise > 0.0 or heading_noise > 0.0 or l3_differs


def end_flags(e: Real, termination_distance: float, closed: Any, status: Any) -> tuple[Any, Any]:
    """``(terminated, at_end)``: ``|e| > termination_distance`` [m], or H reached an open path's end (``status`` is
    :data:`amigo_gym.paths.STATUS_END`, ``closed`` 0)."""
    at_end = (status == STATUS_END) & (closed == 0)
    terminated = off_path(np.abs(e), termination_distance) | at_end
    return terminated, at_end


def preview_entry(
    mcb: Real, msb: Real, mx: Real, my: Real, qx: Real, qy: Real, q_k: Real, l3: float, scale: float, bound: float
) -> tuple[Real, Real, Real]:
    """One preview point's fields: the path point ``(qx, qy)`` [m] in the measured frame of A (origin ``(mx, my)``,
    heading cosine and sine ``mcb``, ``msb``) over ``scale``, clipped to ``+-bound``, and its curvature field."""
    dx = qx - mx
    dy = qy - my
    return (
        clip((mcb * dx + msb * dy) / scale, -bound, bound),
        clip((mcb * dy - msb * dx) / scale, -bound, bound),
        curvature_feature(q_k, l3),
    )


def speed_observations(
    v_ref: Real, v_ahead: Real, v_meas: Real, mw1: Real, mw2: Real, v_max: float, w_max: float
) -> tuple[Real, Real, Real, Real, Real]:
    """The speed fields: ``v_ref / v_max``, ``v_ahead / v_max``, ``clip((v_meas - v_ref) / v_max, +-2)`` and
    ``clip(w_i / w_max, +-2)`` of the measured wheel rates."""
    return (
        v_ref / v_max,
        v_ahead / v_max,
        clip((v_meas - v_ref) / v_max, -2.0, 2.0),
        clip(mw1 / w_max, -2.0, 2.0),
        clip(mw2 / w_max, -2.0, 2.0),
    )


def check_feasible(p: TrackingParams, path: Any) -> dict[str, Any]:
    """Check a fixed path against the nominal robot's wheel rate and rotational ramp (none with ``ideal_actuators``)
    at the highest reference speed (:func:`amigo_gym.paths.feasibility`); apply ``p.feasibility`` to a problem.
    Returns the report (:meth:`amigo_gym.paths.Feasibility.report`)."""
    # cached for a ClothoidPath (frozen: its value is its key); a user's path object is analysed each time
    analyse = _feasibility if type(path) is ClothoidPath else _feasibility.__wrapped__
    f = analyse(path, p.speed_range[1], p.robot, None if p.ideal_actuators else p.actuators.rot_acceleration)
    _apply_feasibility(p, None if f.feasible else f.message(), stacklevel=4)
    return f.report()


def _apply_feasibility(p: TrackingParams, problem: str | None, stacklevel: int) -> None:
    """``p.feasibility`` on a problem: ``"error"`` raises one line, ``"warn"`` warns, ``"off"`` runs."""
    if problem is None or p.feasibility == "off":
        return
    if p.feasibility == "error":
        raise ValueError(f"{problem} (feasibility='warn' or 'off' runs it anyway)")
    warnings.warn(f"AmigoBot-v1: {problem}; running it (feasibility='warn')", UserWarning, stacklevel=stacklevel)


@lru_cache(maxsize=256)
def _feasibility(path: Any, v: float, robot: RobotParams, rot: float | None) -> Feasibility:
    """:func:`amigo_gym.paths.feasibility` at the speed ``v`` [m/s] of A, ramp limit ``rot`` [rad/s^2] or None."""
    return feasibility(path, v, robot, "A", max_rotational_acceleration=rot)


#: values of ``info["end_condition"]``: none (going on or truncated), H within ``goal_tolerance`` of an open path's end
#: point, H past that end, H farther than ``termination_distance`` from the path (the first that applies)
END_CONDITIONS: tuple[str, ...] = ("", "goal", "end_of_path", "off_path")


def goal_point(p: TrackingParams, path: Any) -> tuple[float, float]:
    """The end point ``(x, y)`` [m] of an open ``path`` when ``p.goal_tolerance > 0``, else ``(nan, nan)``."""
    if p.goal_tolerance <= 0.0 or bool(path.closed):
        return math.nan, math.nan
    q = path.pose_columns(float(path.length))
    return float(q.x), float(q.y)


def goal_reached(p: TrackingParams, hx: Real, hy: Real, gx: Real, gy: Real) -> Any:
    """``(hx - gx)^2 + (hy - gy)^2 <= goal_tolerance^2`` [m^2] (False for a NaN goal)."""
    dx = hx - gx
    dy = hy - gy
    return dx * dx + dy * dy <= p.goal_tolerance * p.goal_tolerance


class Envelope(NamedTuple):
    """A family's bounds of ``|kappa|`` [1/m] and ``|dkappa/ds|`` [1/m^2] over its paths; ``what``: its parameters."""

    family: str
    max_curvature: float
    max_curvature_rate: float
    what: str


def _segment_bounds(path: Any) -> tuple[float, float]:
    k = max(max(abs(g.curvature), abs(g.curvature + g.curvature_rate * g.length)) for g in path.segments)
    c = max(abs(g.curvature_rate) for g in path.segments)
    return float(k), float(c)


def drawn_envelopes(p: TrackingParams) -> list[Envelope]:
    """The :class:`Envelope` of every family ``path="random"`` or ``"mixed"`` draws (else ``[]``).

    Random paths: ``|kappa| <= max_curvature``, ``|dkappa/ds| <= min(max_curvature_rate, 2 max_curvature /
    min_piece)``. Mixed adds circles of radius >= 0.5 m and the sharpest figure-8 and lane change of
    :data:`MIXED_RANGES` (read from their segments).
    """
    if p.path not in ("random", "mixed"):
        return []
    vals = {k: r.default for k, r in RANDOM_RANGES.items()} | dict(p.path_params)
    kmax = vals["max_curvature"]
    rate = min(vals["max_curvature_rate"], 2.0 * kmax / vals["min_piece"])
    what = f"max_curvature {kmax:g} 1/m, max_curvature_rate {vals['max_curvature_rate']:g} 1/m^2"
    out = [Envelope("random", kmax, rate, what)]
    if p.path == "mixed":
        r_min = MIXED_RANGES["circle"]["radius"][0]
        out.append(Envelope("circle", 1.0 / r_min, 0.0, f"radius {r_min:g} m"))
        size = MIXED_RANGES["figure8"]["size"][0]
        k8, c8 = _segment_bounds(_cached_family("figure8", (("size", size),)))
        out.append(Envelope("figure8", k8, c8, f"size {size:g} m"))
        off = max(abs(x) for x in MIXED_RANGES["lane_change"]["offset"])
        length = MIXED_RANGES["lane_change"]["length"][0]
        kl, cl = _segment_bounds(_cached_family("lane_change", (("length", length), ("offset", off))))
        out.append(Envelope("lane_change", kl, cl, f"offset {off:g} m over length {length:g} m"))
    return out


def envelope_needs(e: Envelope, speed: float, robot: RobotParams) -> tuple[float, float]:
    r"""Upper bounds of the wheel rate [rad/s] and rotational acceleration [rad/s^2] the exact inverse solution needs
    on any path within ``e`` at the constant speed ``speed`` [m/s] of A; ``inf`` when H may fall 90 degrees behind.

    With ``sigma = kappa_max l3 < 1`` bounding ``|sin psi|`` of the heading lag and ``c = sqrt(1 - sigma^2)``:

    .. math::
        |\dot\alpha_i| \le \frac{v + l_1 v \sigma / (l_3 c)}{\min(r_1, r_2)}, \qquad
        |\ddot\beta| \le \frac{v^2 c_{max}}{c^4}.
    """
    sigma = e.max_curvature * robot.l3
    if sigma >= 1.0:
        return math.inf, math.inf
    c = math.sqrt(1.0 - sigma * sigma)
    wheel = (speed + robot.l1 * speed * sigma / (robot.l3 * c)) / min(robot.r1, robot.r2)
    rot = speed * speed * e.max_curvature_rate / c**4
    return wheel, rot


def feasible_random_curvature(
    speed: float,
    robot: RobotParams | None = None,
    rot_acceleration: float | None = None,
    rate_per_curvature: float = 1.0,
    min_piece: float = 0.5,
) -> float:
    r"""The largest ``max_curvature`` [1/m] of ``path="random"`` with ``max_curvature_rate = rho max_curvature``
    (``rho = rate_per_curvature`` [1/m], in (0, 1e3]) whose :func:`envelope_needs` at the speed ``speed`` [m/s] of A
    stay within ``robot.max_wheel_rate`` and ``rot_acceleration`` [rad/s^2] (default 0.87), by bisection on
    ``kappa`` in ``(0, 1/l3)`` to a relative 1e-12; ``min_piece`` [m] in [0.01, 100] bounds the rate by
    ``2 kappa / min_piece``.
    """
    robot = RobotParams() if robot is None else robot
    acc = ActuatorParams().rot_acceleration if rot_acceleration is None else rot_acceleration
    o = "feasible_random_curvature"
    check_real(o, "speed", speed, 0.0, robot.max_speed, low_open=True)
    check_real(o, "rot_acceleration", acc, 0.0, 100.0, low_open=True)
    check_real(o, "rate_per_curvature", rate_per_curvature, 0.0, 1e3, low_open=True)
    check_real(o, "min_piece", min_piece, 0.01, 100.0)
    slope = min(rate_per_curvature, 2.0 / min_piece)

    def ok(kappa: float) -> bool:
        wheel, rot = envelope_needs(Envelope("random", kappa, slope * kappa, ""), speed, robot)
        return wheel <= robot.max_wheel_rate and rot <= acc

    lo, hi = 0.0, 1.0 / robot.l3
    if not ok(1e-12 * hi):
        return 0.0
    while hi - lo > 1e-12 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def drawn_feasibility_problem(p: TrackingParams) -> str | None:
    """Why a path drawn under ``path="random"``/``"mixed"`` can need more than the robot has (:func:`envelope_needs`
    over :func:`drawn_envelopes` at the highest reference speed), as one line, or ``None``."""
    v = p.speed_range[1]
    robot = p.robot
    for e in drawn_envelopes(p):
        wheel, rot = envelope_needs(e, v, robot)
        head = f"path={p.path!r}: its {e.family} paths ({e.what}) at speed {v:g} m/s"
        if math.isinf(wheel):
            return (
                f"{head} can turn the heading 90 degrees away from the path (curvature above 1/l3 = "
                f"{1.0 / robot.l3:g} 1/m): H cannot follow them; lower max_curvature"
            )
        if wheel > robot.max_wheel_rate:
            return (
                f"{head} can need {wheel:.3g} rad/s of wheel rate, above the robot's limit of "
                f"{robot.max_wheel_rate:g} rad/s; lower the speed or the curvature"
            )
        limit = p.actuators.rot_acceleration
        if rot > limit:
            return (
                f"{head} can need {rot:.3g} rad/s^2 of rotational acceleration, above the robot's limit of "
                f"{limit:g} rad/s^2 (actuators.rot_acceleration); lower the speed or max_curvature_rate"
            )
    return None


def check_task(p: TrackingParams) -> tuple[Any, dict[str, Any] | None]:
    """The fixed path of ``p`` and its feasibility report (``None``, ``None`` for drawn paths), after applying
    ``p.feasibility`` (:func:`check_feasible`, :func:`drawn_feasibility_problem`)."""
    fixed = fixed_path(p)
    if fixed is not None:
        return fixed, check_feasible(p, fixed)
    _apply_feasibility(p, drawn_feasibility_problem(p), stacklevel=3)
    return None, None


#: ranges of the family parameters drawn per episode by ``path="mixed"``
MIXED_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "circle": {"radius": (0.5, 3.0)},
    "figure8": {"size": (3.0, 6.0)},
    "lane_change": {"offset": (-1.0, 1.0), "length": (3.0, 6.0)},
}


def fixed_path(p: TrackingParams) -> Any:
    """The path of a task whose path is not drawn per episode, else ``None`` (``"random"`` and ``"mixed"``)."""
    if not isinstance(p.path, str):
        return p.path
    if p.path in ("circle", "manoeuvre"):  # (path_params: sorted pairs)
        return _cached_family(p.path, (("direction", p.direction), ("radius", p.radius), *p.path_params))
    return _cached_family(p.path, p.path_params) if p.path in ("figure8", "lane_change") else None


#: bytes of family paths a process keeps built (the least recently used dropped beyond it)
PATH_CACHE_BYTES = 64 * 2**20
_FAMILY_CACHE: OrderedDict[tuple[Any, ...], tuple[Any, int]] = OrderedDict()
_cache_bytes = 0


def path_nbytes(path: Any) -> int:
    """An estimate of the memory of a built :class:`amigo_gym.paths.ClothoidPath` [bytes]."""
    return int(path._t.flat.nbytes) + 400 * len(path.segments) + 2048


def _cached_family(
    name: str, items: tuple[tuple[str, Any], ...], rng_seed: int | None = None, loops: PathLoops | None = None
) -> Any:
    """A family path, built once per process for each parameter set (and seed), within :data:`PATH_CACHE_BYTES`."""
    global _cache_bytes
    key = (name, items) if rng_seed is None else (name, (("id", rng_seed), *items))
    got = _FAMILY_CACHE.get(key)
    if got is not None:
        _FAMILY_CACHE.move_to_end(key)
        return got[0]
    rng = None if rng_seed is None else np.random.default_rng(rng_seed)
    path = make_family_path(name, rng, loops=loops, **dict(items))
    size = path_nbytes(path)
    _FAMILY_CACHE[key] = (path, size)
    _cache_bytes += size
    while _cache_bytes > PATH_CACHE_BYTES and len(_FAMILY_CACHE) > 1:
        _, (_, old) = _FAMILY_CACHE.popitem(last=False)
        _cache_bytes -= old
    return path


def random_pool_path(p: TrackingParams, path_id: int, loops: PathLoops | None = None) -> Any:
    """Random path number ``path_id`` of the pool: ``random_path(default_rng(path_id), **path_params)``, cached."""
    return _cached_family("random", p.path_params if p.path in ("random", "mixed") else (), path_id, loops)


def draw_path(
    rng: np.random.Generator, p: TrackingParams, loops: PathLoops | None = None
) -> tuple[Any, dict[str, Any]]:
    """The episode's path and its ``info`` description (family, parameters), drawn from ``rng`` for ``"random"`` and
    ``"mixed"`` (:func:`draw_family`). ``loops``: the compiled path-building loops or None (the same path either
    way)."""
    if not isinstance(p.path, str) or p.path not in ("random", "mixed"):
        fam = p.path if isinstance(p.path, str) else getattr(p.path, "name", type(p.path).__name__)
        return fixed_path(p), {"family": fam}
    info = draw_family(rng, p)
    if info["family"] == "random":
        return random_pool_path(p, info["id"], loops), info
    # continuous parameters do not repeat: built, not cached
    return FAMILIES[info["family"]].build(loops=loops, **{k: v for k, v in info.items() if k != "family"}), info


def draw_family(rng: np.random.Generator, p: TrackingParams) -> dict[str, Any]:
    """The description of the path of ``path="random"`` or ``"mixed"`` drawn from ``rng``: ``{"family": "random",
    "id": pool number}`` or a family of :data:`MIXED_FAMILIES` with its drawn parameters (:data:`MIXED_RANGES`; a
    circle's ``direction`` +-1)."""
    fam = "random" if p.path == "random" else MIXED_FAMILIES[int(rng.integers(len(MIXED_FAMILIES)))]
    if fam == "random":
        return {"family": "random", "id": int(rng.integers(p.random_pool))}
    values: dict[str, Any] = {name: float(rng.uniform(lo, hi)) for name, (lo, hi) in MIXED_RANGES[fam].items()}
    if fam == "circle":
        values["direction"] = 1 if int(rng.integers(2)) == 0 else -1
    return {"family": fam, **values}


def episode_draws(p: TrackingParams) -> tuple[list[tuple[float, float]], bool]:
    """The intervals ``(lo, hi)`` of :func:`draw_episode`'s uniform draws before ``u`` (speed, then
    :class:`~amigo_gym.model.randomization.EpisodeDraw`'s fields; none drawn where ``lo == hi``) and whether it draws
    a key."""
    r = p.randomize
    return [p.speed_range, *intervals(r)], r.has_noise or not p.ideal_actuators


def draw_episode(rng: np.random.Generator, p: TrackingParams) -> tuple[Episode, tuple[float, float, float]]:
    """Draw one episode (:class:`Episode` of floats) and the start offsets ``u ~ U[-1, 1]^3`` from ``rng``, in this
    order: speed (when a range), randomisation, ``u``, the key of the per-step draws (0, not drawn, with
    ``ideal_actuators`` and no noise); :func:`episode_draws`."""
    (lo, hi), keyed = p.speed_range, episode_draws(p)[1]
    v = lo if lo == hi else float(rng.uniform(lo, hi))
    d = sample(rng, p.randomize)
    u0, u1, u2 = rng.uniform(-1.0, 1.0, size=3).tolist()
    return episode_of(p, v, d, draw_key(rng) if keyed else 0), (u0, u1, u2)


def episode_of(p: TrackingParams, v: Real, d: Any, key: Any) -> Episode:
    """The :class:`Episode` of the speed ``v`` [m/s], the randomisation ``d`` (an
    :class:`~amigo_gym.model.randomization.EpisodeDraw`) and the ``key``: floats, or columns (``lag`` int64)."""
    true = p.robot if p.true_robot is None else p.true_robot  # the simulated robot before randomisation
    delay = p.actuators.delay + d.delay
    lag, t_switch = actuators.delay_split(where(delay > actuators.MAX_DELAY, actuators.MAX_DELAY, delay), p.dt)
    t_brake = p.profile_duration - v / p.profile_decel if p.speed_profile == "trapezoid" else math.inf
    return Episode(
        r1=true.r1 * d.r1_scale,
        r2=true.r2 * d.r2_scale,
        l1=true.l1 * d.track_scale,
        l3=true.l3,
        slip_max=d.slip_max,
        lag=lag,
        t_switch=t_switch,
        key=key,
        v_cruise=v,
        t_brake=t_brake,
    )


def episode_template(p: TrackingParams) -> Episode | None:
    """The one episode :func:`draw_episode` gives when it draws only ``u`` (AmigoBot-v0's settings), else ``None``."""
    lo, hi = p.speed_range
    if lo != hi or not p.ideal_actuators or p.randomize.has_noise:  # (ideal actuators: no randomised range)
        return None
    return draw_episode(np.random.default_rng(0), p)[0]


#: ``(path, x, y, hint) -> progress``: H's progress [m] at ``(x, y)``, as ``path.locate`` gives it
ProgressFn = Callable[[Any, Any, Any, Any], Real]
#: ``(path, s) -> PathPose``: the path's pose at the arc length ``s`` [m], as ``path.pose_columns(s)``
PoseFn = Callable[[Any, Any], Any]


def _progress(k: Constants, path: Any, x: Real, y: Real, hint: Real, progress: ProgressFn | None) -> Real:
    if progress is not None:
        return progress(path, x, y, hint)
    s_h: Real = path.locate(x, y, hint, k.window, k.window).progress
    return s_h


def start_offsets(
    x: Real, y: Real, theta: Real, u: tuple[Real, Real, Real], position_noise: float, heading_noise: float
) -> tuple[Real, Real, Real]:
    """H's start ``(x + u0 position_noise, y + u1 position_noise)`` [m] and heading ``theta + u2 heading_noise``
    [rad] from the path's start ``(x, y, theta)`` and the draws ``u`` in [-1, 1]."""
    return x + u[0] * position_noise, y + u[1] * position_noise, theta + u[2] * heading_noise


def start_state(
    k: Constants,
    path: Any,
    ep: Episode,
    u: tuple[Real, Real, Real],
    progress: ProgressFn | None = None,
    path_pose: PoseFn | None = None,
) -> State:
    """The start state: H at the path's start plus ``u[:2] init_position_noise`` [m], heading along the tangent plus
    ``u[2] init_heading_noise`` [rad], A ``l3`` (true) behind H; wheels at rest (or rolling at the reference speed),
    angles 0, the previous command the wheels' state. ``progress``, ``path_pose``: compiled twins (default the path's
    methods)."""
    p = k.params
    start = path.pose_columns(0.0 * u[0]) if path_pose is None else path_pose(path, 0.0 * u[0])
    hx, hy, beta = start_offsets(start.x, start.y, start.theta, u, p.init_position_noise, p.init_heading_noise)
    ax, ay = a_from_h(hx, hy, col_cos(beta), col_sin(beta), ep.l3)
    zero = 0.0 * u[0]
    if p.start_at_rest:
        w1 = w2 = zero
    else:
        w1, w2 = actuators.wheel_rates_columns(reference_speed(p, ep, zero), zero, k.nominal)
    s_h = _progress(k, path, hx, hy, zero, progress)
    return State(ax, ay, beta, w1, w2, zero, zero, s_h, w1 / k.w_max, w2 / k.w_max, 0)


def step_columns(
    k: Constants, path: Any, state: State, ep: Episode, ring: NDArray[np.float64], ring_step: int, a1: Real, a2: Real
) -> tuple[State, Outcome, Any]:
    """One step: clip the action; with ``ideal_actuators`` hold the setpoints ``w_i = a_i w_max`` [rad/s] over
    ``dt`` (the pose advances by the exact arc, the heading bounded as AmigoBot-v0's), else write them into the
    command ``ring`` (``(L, 2)`` or ``(N, L, 2)``, in place, at ``ring_step``), read those in effect after the delay
    and take the exact actuator step with the step's slip; then evaluate the new state (:func:`evaluate_columns`).
    Returns the new state, its :class:`Outcome`, the draws (:class:`~amigo_gym.model.randomization.StepNoise`).
    """
    p = k.params
    dt = p.dt
    c1, c2, cmd1, cmd2 = action_commands(a1, a2, k.w_max)
    noise = randomization.step_noise(ep.key, state.steps, p.randomize, ep.slip_max)
    heading: tuple[Real, Real] | None = None
    if p.ideal_actuators:
        v, bdot = body_velocity_columns(cmd1, cmd2, k.nominal)
        arc = arc_step(state.x, state.y, state.beta, v, bdot, dt)
        x, y, beta, w1, w2, heading = arc.x, arc.y, bound_angle(arc.beta), cmd1, cmd2, (arc.cos_beta, arc.sin_beta)
        alpha1, alpha2 = advance_angle(state.alpha1, cmd1, dt), advance_angle(state.alpha2, cmd2, dt)
    else:
        actuators.ring_write(ring, ring_step, cmd1, cmd2)
        o1, o2, n1, n2 = actuators.ring_read(ring, ring_step, ep.lag)
        act = actuators.actuator_step(
            state.x, state.y, state.beta, state.w1, state.w2, o1, o2, n1, n2, ep.t_switch, dt, k.nominal,
            p.actuators, ep.r1, ep.r2, ep.l1, noise.slip1, noise.slip2, k.n_sub,
        )  # fmt: skip
        x, y, beta, w1, w2, v = act.x, act.y, act.beta, act.w1, act.w2, act.v_true
        alpha1, alpha2 = state.alpha1 + act.dalpha1, state.alpha2 + act.dalpha2
    steps = state.steps + 1
    new = State(x, y, beta, w1, w2, alpha1, alpha2, state.progress, c1, c2, steps)
    rates = (state.w1, state.w2)
    out, progress = evaluate_columns(k, path, new, ep, noise, v, state.a1, state.a2, steps * dt, rates, heading)
    return new._replace(progress=progress), out, noise


def evaluate_columns(
    k: Constants,
    path: Any,
    st: State,
    ep: Episode,
    noise: Any,
    v_true: Real,
    prev1: Real,
    prev2: Real,
    t: Real,
    prev_rates: tuple[Real, Real] | None = None,
    heading: tuple[Real, Real] | None = None,
) -> tuple[Outcome, Real]:
    """Observation, reward and end of the state ``st`` at time ``t`` [s] (module docstring), and H's new progress [m].

    ``prev1``, ``prev2``: the previous command; ``prev_rates``: the wheel rates before the step [rad/s] (default the
    state's own); ``heading``: ``(cos beta, sin beta)`` of the state when known.
    """
    p = k.params
    l3 = k.l3
    cb, sb = (col_cos(st.beta), col_sin(st.beta)) if heading is None else heading
    hx, hy = h_from_a(st.x, st.y, cb, sb, ep.l3)
    loc = path.locate(hx, hy, st.progress, k.window, k.window)
    e = loc.cross_track_error
    cos_psi, sin_psi = heading_error(cb, sb, loc.cos_theta, loc.sin_theta)
    v_ref = reference_speed(p, ep, t)
    cos_ss, sin_ss = steady_heading(loc.curvature, l3)
    pw1, pw2 = (st.w1, st.w2) if prev_rates is None else prev_rates
    da1, da2 = command_change(p.reward == "v0", st.w1, st.w2, pw1, pw2, st.a1, st.a2, prev1, prev2)
    change_sq, scales = da1 * da1 + da2 * da2, (p.sigma_track, p.sigma_speed, p.smooth_weight, k.smooth_scale_sq)
    terms = reward_term_columns(np.abs(e), np.abs(v_true - v_ref), cos_psi, sin_psi, cos_ss, sin_ss, change_sq, *scales)
    reward = reward_product(*terms)
    terminated, at_end = end_flags(e, p.termination_distance, path.closed, loc.status)
    mx, my, mb, mw1, mw2 = measurements(
        st.x, st.y, st.beta, st.w1, st.w2, noise.x, noise.y, noise.beta, noise.rate1, noise.rate2
    )
    if measured_differs(p.randomize.position_noise, p.randomize.heading_noise, ep_l3_differs(k, ep)):
        mcb, msb = col_cos(mb), col_sin(mb)
        mloc = path.locate(*h_from_a(mx, my, mcb, msb, l3), loc.progress, k.window, k.window)
    else:
        mcb, msb, mloc = cb, sb, loc
    m_e, m_k, m_s = mloc.cross_track_error, mloc.curvature, mloc.progress
    m_cos_psi, m_sin_psi = heading_error(mcb, msb, mloc.cos_theta, mloc.sin_theta)
    v_meas, _ = body_velocity_of(mw1, mw2, k.nominal.r1, k.nominal.r2, 2.0 * k.nominal.l1)
    if p.observation == "v0":
        obs: Any = observe_columns(
            path, p.preview, l3, p.error_scale, k.e_max, k.w_max, k.v_max, m_e, m_sin_psi, m_cos_psi, m_k, m_s,
            mw1, mw2, v_meas, v_ref,
        )  # fmt: skip
    else:
        obs = [*observe_head(m_e, m_sin_psi, m_cos_psi, m_k, l3, p.error_scale, k.e_max)]
        if type(m_s) is float and hasattr(path, "pose_floats"):  # one robot on a ClothoidPath
            ahead: list[Any] = path.pose_floats([m_s + d for d in p.preview])
        else:
            ahead = [path.pose_columns(m_s + d) for d in p.preview]
        for q, bound in zip(ahead, k.preview_bounds, strict=True):
            obs += preview_entry(mcb, msb, mx, my, q.x, q.y, q.curvature, l3, p.preview_scale, bound)
        v_ahead = reference_speed(p, ep, t + SPEED_LOOKAHEAD)
        obs += [*speed_observations(v_ref, v_ahead, v_meas, mw1, mw2, k.v_max, k.w_max), st.a1, st.a2]
    out = Outcome(tuple(obs), terms, reward, terminated, hx, hy, e, v_true, v_ref, mx, my, mb, mw1, mw2, at_end)
    return out, loc.progress


def command_change(
    wheel_rates: bool, w1: Real, w2: Real, pw1: Real, pw2: Real, a1: Real, a2: Real, pa1: Real, pa2: Real
) -> tuple[Real, Real]:
    """The change the smoothness term penalises: with ``wheel_rates`` (``reward="v0"``) ``(w1 - pw1, w2 - pw2)``
    [rad/s], else ``(a1 - pa1, a2 - pa2)`` [-]."""
    return (w1 - pw1, w2 - pw2) if wheel_rates else (a1 - pa1, a2 - pa2)


def ep_l3_differs(k: Constants, ep: Episode) -> bool:
    """Whether the true ``l3`` differs from the nominal."""
    l3 = ep.l3
    if type(l3) is float:
        return l3 != k.l3
    return bool(np.any(np.asarray(l3) != k.l3))


def reset_columns(k: Constants, path: Any, st: State, ep: Episode, noise: Any) -> Outcome:
    """The :class:`Outcome` of a start state (smoothness term 1: the previous command is the state's own)."""
    v_true, t = start_speed_time(st, ep)
    out, _ = evaluate_columns(k, path, st, ep, noise, v_true, st.a1, st.a2, t)
    return out


def start_speed_time(st: State, ep: Episode) -> tuple[Real, Real]:
    """The true speed of A [m/s] (no slip) and the time 0 [s] of a start state."""
    zero = 0.0 * st.x
    v, _ = body_velocity_of(st.w1, st.w2, ep.r1, ep.r2, 2.0 * ep.l1)
    return v + zero, zero


NO_NOISE = StepNoise(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class Begin(NamedTuple):
    """A new episode of one robot (:func:`begin_episode`)."""

    path: Any
    path_info: dict[str, Any]
    episode: Episode
    state: State
    outcome: Outcome


def begin_episode(rng: np.random.Generator, k: Constants, pose: tuple[float, float, float] | None = None) -> Begin:
    """Draw, start and evaluate one robot's episode (:func:`start_episode`, :func:`reset_columns`)."""
    path, info, ep, st = start_episode(rng, k, pose)
    return Begin(path, info, ep, st, reset_columns(k, path, st, ep, NO_NOISE))


def start_episode(
    rng: np.random.Generator,
    k: Constants,
    pose: tuple[float, float, float] | None = None,
    progress: ProgressFn | None = None,
    loops: PathLoops | None = None,
    path_pose: PoseFn | None = None,
) -> tuple[Any, dict[str, Any], Episode, State]:
    """``(path, path_info, episode, state)``: draw the path, then the episode, from ``rng`` and build the start state
    (``pose`` replaces the drawn pose of A). ``progress``, ``loops``, ``path_pose``: compiled twins or None."""
    path, info = draw_path(rng, k.params, loops)
    ep, u = draw_episode(rng, k.params)
    st = start_state(k, path, ep, u, progress, path_pose)
    if pose is not None:
        st = placed_state(k, path, ep, st, tuple(float(c) for c in pose), progress)
        st = st._replace(progress=float(st.progress))
    return path, info, ep, st


def placed_state(
    k: Constants, path: Any, ep: Episode, st: State, pose: tuple[Real, ...], progress: ProgressFn | None = None
) -> State:
    """The start state ``st`` with A at ``pose = (x_A, y_A, beta)`` [m, m, rad] and H's progress there."""
    x, y, b = pose
    hx, hy = h_from_a(x, y, col_cos(b), col_sin(b), ep.l3)
    return st._replace(x=x, y=y, beta=b, progress=_progress(k, path, hx, hy, 0.0, progress))
