"""Paths from data (amigo_gym.paths.points): fits against known curves, files, bad input, the env on a fitted path."""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the environments)
from amigo_gym.paths import ClothoidPath, ClothoidSegment, fit_points, from_file, from_points, make_family_path


def test_circle_points_give_the_circles_length_and_curvature() -> None:
    """200 points on a circle of radius 1.5 m (closed form: length 3 pi, curvature 2/3)."""
    r = 1.5
    u = np.linspace(0.0, 2.0 * math.pi, 200, endpoint=False)
    pts = np.c_[r * np.cos(u), r * np.sin(u)]
    fit = fit_points(pts, closed=True)
    path = fit.path
    assert type(path) is ClothoidPath and path.closed
    assert abs(path.length - 2.0 * math.pi * r) < 1e-6
    s = np.linspace(0.0, path.length, 2000, endpoint=False)
    assert np.max(np.abs(path.curvature(s) - 1.0 / r)) < 1e-4 / r
    # the stated bound: every point within max_error <= tolerance of the path (closest point, independent search)
    assert fit.max_error <= 1e-3
    loc = path.locate(pts[:, 0], pts[:, 1])
    assert np.max(loc.distance) <= fit.max_error + 1e-12
    # every fitted point lies on the true circle
    q = path.point(s)
    assert np.max(np.abs(np.hypot(q[:, 0], q[:, 1]) - r)) < 1e-6


def test_clothoid_points_give_the_clothoids_curvature() -> None:
    """61 points on an Euler spiral (curvature 0.2 -> 1.1 1/m over 3 m): curvature, length and shape."""
    ref = ClothoidPath((ClothoidSegment.transition(3.0, 0.2, 1.1),), start=(0.5, -0.2), start_angle=0.3)
    pts = ref.point(np.linspace(0.0, 3.0, 61))
    fit = fit_points(pts)
    assert abs(fit.path.length - 3.0) < 1e-7
    s = np.linspace(0.0, 2.999, 300)
    # the spline's curvature: to 2.5e-3 at the ends (not-a-knot), 3e-4 inside
    assert np.max(np.abs(fit.path.curvature(s) - ref.curvature(s))) < 2.5e-3
    assert np.max(np.abs(fit.path.curvature(s[30:-30]) - ref.curvature(s[30:-30]))) < 3e-4
    assert np.max(np.abs(fit.path.point(s) - ref.point(s))) < 1e-4
    assert np.allclose(fit.point_s, np.linspace(0.0, 3.0, 61), atol=1e-7)


def test_a_figure8_closes_and_keeps_its_shape() -> None:
    """A closed path whose total turn is 0 (the figure-8 family), sampled every 5 cm."""
    fig = make_family_path("figure8", None)
    pts = fig.point(np.arange(0.0, fig.length, 0.05))
    fit = fit_points(pts, closed=True)
    assert fit.path.closed and abs(fit.path._t.turn) < 1e-12
    assert abs(fit.path.length - fig.length) < 1e-5
    s = np.linspace(0.0, fig.length, 1000, endpoint=False)
    assert np.max(np.abs(fit.path.point(s) - fig.point(s))) < 1e-4


def test_tolerance_is_met_or_refused() -> None:
    u = np.linspace(0.0, 1.0, 12)
    pts = np.c_[4.0 * u, np.sin(3.0 * u)]
    fit = fit_points(pts, tolerance=1e-6)
    assert fit.max_error <= 1e-6
    with pytest.raises(ValueError, match="above tolerance"):
        fit_points(pts, tolerance=1e-9, step=10.0)


@pytest.mark.parametrize(
    ("points", "closed", "message"),
    [
        ([[0, 0], [1, float("nan")], [2, 0]], False, r"points\[1\] must be finite"),
        ([[0, 0, 0], [1, 1, 1]], False, r"shape \(n, 2\)"),
        ([0.0, 1.0, 2.0], False, r"shape \(n, 2\)"),
        ([[0, 0]], False, "at least 2"),
        ([[0, 0], [1, 0], [0, 0]], True, "at least 3"),
        ([[0, 0], [1, 0], [1, 0], [2, 1]], False, r"points\[2\] repeats points\[1\]"),
        ([["a", "b"], ["c", "d"]], False, "real numbers"),
        ("points.csv", False, "from_file"),
    ],
)
def test_bad_points_are_refused_in_one_line(points: object, closed: bool, message: str) -> None:
    with pytest.raises(ValueError, match=message) as err:
        from_points(points, closed)
    assert "\n" not in str(err.value)


