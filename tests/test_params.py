"""Parameters: defaults are the paper's Table 1 and the real robot's data (docs/model.md); bad values are refused."""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import pytest

from amigo_gym.model.params import RobotParams, check_real
from amigo_gym.paths import CirclePath
from amigo_gym.task.v1 import TrackingParams

# docs/model.md, "Construction data" and "Public data on the real robot"
TABLE_1 = {"l1": 0.12, "l3": 0.08, "l4": 0.03, "l5": 0.12, "r1": 0.05, "r2": 0.05, "r3": 0.03}
ROBOT_LIMITS = {
    "max_speed": 0.75,
    "max_acceleration": 0.3,
    "max_deceleration": 0.75,
    "max_rotation_rate": 0.87,
    "body_length": 0.330,
    "body_width": 0.279,
}
RANGE = re.compile(r"[\[(](-?[0-9.e+-]+|-inf), (-?[0-9.e+-]+|inf)[\])]")


def test_robot_defaults_are_table_1_and_robot_data() -> None:
    r = RobotParams()
    for name, value in {**TABLE_1, **ROBOT_LIMITS}.items():
        assert getattr(r, name) == value, name
    # 0.75 m/s over a 0.05 m wheel (docs/model.md)
    assert r.max_wheel_rate == pytest.approx(15.0, abs=1e-12)


def test_env_defaults() -> None:
    p = TrackingParams.v0()
    assert p.speed == 0.2  # the paper's v_A
    assert p.dt == 0.1
    assert p.radius == 1.0
    assert p.direction == 1
    assert p.path == CirclePath(radius=1.0, direction=1)
    assert p.robot == RobotParams()


def test_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        RobotParams().l1 = 0.2  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        TrackingParams.v0().speed = 0.3  # type: ignore[misc]


BAD_ROBOT: list[tuple[str, Any]] = [
    ("l1", 0.0),
    ("l1", -0.1),
    ("l3", math.nan),
    ("l5", math.inf),
    ("r1", 0.0),
    ("r2", -math.inf),
    ("r3", "abc"),
    ("max_speed", 0.0),
    ("l4", 0.05),  # H must be above ground: l4 < r1
    ("l4", 0.0),
]


@pytest.mark.parametrize(("field", "value"), BAD_ROBOT)
def test_robot_rejects(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=re.escape(f"RobotParams.{field}")) as exc:
        RobotParams(**{field: value})
    assert RANGE.search(str(exc.value)), str(exc.value)


BAD_ENV: list[tuple[str, Any]] = [
    ("dt", 0.0),
    ("dt", 2.5),
    ("dt", math.nan),
    ("radius", -1.0),
    ("radius", 0.08),  # must exceed l3
    ("radius", math.inf),
    ("speed", 0.0),
    ("speed", 0.76),  # above the robot's 0.75 m/s
    ("speed", math.nan),
    ("straight_length", -0.1),
    ("termination_distance", 0.0),
    ("init_position_noise", 0.2),  # > termination_distance / 2
    ("init_heading_noise", math.pi / 4 + 1e-9),
    ("error_scale", 0.0),
    ("sigma_track", 0.0),
    ("sigma_speed", -1.0),
    ("sigma_smooth", math.inf),
    ("smooth_weight", 1.0),
]


@pytest.mark.parametrize(("field", "value"), BAD_ENV)
def test_env_rejects(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=re.escape(f"TrackingParams.v0.{field}")) as exc:
        TrackingParams.v0(**{field: value})
    assert RANGE.search(str(exc.value)), str(exc.value)


@pytest.mark.parametrize("value", [0, 2, -2, True])
def test_env_rejects_direction(value: Any) -> None:
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.direction.*\+1.*-1"):
        TrackingParams.v0(direction=value)


@pytest.mark.parametrize("value", ["square", "", "Circle"])
def test_env_rejects_path(value: Any) -> None:
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.path.*'circle'.*'manoeuvre'"):
        TrackingParams.v0(path=value)


def test_env_rejects_preview_and_robot() -> None:
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.preview\[1\]"):
        TrackingParams.v0(preview=(0.2, -0.1))
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.preview\[0\]"):
        TrackingParams.v0(preview=(math.nan,))
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.robot"):
        TrackingParams.v0(robot="amigobot")  # type: ignore[arg-type]


def test_limits_follow_the_robot() -> None:
    """The radius bound is the robot's l3 and the speed bound its max_speed, not fixed numbers."""
    big = RobotParams(l3=0.2, max_speed=1.0)
    with pytest.raises(ValueError, match=r"TrackingParams\.v0\.radius"):
        TrackingParams.v0(robot=big, radius=0.15)
    assert TrackingParams.v0(robot=big, radius=2.0, speed=0.9).speed == 0.9
    assert TrackingParams.v0(preview=[0.1, 0.3]).preview == (0.1, 0.3)  # type: ignore[arg-type]


def test_check_real() -> None:
    assert check_real("O", "x", 1, 0.0, 1.0) == 1.0
    assert isinstance(check_real("O", "x", 1, 0.0, 1.0), float)
    with pytest.raises(ValueError, match=re.escape("O.x must be a finite number in (0, 1]")):
        check_real("O", "x", 0.0, 0.0, 1.0, low_open=True)
    with pytest.raises(ValueError, match=re.escape("O.x must be a finite number in [0, 1)")):
        check_real("O", "x", 1.0, 0.0, 1.0, high_open=True)
    with pytest.raises(ValueError, match=re.escape("O.x must be a real number")):
        check_real("O", "x", None)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"O\.x must be a finite number"):
        check_real("O", "x", -math.inf)
