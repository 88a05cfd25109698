"""Clothoid paths against independent facts: mpmath quadrature, closed forms (circle, straight-line lag), the v0
paths, finite differences, brute-force distances, and SciPy's integration of the inverse solution."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
from numpy.typing import NDArray

from amigo_gym.model.kinematics import circle_steady_state
from amigo_gym.model.params import RobotParams
from amigo_gym.paths import (
    FAMILIES,
    STATUS_END,
    STATUS_INTERIOR,
    STATUS_START,
    STATUS_WINDOW,
    CirclePath,
    ClothoidPath,
    ClothoidSegment,
    ManoeuvrePath,
    circle,
    feasibility,
    figure8,
    heading_lag_profile,
    lane_change,
    make_family_path,
    manoeuvre,
    preview,
    random_path,
)
from amigo_gym.task.inverse import ConstantSpeed, solve_inverse

Array = NDArray[np.float64]
Seg = ClothoidSegment


def _mp_path(segs: list[Seg], start: tuple[float, float, float]) -> list[tuple[float, mpmath.mpf, ...]]:
    """Start poses (s0, x, y, theta) of the segments by mpmath quadrature at 30 digits."""
    mpmath.mp.dps = 30
    x, y, th = (mpmath.mpf(v) for v in start)
    s0 = mpmath.mpf(0)
    out = []
    for g in segs:
        out.append((s0, x, y, th))
        x, y, th = _mp_advance(x, y, th, g, mpmath.mpf(g.length))
        s0 += mpmath.mpf(g.length)
    out.append((s0, x, y, th))
    return out


def _mp_advance(x: mpmath.mpf, y: mpmath.mpf, th: mpmath.mpf, g: Seg, u: mpmath.mpf) -> tuple[mpmath.mpf, ...]:
    k, c = mpmath.mpf(g.curvature), mpmath.mpf(g.curvature_rate)
    nodes = mpmath.linspace(0, u, 9)
    dx = mpmath.quad(lambda t: mpmath.cos(th + k * t + c * t * t / 2), nodes)
    dy = mpmath.quad(lambda t: mpmath.sin(th + k * t + c * t * t / 2), nodes)
    return x + dx, y + dy, th + k * u + c * u * u / 2


MIXED = [
    Seg.line(1.0),
    Seg.transition(2.0, 0.0, 1.5),
    Seg.arc(3.0, 1.5),
    Seg.transition(2.5, 1.5, -0.7),
    Seg(1.0, 0.1, 1e-12),  # a tiny curvature rate: the textbook Fresnel difference loses digits here
    Seg(4.0, -3.0, 0.9),  # curvature through zero, turning 9 rad: split into pieces
]


def test_geometry_against_mpmath() -> None:
    """Points and tangent angles of a mixed path equal 30-digit quadrature to 1e-12 m / rad."""
    start = (0.3, -1.2, 0.7)
    path = ClothoidPath(tuple(MIXED), start[:2], start[2])
    poses = _mp_path(MIXED, start)
    s_all = np.concatenate([np.linspace(0.0, path.length, 23), [3.0, 6.0 + 1e-9, 8.49, path.length]])
    worst = 0.0
    got = path.point(s_all)
    th_got = path.tangent_angle(s_all)
    for s, p, th in zip(s_all, got, th_got, strict=True):
        i = max(j for j in range(len(MIXED)) if float(poses[j][0]) <= s) if s < path.length else len(MIXED) - 1
        s0, x, y, t0 = poses[i]
        xe, ye, te = _mp_advance(x, y, t0, MIXED[i], mpmath.mpf(float(s)) - s0)
        worst = max(worst, abs(p[0] - float(xe)), abs(p[1] - float(ye)), abs(th - float(te)))
    assert worst < 1e-12, worst
    assert path.length == pytest.approx(13.5, abs=1e-15)


def test_line_and_arc_closed_forms() -> None:
    """A line is p0 + s (cos, sin)(theta0); an arc c + R (sin, -cos)(theta) -- exact, any length."""
    line = ClothoidPath((Seg.line(50.0),), (1.0, 2.0), 0.4)
    s = np.linspace(-3.0, 60.0, 101)  # beyond the ends: the straight continuation
    np.testing.assert_allclose(
        line.point(s), np.column_stack((1 + s * math.cos(0.4), 2 + s * math.sin(0.4))), atol=1e-12
    )
    arc = ClothoidPath((Seg.arc(40.0, -1 / 0.7),), (0.0, 0.0), 0.0)
    s = np.linspace(0.0, 40.0, 101)
    th = -s / 0.7
    np.testing.assert_allclose(arc.point(s), np.column_stack((-0.7 * np.sin(th), -0.7 + 0.7 * np.cos(th))), atol=1e-12)
    np.testing.assert_allclose(arc.tangent_angle(s), th, atol=1e-12)


@pytest.mark.parametrize(("radius", "d", "start", "angle"), [(1.0, 1, (0.0, 0.0), 0.0), (0.3, -1, (2.0, -1.0), 1.3)])
def test_circle_family_matches_circlepath(radius: float, d: int, start: tuple[float, float], angle: float) -> None:
    path = circle(radius, d, start, angle)
    ref = CirclePath(radius, start, angle, d)
    s = np.linspace(-5.0, 4 * ref.length, 997)
    assert np.abs(path.point(s) - ref.point(s)).max() < 1e-12
    assert np.abs(path.tangent_angle(s) - ref.tangent_angle(s)).max() < 1e-12
    np.testing.assert_allclose(path.curvature(s), d / radius, rtol=1e-15)
    assert path.length == pytest.approx(ref.length, rel=1e-15)
    rng = np.random.default_rng(3)
    q = ref.point(rng.uniform(0, ref.length, 500)) + rng.uniform(-0.8, 0.8, (500, 2)) * radius * 0.3
    a, b = path.project(q), ref.project(q)
    ds = np.abs(a.s - b.s)
    ds = np.minimum(ds, ref.length - ds)  # the same point at 0 and one lap
    assert ds.max() < 1e-12
    assert np.abs(a.cross_track_error - b.cross_track_error).max() < 1e-12
    assert np.abs(a.curvature - b.curvature).max() == 0.0


@pytest.mark.parametrize(
    ("radius", "d", "start", "angle", "pieces"),
    [(1.0, 1, (0.0, 0.0), 0.0, 1), (0.3, -1, (2.0, -1.0), 1.3, 1), (0.8, -1, (1.0, 2.0), -2.9, 3)],
)
def test_hinted_projection_on_a_circle_in_closed_form(
    radius: float, d: int, start: tuple[float, float], angle: float, pieces: int
) -> None:  # fmt: skip
    """With a hint on a circle (arcs of one curvature, closed) the foot is in closed form (no coarse search): against
    :class:`CirclePath` to 1e-12 m on the lap nearest the hint, and clamped at the window's edge beyond it; the pose
    (also in closed form) against :class:`CirclePath`'s too."""
    arc = Seg.arc(2.0 * math.pi * radius / pieces, d / radius)
    path = ClothoidPath((arc,) * pieces, start, angle, closed=True)
    ref = CirclePath(radius, start, angle, d)
    assert path._t.flat[6:9].tolist() == pytest.approx([d / radius, *ref.center], abs=1e-15)
    assert figure8(4.0)._t.flat[6:9].tolist() == [0.0, 0.0, 0.0]  # not a circle: the coarse search
    rng = np.random.default_rng(5)
    s_true = rng.uniform(-3 * ref.length, 3 * ref.length, 400)
    e = rng.uniform(-0.6, 0.6, 400) * radius
    th = ref.tangent_angle(s_true)
    q = ref.point(s_true) + e[:, None] * np.column_stack((-np.sin(th), np.cos(th)))
    hint = s_true + rng.uniform(-0.4, 0.4, 400) * radius
    r = path.locate(q[:, 0], q[:, 1], s_prev=hint, max_advance=0.475)
    assert np.abs(r.progress - s_true).max() < 1e-12
    assert np.abs(path.point(s_true) - ref.point(s_true)).max() < 1e-12  # the pose in closed form too, laps included
    assert np.abs(path.tangent_angle(s_true) - th).max() < 1e-12
    assert path.pose_columns(float(s_true[0])).x == pytest.approx(float(ref.point(s_true[0])[0]), abs=1e-12)
    assert np.abs(r.cross_track_error - e).max() < 1e-12
    assert (r.status == STATUS_INTERIOR).all()
    far = path.locate(float(q[0, 0]), float(q[0, 1]), s_prev=float(s_true[0]) - 0.5, max_advance=0.2)
    assert (far.progress, far.status) == (pytest.approx(float(s_true[0]) - 0.3, abs=1e-12), STATUS_WINDOW)