def test_csv_and_json_files(tmp_path: Path) -> None:
    u = np.linspace(0.0, 2.0 * math.pi, 40, endpoint=False)
    pts = np.c_[np.cos(u), np.sin(u)]
    csv_file = tmp_path / "pts.csv"
    csv_file.write_text("# a comment\nt,x,y\n" + "".join(f"{i},{x!r},{y!r}\n" for i, (x, y) in enumerate(pts.tolist())))
    json_file = tmp_path / "pts.json"
    json_file.write_text(json.dumps({"x": pts[:, 0].tolist(), "y": pts[:, 1].tolist(), "closed": True}))
    a = from_file(csv_file, closed=True)
    b = from_file(json_file)  # closed from the file
    c = from_points(pts, closed=True)
    assert b.closed and a.closed
    assert a.segments == c.segments == b.segments
    rows = tmp_path / "rows.json"
    rows.write_text(json.dumps([{"x": x, "y": y} for x, y in pts.tolist()]))
    assert not from_file(rows).closed


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("a.csv", "x,z\n0,0\n1,1\n", r"missing column\(s\) \['y'\]"),
        ("b.csv", "x,y\n0,0\n1,abc\n", "row 3, column 'y' must be a number"),
        ("c.csv", "x,y\n0,0\n1,nan\n", "row 3, column 'y' must be finite"),
        ("d.csv", "", "empty"),
        ("e.json", '{"x": [0, 1]}', r"missing key\(s\) \['y'\]"),
        ("f.json", '{"x": [0, 1], "y": [0, "1"]}', "point 1, 'y' must be a finite number"),
        ("g.json", "{", "not valid JSON"),
        ("h.csv", "x,y\n0,0\n", "at least 2"),
    ],
)
def test_bad_files_are_refused_naming_the_file(tmp_path: Path, name: str, text: str, message: str) -> None:
    f = tmp_path / name
    f.write_text(text)
    with pytest.raises(ValueError, match=message) as err:
        from_file(f)
    assert name in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(FileNotFoundError, match="no such points file"):
        from_file(tmp_path / "missing.csv")


def test_env_on_fitted_circle_matches_the_builtin_circle() -> None:
    """A single env on from_points(points of the circle family) steps like the built-in circle family."""
    fam = make_family_path("circle", None, radius=1.0, direction=1)
    pts = fam.point(np.arange(0.0, fam.length, 0.05))
    mine = from_points(pts, closed=True)
    kw = {"speed": 0.2, "max_episode_steps": 200, "randomize": "none"}
    e1 = gym.make("AmigoBot-v1", path=mine, **kw)
    e2 = gym.make("AmigoBot-v1", path="circle", radius=1.0, **kw)
    o1, _ = e1.reset(seed=3)
    o2, _ = e2.reset(seed=3)
    assert np.allclose(o1, o2, atol=1e-4)
    from amigo_gym.policies import AnalyticTrackingPolicy

    policy = AnalyticTrackingPolicy(e2.unwrapped.params)  # type: ignore[attr-defined]
    state, start = None, np.array([True])
    for _ in range(150):
        act, state = policy.predict(o2[None, :], state, start)  # the built-in env's action drives both
        start = np.array([False])
        a = act[0]
        o1, r1, t1, _, i1 = e1.step(a)
        o2, r2, t2, _, i2 = e2.step(a)
        assert np.allclose(i1["pose"], i2["pose"], atol=1e-4)  # the same robot; starts differ by the tangent fit
        assert abs(i1["cross_track_error"] - i2["cross_track_error"]) < 1e-5
        assert abs(r1 - r2) < 1e-3 and t1 == t2
        assert np.allclose(o1, o2, atol=2e-3)
        assert not t1
    if e1.unwrapped._kernel is not None:  # type: ignore[attr-defined]
        assert e1.unwrapped._in_kernel  # type: ignore[attr-defined]  # a fitted path runs the compiled step


# --------------------------------------------------------------------------- points as users bring them


def _circle(n: int, r: float = 3.0) -> np.ndarray:
    u = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    return np.c_[r * np.cos(u), r * np.sin(u)]


@pytest.mark.parametrize(
    ("points", "message"),
    [
        (1000.0 * _circle(190), r"spread over 8.48e\+03 m, outside \[0.33, 1000\] m; .*metres \(millimetres\?\)"),
        (np.c_[np.linspace(0.0, 1e-6, 11), np.zeros(11)], r"span a path of 1e-06 m, outside \[0.33, 1000\] m"),
        (_circle(190, 0.05), r"span a path of 0.314 m, outside \[0.33"),  # a circle smaller than the robot
    ],
)
def test_points_not_in_metres_are_refused_in_one_line(points: np.ndarray, message: str) -> None:
    """A 3 m circle in millimetres (a 19 km path; the fit used to exhaust memory), a 1 um line, a 5 cm circle."""
    with pytest.raises(ValueError, match=r"^from_points\.points " + message) as err:
        from_points(points, closed=points.shape[0] == 190)
    assert "\n" not in str(err.value) and "metres" in str(err.value)


def test_the_length_limits_are_what_is_refused() -> None:
    """Just inside the limits passes: a 0.34 m line and a 999 m line."""
    assert abs(from_points(np.c_[np.linspace(0.0, 0.34, 5), np.zeros(5)]).length - 0.34) < 1e-12
    assert abs(from_points(np.c_[np.linspace(0.0, 999.0, 5), np.zeros(5)], step=10.0).length - 999.0) < 1e-9


