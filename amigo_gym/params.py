"""Robot and task parameters as frozen, validated dataclasses.

Every length is in metres, every angle in radians, every time in seconds. Parameters are passed
explicitly to the pure functions of :mod:`amigo_gym.kinematics`, :mod:`amigo_gym.paths` and
:mod:`amigo_gym.task`; there are no module-level settings.

Sources
-------
* Construction data: Table 1 of the AmigoBot paper (docs/model.md), read as in ``docs/model.md``:
  ``l1 = 0.12, l3 = 0.08, l4 = 0.03, l5 = 0.12, r1 = r2 = 0.05, r3 = 0.03`` m.
* Limits of the real robot: Adept MobileRobots' (formerly ActivMedia) AmigoBot robot parameter
  files and the MobileSim simulator model of the AmigoBot-SH, as collected in ``docs/model.md``:
  maximum speed 0.75 m/s (0.5 m/s for the older AmigoBot), acceleration 0.3 m/s^2, deceleration
  0.75 m/s^2, rotation 0.87 rad/s with rotational acceleration 0.87 rad/s^2 and deceleration
  2.5 rad/s^2; body 0.330 m long and 0.279 m wide, bounding radius 0.18 m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Literal

__all__ = ["RobotParams", "EnvParams", "check_range"]


def check_range(
    owner: str,
    name: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Check that ``value`` is a finite real number in the given interval.

    Raises:
        ValueError: naming ``owner.name``, the allowed range and the offending value.
    """
    lo_b = "(" if low_open else "["
    hi_b = ")" if high_open else "]"
    rng = f"{lo_b}{low:g}, {high:g}{hi_b}"
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}.{name} must be a real number in {rng}, got {value!r}") from None
    ok = math.isfinite(v)
    ok = ok and (v > low if low_open else v >= low)
    ok = ok and (v < high if high_open else v <= high)
    if not ok:
        raise ValueError(f"{owner}.{name} must be a finite number in {rng}, got {value!r}")
    return v


@dataclass(frozen=True)
class RobotParams:
    """Geometry and limits of the AmigoBot (paper's Table 1 and the real robot's data).

    Attributes:
        l1: half track, distance from axle midpoint A to each wheel contact point [m]. Table 1: 0.12.
        l3: distance from A to the tracked point H along the heading (look-ahead) [m]. Table 1: 0.08.
        l4: depth of H below the wheel-axis height ``r1``; H is at height ``r1 - l4`` [m]. Table 1: 0.03.
        l5: distance from A to the castor's swivel along the body axis [m]. Table 1: 0.12.
        r1: radius of wheel 1, the right drive wheel [m]. Table 1: 0.05.
        r2: radius of wheel 2, the left drive wheel [m]. Table 1: 0.05.
        r3: radius of wheel 3, the castor [m]. Table 1: 0.03.
        max_speed: largest rim speed of a drive wheel [m/s]. AmigoBot-SH: 0.75 (MobileSim model).
        max_acceleration: translational acceleration of the real controller [m/s^2]: 0.3.
        max_deceleration: translational deceleration of the real controller [m/s^2]: 0.75.
        max_rotation_rate: rotational velocity limit of the simulator model [rad/s]: 0.87.
        body_length: body length, for rendering [m]: 0.330.
        body_width: body width, for rendering [m]: 0.279.
    """

    l1: float = 0.12
    l3: float = 0.08
    l4: float = 0.03
    l5: float = 0.12
    r1: float = 0.05
    r2: float = 0.05
    r3: float = 0.03
    max_speed: float = 0.75
    max_acceleration: float = 0.3
    max_deceleration: float = 0.75
    max_rotation_rate: float = 0.87
    body_length: float = 0.330
    body_width: float = 0.279

    def __post_init__(self) -> None:
        for f in fields(self):
            check_range("RobotParams", f.name, getattr(self, f.name), 0.0, low_open=True)
        check_range("RobotParams", "l4", self.l4, 0.0, self.r1, low_open=True, high_open=True)

    @property
    def max_wheel_rate(self) -> float:
        """Largest wheel rate magnitude [rad/s]: ``max_speed / max(r1, r2)`` (15 rad/s by default).

        Both wheels share this limit so that neither rim exceeds ``max_speed``.
        """
        return self.max_speed / max(self.r1, self.r2)


PathName = Literal["circle", "manoeuvre"]