def test_manoeuvre_family_matches_manoeuvrepath() -> None:
    path = manoeuvre(0.8, 1.5, -1)
    ref = ManoeuvrePath(0.8, 1.5, -1)
    s = np.linspace(0.0, ref.length, 501)
    assert np.abs(path.point(s) - ref.point(s)).max() < 1e-12
    assert np.abs(path.tangent_angle(s) - ref.tangent_angle(s)).max() < 1e-12
    np.testing.assert_array_equal(path.curvature(s[s > 1.5]), -1.25)
    np.testing.assert_array_equal(path.curvature(s[s < 1.5]), 0.0)


def _fd_check(path: ClothoidPath, s: Array, h: float = 1e-4) -> tuple[float, float, float]:
    """Worst errors of tangent = dp/ds, curvature = dtheta/ds, rate = dkappa/ds by central differences."""
    dp = (path.point(s + h) - path.point(s - h)) / (2 * h)
    th = path.tangent_angle(s)
    e_t = np.abs(dp - np.column_stack((np.cos(th), np.sin(th)))).max()
    e_k = np.abs((path.tangent_angle(s + h) - path.tangent_angle(s - h)) / (2 * h) - path.curvature(s)).max()
    e_c = np.abs((path.curvature(s + h) - path.curvature(s - h)) / (2 * h) - path.curvature_rate(s)).max()
    return float(e_t), float(e_k), float(e_c)


