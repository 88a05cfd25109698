"""Domain randomisation of AmigoBot-v1 (:class:`Randomization`; :data:`PRESETS` are the project's choices).

:func:`sample` draws one episode's values from the env's ``np_random`` in a fixed order (``reset(seed=...)``
reproduces them); per-step draws (slips ``s_i ~ U(0, s_max)``, Gaussian measurement noise; the true state is never
perturbed) are a pure function of a per-episode key and the step (:func:`step_noise`, a counter-based SplitMix64),
the same for one robot and a batch."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from amigo_gym.model.actuators import MAX_DELAY
from amigo_gym.model.kinematics import Real
from amigo_gym.model.params import check_pair, check_real


@dataclass(frozen=True)
class Randomization:
    """Ranges ``(low, high)`` of the randomised quantities (``(x, x)`` fixes one; default: nothing randomised):
    ``wheel_radius`` and ``track`` scales [-] within [0.5, 1.5], ``slip`` [-] within [0, 0.5], ``delay`` [s] within
    [0, MAX_DELAY]; noise standard deviations ``position_noise`` [m] within [0, 0.1], ``heading_noise`` [rad] within
    [0, 0.2], ``wheel_rate_noise`` [rad/s] within [0, 2]."""

    wheel_radius: tuple[float, float] = (1.0, 1.0)
    track: tuple[float, float] = (1.0, 1.0)
    slip: tuple[float, float] = (0.0, 0.0)
    delay: tuple[float, float] = (0.0, 0.0)
    position_noise: float = 0.0
    heading_noise: float = 0.0
    wheel_rate_noise: float = 0.0

    def __post_init__(self) -> None:
        ranges = {"wheel_radius": (0.5, 1.5), "track": (0.5, 1.5), "slip": (0.0, 0.5), "delay": (0.0, MAX_DELAY),
                  "position_noise": (0.0, 0.1), "heading_noise": (0.0, 0.2),
                  "wheel_rate_noise": (0.0, 2.0)}  # fmt: skip
        for i, (name, (low, high)) in enumerate(ranges.items()):
            check = check_pair if i < 4 else check_real  # the four ranges, then the noise levels
            object.__setattr__(self, name, check("Randomization", name, getattr(self, name), low, high))

    @property
    def has_noise(self) -> bool:
        """True when the measurements are noisy."""
        return self.position_noise > 0 or self.heading_noise > 0 or self.wheel_rate_noise > 0


#: named presets of ``randomize=``: ``mild`` a calibrated robot on a clean floor, ``hard`` an uncalibrated one with
#: worn tyres, a slippery floor and a slow link
PRESETS: dict[str, Randomization] = {
    "none": Randomization(),
    "mild": Randomization(wheel_radius=(0.98, 1.02), track=(0.98, 1.02), slip=(0.0, 0.02), delay=(0.0, 0.05),
                          position_noise=0.002, heading_noise=0.005, wheel_rate_noise=0.05),
    "hard": Randomization(wheel_radius=(0.95, 1.05), track=(0.95, 1.05), slip=(0.0, 0.1), delay=(0.0, 0.15),
                          position_noise=0.005, heading_noise=0.01, wheel_rate_noise=0.2),
}  # fmt: skip


def make_randomization(value: str | Randomization | Mapping[str, Any] | None) -> Randomization:
    """``randomize=``: a preset name, a :class:`Randomization`, or a mapping of its fields; ``ValueError`` for an
    unknown preset or field, or a bad range (naming the field, value and allowed range)."""
    if value is None:
        return PRESETS["none"]
    if isinstance(value, Randomization):
        return value
    if isinstance(value, str):
        if value not in PRESETS:
            raise ValueError(f"randomize must be one of {sorted(PRESETS)} or a mapping of ranges, got {value!r}")
        return PRESETS[value]
    if isinstance(value, Mapping):
        names = {f.name for f in fields(Randomization)}
        if bad := sorted(str(k) for k in value if k not in names):
            raise ValueError(f"randomize: unknown field(s) {bad}; allowed: {sorted(names)}")
        return Randomization(**{str(k): v for k, v in value.items()})  # (pairs as lists too: JSON)
    raise ValueError(f"randomize must be a preset name, a Randomization or a mapping, got {type(value).__name__}")


class EpisodeDraw(NamedTuple):
    """One episode's scales of the true right and left wheel radii and half track [-], slip bound [-], delay [s]."""

    r1_scale: float
    r2_scale: float
    track_scale: float
    slip_max: float
    delay: float


def intervals(r: Randomization) -> list[tuple[float, float]]:
    """The intervals ``(lo, hi)`` of one episode's uniform draws, in the order of :class:`EpisodeDraw`."""
    return [r.wheel_radius, r.wheel_radius, r.track, r.slip, r.delay]


def sample(rng: np.random.Generator, r: Randomization) -> EpisodeDraw:
    """Draw one episode's values from ``rng``: ``U(lo, hi)`` of each of :func:`intervals` (none where ``lo == hi``)."""
    return EpisodeDraw(*(lo if lo == hi else float(rng.uniform(lo, hi)) for lo, hi in intervals(r)))


class StepNoise(NamedTuple):
    """One step's per-step draws as columns: slip factors [-] and measurement noise [m, m, rad, rad/s, rad/s]."""

    slip1: Real
    slip2: Real
    x: Real
    y: Real
    beta: Real
    rate1: Real
    rate2: Real


_M64 = 0xFFFFFFFFFFFFFFFF