def test_shuffled_points_are_named_as_such() -> None:
    """190 points of a 3 m circle in random order: refused as out of order (the fit with a large tolerance used to
    give a 91 m path with curvature up to 1951 1/m); the same points in order fit."""
    pts = _circle(190)
    shuffled = pts[np.random.default_rng(0).permutation(len(pts))]
    for tol in (1e-3, 1.0):
        with pytest.raises(ValueError, match=r"^from_points\.points are not in path order: .*sort them") as err:
            from_points(shuffled, closed=True, tolerance=tol)
        assert "\n" not in str(err.value)
    assert abs(from_points(pts, closed=True).length - 6.0 * math.pi) < 1e-4


@pytest.fixture(scope="module")
def gps_circle() -> np.ndarray:
    """A GPS-like trace of a 3 m circle: 190 points (every 10 cm), 2 cm Gaussian noise per coordinate."""
    return _circle(190) + np.random.default_rng(1).normal(size=(190, 2)) * 0.02


def test_a_noisy_trace_is_smoothed_to_its_curvature(gps_circle: np.ndarray) -> None:
    """With smoothing=0.02 the curvature is within 20 % of the circle's 1/3 1/m everywhere (interpolated, the noise
    gives curvatures of tens of 1/m), and AmigoBot-v1 at 0.2 m/s accepts the path (its feasibility check refuses
    the interpolated one)."""
    fit = fit_points(gps_circle, closed=True, smoothing=0.02)
    s = np.linspace(0.0, fit.path.length, 4000, endpoint=False)
    assert np.max(np.abs(fit.path.curvature(s) * 3.0 - 1.0)) < 0.2
    assert abs(fit.path.length / (6.0 * math.pi) - 1.0) < 0.02
    # the stated bound: the smoothing moves the points by their 2-D noise, 2 cm * sqrt(2) RMS
    assert fit.smoothed == pytest.approx(0.02 * math.sqrt(2.0), rel=1e-2) and fit.max_error <= 1e-3
    env = gym.make("AmigoBot-v1", path=fit.path, speed=0.2)
    assert env.reset(seed=0)[1]["feasibility"]["feasible"]
    raw = from_points(gps_circle, closed=True)
    assert np.max(np.abs(raw.curvature(s[s < raw.length]) * 3.0 - 1.0)) > 10.0
    with pytest.raises(ValueError, match="feasib"):
        gym.make("AmigoBot-v1", path=raw, speed=0.2)


def test_dense_noisy_points_are_grouped_before_smoothing() -> None:
    """An open 4 m straight-then-arc trace sampled every 2 mm with 2 cm noise (noise 10 times the spacing):
    the curvature of the arc (radius 2 m) within 20 %, the straight within 0.1 1/m; at the open end the curvature
    falls to 0 over the last 0.6 m (natural ends, module docstring)."""
    ref = ClothoidPath((ClothoidSegment.line(2.0), ClothoidSegment.transition(0.5, 0.0, 0.5),
                        ClothoidSegment.arc(2.0, 0.5)))  # fmt: skip
    pts = ref.point(np.arange(0.0, ref.length, 0.002))
    pts += np.random.default_rng(2).normal(size=pts.shape) * 0.02
    path = from_points(pts, smoothing=0.02)
    s = np.linspace(0.0, path.length, 2000)
    k = path.curvature(s)
    assert np.max(np.abs(k[s < 1.5])) < 0.1
    assert np.max(np.abs(k[(s > 3.0) & (s < path.length - 0.6)] / 0.5 - 1.0)) < 0.2
    assert abs(k[-1]) < 0.1


def test_bad_smoothing_is_refused() -> None:
    for bad, message in ((0.0, r"smoothing must be in \(0, 1\]"), (-1.0, "smoothing"), ("a", "smoothing")):
        with pytest.raises(ValueError, match=message):
            from_points(_circle(50), closed=True, smoothing=bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"smoothing=1 m needs groups of 4 points to get 3 sigma apart, leaving 2"):
        from_points(np.c_[np.linspace(0.0, 1.0, 8), np.zeros(8)], smoothing=1.0)


def test_the_points_file_cache_is_bounded_by_bytes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Three files whose paths take about the same memory, under a budget of 2.5 of them: the oldest is dropped;
    the newest is kept even alone over the budget."""
    from amigo_gym.paths import points

    monkeypatch.setattr(points, "_FILE_CACHE", {})
    files = []
    for i in range(3):
        f = tmp_path / f"c{i}.csv"
        f.write_text("x,y\n" + "".join(f"{x!r},{y!r}\n" for x, y in _circle(400, 10.0 - 0.01 * i).tolist()))
        files.append(f)
        points.cached_file_path(f)
        if i == 0:
            ((_, size),) = points._FILE_CACHE.values()
            assert size > 1e6  # 63 m of path: its samples every 2 cm, its segments
            monkeypatch.setattr(points, "CACHE_BYTES", int(2.5 * size))
    assert [k[0] for k in points._FILE_CACHE] == [str(f.resolve()) for f in files[1:]]
    assert points.cached_file_path(files[2]) is points._FILE_CACHE[next(reversed(points._FILE_CACHE))][0]
    monkeypatch.setattr(points, "CACHE_BYTES", 1)
    points.cached_file_path(files[0])
    assert [k[0] for k in points._FILE_CACHE] == [str(files[0].resolve())]