@dataclass(frozen=True)
class EnvParams:
    """Settings of the ``AmigoBot`` tracking task (all keyword arguments of ``gym.make``).

    Attributes:
        robot: robot geometry and limits.
        dt: control period; wheel rates are held over it [s]. Default 0.1 (the robot's 100 ms cycle).
            Range (0, 2].
        radius: radius ``R`` of the circle that H must follow [m]; must exceed ``robot.l3`` so that
            the steady state exists (``R_A = sqrt(R^2 - l3^2)``). Default 1.0.
        speed: reference speed of point A, ``v_A`` [m/s], in (0, robot.max_speed]. Default 0.2.
        direction: +1 for a left (counter-clockwise) circle as in the paper's eq. (6), -1 for right.
        path: ``"circle"`` (eq. 6: through the origin, tangent to x0 there) or ``"manoeuvre"``
            (a straight segment of ``straight_length`` along x0 from the origin, then the circle).
        straight_length: length of the straight part of the manoeuvre path [m], >= 0. Default 1.0.
        termination_distance: the episode terminates when |cross-track error of H| exceeds it [m].
            Default 0.25.
        init_position_noise: half-width of the uniform perturbation of H's start position, per
            axis [m], in [0, termination_distance/2]. Default 0.02.
        init_heading_noise: half-width of the uniform perturbation of the start heading [rad], in
            [0, pi/4]. Default 0.1.
        error_scale: the observation reports the cross-track error divided by this [m]. Default 0.05.
        preview: distances ahead of H's closest path point at which the path curvature is also
            observed [m], each in [0, 10]. Default (0.2, 0.4).
        sigma_track: scale of the tracking reward term ``exp(-|e|/sigma_track)`` [m]. Default 0.02.
        sigma_speed: scale of the speed term ``exp(-|v_A - v_ref|/sigma_speed)`` [m/s]. Default 0.05.
        sigma_smooth: scale of the change of normalised action in the smoothness term [-]. Default 0.1.
        smooth_weight: largest loss the smoothness term can cause, in [0, 1). Default 0.2.
    """

    robot: RobotParams = RobotParams()
    dt: float = 0.1
    radius: float = 1.0
    speed: float = 0.2
    direction: int = 1
    path: PathName = "circle"
    straight_length: float = 1.0
    termination_distance: float = 0.25
    init_position_noise: float = 0.02
    init_heading_noise: float = 0.1
    error_scale: float = 0.05
    preview: tuple[float, ...] = (0.2, 0.4)
    sigma_track: float = 0.02
    sigma_speed: float = 0.05
    sigma_smooth: float = 0.1
    smooth_weight: float = 0.2

    def __post_init__(self) -> None:
        o = "EnvParams"
        if not isinstance(self.robot, RobotParams):
            raise ValueError(f"{o}.robot must be a RobotParams, got {type(self.robot).__name__}")
        check_range(o, "dt", self.dt, 0.0, 2.0, low_open=True)
        check_range(o, "radius", self.radius, self.robot.l3, 1e3, low_open=True)
        check_range(o, "speed", self.speed, 0.0, self.robot.max_speed, low_open=True)
        if self.direction not in (1, -1) or isinstance(self.direction, bool):
            raise ValueError(f"{o}.direction must be +1 (left turn) or -1 (right), got {self.direction!r}")
        if self.path not in ("circle", "manoeuvre"):
            raise ValueError(f"{o}.path must be 'circle' or 'manoeuvre', got {self.path!r}")
        check_range(o, "straight_length", self.straight_length, 0.0, 1e3)
        check_range(o, "termination_distance", self.termination_distance, 0.0, 10.0, low_open=True)
        check_range(o, "init_position_noise", self.init_position_noise, 0.0, self.termination_distance / 2)
        check_range(o, "init_heading_noise", self.init_heading_noise, 0.0, math.pi / 4)
        check_range(o, "error_scale", self.error_scale, 0.0, 10.0, low_open=True)
        if not isinstance(self.preview, tuple):
            object.__setattr__(self, "preview", tuple(self.preview))
        for i, d in enumerate(self.preview):
            check_range(o, f"preview[{i}]", d, 0.0, 10.0)
        check_range(o, "sigma_track", self.sigma_track, 0.0, low_open=True)
        check_range(o, "sigma_speed", self.sigma_speed, 0.0, low_open=True)
        check_range(o, "sigma_smooth", self.sigma_smooth, 0.0, low_open=True)
        check_range(o, "smooth_weight", self.smooth_weight, 0.0, 1.0, high_open=True)

    @property
    def speed_h(self) -> float:
        """Steady speed of H on the circle [m/s]: ``v_A R / R_A`` (H runs on the outer circle)."""
        return self.speed * self.radius / math.sqrt(self.radius**2 - self.robot.l3**2)

    @property
    def lap_time(self) -> float:
        """Time of one steady lap of the circle [s]: ``2 pi R_A / v_A``."""
        return 2 * math.pi * math.sqrt(self.radius**2 - self.robot.l3**2) / self.speed
