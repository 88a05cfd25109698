r"""The AmigoBot-v1 task as pure, batched functions: settings, start, step, observation, reward, end.

``AmigoBot-v1`` is the real robot on many paths: actions are wheel-rate *setpoints* that the firmware
ramps (:mod:`amigo_gym.model.actuators`), the simulated robot may differ from the nominal one (``true_robot``,
:mod:`amigo_gym.model.randomization`), commands may arrive late, wheels may slip, and measurements may be
noisy; point H follows a path of any family (:mod:`amigo_gym.paths`). Both
:class:`amigo_gym.envs.AmigoBotV1Env` and :class:`amigo_gym.envs.AmigoBotV1VectorEnv` call the column
functions here (floats for one robot, ``(N,)`` arrays for a batch), so that they run the same code.

Observation (float32, every field named in :data:`OBS_FIELDS` order; "measured" means computed from
the noisy pose and wheel rates, with the nominal robot). ``e`` is H's signed cross-track error
(positive left), ``psi`` the heading minus the path tangent at H's closest point, ``kappa`` the path
curvature, ``(x_i, y_i)`` the path point ``d_i`` ahead of H's closest point in the robot frame (origin A,
x along the heading), ``v_ref`` the reference speed of A:

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

Reward: the product of four named terms in [0, 1] (as AmigoBot-v0's, from the *true* state):

.. math::
    r = e^{-|e|/\sigma_e} \cdot e^{-|v_A - v_{ref}|/\sigma_v} \cdot \tfrac12(1 + \cos(\psi - \psi_{ss}))
        \cdot \left(1 - w_s (1 - e^{-(\|\Delta a\|/\sigma_a)^2})\right)

``track``, ``speed``, ``heading``, ``smooth``; ``psi_ss = -asin(kappa l3)`` is the heading error of the
exact steady state, ``v_A`` the true speed of A at the end of the step and ``Delta a`` the change of the
normalised command. Ignoring the reference speed costs the speed term.

End: terminated when ``|e| > termination_distance`` (true H) or when H reaches the end of an open path;
truncated by the registration's time limit.

This module may import numpy and the core modules (params, kinematics, fresnel, actuators, paths,
randomization; :mod:`amigo_gym.logs` inside :func:`make_tracking_params`, for a robot file); never the
environments, policies, training or the CLI.
"""

from __future__ import annotations

import math
import os
import warnings
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model import actuators
from amigo_gym.model.actuators import ActuatorParams
from amigo_gym.model.kinematics import (
    Real,
    advance_angle,
    arc_step,
    body_velocity_columns,
    body_velocity_of,
    col_cos,
    col_sin,
    h_from_a,
)
from amigo_gym.model.numeric import clip
from amigo_gym.model.params import EnvParams, RobotParams, check_range, show_value
from amigo_gym.model.randomization import Randomization, StepNoise, make_randomization
from amigo_gym.paths import CirclePath, ClothoidPath, ManoeuvrePath, make_path
from amigo_gym.paths.clothoid import PathLoops
from amigo_gym.task.v0 import (
    OBS_HEAD,
    OBS_TAIL,
    bound_angle,
    curvature_feature,
    error_bound,
    heading_error,
    obs_bounds_of,
    observe_columns,
    observe_head,
    off_path,
    reward_product,
    reward_term_columns,
    steady_heading,
)

if TYPE_CHECKING:
    from amigo_gym.paths import Feasibility

#: :data:`amigo_gym.paths.STATUS_END`: the projection is clamped at an open path's end
STATUS_END = 2

REWARD_TERMS: tuple[str, ...] = ("track", "speed", "heading", "smooth")
#: names accepted by ``path=`` (or pass a path object implementing :class:`amigo_gym.paths.PathSpec`)
PATH_FAMILIES: tuple[str, ...] = ("circle", "manoeuvre", "figure8", "lane_change", "random", "mixed")
#: the families ``"mixed"`` draws from, with equal probability
MIXED_FAMILIES: tuple[str, ...] = ("circle", "figure8", "lane_change", "random")
#: how far ahead the reference speed is also observed [s]
SPEED_LOOKAHEAD = 1.0
#: smallest control period [s]: the delay ring then keeps ``ring_length(0.001) = 501`` commands per robot (8 KB;
#: :func:`amigo_gym.model.actuators.ring_length`: the whole steps of MAX_DELAY = 0.5 s, 499 in binary, plus 2)
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
#: the range checks whose low (high) end is open
_LOW_OPEN = frozenset({"radius", "profile_accel", "profile_decel", "profile_duration", "termination_distance"})
_HIGH_OPEN = frozenset({"smooth_weight"})