@pytest.mark.parametrize("name", ["mixed", "figure8", "lane_change", "random"])
def test_derivatives_by_finite_differences(name: str) -> None:
    path = {
        "mixed": ClothoidPath(tuple(MIXED)),
        "figure8": figure8(3.0),
        "lane_change": lane_change(0.8, 2.5),
        "random": random_path(np.random.default_rng(5), 30.0, 2.0, 3.0),
    }[name]
    brk = np.asarray(path.breakpoints())
    s = np.random.default_rng(1).uniform(0.0, path.length, 400)
    s = s[np.min(np.abs(s[:, None] - brk[None, :]), axis=1) > 1e-3]  # away from curvature kinks
    e_t, e_k, e_c = _fd_check(path, s)
    kmax = path.max_abs_curvature
    assert e_t < 1e-8 * (1 + kmax**2) + 1e-10, e_t  # h^2 kappa^2 / 6 plus rounding
    assert e_k < 1e-9, e_k  # theta is quadratic on a piece: exact up to rounding / h
    assert e_c < 1e-9, e_c


def test_projection_is_the_closest_point() -> None:
    """Foot points are orthogonal to machine precision and no farther than the densest brute-force sample."""
    path = random_path(np.random.default_rng(11), 25.0, 1.5, 2.0)
    rng = np.random.default_rng(2)
    s_true = rng.uniform(0.5, path.length - 0.5, 300)
    q = path.point(s_true) + rng.uniform(-0.3, 0.3, (300, 2))
    r = path.locate(q[:, 0], q[:, 1])
    dense = path.point(np.linspace(0.0, path.length, 250_001))  # 1e-4 m apart
    brute = np.sqrt(((q[:, None, :] - dense[None, ::25, :]) ** 2).sum(-1)).min(axis=1)  # coarse, cheap first pass
    assert np.all(r.distance <= brute + 1e-12)
    near = np.abs(np.asarray(r.s)[:, None] - np.linspace(0.0, path.length, 250_001)[None, ::25]) < 0.5
    assert near.any(axis=1).all()
    g = (q[:, 0] - r.x) * r.cos_theta + (q[:, 1] - r.y) * r.sin_theta
    inner = r.status == STATUS_INTERIOR  # this path passes near its own end: a few points clamp there
    assert inner.sum() > 280
    assert np.abs(g[inner]).max() < 1e-13
    np.testing.assert_allclose(np.abs(r.cross_track_error[inner]), r.distance[inner], atol=1e-13)
    np.testing.assert_allclose(np.column_stack((r.x, r.y)), path.point(r.s), atol=1e-13)


