"""A batch of ``N`` paths, one per sub-environment (any mix of families and user paths), with
:class:`~amigo_gym.paths.clothoid.PathSpec` on ``(N,)`` columns: row ``i`` of a result equals ``paths[i]``'s own for
row ``i``'s floats. :class:`~amigo_gym.paths.clothoid.ClothoidPath` s are evaluated row by row from a padded
``(N, W)`` table of their flat vectors, one object for all rows on the columns, other paths once per object.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.kinematics import Real
from amigo_gym.paths.classic import PathPoint, PathPose
from amigo_gym.paths.clothoid import (
    ClothoidPath,
    ClothoidSegment,
    PathSpec,
    check_hint,
    check_window,
    locate_columns,
    pose_columns_of,
)

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: stands in the padded tables for the rows of a path that is not a ClothoidPath (their results are replaced)
_PLACEHOLDER = ClothoidPath((ClothoidSegment.line(1.0),))


def _check_paths(paths: Sequence[PathSpec], where: str) -> list[PathSpec]:
    for i, p in enumerate(paths):
        if not all(hasattr(p, a) for a in ("length", "closed", "pose_columns", "locate")):
            raise ValueError(
                f"{where}[{i}] must have length, closed, pose_columns and locate (amigo_gym.paths.PathSpec), "
                f"got {type(p).__name__}"
            )
    return list(paths)


@dataclass
class _Padded:
    """The rows' flat path vectors: row ``i``'s in ``flat[i]``, at ``start[i] = i W`` in ``flat.reshape(-1)``."""

    flat: Array
    start: IntArray

    def write(self, rows: IntArray | NDArray[np.intp], path: PathSpec) -> None:
        """Rows ``rows`` take ``path``'s flat vector (:data:`_PLACEHOLDER`'s if not a ClothoidPath), the table
        widened if it is longer than any before."""
        f = (path if isinstance(path, ClothoidPath) else _PLACEHOLDER)._t.flat
        n, w = self.flat.shape
        if f.size > w:
            wide = np.zeros((n, f.size))
            wide[:, :w] = self.flat
            self.flat, self.start = wide, np.arange(n, dtype=np.int64) * f.size
        self.flat[np.asarray(rows, dtype=np.int64), : f.size] = f


class PathBatch:
    """``N >= 1`` paths (:class:`~amigo_gym.paths.clothoid.PathSpec` s), one per row, with the column interface
    of a path (module docstring)."""

    def __init__(self, paths: Sequence[PathSpec]) -> None:
        seq = _check_paths(list(paths), "PathBatch.paths")
        if not seq:
            raise ValueError("PathBatch.paths must hold at least one path, got none")
        n = len(seq)
        self._paths: list[PathSpec] = seq
        self._ids = np.zeros(n, dtype=np.int64)
        self._length = np.zeros(n)
        self._closed = np.zeros(n, dtype=np.bool_)
        self._objects: dict[int, PathSpec] = {}
        self._foreign_objects: dict[int, PathSpec] = {}
        self._counts: dict[int, int] = {}
        self._tables: _Padded | None = None
        self._set(np.arange(n, dtype=np.intp), seq)

    def _set(self, rows: NDArray[np.intp], paths: Sequence[PathSpec]) -> None:
        for oid in self._ids[rows].tolist():
            old = self._counts.get(oid)
            if old is not None:  # (at construction the ids are 0: no object has id 0)
                if old == 1:
                    del self._counts[oid], self._objects[oid]
                    self._foreign_objects.pop(oid, None)
                else:
                    self._counts[oid] = old - 1
        groups: dict[int, tuple[PathSpec, list[int]]] = {}
        for r, p in zip(rows.tolist(), paths, strict=True):
            groups.setdefault(id(p), (p, []))[1].append(r)
            self._paths[r] = p
        for oid, (p, rs) in groups.items():
            self._objects[oid] = p
            if not isinstance(p, ClothoidPath):
                self._foreign_objects[oid] = p
            self._counts[oid] = self._counts.get(oid, 0) + len(rs)
        self._ids[rows] = [id(p) for p in paths]  # the per-row columns in one assignment each
        self._length[rows] = [float(p.length) for p in paths]
        self._closed[rows] = [bool(p.closed) for p in paths]
        if self._tables is not None:
            for p, rs in groups.values():
                self._tables.write(np.asarray(rs, dtype=np.intp), p)

    def _padded(self) -> _Padded:
        if self._tables is None:
            clothoids = [p for p in self._objects.values() if isinstance(p, ClothoidPath)] + [_PLACEHOLDER]
            n, w = len(self._paths), max(p._t.flat.size for p in clothoids)
            t = _Padded(np.zeros((n, w)), np.arange(n, dtype=np.int64) * w)
            order = np.argsort(self._ids, kind="stable")  # rows grouped by object: O(N log N), not O(N * objects)
            ids = self._ids[order]
            starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
            for rows in np.split(order, starts[1:]):
                t.write(rows, self._objects[int(self._ids[rows[0]])])
            self._tables = t
        return self._tables

    def replace(self, rows: ArrayLike, paths: Sequence[PathSpec]) -> None:
        """Rows ``rows`` (distinct, ``(k,)``) take ``paths`` (``k`` paths), in place (autoreset); cost O(k W)."""
        ra = np.asarray(rows)
        if ra.ndim != 1 or not (ra.size == 0 or np.issubdtype(ra.dtype, np.integer)):
            raise ValueError(f"PathBatch.replace.rows must be a 1-D array of row numbers, got {rows!r}")
        ps = _check_paths(list(paths), "PathBatch.replace.paths")
        if len(ps) != ra.size:
            raise ValueError(f"PathBatch.replace: {ra.size} rows but {len(ps)} paths")
        n = len(self._paths)
        ra = ra.astype(np.intp)
        if ra.size and (ra.min() < 0 or ra.max() >= n):
            raise ValueError(f"PathBatch.replace.rows must lie in [0, {n}), got {rows!r}")
        if np.unique(ra).size != ra.size:
            raise ValueError(f"PathBatch.replace.rows must be distinct, got {rows!r}")
        self._set(ra, ps)

    def __len__(self) -> int:
        return len(self._paths)

    def __getitem__(self, i: int) -> PathSpec:
        """Path of row ``i``."""
        return self._paths[i]

    @property
    def paths(self) -> tuple[PathSpec, ...]:
        """The paths of the rows, ``N`` of them."""
        return tuple(self._paths)

    @property
    def length(self) -> Array:
        """``(N,)`` lap length of each row's path [m] (a read-only view, updated by :meth:`replace`)."""
        return _read_only(self._length)

    @property
    def closed(self) -> BoolArray:
        """``(N,)`` whether each row's path is closed (a read-only view, updated by :meth:`replace`)."""
        return _read_only(self._closed)

    def _column(self, name: str, v: Real | None) -> Array:
        n = len(self._paths)
        a = np.asarray(v, dtype=np.float64)
        try:
            return np.ascontiguousarray(np.broadcast_to(a, (n,)))
        except ValueError:
            raise ValueError(f"PathBatch: {name} must be a float or a column of shape ({n},), got {a.shape}") from None

    def _uniform(self) -> PathSpec | None:
        return next(iter(self._objects.values())) if len(self._objects) == 1 else None

    def _foreign(self) -> list[tuple[PathSpec, NDArray[np.intp]]]:
        return [(p, np.flatnonzero(self._ids == oid)) for oid, p in self._foreign_objects.items()]

    def _full(self, fields: Sequence[Any], rows: NDArray[np.intp] | None = None) -> list[NDArray[Any]]:
        n = len(self._paths) if rows is None else rows.size
        return [np.array(np.broadcast_to(np.asarray(f), (n,))) for f in fields]

    def pose_columns(self, s: Real) -> PathPose:
        """:class:`~amigo_gym.paths.classic.PathPose` of ``(N,)`` columns: each row's path at ``s`` [m] (``(N,)``
        or a float for all rows)."""
        sa = self._column("s", s)
        only = self._uniform()
        if only is not None:
            return PathPose(*self._full(only.pose_columns(float(sa[0]) if sa.size == 1 else sa)))
        foreign = self._foreign()
        if len(foreign) == len(self._objects):
            out = [np.zeros(sa.shape) for _ in PathPose._fields]
        else:
            t = self._padded()
            out = self._full(pose_columns_of(t.flat.reshape(-1), t.start, sa))
        for p, rows in foreign:
            for o, v in zip(out, self._full(p.pose_columns(sa[rows]), rows), strict=True):
                o[rows] = v
        return PathPose(*out)

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        """Closest point of each row's path to ``(x, y)`` [m] (``(N,)`` or floats), keeping progress from ``s_prev``
        [m] (``(N,)``, or None: global) as :meth:`ClothoidPath.locate`; a
        :class:`~amigo_gym.paths.classic.PathPoint` of ``(N,)`` columns (``status`` int64)."""
        xa = self._column("x", x)
        ya = self._column("y", y)
        ahead, behind = check_window(max_advance, max_retreat)
        sp = sp_in = None if s_prev is None else self._column("s_prev", s_prev)
        only = self._uniform()
        if only is not None:
            if xa.size == 1:  # one row: the path's float code (faster)
                sp1 = None if sp is None else float(sp[0])
                return self._point(only.locate(float(xa[0]), float(ya[0]), sp1, max_advance, max_retreat))
            return self._point(only.locate(xa, ya, sp, max_advance, max_retreat))
        foreign = self._foreign()
        if len(foreign) == len(self._objects):
            out: list[NDArray[Any]] = [np.zeros(xa.shape) for _ in PathPoint._fields]
            out[-1] = out[-1].astype(np.int64)
        else:
            if sp is not None and not np.isfinite(sp).all():  # refused on a ClothoidPath's row, ignored on another's
                check_hint(sp[~np.isin(self._ids, list(self._foreign_objects))])
                sp = np.where(np.isfinite(sp), sp, 0.0)
            t = self._padded()
            out = [np.asarray(v) for v in locate_columns(t.flat.reshape(-1), t.start, xa, ya, sp, ahead, behind)]
        for p, rows in foreign:
            got = p.locate(xa[rows], ya[rows], None if sp_in is None else sp_in[rows], max_advance, max_retreat)
            for o, v in zip(out, self._full(got, rows), strict=True):
                o[rows] = v
        return PathPoint._make(out)

    def _point(self, got: PathPoint) -> PathPoint:
        f = self._full(got)
        f[-1] = f[-1].astype(np.int64)
        return PathPoint(*f)


def _read_only(a: NDArray[Any]) -> NDArray[Any]:
    v = a.view()
    v.flags.writeable = False
    return v