def draw_key(rng: np.random.Generator) -> int:
    """A fresh 64-bit episode key for :func:`step_noise`, from the env's generator."""
    return int(rng.integers(0, 2**63, dtype=np.int64)) * 2 + int(rng.integers(0, 2, dtype=np.int64))


def step_noise(key: ArrayLike, step: ArrayLike, r: Randomization, slip_max: Real) -> StepNoise:
    """Step ``step``'s (0 first) draws for the episodes of keys ``key`` (:func:`draw_key`), ``(...)``: slips
    ``U(0, slip_max)`` and Gaussian noise of ``r``'s levels, exact zeros where off. Uniform channels: 0, 1 the slips,
    ``2 (ch + 1)`` and ``2 (ch + 1) + 1`` noise channel ``ch`` (0-4: ``x, y, beta, rate1, rate2``)."""
    one = type(key) is int and type(step) is int and type(slip_max) is float  # one robot: on Python ints
    levels = (r.position_noise, r.heading_noise, r.wheel_rate_noise)
    buf: list[Any] = [0.0] * 10
    with np.errstate(over="ignore"):  # numpy scalars (0-d) warn where uint64 wraps; arrays do not
        k, n = (key, step) if one else (np.asarray(key, dtype=np.uint64), np.asarray(step, dtype=np.uint64))
        s1, s2, on = step_uniforms(buf, 0, 5, k, n, slip_max, *levels)
    out: list[Any] = [0.0, 0.0, 0.0, 0.0, 0.0]
    if on:
        step_normals(out, 0, np.log(buf[:on]), 0, np.cos(buf[5 : 5 + on]), 0, *levels)
    if one or (np.ndim(key) == 0 and np.ndim(step) == 0 and np.ndim(slip_max) == 0):  # one robot: plain floats
        return StepNoise(*(float(c) for c in (s1, s2, *out)))
    return StepNoise(s1, s2, *out)


_GAMMA = 0x9E3779B97F4A7C15
_MIX1 = 0xBF58476D1CE4E5B9
_MIX2 = 0x94D049BB133111EB
_INV_2_53 = 1.0 / 9007199254740992.0
_TWO_PI = 2.0 * math.pi


def _uint64(n: int) -> int:
    """``n mod 2**64``; compiled code overloads it with ``np.uint64(n)``."""
    return n & _M64


def _counter_uniform_int(key: Any, step: Any, channel: int) -> Any:
    """Uniform numbers in ``(0, 1)`` of ``key``, ``step`` (Python ints, ``uint64`` when compiled, or ``uint64``
    columns) and ``channel`` in ``[0, 256)``: ``u = (floor(h / 2^11) + 1/2) / 2^53``,
    ``h = splitmix64(key + gamma (256 step + channel + 1))`` mod ``2**64``, ``gamma = 0x9E3779B97F4A7C15``."""
    z = (key + _uint64(step * 256 + channel + 1) * _GAMMA) & _M64
    z = ((z ^ (z >> 30)) * _MIX1) & _M64
    z = ((z ^ (z >> 27)) * _MIX2) & _M64
    z = z ^ (z >> 31)
    return ((z >> 11) + 0.5) * _INV_2_53


def noise_level(channel: int, position: float, heading: float, rate: float) -> float:
    """Standard deviation of noise channel ``channel`` (0-4: ``x, y, beta, rate1, rate2``) [m, m, rad, rad/s]."""
    return position if channel < 2 else (heading if channel == 2 else rate)


def channels_on(position: float, heading: float, rate: float) -> int:
    """How many of the five noise channels are on (a level above 0)."""
    return 2 * (position > 0.0) + (heading > 0.0) + 2 * (rate > 0.0)


def step_uniforms(
    buf: Any, u1_at: int, u2_at: int, key: Any, step: Any, slip_max: Real, position: float, heading: float, rate: float
) -> tuple[Real, Real, int]:
    """The uniforms of :func:`step_noise`: ``(slip1, slip2, on)`` (slips 0.0 when no ``slip_max`` is above 0, ``on``
    noise channels); ``u1`` of the ``j``-th channel on at ``buf[u1_at + j]``, ``2 pi u2`` at ``buf[u2_at + j]``."""
    s1 = 0.0
    s2 = 0.0
    if np.any(slip_max > 0.0):
        s1 = slip_max * _counter_uniform_int(key, step, 0)
        s2 = slip_max * _counter_uniform_int(key, step, 1)
    on = 0
    for ch in range(5):
        if noise_level(ch, position, heading, rate) > 0.0:
            buf[u1_at + on] = _counter_uniform_int(key, step, 2 * (ch + 1))
            buf[u2_at + on] = _TWO_PI * _counter_uniform_int(key, step, 2 * (ch + 1) + 1)
            on += 1
    return s1, s2, on


def step_normals(
    out: Any, out_at: int, logs: Any, log_at: int, coss: Any, cos_at: int, position: float, heading: float, rate: float
) -> None:
    r"""The normals of :func:`step_noise` into ``out[out_at : out_at + 5]`` (0.0 for a channel off): Box–Muller,
    :math:`\sigma \sqrt{-2 \ln u_1} \cos(2\pi u_2)`, of ``log u1 = logs[log_at + j]``, ``cos = coss[cos_at + j]``."""
    on = 0
    for ch in range(5):
        level = noise_level(ch, position, heading, rate)
        value: Real = 0.0
        if level > 0.0:
            value = level * (np.sqrt(-2.0 * logs[log_at + on]) * coss[cos_at + on])
            on += 1
        out[out_at + ch] = value
