"""PathBatch: row i of every column result equals path i's own float result to 1e-12 (the float route takes arcs in
closed form, the columns a quadrature; all families, windows,
figure-8 crossings, beyond the ends of open paths, several laps of closed ones), replace/grow, uniform batches,
and paths of the user's own grouped by object."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from amigo_gym.model.kinematics import Real
from amigo_gym.paths import (
    STATUS_END,
    STATUS_START,
    ClothoidPath,
    PathBatch,
    PathPoint,
    PathPose,
    PathSpec,
    circle,
    figure8,
    lane_change,
    manoeuvre,
    random_path,
)

Array = np.ndarray[Any, np.dtype[np.float64]]


def _sign(rng: np.random.Generator) -> int:
    return 1 if rng.random() < 0.5 else -1


def _random_paths(rng: np.random.Generator, n: int) -> list[ClothoidPath]:
    """``n`` paths cycling through every family with random parameters (and a few custom clothoid paths)."""
    out: list[ClothoidPath] = []
    for i in range(n):
        kind = i % 6
        if kind == 0:
            start = (float(rng.uniform(-2, 2)), float(rng.uniform(-2, 2)))
            out.append(circle(float(rng.uniform(0.3, 5.0)), _sign(rng), start, float(rng.uniform(-4, 4))))
        elif kind == 1:
            out.append(
                manoeuvre(float(rng.uniform(0.3, 3)), float(rng.uniform(0, 3)), _sign(rng), rng.uniform(0.3, 2.5))
            )
        elif kind == 2:
            out.append(figure8(float(rng.uniform(1, 8)), float(rng.uniform(0.5, 1.9)), float(rng.uniform(0, 1.2))))
        elif kind == 3:
            length = float(rng.uniform(1.0, 5.0))
            off = float(rng.uniform(-0.6, 0.6)) * length
            out.append(lane_change(off, length, float(rng.uniform(0, 2))))
        elif kind == 4:
            g = np.random.default_rng(int(rng.integers(1 << 30)))
            out.append(
                random_path(g, float(rng.uniform(1, 30)), float(rng.uniform(0.2, 3)), float(rng.uniform(0.2, 5)))
            )
        else:  # a custom start pose and sample spacing
            g = np.random.default_rng(int(rng.integers(1 << 30)))
            base = random_path(g, float(rng.uniform(1, 10)), 2.0, 3.0)
            start = (float(rng.uniform(-3, 3)), float(rng.uniform(-3, 3)))
            out.append(
                ClothoidPath(base.segments, start, float(rng.uniform(-4, 4)), False, float(rng.uniform(0.003, 0.2)))
            )
    return out


def _queries(rng: np.random.Generator, paths: Sequence[PathSpec]) -> tuple[Array, Array, Array]:
    """Points near each path (some far), at arc lengths over several laps (closed) or beyond the ends (open),
    and hints near the true arc length."""
    s_true = np.array(
        [rng.uniform(-1.0, 3.0) * p.length if p.closed else rng.uniform(-0.3, 1.3) * p.length for p in paths]
    )
    pose = [p.pose_columns(float(s)) for p, s in zip(paths, s_true, strict=True)]
    off = rng.uniform(-0.6, 0.6, len(paths))
    x = np.array([float(q.x) - o * float(q.sin_theta) for q, o in zip(pose, off, strict=True)])
    y = np.array([float(q.y) + o * float(q.cos_theta) for q, o in zip(pose, off, strict=True)])
    far = rng.random(len(paths)) < 0.1
    x[far] += rng.uniform(-5, 5, far.sum())
    y[far] += rng.uniform(-5, 5, far.sum())
    return x, y, s_true + rng.uniform(-0.3, 0.3, len(paths))


def _assert_rows(got: PathPoint | PathPose, refs: Sequence[PathPoint | PathPose]) -> None:
    """Every field of ``got`` is an ``(N,)`` array whose row i is ``refs[i]``'s field: the status exactly, the floats
    within 1e-12 (relative, of at least 1 m, rad or 1/m), NaN where the reference has NaN."""
    n = len(refs)
    for f in got._fields:
        col = getattr(got, f)
        assert isinstance(col, np.ndarray) and col.shape == (n,), (f, type(col), np.shape(col))
        assert col.dtype == (np.int64 if f == "status" else np.float64), (f, col.dtype)
        ref = np.array([getattr(r, f) for r in refs], dtype=col.dtype)
        if f == "status":
            bad = np.flatnonzero(col != ref)
        else:
            off = np.abs(col - ref) > 1e-12 * np.maximum(1.0, np.abs(ref))
            bad = np.flatnonzero(np.where(np.isnan(ref), ~np.isnan(col), off | np.isnan(col)))
        assert bad.size == 0, f"{f}: rows {bad[:5].tolist()}: {col[bad[:5]]} != {ref[bad[:5]]}"


def _ref_locate(
    paths: Sequence[PathSpec], x: Array, y: Array, sp: Array | None, ahead: float = 0.5, behind: float | None = None
) -> list[PathPoint]:
    if sp is None:
        return [p.locate(float(a), float(b)) for p, a, b in zip(paths, x, y, strict=True)]
    return [p.locate(float(a), float(b), float(c), ahead, behind) for p, a, b, c in zip(paths, x, y, sp, strict=True)]


@pytest.mark.parametrize("seed", [0, 1])
def test_locate_windowed_agrees(seed: int) -> None:
    rng = np.random.default_rng(seed)
    paths = _random_paths(rng, 72)
    batch = PathBatch(paths)
    for ahead, behind in [(0.5, None), (0.25, 0.6), (1.3, 0.1)]:
        x, y, sp = _queries(rng, paths)
        _assert_rows(batch.locate(x, y, sp, ahead, behind), _ref_locate(paths, x, y, sp, ahead, behind))


def test_locate_global_agrees() -> None:
    rng = np.random.default_rng(2)
    paths = _random_paths(rng, 48)
    batch = PathBatch(paths)
    x, y, _ = _queries(rng, paths)
    _assert_rows(batch.locate(x, y), _ref_locate(paths, x, y, None))


def test_pose_columns_agree_over_laps_and_beyond_ends() -> None:
    rng = np.random.default_rng(3)
    paths = _random_paths(rng, 60)
    batch = PathBatch(paths)
    length = batch.length
    for s in (
        rng.uniform(-2.0, 4.0) * length,
        np.where(batch.closed, 3.0 * length, length + 0.7),  # whole laps; past the end
        np.zeros(len(paths)),
        -rng.uniform(0.0, 2.0, len(paths)),
        length,
        -length,
        np.array([p._t.s0[rng.integers(len(p._t.s0))] for p in paths]),  # exactly at a piece's start
    ):
        _assert_rows(batch.pose_columns(s), [p.pose_columns(float(v)) for p, v in zip(paths, s, strict=True)])


def test_figure8_crossing_keeps_each_branch() -> None:
    """Points near the crossing with hints on either branch: every row as its own path, on its own branch."""
    rng = np.random.default_rng(4)
    paths = [
        figure8(float(rng.uniform(2, 6)), float(rng.uniform(0.6, 1.8)), float(rng.uniform(0, 1))) for _ in range(24)
    ]
    batch = PathBatch(paths)
    length = batch.length
    lap = rng.integers(-1, 3, len(paths))
    branch = np.where(np.arange(len(paths)) % 2 == 0, 0.25, 0.75)
    sp = (lap + branch) * length + rng.uniform(-0.05, 0.05, len(paths))
    x = rng.uniform(-0.05, 0.05, len(paths))
    y = rng.uniform(-0.05, 0.05, len(paths))
    got = batch.locate(x, y, sp, 0.3)
    _assert_rows(got, _ref_locate(paths, x, y, sp, 0.3))
    assert np.all(np.abs(np.asarray(got.progress) - sp) < 0.3)  # stayed on the hinted branch


def test_open_path_ends_status() -> None:
    rng = np.random.default_rng(5)
    paths = [lane_change(0.4, 3.0, 1.0), random_path(np.random.default_rng(7), 6.0)] * 4
    batch = PathBatch(paths)
    sp = np.where(np.arange(8) % 2 == 0, 0.0, batch.length)
    before = np.array([p.pose_columns(-0.3) for p in paths], dtype=np.float64)[:, :2]
    after = np.array([[float(v) for v in p.pose_columns(float(p.length) + 0.3)[:2]] for p in paths])
    pts = np.where((np.arange(8) % 2 == 0)[:, None], before, after) + rng.uniform(-0.01, 0.01, (8, 2))
    got = batch.locate(pts[:, 0], pts[:, 1], sp, 0.4)
    _assert_rows(got, _ref_locate(paths, pts[:, 0], pts[:, 1], sp, 0.4))
    assert np.array_equal(got.status, np.where(np.arange(8) % 2 == 0, STATUS_START, STATUS_END))


def test_replace_grows_and_keeps_rows_exact() -> None:
    rng = np.random.default_rng(6)
    paths = [circle(1.0)] * 3 + _random_paths(rng, 9)
    batch = PathBatch(paths)
    x, y, sp = _queries(rng, paths)
    batch.locate(x, y, sp)  # builds the tables
    assert batch._tables is not None
    p_before = batch._tables.flat.shape[1]
    big = manoeuvre(0.5, 2.0, 1, 40.0)  # many pieces, many samples: the padded arrays grow
    rows = np.array([1, 7, 4], dtype=np.intp)
    new = [big, circle(2.5, -1), paths[5]]
    batch.replace(rows, new)
    for r, p in zip(rows, new, strict=True):
        paths[r] = p
        assert batch[int(r)] is p
    assert batch._tables.flat.shape[1] > p_before
    assert np.array_equal(batch.length, [p.length for p in paths])
    assert np.array_equal(batch.closed, [p.closed for p in paths])
    x, y, sp = _queries(rng, paths)
    _assert_rows(batch.locate(x, y, sp, 0.4), _ref_locate(paths, x, y, sp, 0.4))
    _assert_rows(batch.locate(x, y), _ref_locate(paths, x, y, None))
    _assert_rows(batch.pose_columns(sp), [p.pose_columns(float(v)) for p, v in zip(paths, sp, strict=True)])
    batch.replace(np.array([], dtype=np.intp), [])  # nothing


def test_from_path_uniform_needs_no_tables_and_switches_to_mixed() -> None:
    rng = np.random.default_rng(8)
    path = figure8(3.0)
    batch = PathBatch([path] * 40)
    assert len(batch) == 40 and batch[17] is path
    paths = [path] * 40
    x, y, sp = _queries(rng, paths)
    _assert_rows(batch.locate(x, y, sp), _ref_locate(paths, x, y, sp))
    _assert_rows(batch.locate(x, y), _ref_locate(paths, x, y, None))
    _assert_rows(batch.pose_columns(sp), [path.pose_columns(float(v)) for v in sp])
    assert batch._tables is None  # no padding cost while every row uses one path
    # a float for all rows broadcasts
    _assert_rows(batch.pose_columns(0.5), [path.pose_columns(0.5)] * 40)
    # autoreset puts other paths in some rows: exact on every row
    other = _random_paths(rng, 6)
    batch.replace(np.arange(0, 40, 7), other)
    for r, p in zip(range(0, 40, 7), other, strict=True):
        paths[r] = p
    x, y, sp = _queries(rng, paths)
    _assert_rows(batch.locate(x, y, sp), _ref_locate(paths, x, y, sp))
    # and back to a single path
    batch.replace(np.arange(0, 40, 7), [path] * 6)
    assert batch._uniform() is path
    _assert_rows(batch.locate(x, y, sp), _ref_locate([path] * 40, x, y, sp))


class OwnPath:
    """A path of the user's own (not a ClothoidPath): a circle shifted by (dx, dy); counts the calls."""

    def __init__(self, radius: float, dx: float) -> None:
        self._p = circle(radius)
        self._dx = dx
        self.calls = 0

    @property
    def length(self) -> float:
        return self._p.length

    @property
    def closed(self) -> bool:
        return True

    def pose_columns(self, s: Real) -> PathPose:
        self.calls += 1
        q = self._p.pose_columns(s)
        return q._replace(x=q.x + self._dx)

    def locate(
        self, x: Real, y: Real, s_prev: Real | None = None, max_advance: float = 0.5, max_retreat: float | None = None
    ) -> PathPoint:
        self.calls += 1
        q = self._p.locate(x - self._dx, y, s_prev, max_advance, max_retreat)
        return q._replace(x=q.x + self._dx)