def _pair_or_float(owner: str, name: str, value: Any, low: float, high: float) -> float | tuple[float, float]:
    """A float in ``(low, high]`` or a pair ``(a, b)`` with ``low < a <= b <= high``."""
    if isinstance(value, (tuple, list)) and not isinstance(value, str):
        if len(value) != 2:
            raise ValueError(
                f"{owner}.{name} must be a number or a pair (low, high) in ({low:g}, {high:g}], got {value!r}"
            )
        a = check_range(owner, f"{name}[0]", value[0], low, high, low_open=True)
        b = check_range(owner, f"{name}[1]", value[1], low, high, low_open=True)
        if a > b:
            raise ValueError(f"{owner}.{name} must have low <= high, got {value!r}")
        return (a, b)
    return check_range(owner, name, value, low, high, low_open=True)


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
        speed: reference speed of A [m/s]: a number in (0, robot.max_speed] or a pair ``(low, high)``
            drawn per episode. Default 0.2.
        speed_profile: ``"constant"``, or ``"trapezoid"`` (start at 0, accelerate at ``profile_accel``,
            cruise at ``speed``, brake at ``profile_decel`` to stop at ``profile_duration``).
        profile_accel, profile_decel: the trapezoid's rates [m/s^2], within the robot's
            (``max_acceleration`` 0.3, ``max_deceleration`` 0.75). Defaults 0.2 and 0.5.
        profile_duration: time at which the trapezoid stops [s]. Default 40.
        start_at_rest: the wheels start at rest (a real robot's start); else rolling straight at the
            reference speed. Default True.
        termination_distance: the episode terminates when H is farther than this from the path [m].
        init_position_noise: half-width of the uniform start offset of H per axis [m].
        init_heading_noise: half-width of the uniform start heading offset [rad].
        error_scale: the observation divides the cross-track error by this [m].
        preview: distances ahead of H's closest point at which the path is observed [m], each in (0, 5].
        preview_scale: the observation divides preview coordinates by this [m].
        sigma_track, sigma_speed, sigma_smooth, smooth_weight: reward scales (module docstring).
        feasibility: what a fixed path the robot cannot track at the highest ``speed`` does at construction
            (:func:`check_feasible`): ``"error"`` (default) refuses it, ``"warn"`` warns and runs it, ``"off"``
            runs it silently; the report (where the path exceeds the wheel-rate or acceleration limits) is the
            env's ``feasibility`` attribute and ``info["feasibility"]`` at reset in every mode.
        goal_tolerance: an open path's episode terminates as a success when H is within this distance [m] of
            the path's end point (``info["end_condition"] == "goal"``), in [0, 10]; 0 (default): only when H
            passes the end (``"end_of_path"``).
        ideal_actuators: ``True``: the wheels take the commanded rates ``a w_max`` at once and hold them over the
            step (AmigoBot-v0's actuators; the pose advances by the exact arc). Requires no delay, no slip, no
            ``true_robot`` and no randomised geometry. Default False (the firmware's ramps).
        observation: the observation layout: ``"v1"`` (default, module table) or ``"v0"``, AmigoBot-v0's
            (:func:`amigo_gym.task.v0.obs_names`), from the measured state.
        reward: ``"v1"`` (default): the smoothness term's change is that of the normalised command over
            ``2 sigma_smooth``; ``"v0"``: AmigoBot-v0's, the change of the wheel rates over ``w_max sigma_smooth``.

    AmigoBot-v0 is the configuration :func:`v0_configuration` (``tests/test_v0_as_v1.py``).
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
            from amigo_gym.paths.points import cached_file_path, is_points_file

            if not is_points_file(self.path):
                raise ValueError(
                    f"{o}.path must be one of {list(PATH_FAMILIES)}, a points file (.csv, .json) or a path object, "
                    f"got {self.path!r}"
                )
            s(self, "path", cached_file_path(self.path))  # amigo_gym.paths.from_file, fitted once per file
        if not isinstance(self.path, str):  # a path object: checked, wrapped unless a ClothoidPath (paths.user)
            from amigo_gym.paths.user import check_path

            s(self, "path", check_path(self.path, "AmigoBot-v1"))
        # AmigoBot-v0's configuration (ideal actuators, v0's observation and reward) keeps AmigoBot-v0's ranges
        # (EnvParams's): its steps need no delay ring, so dt in [1e-6, 2] s
        v0 = self.ideal_actuators and self.observation == "v0" and self.reward == "v0"
        r = self.robot
        sigma_high = 1e6 if v0 else 10.0
        ranges = (
            ("dt", *((1e-6, 2.0) if v0 else (MIN_DT, 1.0))),
            ("radius", r.l3, 1e3),
            ("profile_accel", 0.0, r.max_acceleration),
            ("profile_decel", 0.0, r.max_deceleration),
            ("profile_duration", 0.0, 1e5),
            ("termination_distance", 0.0, 10.0),
            ("init_heading_noise", 0.0, math.pi / 4),
            ("error_scale", 1e-6 if v0 else 1e-4, 10.0),
            ("preview_scale", 1e-2, 10.0),
            ("sigma_track", 1e-6, sigma_high),
            ("sigma_speed", 1e-6, sigma_high),
            ("sigma_smooth", 1e-6, sigma_high),
            ("smooth_weight", 0.0, 1.0),
            ("goal_tolerance", 0.0, 10.0),
        )
        for name, low, high in ranges:
            value = getattr(self, name)
            s(
                self,
                name,
                check_range(o, name, value, low, high, low_open=name in _LOW_OPEN, high_open=name in _HIGH_OPEN),
            )
        high = self.termination_distance / 2
        s(self, "init_position_noise", check_range(o, "init_position_noise", self.init_position_noise, 0.0, high))
        if isinstance(self.direction, bool) or self.direction not in (1, -1):
            raise ValueError(f"{o}.direction must be +1 (left turn) or -1 (right), got {self.direction!r}")
        if isinstance(self.random_pool, bool) or not isinstance(self.random_pool, int) or self.random_pool < 1:
            raise ValueError(f"{o}.random_pool must be an integer >= 1, got {self.random_pool!r}")
        s(self, "speed", _pair_or_float(o, "speed", self.speed, 0.0, r.max_speed))
        if isinstance(self.preview, (str, bytes)) or not hasattr(self.preview, "__iter__"):
            raise ValueError(f"{o}.preview must be a sequence of distances in (0, 5] m, got {self.preview!r}")
        far, near_open = (10.0, False) if v0 else (5.0, True)  # v0's previews: [0, 10] m
        prev = (check_range(o, f"preview[{i}]", d, 0.0, far, low_open=near_open) for i, d in enumerate(self.preview))
        s(self, "preview", tuple(prev))
        s(self, "path_params", _path_params(o, self.path, self.path_params))
        _check_combined(o, self)

    @property
    def simulated_robot(self) -> RobotParams:
        """The robot that is simulated before randomisation: ``true_robot``, or the nominal one."""
        return self.robot if self.true_robot is None else self.true_robot

    @property
    def speed_range(self) -> tuple[float, float]:
        """``(low, high)`` of the reference cruise speed [m/s] (equal for a constant)."""
        sp = self.speed
        return sp if isinstance(sp, tuple) else (float(sp), float(sp))


def _path_params(owner: str, path: Any, value: Any) -> tuple[tuple[str, float], ...]:
    """``path_params`` as sorted ``(name, float)`` pairs, checked against the family of ``path`` (one-line errors).

    Accepts a mapping or a sequence of ``(name, value)`` pairs (what a JSON round trip of the pairs gives).

    Raises:
        ValueError: not a mapping or pairs; a name the family does not have; a value outside its range
            (:class:`amigo_gym.paths.ParamRange`); a parameter that would go unused (``path="mixed"``, a path
            object); ``radius``/``direction`` for circle and manoeuvre (set by the keywords of those names).
    """
    from amigo_gym.paths.families import FAMILIES, RANDOM_RANGES

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
    if path == "mixed":  # only its random family takes parameters (e.g. a curvature curriculum)
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

    ``robot`` a :class:`RobotParams` or a mapping of its fields; ``true_robot`` a mapping of the fields
    that differ from the nominal robot (or a whole ``RobotParams``, or the path of a robot file such as the
    ``robot.json`` of ``amigo-gym identify``: its ``r1``, ``r2``, ``l1`` [m] on the nominal robot, its ``delay``
    [s] and ramp rates on ``actuators``, where an ``actuators`` mapping's own fields win; :mod:`amigo_gym.logs`);
    ``actuators`` a mapping of
    :class:`ActuatorParams` fields; ``randomize`` a preset name or a mapping of :class:`Randomization` fields;
    ``path_params`` a mapping; ``params`` a whole :class:`TrackingParams` or a mapping of its fields.

    Raises:
        TypeError: an unknown keyword (listing the allowed ones).
        ValueError: a bad value, naming the field, the value and the allowed range.
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
        robot = _robot_from_mapping(owner, "robot", RobotParams(), robot)
        settings["robot"] = robot
    tr = settings.get("true_robot")
    act_file: dict[str, float] = {}
    if isinstance(tr, str | os.PathLike):
        # a robot file (robot.json of `amigo-gym identify`): r1, r2, l1 [m] and the actuators' delay [s], ramps
        from amigo_gym.logs import load_robot_file

        try:
            tr, act_file = load_robot_file(tr)
        except (FileNotFoundError, ValueError) as exc:
            raise type(exc)(f"{owner}: true_robot: {exc}") from None
    if isinstance(tr, Mapping):
        settings["true_robot"] = _robot_from_mapping(owner, "true_robot", robot, tr)
    act = settings.get("actuators")
    if act_file:
        if isinstance(act, Mapping):
            act = {**act_file, **act}  # the fields the actuators keyword names win
        else:
            act = replace(base.actuators if act is None else act, **act_file)
        settings["actuators"] = act
    if isinstance(act, Mapping):
        allowed = {f.name for f in fields(ActuatorParams)}
        bad = sorted(str(k) for k in act if k not in allowed)
        if bad:
            raise ValueError(f"{owner}: unknown actuators field(s) {bad}; allowed: {sorted(allowed)}")
        settings["actuators"] = ActuatorParams(**act)
    if "randomize" in settings:
        settings["randomize"] = make_randomization(settings["randomize"])
    if isinstance(settings.get("preview"), list):
        settings["preview"] = tuple(settings["preview"])
    if isinstance(settings.get("speed"), list):
        settings["speed"] = tuple(settings["speed"])
    return replace(base, **settings) if settings else base


def _robot_from_mapping(owner: str, name: str, base: RobotParams, values: Mapping[str, Any]) -> RobotParams:
    allowed = {f.name for f in fields(RobotParams)}
    bad = sorted(str(k) for k in values if k not in allowed)
    if bad:
        raise ValueError(f"{owner}: unknown {name} field(s) {bad}; allowed: {sorted(allowed)}")
    return replace(base, **{str(k): v for k, v in values.items()})


# --------------------------------------------------------------------------- observation layout


def obs_fields(p: TrackingParams) -> tuple[str, ...]:
    """Names of the observation's components, in order (module table; ``observation="v0"``: AmigoBot-v0's)."""
    if p.observation == "v0":
        return (*OBS_HEAD, *(f"curvature_ahead_{i + 1}" for i in range(len(p.preview))), *OBS_TAIL)
    out = list(OBS_HEAD)  # AmigoBot-v0's head: error, heading error, curvature
    for d in p.preview:
        out += [f"preview_x_{d:g}m", f"preview_y_{d:g}m", f"preview_curvature_{d:g}m"]
    speeds = ("reference_speed", "reference_speed_ahead", "speed_error", "wheel_rate_1", "wheel_rate_2")
    return (*out, *speeds, "previous_command_1", "previous_command_2")


def obs_bounds(p: TrackingParams) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Finite ``(low, high)`` bounds of the observation (module table; ``observation="v0"``: AmigoBot-v0's)."""
    if p.observation == "v0":
        return obs_bounds_of(p.termination_distance, p.error_scale, len(p.preview))
    high = [error_bound(p.termination_distance, p.error_scale), 1.0, 1.0, 1.0]
    for b in constants(p).preview_bounds:
        high += [b, b, 1.0]
    high += [1.0, 1.0, 2.0, 2.0, 2.0, 1.0, 1.0]
    hi = np.array(high)
    lo = -hi
    lo[len(high) - 7] = 0.0  # reference speed
    lo[len(high) - 6] = 0.0  # reference speed ahead
    return lo, hi


# --------------------------------------------------------------------------- constants and state


@dataclass(frozen=True)
class Constants:
    """Numbers a step needs, derived once from :class:`TrackingParams` (:func:`constants`); internal."""

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
    """Commands kept per robot in the delay ring: ``ring_length(dt)`` (delays up to ``MAX_DELAY``), or 2 with
    ``ideal_actuators`` (no delay: the ring is never read, and ``dt`` may be as small as AmigoBot-v0's 1e-6 s)."""
    return actuators.ring_length(p.dt, 0.0 if p.ideal_actuators else actuators.MAX_DELAY)


def constants(p: TrackingParams) -> Constants:
    """The :class:`Constants` of ``p``."""
    robot = p.robot
    w_max = robot.max_wheel_rate
    # the projection window: farther than H can move in one step (speed of H <= v + l3 |w|)
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
        # the smoothness term's squared scale: (2 sigma_smooth)^2 of the command's change (reward="v1"), or
        # (w_max sigma_smooth)^2 [rad^2/s^2] of the wheel rates' change (reward="v0", AmigoBot-v0's)
        smooth_scale_sq=smooth * smooth if p.reward == "v0" else 4.0 * p.sigma_smooth * p.sigma_smooth,
    )


#: the settings AmigoBot-v0's ``EnvParams`` and AmigoBot-v1's ``TrackingParams`` share, under the same name and meaning
#: (:func:`v0_settings`, :func:`v0_configuration`)
V0_SHARED_SETTINGS: tuple[str, ...] = (
    "robot",
    "dt",
    "speed",
    "termination_distance",
    "init_position_noise",
    "init_heading_noise",
    "error_scale",
    "preview",
    "sigma_track",
    "sigma_speed",
    "sigma_smooth",
    "smooth_weight",
)


def v0_settings(p: TrackingParams) -> EnvParams | None:
    """The AmigoBot-v0 task that ``p`` describes, or ``None``: the settings whose steps AmigoBot-v0's compiled
    step runs as AmigoBot-v0 (``gym.make("AmigoBot-v0")``), and whose info has AmigoBot-v0's keys.

    They are ``ideal_actuators=True, observation="v0", reward="v0"``, no measurement noise (the ideal actuators
    already exclude delay, slip, a true robot and randomised geometry), ``start_at_rest=False``, a constant
    ``speed`` with the constant profile, ``goal_tolerance=0`` and a path object equal to the path of the returned
    :class:`amigo_gym.model.params.EnvParams` (``CirclePath(radius, direction=...)`` or
    ``ManoeuvrePath(radius, straight_length, direction)``, from the origin along x0); settings that
    :class:`~amigo_gym.model.params.EnvParams` refuses (e.g. a speed the circle cannot be driven at) are not v0's.
    """
    path = p.path
    kind: Literal["circle", "manoeuvre"] = "circle" if type(path) is CirclePath else "manoeuvre"
    if (
        type(path) not in (CirclePath, ManoeuvrePath)
        or not (p.ideal_actuators and p.observation == "v0" and p.reward == "v0")
        or p.randomize.has_noise
        or p.start_at_rest
        or isinstance(p.speed, tuple)
        or p.speed_profile != "constant"
        or p.goal_tolerance != 0.0
    ):
        return None
    try:
        e = EnvParams(
            **{name: getattr(p, name) for name in V0_SHARED_SETTINGS},
            radius=path.radius,
            direction=path.direction,
            path=kind,
            straight_length=getattr(path, "straight_length", 1.0),
        )
    except ValueError:
        return None
    return e if make_path(e) == path else None


def v0_configuration(e: EnvParams) -> TrackingParams:
    """AmigoBot-v0's task ``e`` as AmigoBot-v1's settings: the inverse of :func:`v0_settings`
    (``v0_settings(v0_configuration(e)) == e``), what ``gym.make("AmigoBot-v0", ...)`` runs.

    Ideal actuators, v0's observation and reward, no randomisation, wheels rolling at the start, the path of ``e``
    as a path object (:func:`amigo_gym.paths.make_path`), ``feasibility="off"`` (``e`` is drivable:
    :class:`~amigo_gym.model.params.EnvParams` checked it) and every other setting of ``e``.
    """
    return TrackingParams(
        **{name: getattr(e, name) for name in V0_SHARED_SETTINGS},
        randomize=make_randomization("none"),
        path=make_path(e),
        radius=e.radius,
        direction=e.direction,
        start_at_rest=False,
        feasibility="off",
        ideal_actuators=True,
        observation="v0",
        reward="v0",
    )


class Episode(NamedTuple):
    """What is drawn once per episode (columns).

    Attributes:
        r1, r2, l1, l3: the true geometry [m].
        slip_max: bound of the per-step slip [-].
        lag, t_switch: the delay as whole steps and the switch time within a step [s] (``delay = lag dt + t_switch``).
        key: the key of the per-step draws (uint64).
        v_cruise: the reference cruise speed [m/s].
        t_brake: time at which the trapezoid starts braking [s] (``inf`` for a constant speed).
    """

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
    """The state of one robot or a batch (columns).

    Attributes:
        x, y, beta: true pose of A [m, m, rad].
        w1, w2: actual wheel rates [rad/s] (the actuator state).
        alpha1, alpha2: wheel angles [rad].
        progress: H's arc length along the path, unwrapped over laps [m] (the projection's hint).
        a1, a2: the previous action (normalised command) [-].
        steps: steps taken in the episode (int).
    """

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
    """What the environments report about a state (columns).

    Attributes:
        obs: the observation's columns, in :func:`obs_fields` order (float64; the envs cast to float32).
        terms: the reward terms in :data:`REWARD_TERMS` order.
        reward: their product.
        terminated: H left the path or reached an open path's end (bool columns).
        h_x, h_y: true H [m].
        error: H's true signed cross-track error [m].
        v_true: true speed of A [m/s]; v_ref: the reference speed [m/s].
        meas_x, meas_y, meas_beta: the measured pose [m, m, rad]; meas_w1, meas_w2: measured wheel rates [rad/s].
        end_of_path: H reached the end of an open path (a terminal state that is a success, not a failure).
    """

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


# --------------------------------------------------------------------------- column helpers


# The polymorphic helpers of the shared pieces below (numpy's elementwise form on columns, the float form on floats;
# the compiled step runs the float form): amigo_gym.model.numeric, one home for both tasks and the model.
_clip = clip
_min = np.minimum
_abs = np.abs


def _max0(x: Any) -> Any:
    return np.maximum(x, 0.0)


def reference_speed(p: TrackingParams, ep: Episode, t: Real) -> Real:
    r"""Reference speed of A at episode time ``t`` [s], in [m/s].

    Constant: ``v_ref = v``. Trapezoid (start, cruise, brake): :func:`reference_speed_of` with ``a_up =
    profile_accel``, ``a_down = profile_decel``, ``t_b`` = :attr:`Episode.t_brake`. Floats or columns.
    """
    trapezoid = p.speed_profile == "trapezoid"
    return reference_speed_of(trapezoid, ep.v_cruise, p.profile_accel, p.profile_decel, ep.t_brake, t)


def reference_speed_of(trapezoid: bool, v: Real, accel: float, decel: float, t_brake: Real, t: Real) -> Real:
    r""":func:`reference_speed` from numbers [m/s]: the cruise speed ``v``, or when ``trapezoid`` (start, cruise,
    brake)

    .. math:: v_{ref}(t) = \max\bigl(0, \min(a_{up} t,\; v,\; v - a_{down} (t - t_b))\bigr),
        \qquad t_b = T - v / a_{down}

    (``T = profile_duration``), the minima left to right. Floats or columns; compiled by the compiled step."""
    out: Real = _max0(_min(_min(accel * t, v), v - decel * (t - t_brake))) if trapezoid else v
    return out


# The pieces of :func:`evaluate_columns` (floats or columns; the compiled step compiles them: one source).


def action_commands(a1: Real, a2: Real, w_max: float) -> tuple[Real, Real, Real, Real]:
    """The action clipped to [-1, 1] and the setpoints it asks for: ``(c1, c2, c1 w_max, c2 w_max)`` [-, -, rad/s,
    rad/s]. Floats or columns; compiled by the compiled step."""
    c1 = _clip(a1, -1.0, 1.0)
    c2 = _clip(a2, -1.0, 1.0)
    return c1, c2, c1 * w_max, c2 * w_max


def measurements(
    x: Real, y: Real, beta: Real, w1: Real, w2: Real, nx: Real, ny: Real, nbeta: Real, nr1: Real, nr2: Real
) -> tuple[Real, Real, Real, Real, Real]:
    """The measured pose of A and wheel rates: the true ones plus the step's noise [m, m, rad, rad/s, rad/s]. Floats
    or columns; compiled by the compiled step."""
    return x + nx, y + ny, beta + nbeta, w1 + nr1, w2 + nr2


def measured_differs(position_noise: float, heading_noise: float, l3_differs: bool) -> bool:
    """Whether the measured H differs from the true one, so that it is projected on its own: noise on the position
    [m] or heading [rad], or a true ``l3`` other than the nominal (:func:`ep_l3_differs`). Compiled by the compiled
    step."""
    return position_noise > 0.0 or heading_noise > 0.0 or l3_differs


def end_flags(e: Real, termination_distance: float, closed: Any, status: Any) -> tuple[Any, Any]:
    """``(terminated, at_end)``: H is farther than ``termination_distance`` [m] from the path (``|e|``, true H) or has
    reached the end of an open path (``status`` is :data:`STATUS_END`, ``closed`` false or 0). Floats (bools) or
    columns (bool arrays); compiled by the compiled step."""
    at_end = (status == STATUS_END) & (closed == 0)
    terminated = off_path(_abs(e), termination_distance) | at_end
    return terminated, at_end


def preview_entry(
    mcb: Real, msb: Real, mx: Real, my: Real, qx: Real, qy: Real, q_k: Real, l3: float, scale: float, bound: float
) -> tuple[Real, Real, Real]:
    """One preview point's three fields: the path point ``(qx, qy)`` [m] in the measured robot frame (origin A
    ``(mx, my)``, heading cosine and sine ``mcb``, ``msb``) over ``preview_scale``, clipped to ``+-bound``, and its
    curvature field (:func:`amigo_gym.task.v0.curvature_feature`). Floats or columns; compiled by the compiled step."""
    dx = qx - mx
    dy = qy - my
    return (
        _clip((mcb * dx + msb * dy) / scale, -bound, bound),
        _clip((mcb * dy - msb * dx) / scale, -bound, bound),
        curvature_feature(q_k, l3),
    )


def speed_observations(
    v_ref: Real, v_ahead: Real, v_meas: Real, mw1: Real, mw2: Real, v_max: float, w_max: float
) -> tuple[Real, Real, Real, Real, Real]:
    """The observation's speed fields: ``v_ref / v_max``, ``v_ref(t + lookahead) / v_max``, ``clip((v_meas -
    v_ref) / v_max, +-2)``, ``clip(w_i / w_max, +-2)`` of the measured wheel rates. Floats or columns; compiled by
    the compiled step."""
    return (
        v_ref / v_max,
        v_ahead / v_max,
        _clip((v_meas - v_ref) / v_max, -2.0, 2.0),
        _clip(mw1 / w_max, -2.0, 2.0),
        _clip(mw2 / w_max, -2.0, 2.0),
    )


# --------------------------------------------------------------------------- paths


def check_feasible(p: TrackingParams, path: Any) -> dict[str, Any]:
    """Check a task against what the nominal robot has; refuse it (one-line ``ValueError``), warn or say nothing
    as ``p.feasibility`` says (``"error"``, ``"warn"``, ``"off"``).

    Checks the wheel rate (``robot.max_wheel_rate``) and the rotational speed ramp
    (``actuators.rot_acceleration``; none with ``ideal_actuators``, whose accelerations are unbounded) at the
    highest reference speed, with the exact heading lag of H (:func:`amigo_gym.paths.feasibility`), and the
    trapezoid's rates against the robot's ramps.

    Returns:
        the report (:meth:`amigo_gym.paths.Feasibility.report`): ``feasible``, ``message``, the peaks and, in
        ``exceeded``, the arc-length intervals [m] where each limit is exceeded.
    """
    # remembered per process for a ClothoidPath (frozen: its value is its key; every env of a vector of single envs
    # checks the same task, an RK4 lag profile of tens of ms); another path object (a user's) analysed each time
    analyse = _feasibility if type(path) is ClothoidPath else _feasibility.__wrapped__
    f = analyse(path, p.speed_range[1], p.robot, None if p.ideal_actuators else p.actuators.rot_acceleration)
    _apply_feasibility(p, None if f.feasible else f.message(), stacklevel=4)
    return f.report()


def _apply_feasibility(p: TrackingParams, problem: str | None, stacklevel: int) -> None:
    """Apply ``p.feasibility`` to a problem: ``"error"`` raises a one-line ``ValueError``, ``"warn"`` warns and
    runs, ``"off"`` runs."""
    if problem is None or p.feasibility == "off":
        return
    if p.feasibility == "error":
        raise ValueError(f"{problem} (feasibility='warn' or 'off' runs it anyway)")
    warnings.warn(f"AmigoBot-v1: {problem}; running it (feasibility='warn')", UserWarning, stacklevel=stacklevel)


@lru_cache(maxsize=256)
def _feasibility(path: Any, v: float, robot: RobotParams, rot: float | None) -> Feasibility:
    """:func:`amigo_gym.paths.feasibility` of ``path`` at the speed ``v`` [m/s] of A, with the ramp limit ``rot``
    [rad/s^2] (``None``: unbounded)."""
    from amigo_gym.paths import feasibility

    return feasibility(path, v, robot, "A", max_rotational_acceleration=rot)


#: values of ``info["end_condition"]``: ``""`` the episode goes on (or ended by truncation), ``"goal"`` H came within
#: ``goal_tolerance`` of an open path's end point, ``"end_of_path"`` H passed that end, ``"off_path"`` H was farther
#: than ``termination_distance`` from the path (the first that applies, in this order)
END_CONDITIONS: tuple[str, ...] = ("", "goal", "end_of_path", "off_path")


def goal_point(p: TrackingParams, path: Any) -> tuple[float, float]:
    """The end point ``(x, y)`` [m] of an open ``path`` when ``p.goal_tolerance > 0``; else ``(nan, nan)``, which
    no H reaches (:func:`goal_reached`)."""
    if p.goal_tolerance <= 0.0 or bool(path.closed):
        return math.nan, math.nan
    q = path.pose_columns(float(path.length))
    return float(q.x), float(q.y)


def goal_reached(p: TrackingParams, hx: Real, hy: Real, gx: Real, gy: Real) -> Any:
    """Whether H ``(hx, hy)`` is within ``p.goal_tolerance`` of the goal ``(gx, gy)`` [m] (:func:`goal_point`):
    ``(hx - gx)^2 + (hy - gy)^2 <= goal_tolerance^2`` (False for a NaN goal). Floats or columns."""
    dx = hx - gx
    dy = hy - gy
    return dx * dx + dy * dy <= p.goal_tolerance * p.goal_tolerance


def end_condition(terminated: bool, end_of_path: bool, goal: bool) -> str:
    """The entry of :data:`END_CONDITIONS` for one robot's step."""
    if goal:
        return "goal"
    if end_of_path:
        return "end_of_path"
    return "off_path" if terminated else ""


class Envelope(NamedTuple):
    """Bounds of the paths a drawn task can give (:func:`drawn_envelopes`).

    Attributes:
        family: the family's name.
        max_curvature: bound of ``|kappa|`` over its paths [1/m].
        max_curvature_rate: bound of ``|dkappa/ds|`` [1/m^2].
        what: the parameters, for messages.
    """

    family: str
    max_curvature: float
    max_curvature_rate: float
    what: str


def _segment_bounds(path: Any) -> tuple[float, float]:
    """``max |kappa|`` and ``max |dkappa/ds|`` over the segments of a :class:`amigo_gym.paths.ClothoidPath`."""
    k = max(max(abs(g.curvature), abs(g.curvature + g.curvature_rate * g.length)) for g in path.segments)
    c = max(abs(g.curvature_rate) for g in path.segments)
    return float(k), float(c)


def drawn_envelopes(p: TrackingParams) -> list[Envelope]:
    """Curvature and curvature-rate bounds of every path ``path="random"`` or ``"mixed"`` can draw (else ``[]``).

    * random paths (:func:`amigo_gym.paths.random_path`): ``|kappa| <= max_curvature`` and ``|dkappa/ds| <=
      min(max_curvature_rate, 2 max_curvature / min_piece)`` (a ramp changes the curvature by at most
      ``2 max_curvature`` over at least ``min_piece``);
    * mixed: circles of radius >= 0.5 m; figure-8s and lane changes at the corner of :data:`MIXED_RANGES` where
      they are sharpest (the smallest figure-8, the largest offset over the shortest length: shrinking a path
      by a factor scales its curvature up by that factor and its rate by the square), read from the segments
      of those paths; and its random paths (the defaults, or ``path_params``, which apply to them only).
    """
    from amigo_gym.paths.families import RANDOM_RANGES

    if p.path in ("random", "mixed"):
        vals = {k: r.default for k, r in RANDOM_RANGES.items()} | dict(p.path_params)
    else:
        return []
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
    r"""Upper bounds of the wheel rate [rad/s] and rotational acceleration [rad/s^2] that the exact inverse solution
    needs on any path within the envelope ``e`` at the constant speed ``speed`` of A (as
    :func:`amigo_gym.paths.feasibility` computes them on one path); ``inf`` when H may fall 90 degrees behind.

    With the heading lag ``psi`` of :func:`amigo_gym.paths.heading_lag_profile`,
    ``dpsi/ds = u = kappa - sin(psi) / l3``, starting from the quasi-steady lag (``u = 0``) on a path of continuous
    curvature: ``sin psi`` can only move towards ``kappa l3``, so ``|sin psi| <= sigma = kappa_max l3`` (needs
    ``sigma < 1``), and ``du/ds = kappa' - (cos(psi) / l3) u`` keeps ``|u| <= c_max l3 / c`` with
    ``c = sqrt(1 - sigma^2) <= cos psi``. Then, with ``v_H = v / cos psi``,
    ``betadot = v tan(psi) / l3`` and ``betaddot = v^2 u / (l3 cos^3 psi)``:

    .. math::
        |\dot\alpha_i| \le \frac{v + l_1 v \sigma / (l_3 c)}{\min(r_1, r_2)}, \qquad
        |\ddot\beta| \le \frac{v^2 c_{max}}{c^4}.

    Both are reached on a long enough arc of curvature ``kappa_max`` and a long enough ramp at rate ``c_max``
    (e.g. 16.8 rad/s and 0.57 rad/s^2 for the default random paths at 0.75 m/s, where the peaks of 100 pool paths
    reach 16.80 and 0.568).
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
    r"""The largest ``max_curvature`` [1/m] of ``path="random"`` paths with ``max_curvature_rate = rate_per_curvature
    max_curvature`` that the environments accept at the constant speed ``speed`` [m/s] of A
    (:func:`drawn_feasibility_problem`: :func:`envelope_needs` within ``robot.max_wheel_rate`` and
    ``rot_acceleration``).

    With ``sigma = kappa l3``, ``c = sqrt(1 - sigma^2)`` and the envelope's rate ``c_max = min(rho, 2 / min_piece)
    kappa`` (``rho = rate_per_curvature`` [1/m]), both needs grow with ``kappa``:

    .. math::
        \frac{v (1 + l_1 \sigma / (l_3 c))}{\min(r_1, r_2)} \le \dot\alpha_{max}, \qquad
        \frac{v^2 c_{max}}{c^4} \le \ddot\beta_{max},

    so the limit is found by bisection on ``kappa`` in ``(0, 1/l3)`` (to a relative 1e-12). The default ratio
    ``rho = 1`` 1/m is the random family's (``max_curvature`` 1 1/m, ``max_curvature_rate`` 1 1/m^2). E.g. 10.1 1/m at
    0.1 m/s and 4.26 1/m at 0.4 m/s on the nominal AmigoBot (the rotational ramp binds at both).

    Args:
        speed: A's reference speed [m/s], in (0, robot.max_speed]. robot: the nominal robot (default
            :class:`RobotParams`). rot_acceleration: the ramp of the rotational speed [rad/s^2] (default
            :class:`ActuatorParams`'s 0.87). rate_per_curvature: ``rho`` [1/m], in (0, 1e3]. min_piece: the random
            family's ``min_piece`` [m], in [0.01, 100].
    """
    robot = RobotParams() if robot is None else robot
    acc = ActuatorParams().rot_acceleration if rot_acceleration is None else rot_acceleration
    o = "feasible_random_curvature"
    check_range(o, "speed", speed, 0.0, robot.max_speed, low_open=True)
    check_range(o, "rot_acceleration", acc, 0.0, 100.0, low_open=True)
    check_range(o, "rate_per_curvature", rate_per_curvature, 0.0, 1e3, low_open=True)
    check_range(o, "min_piece", min_piece, 0.01, 100.0)
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
    """Why a path drawn under ``path="random"``/``"mixed"`` settings can need more than the robot has, or ``None``.

    The same limits as :func:`check_feasible` (``robot.max_wheel_rate``, ``actuators.rot_acceleration``) at the
    highest reference speed, with the bounds of :func:`envelope_needs` over :func:`drawn_envelopes`: a task without a
    problem draws only paths that :func:`check_feasible` would accept. One line naming the family, its parameters,
    the need and the limit.
    """
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
    """The fixed path of ``p`` (:func:`fixed_path`, ``None`` when drawn) and its feasibility report (``None`` for
    drawn paths), after applying ``p.feasibility``: :func:`check_feasible` on a fixed path,
    :func:`drawn_feasibility_problem` on drawn ones."""
    fixed = fixed_path(p)
    if fixed is not None:
        return fixed, check_feasible(p, fixed)
    _apply_feasibility(p, drawn_feasibility_problem(p), stacklevel=3)
    return None, None


#: ranges of the family parameters drawn per episode by ``path="mixed"`` (the environments check at construction
#: that every path they can draw is feasible at the highest reference speed: :func:`drawn_feasibility_problem`)
MIXED_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "circle": {"radius": (0.5, 3.0)},
    "figure8": {"size": (3.0, 6.0)},
    "lane_change": {"offset": (-1.0, 1.0), "length": (3.0, 6.0)},
}


def fixed_path(p: TrackingParams) -> Any:
    """The path of a task whose path is not drawn per episode, else ``None`` (``"random"`` and ``"mixed"``)."""
    if not isinstance(p.path, str):
        return p.path
    extra = tuple(sorted(dict(p.path_params).items()))
    if p.path in ("circle", "manoeuvre"):
        return _cached_family(p.path, (("direction", p.direction), ("radius", p.radius), *extra))
    return _cached_family(p.path, extra) if p.path in ("figure8", "lane_change") else None


#: bytes of family paths a process keeps built (:func:`_cached_family`): 64 MiB, e.g. the whole default random pool
#: (1024 paths of about 25 KB) with room to spare; the least recently used paths are dropped beyond it
PATH_CACHE_BYTES = 64 * 2**20
_FAMILY_CACHE: OrderedDict[tuple[Any, ...], tuple[Any, int]] = OrderedDict()
_cache_bytes = 0


def path_nbytes(path: Any) -> int:
    """An estimate of the memory of a built :class:`amigo_gym.paths.ClothoidPath` [bytes]: its tables' arrays, about
    400 bytes per segment and 2 KiB for the objects (within a factor 2 of ``tracemalloc``'s count,
    ``tests/test_bad_inputs_v1.py``)."""
    # the tables are one flat vector (their arrays are views of it)
    return int(path._t.flat.nbytes) + 400 * len(path.segments) + 2048


def _cached_family(
    name: str, items: tuple[tuple[str, Any], ...], rng_seed: int | None = None, loops: PathLoops | None = None
) -> Any:
    """A family path, built once per process for each parameter set (and seed of a random one) and kept within
    :data:`PATH_CACHE_BYTES` (least recently used dropped first). ``loops``: as :func:`draw_path`."""
    from amigo_gym.paths import make_family_path

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
    """Random path number ``path_id`` of the pool: ``random_path(default_rng(path_id), **path_params)``, cached
    (``loops``: as :func:`draw_path`)."""
    extra = tuple(sorted(dict(p.path_params).items())) if p.path in ("random", "mixed") else ()
    return _cached_family("random", extra, rng_seed=path_id, loops=loops)


def draw_path(
    rng: np.random.Generator, p: TrackingParams, loops: PathLoops | None = None
) -> tuple[Any, dict[str, Any]]:
    """The episode's path and its description for ``info`` (family and parameters), drawn from ``rng`` for
    ``"random"`` and ``"mixed"`` (else the fixed path, no draw). ``loops``: the compiled path-building loops
    (:func:`amigo_gym.sim.fast_v1.path_loops`) or None; the same path either way."""
    from amigo_gym.paths import make_family_path

    if not isinstance(p.path, str) or p.path not in ("random", "mixed"):
        fam = p.path if isinstance(p.path, str) else getattr(p.path, "name", type(p.path).__name__)
        return fixed_path(p), {"family": fam}
    fam = "random" if p.path == "random" else MIXED_FAMILIES[int(rng.integers(len(MIXED_FAMILIES)))]
    if fam == "random":
        pid = int(rng.integers(p.random_pool))
        return random_pool_path(p, pid, loops), {"family": "random", "id": pid}
    values: dict[str, Any] = {}
    for name, (lo, hi) in MIXED_RANGES[fam].items():
        values[name] = float(rng.uniform(lo, hi))
    if fam == "circle":
        values["direction"] = 1 if int(rng.integers(2)) == 0 else -1
    # parameters drawn from continuous ranges do not repeat: built, not cached
    return make_family_path(fam, None, loops=loops, **values), {"family": fam, **values}


# --------------------------------------------------------------------------- episodes and steps


def draw_episode(rng: np.random.Generator, p: TrackingParams) -> tuple[Episode, tuple[float, float, float]]:
    """Draw one episode's constants (:class:`Episode` of floats) and the start offsets ``u ~ U[-1, 1]^3`` from
    ``rng``, in this order: speed (when a range), randomisation (:func:`amigo_gym.model.randomization.sample`), ``u``,
    the key of the per-step draws (key 0, not drawn, with ``ideal_actuators`` and no noise)."""
    from amigo_gym.model.randomization import draw_key, sample

    lo, hi = p.speed_range
    v = lo if lo == hi else float(rng.uniform(lo, hi))
    d = sample(rng, p.randomize)
    u0, u1, u2 = rng.uniform(-1.0, 1.0, size=3).tolist()
    # (AmigoBot-v0's stream: three uniforms per episode)
    key = 0 if p.ideal_actuators and not p.randomize.has_noise else draw_key(rng)
    true = p.simulated_robot
    delay = p.actuators.delay + d.delay
    delay = min(delay, actuators.MAX_DELAY)
    lag, t_switch = actuators.delay_split(delay, p.dt)
    t_brake = p.profile_duration - v / p.profile_decel if p.speed_profile == "trapezoid" else math.inf
    ep = Episode(
        r1=true.r1 * d.r1_scale,
        r2=true.r2 * d.r2_scale,
        l1=true.l1 * d.track_scale,
        l3=true.l3,
        slip_max=d.slip_max,
        lag=int(lag),
        t_switch=float(t_switch),
        key=key,
        v_cruise=v,
        t_brake=t_brake,
    )
    return ep, (u0, u1, u2)


def episode_template(p: TrackingParams) -> Episode | None:
    """The one episode :func:`draw_episode` gives when its only draws are the start offsets ``u`` (a fixed speed, no
    randomised range, ideal actuators without noise: AmigoBot-v0's settings), else ``None``."""
    lo, hi = p.speed_range
    r = p.randomize
    if (
        lo != hi
        or not p.ideal_actuators
        or r.has_noise
        or any(a != b for a, b in (r.wheel_radius, r.track, r.slip, r.delay))
    ):
        return None
    return draw_episode(np.random.default_rng(0), p)[0]  # (the generator's draws are u alone, not in the episode)


#: ``(path, x, y, hint) -> progress``: H's progress [m] at ``(x, y)`` from the hint, as
#: ``path.locate(x, y, hint, k.window, k.window).progress`` (the single env passes its compiled twin)
ProgressFn = Callable[[Any, Any, Any, Any], Real]
#: ``(path, s) -> PathPose``: the path's pose at the arc length ``s``, as ``path.pose_columns(s)`` (the compiled step's
#: environments pass its compiled twin)
PoseFn = Callable[[Any, Any], Any]


def _progress(k: Constants, path: Any, x: Real, y: Real, hint: Real, progress: ProgressFn | None) -> Real:
    """H's progress at ``(x, y)`` from ``hint``: ``progress`` when given, else by ``path.locate``."""
    if progress is not None:
        return progress(path, x, y, hint)
    s_h: Real = path.locate(x, y, hint, k.window, k.window).progress
    return s_h


def start_state(
    k: Constants,
    path: Any,
    ep: Episode,
    u: tuple[Real, Real, Real],
    progress: ProgressFn | None = None,
    path_pose: PoseFn | None = None,
) -> State:
    """The start state: H at the path's start plus ``u[:2] * init_position_noise``, heading along the tangent
    plus ``u[2] * init_heading_noise``, A ``l3`` (true) behind H; wheels at rest (or rolling at the reference
    speed), wheel angles 0; the previous command is the wheels' state (0 at rest).

    ``progress`` replaces the projection of H (:data:`ProgressFn`; default ``path.locate``), ``path_pose`` the path's
    start pose (:data:`PoseFn`; default ``path.pose_columns``).
    """
    p = k.params
    start = path.pose_columns(0.0 * u[0]) if path_pose is None else path_pose(path, 0.0 * u[0])
    beta = start.theta + u[2] * p.init_heading_noise
    hx = start.x + u[0] * p.init_position_noise
    hy = start.y + u[1] * p.init_position_noise
    ax = hx - ep.l3 * col_cos(beta)
    ay = hy - ep.l3 * col_sin(beta)
    zero = 0.0 * u[0]
    if p.start_at_rest:
        w1 = w2 = zero
    else:
        v0 = reference_speed(p, ep, zero)
        w1, w2 = actuators.wheel_rates_columns(v0, zero, k.nominal)
    s_h = _progress(k, path, hx, hy, zero, progress)
    return State(ax, ay, beta, w1, w2, zero, zero, s_h, w1 / k.w_max, w2 / k.w_max, 0)


def step_columns(
    k: Constants, path: Any, state: State, ep: Episode, ring: NDArray[np.float64], ring_step: int, a1: Real, a2: Real
) -> tuple[State, Outcome, Any]:
    """One step of AmigoBot-v1 in column form: clip the action, write its setpoints ``a w_max`` [rad/s] into the
    command ``ring`` (``(L, 2)`` or ``(N, L, 2)``, in place, at the counter ``ring_step``) and read those in effect
    (the delay), draw the step's slip and noise, take the exact actuator step
    (:func:`amigo_gym.model.actuators.actuator_step`) and evaluate the new state (:func:`evaluate_columns`).

    Returns:
        the new state, its :class:`Outcome`, and the per-step draws (:class:`amigo_gym.model.randomization.StepNoise`).
    """
    from amigo_gym.model.randomization import step_noise

    p = k.params
    c1, c2, cmd1, cmd2 = action_commands(a1, a2, k.w_max)
    if p.ideal_actuators:
        return _ideal_step(k, path, state, ep, c1, c2, cmd1, cmd2)
    actuators.ring_write(ring, ring_step, cmd1, cmd2)
    o1, o2, n1, n2 = actuators.ring_read(ring, ring_step, ep.lag)
    noise = step_noise(ep.key, state.steps, p.randomize, ep.slip_max)
    x, y, beta, w1, w2 = state.x, state.y, state.beta, state.w1, state.w2
    slips = (noise.slip1, noise.slip2, k.n_sub)
    act = actuators.actuator_step(
        x, y, beta, w1, w2, o1, o2, n1, n2, ep.t_switch, p.dt, k.nominal, p.actuators, ep.r1, ep.r2, ep.l1, *slips
    )
    steps = state.steps + 1
    alpha1, alpha2 = state.alpha1 + act.dalpha1, state.alpha2 + act.dalpha2
    new = State(act.x, act.y, act.beta, act.w1, act.w2, alpha1, alpha2, state.progress, c1, c2, steps)
    out, progress = evaluate_columns(
        k, path, new, ep, noise, act.v_true, state.a1, state.a2, steps * p.dt, prev_rates=(state.w1, state.w2)
    )
    return new._replace(progress=progress), out, noise


def _ideal_step(
    k: Constants, path: Any, state: State, ep: Episode, c1: Real, c2: Real, w1: Real, w2: Real
) -> tuple[State, Outcome, Any]:
    r""":func:`step_columns` with ``ideal_actuators``: AmigoBot-v0's motion (its one home: AmigoBot-v0's reference).

    The wheel rates ``w_i = c_i w_max`` [rad/s] (:func:`action_commands`) are held over ``dt``; with
    ``(v, \dot\beta)`` their body velocity (nominal robot), the pose advances by the exact arc
    (:func:`amigo_gym.model.kinematics.arc_step`), whose heading cosine and sine (angle addition) the evaluation uses;
    wheel angles advance by ``w_i dt``. A heading past ``HEADING_LIMIT`` (1e6 rad) is reduced by whole turns
    (:func:`amigo_gym.task.v0.bound_angle`), as AmigoBot-v0's.
    """
    from amigo_gym.model.randomization import step_noise

    p = k.params
    dt = p.dt
    noise = step_noise(ep.key, state.steps, p.randomize, ep.slip_max)
    v, bdot = body_velocity_columns(w1, w2, k.nominal)
    arc = arc_step(state.x, state.y, state.beta, v, bdot, dt)
    steps = state.steps + 1
    alpha1 = advance_angle(state.alpha1, w1, dt)
    alpha2 = advance_angle(state.alpha2, w2, dt)
    new = State(arc.x, arc.y, bound_angle(arc.beta), w1, w2, alpha1, alpha2, state.progress, c1, c2, steps)
    rates, heading = (state.w1, state.w2), (arc.cos_beta, arc.sin_beta)
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
    """Observation, reward and end of the state ``st`` at time ``t`` (module docstring).

    The true H is projected with the hint ``st.progress``; the measured pose (true pose plus ``noise``) is
    projected again only when it differs (noise on, or a true ``l3`` other than the nominal).
    ``prev_rates``: the wheel rates before the step [rad/s] (``reward="v0"``; default the state's own: no change);
    ``heading``: ``(cos beta, sin beta)`` of the state when known (the ideal step's; default ``cos``, ``sin`` of it).

    Returns:
        the :class:`Outcome` and H's new progress [m].
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
    # the reward of AmigoBot-v0, from the true state
    terms = reward_term_columns(_abs(e), _abs(v_true - v_ref), cos_psi, sin_psi, cos_ss, sin_ss, change_sq, *scales)
    reward = reward_product(*terms)
    # on a batch, per-row paths: the open ones end when H passes their end
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
        if type(m_s) is float and hasattr(path, "pose_floats"):  # one robot on a ClothoidPath: the preview together
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
    """The change the smoothness term penalises: with ``wheel_rates`` (AmigoBot-v0's reward) the wheel rates' change
    ``(w1 - pw1, w2 - pw2)`` [rad/s], else the normalised command's ``(a1 - pa1, a2 - pa2)`` [-]. Floats or
    columns; the compiled step calls it too."""
    if wheel_rates:
        return w1 - pw1, w2 - pw2
    return a1 - pa1, a2 - pa2


def ep_l3_differs(k: Constants, ep: Episode) -> bool:
    """Whether the true ``l3`` differs from the nominal (then the measured H is projected separately)."""
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
    """The true speed of A [m/s] (no slip) and the time [s] at which :func:`reset_columns` evaluates a start state."""
    zero = 0.0 * st.x
    v, _ = body_velocity_of(st.w1, st.w2, ep.r1, ep.r2, 2.0 * ep.l1)
    return v + zero, zero


NO_NOISE = StepNoise(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class Begin(NamedTuple):
    """A new episode of one robot (:func:`begin_episode`): floats."""

    path: Any
    path_info: dict[str, Any]
    episode: Episode
    state: State
    outcome: Outcome


def begin_episode(rng: np.random.Generator, k: Constants, pose: tuple[float, float, float] | None = None) -> Begin:
    """Draw, start and evaluate one robot's episode from its generator (:func:`start_episode`, then
    :func:`reset_columns`)."""
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
    """Draw, in order, the path (:func:`draw_path`) and the episode (:func:`draw_episode`) from ``rng``, and build
    the start state (:func:`start_state`; ``pose`` replaces the drawn pose of A): ``(path, path_info, episode,
    state)``. ``progress``, ``loops``, ``path_pose``: the compiled twins of :func:`start_state` and :func:`draw_path`
    (default the float route)."""
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
    """The start state ``st`` with A at ``pose = (x_A, y_A, beta)`` [m, m, rad] instead (floats or columns), H
    ``l3`` (true) ahead of it and H's progress there (from the hint 0)."""
    x, y, b = pose
    hx = x + ep.l3 * col_cos(b)
    hy = y + ep.l3 * col_sin(b)
    return st._replace(x=x, y=y, beta=b, progress=_progress(k, path, hx, hy, 0.0, progress))


def episode_columns(episodes: list[Episode]) -> Episode:
    """Episodes of several robots as one :class:`Episode` of ``(m,)`` columns (``lag`` int64, ``key`` uint64)."""
    cols = list(zip(*episodes, strict=True))
    types: dict[str, Any] = {"lag": np.int64, "key": np.uint64}
    fields = zip(Episode._fields, cols, strict=True)
    arrays: list[Any] = [np.array(c, dtype=types.get(f, np.float64)) for f, c in fields]
    return Episode(*arrays)