def test_offset_along_the_normal_projects_back() -> None:
    """A point p(s) + e n(s) with |e kappa| < 1 and no nearer branch projects to exactly s with error e."""
    path = lane_change(1.0, 3.0)
    s = np.linspace(0.2, path.length - 0.2, 200)
    e = 0.2 * np.sin(7 * s)
    th = path.tangent_angle(s)
    q = path.point(s) + e[:, None] * np.column_stack((-np.sin(th), np.cos(th)))
    for hint in (None, s - 0.1):
        r = path.locate(q[:, 0], q[:, 1], s_prev=hint)
        assert np.abs(r.s - s).max() < 1e-12
        assert np.abs(r.cross_track_error - e).max() < 1e-13


def test_float_and_batch_agree() -> None:
    """One point's locate (floats; closed form on the arcs) and the batch's (columns; quadrature) to 1e-12."""
    path = figure8(4.0)
    rng = np.random.default_rng(4)
    s_prev = rng.uniform(0, 2 * path.length, 20)
    q = path.point(s_prev + 0.1) + rng.uniform(-0.1, 0.1, (20, 2))
    batch = path.locate(q[:, 0], q[:, 1], s_prev=s_prev)
    for i in range(20):
        one = path.locate(float(q[i, 0]), float(q[i, 1]), s_prev=float(s_prev[i]))
        assert isinstance(one.s, float)
        for a, b in zip(one, batch, strict=True):
            assert a == pytest.approx(b[i], rel=1e-12, abs=1e-12)


def test_figure8_crossing_keeps_the_branch() -> None:
    """Driving a point through the crossing twice a lap, for three laps: progress follows the truth to 1e-9."""
    path = figure8(4.0, crossing_angle=0.6)  # a shallow crossing: the branches stay near each other longest
    L = path.length
    np.testing.assert_allclose(path.point([L / 4, 3 * L / 4]), 0.0, atol=1e-12)  # it does cross itself
    s_true = np.arange(0.0, 3 * L, 0.03)
    e = 0.08 * np.sin(s_true * 3.1)
    th = path.tangent_angle(s_true)
    q = path.point(s_true) + e[:, None] * np.column_stack((-np.sin(th), np.cos(th)))
    prev = 0.0
    progress = []
    for x, y in q:
        r = path.locate(float(x), float(y), s_prev=prev, max_advance=0.3)
        prev = r.progress
        progress.append(prev)
    assert np.abs(np.asarray(progress) - s_true).max() < 1e-9
    # without the hint the global search jumps to the other branch somewhere near the crossing
    near = np.abs(np.mod(s_true, L / 2) - L / 4) < 0.15
    glob = path.locate(q[near, 0], q[near, 1])
    jumped = np.abs(np.mod(glob.s - s_true[near] + L / 2, L) - L / 2) > 1.0
    assert jumped.any()