def test_own_paths_grouped_by_object() -> None:
    rng = np.random.default_rng(9)
    own_a, own_b = OwnPath(1.0, 0.5), OwnPath(2.0, -1.0)
    clothoids = _random_paths(rng, 8)
    paths: list[Any] = [own_a, *clothoids[:4], own_b, own_a, *clothoids[4:], own_b, own_a]
    batch = PathBatch(paths)
    x, y, sp = _queries(rng, paths)
    refs = _ref_locate(paths, x, y, sp, 0.4)
    own_a.calls = own_b.calls = 0
    _assert_rows(batch.locate(x, y, sp, 0.4), refs)
    assert own_a.calls == own_b.calls == 1  # one call per distinct object, not per row
    _assert_rows(batch.locate(x, y), _ref_locate(paths, x, y, None))
    _assert_rows(batch.pose_columns(sp), [p.pose_columns(float(v)) for p, v in zip(paths, sp, strict=True)])
    # only paths of one's own (two objects), and a single one
    only = [own_a, own_b, own_b, own_a]
    x, y, sp = _queries(rng, only)
    _assert_rows(PathBatch(only).locate(x, y, sp), _ref_locate(only, x, y, sp))
    one = PathBatch([own_b] * 3)
    _assert_rows(one.locate(x[1:], y[1:], sp[1:]), _ref_locate([own_b] * 3, x[1:], y[1:], sp[1:]))


