"""The robot's parameters as a frozen, validated dataclass, and the checks every setting uses.

Lengths in metres, angles in radians, times in seconds; parameters are passed explicitly (no module-level
settings). Sources (the paper's Table 1, the manufacturer's parameter files and MobileSim model): ``docs/model.md``."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields
from typing import Any

#: largest ``|x_A|``, ``|y_A|`` of a start pose [m]: float64 still resolves 2.3e-10 m there (ulp(1e6)),
#: far below any tracking error the task measures
POSE_LIMIT = 1e6
#: largest ``|beta|`` of a start pose [rad] (159 155 turns): the heading keeps a resolution of 1.2e-10 rad
HEADING_LIMIT = 1e6

# Ranges: physical, and such that every intermediate of a step stays finite and resolved in float64 (wheel and
# turn rates <= 1e5 rad/s, (w_max sigma_smooth)^2 in [1e-28, 1e22], observation bound <= 2e7).
LENGTH_RANGE = (1e-3, 1e2)  # robot lengths [m]
SPEED_RANGE = (1e-3, 1e2)  # max_speed [m/s]
MIN_SPEED = 1e-6  # reference speed [m/s]
LIMIT_RANGE = (1e-6, 1e3)  # max_acceleration, max_deceleration [m/s^2], max_rotation_rate [rad/s]


def show_value(value: Any, width: int = 60) -> str:
    """A one-line, bounded ``repr`` of ``value`` with its type, for error messages."""
    text = " ".join(repr(value).split())
    if len(text) > width:
        text = text[: width - 3] + "..."
    return f"{text} ({type(value).__name__})"


def _real(value: Any) -> float | None:
    """``value`` as a float if a :class:`numbers.Real` or a 0-d integer or floating array (not a bool), else None."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return None
    if isinstance(value, numbers.Real):
        return float(value)
    shape = getattr(value, "shape", None)
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    if shape == () and kind in ("i", "u", "f") and hasattr(value, "item"):
        return float(value.item())
    return None


def check_real(
    owner: str,
    name: str,
    value: Any,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """``value`` as a Python ``float`` (no numpy scalars in the state), checked finite and in the interval; else a
    one-line ``ValueError`` naming ``owner.name``, the range and the value (also for ``bool``, ``str``, complex,
    ``None``, sequences)."""
    v = value if type(value) is float else _real(value)  # (a float as it is: the common case, no call)
    if v is None:
        rng = _interval(low, high, low_open, high_open)
        raise ValueError(f"{owner}.{name} must be a real number in {rng}, got {show_value(value)}")
    if math.isfinite(v) and (v > low if low_open else v >= low) and (v < high if high_open else v <= high):
        return v
    rng = _interval(low, high, low_open, high_open)
    raise ValueError(f"{owner}.{name} must be a finite number in {rng}, got {value!r}")


def check_pair(
    owner: str, name: str, value: Any, low: float, high: float, *, low_open: bool = False
) -> tuple[float, float]:
    """``value`` as a pair of floats ``(a, b)`` with ``a <= b``, each a :func:`check_real` of the interval; else a
    one-line ``ValueError`` naming ``owner.name``, the interval and the value."""
    if isinstance(value, str | bytes) or not hasattr(value, "__len__") or len(value) != 2:
        rng = _interval(low, high, low_open, False)
        raise ValueError(f"{owner}.{name} must be a pair (low, high) within {rng}, got {value!r}")
    a, b = (check_real(owner, f"{name}[{i}]", v, low, high, low_open=low_open) for i, v in enumerate(value))
    if a > b:
        raise ValueError(f"{owner}.{name} must have low <= high, got {value!r}")
    return a, b


def _interval(low: float, high: float, low_open: bool, high_open: bool) -> str:
    """The interval of :func:`check_real`'s messages, e.g. ``(0, inf]``."""
    return f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"


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

    Ranges (else a one-line ``ValueError``): lengths in [1e-3, 100] m, ``l4`` in [1e-6, r1), ``max_speed`` in
    [1e-3, 100] m/s, the other limits in [1e-6, 1e3]; stored as Python floats, non-numbers and bools refused."""

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
        o = "RobotParams"
        for f in fields(self):
            low, high = SPEED_RANGE if f.name == "max_speed" else LIMIT_RANGE if f.name[:4] == "max_" else LENGTH_RANGE
            if f.name != "l4":
                object.__setattr__(self, f.name, check_real(o, f.name, getattr(self, f.name), low, high))
        object.__setattr__(self, "l4", check_real(o, "l4", self.l4, LIMIT_RANGE[0], self.r1, high_open=True))

    @property
    def max_wheel_rate(self) -> float:
        """Largest wheel rate magnitude [rad/s] of both wheels: ``max_speed / max(r1, r2)`` (15 by default)."""
        return self.max_speed / max(self.r1, self.r2)