def test_status_at_ends_and_window() -> None:
    path = lane_change(0.5, 3.0, lead=1.0)
    L = path.length
    r = path.locate(-0.5, 0.2)
    assert (r.s, r.status) == (0.0, STATUS_START)
    assert r.distance == pytest.approx(math.hypot(0.5, 0.2), abs=1e-15)
    assert r.cross_track_error == pytest.approx(0.2, abs=1e-15)
    end = path.point(L)
    r = path.locate(end[0] + 1.0, end[1] - 0.1, s_prev=L - 0.2)
    assert (r.s, r.status) == (L, STATUS_END)
    r = path.locate(0.5, 0.0, s_prev=3.0, max_advance=0.5)  # the point is 2 m behind the window
    assert (r.s, r.status) == (2.5, STATUS_WINDOW)
    r = path.locate(np.array([0.5, 2.0]), np.array([0.01, 0.0]))
    np.testing.assert_array_equal(r.status, [STATUS_INTERIOR, STATUS_INTERIOR])


def test_closed_path_progress_unwraps_laps() -> None:
    path = circle(0.5)
    L = path.length
    r = path.locate(0.0, -0.01, s_prev=5 * L - 0.02)
    assert r.progress == pytest.approx(5 * L, abs=1e-12)
    assert r.s == pytest.approx(0.0, abs=1e-12)
    assert r.tangent_angle == pytest.approx(10 * math.pi, abs=1e-12)


def test_lane_change_geometry() -> None:
    for off, ln in ((0.5, 3.0), (-1.2, 2.0), (0.0, 1.0)):
        path = lane_change(off, ln, lead=0.7)
        np.testing.assert_allclose(path.point(path.length), (ln + 1.4, off), atol=1e-12)
        assert path.tangent_angle(path.length) == pytest.approx(0.0, abs=1e-13)
        brk = np.asarray(path.breakpoints())
        left = path.curvature(np.nextafter(brk[1:-1], -np.inf))
        right = path.curvature(brk[1:-1])
        assert np.abs(left - right).max() < 1e-9  # continuous curvature
    with pytest.raises(ValueError, match=r"lane_change\.offset"):
        lane_change(2.5, 3.0)


def test_figure8_geometry() -> None:
    path = figure8(5.0, crossing_angle=1.2, transition=0.8)
    pts = path.point(np.linspace(0, path.length, 20001))
    assert pts[:, 0].max() == pytest.approx(2.5, abs=1e-7)
    assert pts[:, 0].min() == pytest.approx(-2.5, abs=1e-7)
    th = path.tangent_angle([path.length / 4, 3 * path.length / 4])
    assert abs(math.remainder(th[0] - th[1], math.pi)) == pytest.approx(1.2, abs=1e-12)
    assert path._t.turn == 0.0  # total tangent turn [rad]
    brk = np.asarray(path.breakpoints())
    assert np.abs(path.curvature(np.nextafter(brk[1:-1], -np.inf)) - path.curvature(brk[1:-1])).max() < 1e-9


def test_random_paths_seeded_and_bounded() -> None:
    a = random_path(np.random.default_rng(9), 40.0, 1.3, 0.8)
    b = random_path(np.random.default_rng(9), 40.0, 1.3, 0.8)
    c = random_path(np.random.default_rng(10), 40.0, 1.3, 0.8)
    assert a == b
    assert a != c
    assert a.length == pytest.approx(40.0, abs=1e-12)
    s = np.linspace(0.0, 40.0, 40001)
    assert np.abs(a.curvature(s)).max() <= 1.3 * (1 + 1e-12)
    assert np.abs(np.diff(a.curvature(s)) / np.diff(s)).max() <= 0.8 * (1 + 1e-6)


