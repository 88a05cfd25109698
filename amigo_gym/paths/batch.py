"""A batch of paths, one per sub-environment: the column interface of a path on ``(N,)`` columns.

:class:`PathBatch` holds ``N`` paths (any mix of families and user paths) and offers
:class:`~amigo_gym.paths.clothoid.PathSpec` (``length``, ``closed``, ``pose_columns``, ``locate``) on ``(N,)``
columns, row ``i`` using path ``i``: row ``i`` of :meth:`PathBatch.locate` and :meth:`PathBatch.pose_columns`
equals ``paths[i]``'s own result for row ``i``'s floats.

The :class:`~amigo_gym.paths.clothoid.ClothoidPath` s' flat path vectors are stacked into a padded ``(N, W)``
array evaluated row by row (:func:`~amigo_gym.paths.clothoid.locate_rows`,
:func:`~amigo_gym.paths.clothoid.pose_rows`). When every row holds the same object (:meth:`PathBatch.from_path`)
that object is called with the columns directly (no table). A path of your own may sit in any rows: the rows
are grouped by object, each called once with its rows' ``(k,)`` columns.

Units: arc lengths and points [m], angles [rad], curvature [1/m], curvature rate [1/m^2].
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
    """``paths`` as a list, each with ``length``, ``closed``, ``pose_columns`` and ``locate`` (one-line error)."""
    for i, p in enumerate(paths):
        if not all(hasattr(p, a) for a in ("length", "closed", "pose_columns", "locate")):
            raise ValueError(
                f"{where}[{i}] must have length, closed, pose_columns and locate (amigo_gym.paths.PathSpec), "
                f"got {type(p).__name__}"
            )
    return list(paths)


@dataclass
class _Padded:
    """The rows' flat path vectors: row ``i``'s in ``flat[i]`` (``W`` entries, the longest vector's), at
    ``start[i] = i W`` in ``flat.reshape(-1)``."""

    flat: Array
    start: IntArray

    @classmethod
    def empty(cls, n: int, w: int) -> _Padded:
        return cls(np.zeros((n, w)), np.arange(n, dtype=np.int64) * w)

    def write(self, rows: IntArray, path: ClothoidPath) -> None:
        """Rows ``rows`` take ``path``'s flat vector (the table widens when it is longer than any before)."""
        f = path._t.flat  # same package: the batch stacks the path's own vector
        n, w = self.flat.shape
        if f.size > w:
            wide = np.zeros((n, f.size))
            wide[:, :w] = self.flat
            self.flat, self.start = wide, np.arange(n, dtype=np.int64) * f.size
        self.flat[rows, : f.size] = f

    def pose(self, s: Array) -> PathPose:
        """:func:`~amigo_gym.paths.clothoid.pose_flat` of each row's path at ``s`` ``(N,)`` [m]."""
        return pose_columns_of(self.flat.reshape(-1), self.start, s)


class PathBatch:
    """``N`` paths, one per row, with the column interface of a path (module docstring).

    Args:
        paths: the ``N >= 1`` paths: :class:`~amigo_gym.paths.clothoid.ClothoidPath` s or objects implementing
            :class:`~amigo_gym.paths.clothoid.PathSpec`.
    """

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
        #: the objects that are not ClothoidPaths (a subset of ``_objects``, in its order)
        self._foreign_objects: dict[int, PathSpec] = {}
        self._counts: dict[int, int] = {}
        self._tables: _Padded | None = None
        self._set(np.arange(n, dtype=np.intp), seq)

    @classmethod
    def from_path(cls, path: PathSpec, n: int) -> PathBatch:
        """A batch of ``n >= 1`` rows all using ``path``: evaluated by ``path`` itself on the columns (no padding)."""
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise ValueError(f"PathBatch.from_path.n must be an int >= 1, got {n!r}")
        return cls([path] * int(n))

    # --- rows -------------------------------------------------------------------------------------------

    def _set(self, rows: NDArray[np.intp], paths: Sequence[PathSpec]) -> None:
        """Rows ``rows`` take ``paths``: bookkeeping O(len(rows)), tables O(len(rows) W) when they exist."""
        for r in rows.tolist():
            old = self._counts.get(int(self._ids[r]))
            if old is not None:  # (at construction the ids are 0: no object has id 0)
                oid = int(self._ids[r])
                if old == 1:
                    del self._counts[oid], self._objects[oid]
                    self._foreign_objects.pop(oid, None)
                else:
                    self._counts[oid] = old - 1
        groups: dict[int, tuple[PathSpec, list[int]]] = {}
        for r, p in zip(rows.tolist(), paths, strict=True):
            groups.setdefault(id(p), (p, []))[1].append(r)
        for oid, (p, rs) in groups.items():
            ra = np.asarray(rs, dtype=np.intp)
            self._ids[ra] = oid
            self._length[ra] = float(p.length)
            self._closed[ra] = bool(p.closed)
            self._objects[oid] = p
            if not isinstance(p, ClothoidPath):
                self._foreign_objects[oid] = p
            self._counts[oid] = self._counts.get(oid, 0) + len(rs)
            for r in rs:
                self._paths[r] = p
        if self._tables is not None:
            for p, rs in groups.values():
                self._write(self._tables, np.asarray(rs, dtype=np.intp), p)

    @staticmethod
    def _write(t: _Padded, rows: IntArray | NDArray[np.intp], p: PathSpec) -> None:
        t.write(np.asarray(rows, dtype=np.int64), p if isinstance(p, ClothoidPath) else _PLACEHOLDER)

    def _padded(self) -> _Padded:
        """The padded tables, built on first need (O(N W), once; kept up to date by :meth:`replace`)."""
        if self._tables is None:
            clothoids = [p for p in self._objects.values() if isinstance(p, ClothoidPath)] + [_PLACEHOLDER]
            t = _Padded.empty(len(self._paths), max(p._t.flat.size for p in clothoids))
            order = np.argsort(self._ids, kind="stable")  # rows grouped by object: O(N log N), not O(N * objects)
            ids = self._ids[order]
            starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
            for rows in np.split(order, starts[1:]):
                self._write(t, rows, self._objects[int(self._ids[rows[0]])])
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

    @property
    def num_paths(self) -> int:
        """Number of rows ``N``."""
        return len(self._paths)

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
        v = self._length.view()
        v.flags.writeable = False
        return v

    @property
    def closed(self) -> BoolArray:
        """``(N,)`` whether each row's path is closed (a read-only view, updated by :meth:`replace`)."""
        v = self._closed.view()
        v.flags.writeable = False
        return v

    # --- evaluation -------------------------------------------------------------------------------------

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
        """Result fields as fresh ``(N,)`` arrays (or ``(len(rows),)``)."""
        n = len(self._paths) if rows is None else rows.size
        return [np.array(np.broadcast_to(np.asarray(f), (n,))) for f in fields]

    def pose_columns(self, s: Real) -> PathPose:
        """Point, tangent angle, curvature and curvature rate of each row's path at ``s`` [m].

        Args:
            s: ``(N,)`` arc lengths [m] (or a float for all rows).

        Returns:
            :class:`~amigo_gym.paths.classic.PathPose` of ``(N,)`` columns.
        """
        sa = self._column("s", s)
        only = self._uniform()
        if only is not None:
            return PathPose(*self._full(only.pose_columns(float(sa[0]) if sa.size == 1 else sa)))
        foreign = self._foreign()
        if len(foreign) == len(self._objects):
            out = [np.zeros(sa.shape) for _ in PathPose._fields]
        else:
            out = self._full(self._padded().pose(sa))
        for p, rows in foreign:
            for o, v in zip(out, self._full(p.pose_columns(sa[rows]), rows), strict=True):
                o[rows] = v
        return PathPose(*out)

    def locate(
        self,
        x: Real,
        y: Real,
        s_prev: Real | None = None,
        max_advance: float = 0.5,
        max_retreat: float | None = None,
    ) -> PathPoint:
        """Closest point of each row's path to ``(x, y)``, keeping progress (:meth:`ClothoidPath.locate`).

        Args:
            x, y: ``(N,)`` query points [m] (or floats for all rows).
            s_prev: ``(N,)`` previous progress [m] (unwrapped), or None for a global search.
            max_advance, max_retreat: the window ahead of and behind ``s_prev`` [m], > 0 (``max_retreat``
                defaults to ``max_advance``).

        Returns:
            :class:`~amigo_gym.paths.classic.PathPoint` of ``(N,)`` columns (``status`` int64).
        """
        xa = self._column("x", x)
        ya = self._column("y", y)
        ahead, behind = check_window(max_advance, max_retreat)
        sp = None if s_prev is None else self._column("s_prev", s_prev)
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
            out = [np.asarray(v) for v in self._locate_padded(xa, ya, sp, ahead, behind)]
        for p, rows in foreign:
            got = p.locate(xa[rows], ya[rows], None if sp is None else sp[rows], max_advance, max_retreat)
            for o, v in zip(out, self._full(got, rows), strict=True):
                o[rows] = v
        return PathPoint._make(out)

    def _point(self, got: PathPoint) -> PathPoint:
        f = self._full(got)
        f[-1] = f[-1].astype(np.int64)
        return PathPoint(*f)

    def _locate_padded(self, x: Array, y: Array, sp: Array | None, ahead: float, behind: float) -> PathPoint:
        """:meth:`ClothoidPath.locate` on every row with its own flat path."""
        if sp is not None and not np.isfinite(sp).all():  # refused on a ClothoidPath's row, ignored on another's
            check_hint(sp[~np.isin(self._ids, list(self._foreign_objects))])
            sp = np.where(np.isfinite(sp), sp, 0.0)
        t = self._padded()
        return locate_columns(t.flat.reshape(-1), t.start, x, y, sp, ahead, behind)