def test_properties_and_errors() -> None:
    paths = [circle(1.0), lane_change()]
    batch = PathBatch(paths)
    assert np.array_equal(batch.length, [paths[0].length, paths[1].length])
    assert batch.closed.tolist() == [True, False]
    assert batch.paths == tuple(paths)
    with pytest.raises(ValueError):
        batch.length[0] = 1.0  # read-only
    with pytest.raises(ValueError, match="at least one path"):
        PathBatch([])
    with pytest.raises(ValueError, match=r"paths\[1\]"):
        PathBatch([circle(1.0), "circle"])  # type: ignore[list-item]
    with pytest.raises(ValueError, match="shape"):
        batch.locate(np.zeros(3), np.zeros(3))
    with pytest.raises(ValueError, match="max_advance"):
        batch.locate(np.zeros(2), np.zeros(2), np.zeros(2), -1.0)
    with pytest.raises(ValueError, match="max_retreat"):
        batch.locate(np.zeros(2), np.zeros(2), np.zeros(2), 0.5, math.nan)
    with pytest.raises(ValueError, match="distinct"):
        batch.replace(np.array([1, 1]), [circle(2.0), circle(2.0)])
    with pytest.raises(ValueError, match=r"\[0, 2\)"):
        batch.replace(np.array([2]), [circle(2.0)])
    with pytest.raises(ValueError, match="1 rows but 2 paths"):
        batch.replace(np.array([0]), [circle(2.0), circle(2.0)])
    assert batch[0] is paths[0] and batch[1] is paths[1]  # unchanged by the refused calls


def test_single_row_batches() -> None:
    """N = 1 (the path's float code behind (1,) columns), windowed, global and poses, for every family."""
    rng = np.random.default_rng(10)
    for path in _random_paths(rng, 12):
        batch = PathBatch([path])
        x, y, sp = _queries(rng, [path])
        _assert_rows(batch.locate(x, y, sp, 0.3), _ref_locate([path], x, y, sp, 0.3))
        _assert_rows(batch.locate(float(x[0]), float(y[0])), _ref_locate([path], x, y, None))
        _assert_rows(batch.pose_columns(sp), [path.pose_columns(float(sp[0]))])