def test_registry_and_validation() -> None:
    for name, fam in FAMILIES.items():
        rng = np.random.default_rng(0) if fam.random else None
        path = make_family_path(name, rng)
        assert path.length > 0
        for p, rg in fam.params.items():
            assert rg.low <= rg.default <= rg.high, (name, p)
    bad: list[tuple[str, dict[str, object]]] = [
        ("circle", {"radius": math.nan}),
        ("circle", {"radius": math.inf}),
        ("circle", {"radius": True}),
        ("circle", {"radius": "1.0"}),
        ("circle", {"radius": 0.0}),
        ("circle", {"direction": True}),
        ("manoeuvre", {"straight_length": -1.0}),
        ("figure8", {"crossing_angle": 3.0}),
        ("lane_change", {"length": -2.0}),
        ("random", {"max_curvature": 0.0}),
    ]
    for name, kw in bad:
        with pytest.raises(ValueError) as err:
            make_family_path(name, np.random.default_rng(0), **kw)
        msg = str(err.value)
        assert "\n" not in msg and next(iter(kw)) in msg, msg
    with pytest.raises(ValueError, match="one of"):
        make_family_path("spiral")
    with pytest.raises(ValueError, match="no parameter"):
        make_family_path("circle", radius=1.0, size=2.0)
    with pytest.raises(ValueError, match="needs a numpy"):
        make_family_path("random")
    with pytest.raises(ValueError, match=r"ClothoidSegment\.length"):
        Seg(-1.0)
    with pytest.raises(ValueError, match=r"ClothoidPath\.closed"):
        ClothoidPath((Seg.arc(6.0, 1.0),), closed=True)


def test_preview_closed_forms() -> None:
    line = ClothoidPath((Seg.line(10.0),))
    pv = preview(
        line,
        np.array([1.0, 2.0]),
        np.array([0.3, -0.2]),
        np.array([0.0, math.pi / 2]),
        np.array([1.0, 2.0]),
        (0.2, 0.5),
    )
    np.testing.assert_allclose(pv.forward, [[0.2, 0.5], [0.2, 0.2]], atol=1e-15)
    np.testing.assert_allclose(pv.left, [[-0.3, -0.3], [-0.2, -0.5]], atol=1e-15)
    np.testing.assert_array_equal(pv.curvature, 0.0)
    R, b = 1.5, 0.4  # on a circle, from the start point with heading b (rotate the eq. 6 points by -b)
    pv = preview(circle(R), 0.0, 0.0, b, 0.0, (0.3, 1.0, 4.0))
    d = np.array([0.3, 1.0, 4.0])
    x, y = R * np.sin(d / R), R * (1 - np.cos(d / R))
    np.testing.assert_allclose(pv.forward, math.cos(b) * x + math.sin(b) * y, atol=1e-12)
    np.testing.assert_allclose(pv.left, -math.sin(b) * x + math.cos(b) * y, atol=1e-12)
    np.testing.assert_allclose(pv.curvature, 1 / R, rtol=1e-15)


def test_feasibility_examples_and_message() -> None:
    f = feasibility(circle(1.0), 0.74)
    assert not f.feasible and f.binding == "wheel_rate"
    assert f.needed == pytest.approx(16.58171, abs=1e-5)
    assert f.message() == (
        "path: speed 0.74 m/s on radius 1 m needs 16.6 rad/s on the outer wheel, above the robot's limit of 15 rad/s"
    )
    f = feasibility(circle(0.085, -1), 0.2)
    assert not f.feasible and f.needed == pytest.approx(20.7, abs=0.05) and f.peak_wheel["wheel_rate"] == "outer"
    assert feasibility(circle(1.0), 0.2).feasible
    f = feasibility(circle(0.07), 0.2)  # R < l3: no steady state, the lag reaches 90 degrees
    assert not f.feasible and f.binding == "heading lag"


@pytest.mark.parametrize(("radius", "v"), [(0.3, 0.1), (1.0, 0.5), (4.0, 0.7)])
def test_feasibility_matches_circle_steady_state(radius: float, v: float) -> None:
    robot = RobotParams()
    ss = circle_steady_state(radius, v, robot)
    f = feasibility(circle(radius), v, robot)
    assert f.peaks["wheel_rate"] == pytest.approx(float(np.abs(ss.wheel_rates).max()), rel=1e-10)
    assert f.peaks["rotation_rate"] == pytest.approx(float(ss.betadot), rel=1e-10)
    assert f.peaks["wheel_acceleration"] < 1e-8
    fh = feasibility(circle(radius), float(ss.speed_h), robot, speed_of="H")  # the same motion given by v_H
    assert fh.peaks["wheel_rate"] == pytest.approx(f.peaks["wheel_rate"], rel=1e-10)


