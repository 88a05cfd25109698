"""Path objects of your own: the duck-typed protocol ``AmigoBot-v1`` checks (:func:`check_path`, at ``gym.make``).

``length`` [m] finite > 0 (one traversal); ``closed`` (repeats with period ``length``); ``pose_columns(s)``: for
arc lengths ``s`` [m] (a float or a float64 array) an object with ``x``, ``y`` [m], ``theta`` [rad, continuous]
and ``curvature`` [1/m, positive left] of the shape of ``s`` (an open path also for ``s`` beyond its ends: along
the end tangent). Optional ``locate(x, y, s_prev, max_advance, max_retreat)`` returning a
:class:`~amigo_gym.paths.PathPoint`; else samples every :data:`SAMPLE_SPACING` m (at most :data:`MAX_SAMPLES`)
are searched, then :meth:`~amigo_gym.paths.ClothoidPath.locate`'s Newton iteration runs on ``pose_columns``.
Errors (at ``gym.make``, on a probe, at any later step) name the path, the member and the value."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.kinematics import Real
from amigo_gym.model.params import show_value
from amigo_gym.paths.classic import CirclePath, ManoeuvrePath, PathPoint, PathPose
from amigo_gym.paths.clothoid import ClothoidPath, FloatPose, locate_points

Array = NDArray[np.float64]

#: the members a path object must have (``locate`` is optional)
REQUIRED_MEMBERS: tuple[str, ...] = ("length", "closed", "pose_columns")
#: the fields ``pose_columns`` must return
POSE_FIELDS: tuple[str, ...] = ("x", "y", "theta", "curvature")
#: largest spacing of the samples of the closest-point search without ``locate`` [m]
SAMPLE_SPACING = 0.02
#: most samples of that search
MAX_SAMPLES = 200_000
#: largest accepted ``length`` [m]
MAX_LENGTH = 1e7


def path_name(obj: object) -> str:
    """How messages name a path object: its ``name`` attribute if it is a string, else its class name."""
    name = getattr(obj, "name", None)
    return name if isinstance(name, str) and name else type(obj).__name__


def _finite_column(value: Any, shape: tuple[int, ...], where: str) -> Array:
    # value as a float64 array of shape (a scalar broadcasts), all finite; else a one-line ValueError
    if isinstance(value, str | bytes | bool | np.bool_):
        raise ValueError(f"{where} must be real numbers, got {show_value(value)}")
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{where} must be real numbers, got {show_value(value)}") from None
    if a.shape != shape and a.ndim == 0:
        a = np.broadcast_to(a, shape)
    if a.shape != shape:
        raise ValueError(f"{where} must have the shape of s, {shape}, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{where} must be finite, got {float(a[~np.isfinite(a)][0])!r}")
    return a


class UserPath:
    """A checked path object of your own ``path`` (module docstring), with the full interface ``AmigoBot-v1``
    uses; ``name`` (:func:`path_name`), ``length`` [m] and ``closed`` are its values, checked."""

    def __init__(self, path: Any, owner: str = "AmigoBot-v1") -> None:
        self.path, self.name, self._owner = path, path_name(path), owner
        who = f"{owner}: path {self.name}"
        if missing := [m for m in REQUIRED_MEMBERS if not hasattr(path, m)]:
            raise ValueError(
                f"{who} has no {', '.join(repr(m) for m in missing)}; a path must be a family name or an object "
                "with length [m], closed and pose_columns(s) (amigo_gym.paths.UserPath)"
            )
        length = path.length
        if callable(length):
            raise ValueError(f"{who}: length must be a number [m] (an attribute or property), got a method")
        ok = isinstance(length, int | float | np.integer | np.floating) and not isinstance(length, bool | np.bool_)
        if not (ok and 0.0 < float(length) <= MAX_LENGTH):
            raise ValueError(
                f"{who}: length must be a finite number in (0, {MAX_LENGTH:g}] m, got {show_value(length)}"
            )
        self.length: float = float(length)
        closed = path.closed
        if not isinstance(closed, bool | np.bool_):
            raise ValueError(f"{who}: closed must be True or False, got {show_value(closed)}")
        self.closed: bool = bool(closed)
        if not callable(path.pose_columns):
            raise ValueError(
                f"{who}: pose_columns must be a method pose_columns(s), got {show_value(path.pose_columns)}"
            )
        self._user_locate = getattr(path, "locate", None)
        if self._user_locate is not None and not callable(self._user_locate):
            raise ValueError(f"{who}: locate must be a method (or absent), got {show_value(self._user_locate)}")
        # probes: pose_columns on a column and a float, then locate on points of the path
        probe = np.linspace(0.0, self.length, 7, dtype=np.float64)
        pose = self.pose_columns(probe)
        self.pose_columns(0.0)
        n = min(MAX_SAMPLES, max(8, math.ceil(self.length / SAMPLE_SPACING)))
        self._spacing = self.length / n
        js = np.arange(n + (0 if self.closed else 1), dtype=np.float64)
        samples = self.pose_columns(js * self._spacing)
        # a flat path vector of no pieces (clothoid.PATH_HEADER; not a circle): the samples the projection searches
        head = [0.0, float(js.size), self.length, 0.0, self._spacing, 1.0 if self.closed else 0.0, 0.0, 0.0, 0.0]
        self._flat = np.concatenate((head, samples.x, samples.y))
        loc = self.locate(np.asarray(pose.x), np.asarray(pose.y), probe, 0.5, 0.5)
        _finite_column(loc.progress, probe.shape, f"{who}: locate(...).progress")
        self.locate(float(np.asarray(pose.x)[0]), float(np.asarray(pose.y)[0]), 0.0, 0.5, 0.5)

    def pose_columns(self, s: Real) -> PathPose:
        """The user's ``pose_columns(s)``, checked and completed to a :class:`~amigo_gym.paths.PathPose`
        (``curvature_rate`` the user's or 0)."""
        scalar = not isinstance(s, np.ndarray)
        shape = () if scalar else np.shape(s)
        got = self.path.pose_columns(s)
        where = f"{self._owner}: path {self.name}: pose_columns(s)"
        at = f"s = {float(s)!r} m" if scalar else None
        x, y, th, k = _fields(got, POSE_FIELDS, shape, where, f"an object with {', '.join(POSE_FIELDS)}", at)
        rate = getattr(got, "curvature_rate", None)
        cr = np.zeros(shape) if rate is None else _finite_column(rate, shape, f"{where}.curvature_rate")
        out = PathPose(x, y, th, k, cr, np.cos(th), np.sin(th))
        return PathPose(*(float(v) for v in out)) if scalar else out

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        """The closest path point to ``(x, y)`` [m] (the user's ``locate`` or the sampled search), checked."""
        if self._user_locate is None:  # the sampled search
            scalar = not (isinstance(x, np.ndarray) or isinstance(y, np.ndarray) or isinstance(s_prev, np.ndarray))
            got = locate_points(self._flat, x, y, s_prev, max_advance, max_retreat, self._pose_of)
            return _point(list(got), scalar)
        got = self._user_locate(x, y, s_prev, max_advance, max_retreat)
        scalar = not (isinstance(x, np.ndarray) or isinstance(y, np.ndarray))
        shape = () if scalar else np.broadcast_shapes(np.shape(x), np.shape(y))
        where = f"{self._owner}: path {self.name}: locate(x, y, ...)"
        at = f"x = {float(x)!r}, y = {float(y)!r} m" if scalar else None
        return _point(_fields(got, PathPoint._fields, shape, where, "an amigo_gym.paths.PathPoint", at), scalar)

    def _pose_of(self, _buf: Any, _nodes: Any, _nb: int, _pv: Any, s: float) -> FloatPose:
        x, y, th, kappa, rate, ct, st = self.pose_columns(s)  # floats for a float
        return float(x), float(y), float(th), float(kappa), float(rate), float(ct), float(st)


def _fields(
    got: Any, names: tuple[str, ...], shape: tuple[int, ...], where: str, kind: str, at: str | None
) -> list[Array]:
    # the fields names of a user's result, each _finite_column (at: the point of a float query, for the errors)
    out = []
    for f in names:
        if not hasattr(got, f):
            raise ValueError(f"{where} must return {kind}; it has no {f!r}")
        try:
            out.append(_finite_column(getattr(got, f), shape, f"{where}.{f}"))
        except ValueError as exc:
            raise ValueError(f"{exc} (at {at})" if at else str(exc)) from None
    return out


def _point(vals: list[Any], scalar: bool) -> PathPoint:
    if scalar:
        return PathPoint._make([*(float(v) for v in vals[:-1]), int(vals[-1])])
    return PathPoint._make([*vals[:-1], np.asarray(vals[-1]).astype(np.int64)])


def check_path(path: Any, owner: str = "AmigoBot-v1") -> Any:
    """``path`` as it is if a :class:`~amigo_gym.paths.ClothoidPath`, :class:`~amigo_gym.paths.CirclePath`,
    :class:`~amigo_gym.paths.ManoeuvrePath` or :class:`UserPath`, else a :class:`UserPath` of it (checked; a
    one-line ``ValueError`` naming the path, the member and the value)."""
    if type(path) in (ClothoidPath, CirclePath, ManoeuvrePath) or isinstance(path, UserPath):
        return path
    return UserPath(path, owner)