def test_heading_lag_on_a_line_closed_form() -> None:
    """On a straight line dpsi/ds = -sin(psi)/l3: tan(psi/2) = tan(psi0/2) exp(-s/l3)."""
    robot = RobotParams()
    prof = heading_lag_profile(ClothoidPath((Seg.line(0.8),)), robot, initial_lag=1.2)
    exact = 2 * np.arctan(math.tan(0.6) * np.exp(-prof.s / robot.l3))
    assert np.abs(prof.psi - exact).max() < 1e-9


def test_heading_lag_against_scipy_inverse_solution() -> None:
    """The lag at the manoeuvre's points equals theta - beta of solve_inverse (DOP853, time domain)."""
    robot = RobotParams()
    sol = solve_inverse(ManoeuvrePath(1.0, 1.0), ConstantSpeed(0.2), [0.0, 4.0, 6.0, 9.0], robot)
    for s, beta in zip(sol.s[1:], sol.beta[1:], strict=True):
        laps = (s - 1.0) / (2 * math.pi)
        path = manoeuvre(1.0, 1.0, 1, laps) if s > 1.0 else ClothoidPath((Seg.line(float(s)),))
        prof = heading_lag_profile(path, robot, initial_lag=0.0)
        theta = max(s - 1.0, 0.0)
        assert prof.s[-1] == pytest.approx(s, abs=1e-12)
        assert prof.psi[-1] == pytest.approx(theta - beta, abs=1e-9)


def test_feasibility_accelerations_by_finite_differences() -> None:
    """Wheel acceleration peak = max |d(wheel rate)/dt| from the sampled rates (speed of H held)."""
    path = lane_change(0.6, 1.5, lead=0.5)
    robot = RobotParams()
    v = 0.4
    f = feasibility(path, v, robot, speed_of="H", initial_lag=0.0)
    prof = heading_lag_profile(path, robot, initial_lag=0.0, step_fraction=1 / 256)
    w1 = v * (np.cos(prof.psi) + robot.l1 / robot.l3 * np.sin(prof.psi)) / robot.r1
    w2 = v * (np.cos(prof.psi) - robot.l1 / robot.l3 * np.sin(prof.psi)) / robot.r2
    ds = np.diff(prof.s)
    ok = ds > 1e-9
    acc = np.maximum(np.abs(np.diff(w1)), np.abs(np.diff(w2)))[ok] / ds[ok] * v
    assert f.peaks["wheel_acceleration"] == pytest.approx(acc.max(), rel=2e-3)
    # the documented sampling accuracy of a smooth peak (samples l3/64 apart against l3/256)
    assert f.peaks["wheel_rate"] == pytest.approx(max(np.abs(w1).max(), np.abs(w2).max()), rel=1e-5)


@pytest.mark.parametrize("name", ["figure8", "lane_change"])
@pytest.mark.parametrize(
    "hint", [math.nan, math.inf, np.array([0.1, math.nan]), np.array([[0.2], [-math.inf]])], ids=str
)
def test_a_nan_or_infinite_hint_is_refused_on_both_routes(name: str, hint: float | NDArray[np.float64]) -> None:
    """``locate(x, y, s_prev)`` with a non-finite ``s_prev``: the one-line error naming the value, on the float route
    and on the column route alike (the column route used to fail with an IndexError of a garbage sample number)."""
    path = make_family_path(name)
    bad = float(np.asarray(hint)[~np.isfinite(hint)].flat[0])
    x = 0.1 if isinstance(hint, float) else np.full(np.shape(hint), 0.1)
    with pytest.raises(ValueError, match=rf"^locate\.s_prev must be a finite number in \[-inf, inf\], got {bad}$"):
        path.locate(x, 0.0 * x, hint)
