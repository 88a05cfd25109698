"""Paths against closed forms: the paper's circle (eq. 6), general circles, the manoeuvre path."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray

from amigo_gym.paths import CirclePath, ManoeuvrePath, wrap_angle
from amigo_gym.task.v1 import TrackingParams

Array = NDArray[np.float64]


def rng() -> np.random.Generator:
    return np.random.default_rng(7)


def _same_angle(a: Array, b: Array, atol: float = 1e-12) -> None:
    np.testing.assert_allclose(np.cos(a), np.cos(b), atol=atol)
    np.testing.assert_allclose(np.sin(a), np.sin(b), atol=atol)


@pytest.mark.parametrize("radius", [0.3, 1.0, 4.5])
def test_paper_circle_eq6(radius: float) -> None:
    """x_H = R sin(phi), y_H = R (1 - cos(phi)), phi = s/R; tangent phi; curvature 1/R."""
    p = CirclePath(radius=radius)
    s = np.linspace(-3.0, 40.0, 301)
    phi = s / radius
    np.testing.assert_allclose(
        p.point(s), np.column_stack((radius * np.sin(phi), radius * (1 - np.cos(phi)))), atol=1e-12
    )
    np.testing.assert_allclose(p.tangent_angle(s), phi, atol=1e-12)
    np.testing.assert_allclose(p.curvature(s), 1.0 / radius, rtol=1e-15)
    assert p.center == pytest.approx((0.0, radius), abs=1e-15)
    assert p.length == pytest.approx(2 * math.pi * radius, rel=1e-15)


def _from_center(center: tuple[float, float], radius: float, direction: int, start_phase: float) -> CirclePath:
    """Circle given by its centre [m]; the start is at polar angle ``start_phase`` [rad] about it."""
    p0 = (center[0] + radius * math.cos(start_phase), center[1] + radius * math.sin(start_phase))
    return CirclePath(radius, p0, start_phase + direction * math.pi / 2, direction)


CIRCLES = [
    ((0.0, 0.0), 1.0, 1, 0.0),
    ((2.0, -1.0), 0.7, -1, 1.3),
    ((-3.0, 5.0), 2.5, 1, -2.0),
    ((1.0, 1.0), 0.2, -1, 3.0),
]


@pytest.mark.parametrize(("center", "radius", "d", "phase"), CIRCLES)
def test_general_circle(center: tuple[float, float], radius: float, d: int, phase: float) -> None:
    """Any centre, radius, direction: p(s) = c + R (cos a, sin a), a = phase + d s / R."""
    p = _from_center(center, radius, d, phase)
    c = np.array(center)
    s = np.linspace(0.0, 3 * p.length, 97)
    a = phase + d * s / radius
    np.testing.assert_allclose(p.point(s), c + radius * np.column_stack((np.cos(a), np.sin(a))), atol=1e-12)
    _same_angle(p.tangent_angle(s), a + d * math.pi / 2)
    np.testing.assert_allclose(p.curvature(s), d / radius, rtol=1e-15)
    np.testing.assert_allclose(p.center, center, atol=1e-12)
    # arc length: the chord between s and s + h is 2 R sin(h / 2R)
    h = 0.37
    chord = np.linalg.norm(p.point(s + h) - p.point(s), axis=-1)
    np.testing.assert_allclose(chord, 2 * radius * math.sin(h / (2 * radius)), atol=1e-12)
    # tangent = derivative of the point (central difference, O(h^2) accurate)
    eps = 1e-5
    der = (p.point(s + eps) - p.point(s - eps)) / (2 * eps)
    th = p.tangent_angle(s)
    np.testing.assert_allclose(der, np.column_stack((np.cos(th), np.sin(th))), atol=1e-8)


@pytest.mark.parametrize(("center", "radius", "d", "phase"), CIRCLES)
def test_circle_projection(center: tuple[float, float], radius: float, d: int, phase: float) -> None:
    """A point at polar angle a and distance rho from the centre projects to c + R (cos a, sin a)."""
    p = _from_center(center, radius, d, phase)
    g = rng()
    a = g.uniform(-math.pi, math.pi, 200)
    rho = g.uniform(0.05, 2.0, 200) * radius
    c = np.array(center)
    q = c + rho[:, None] * np.column_stack((np.cos(a), np.sin(a)))
    pr = p.project(q)
    np.testing.assert_allclose(pr.point, c + radius * np.column_stack((np.cos(a), np.sin(a))), atol=1e-12)
    np.testing.assert_allclose(pr.cross_track_error, d * (radius - rho), atol=1e-12)  # inside is left for d = +1
    # the same from the left normal: e = (q - point) . (-sin th, cos th)
    n = np.column_stack((-np.sin(pr.tangent_angle), np.cos(pr.tangent_angle)))
    np.testing.assert_allclose(np.sum((q - pr.point) * n, axis=1), pr.cross_track_error, atol=1e-12)
    np.testing.assert_allclose(pr.s, radius * np.mod(d * (a - phase), 2 * math.pi), atol=1e-9)
    assert np.all((pr.s >= 0) & (pr.s < p.length))
    np.testing.assert_allclose(p.point(pr.s), pr.point, atol=1e-12)
    np.testing.assert_allclose(pr.curvature, d / radius)


@pytest.mark.parametrize("d", [1, -1])
@pytest.mark.parametrize("length", [0.0, 1.0, 2.5])
def test_manoeuvre_closed_form(d: int, length: float) -> None:
    """Straight (s, 0) for s <= L; then the circle of centre (L, d R): (L + R sin phi, d R (1 - cos phi))."""
    radius = 0.8
    m = ManoeuvrePath(radius=radius, straight_length=length, direction=d)
    s = np.linspace(-1.0, length + 12.0, 401)
    phi = (s - length) / radius
    on_line = s <= length
    want = np.where(
        on_line[:, None],
        np.column_stack((s, np.zeros_like(s))),
        np.column_stack((length + radius * np.sin(phi), d * radius * (1 - np.cos(phi)))),
    )
    np.testing.assert_allclose(m.point(s), want, atol=1e-12)
    np.testing.assert_allclose(m.tangent_angle(s), np.where(on_line, 0.0, d * phi), atol=1e-12)
    np.testing.assert_allclose(m.curvature(s), np.where(on_line, 0.0, d / radius))
    assert m.length == pytest.approx(length + 2 * math.pi * radius, rel=1e-15)
    # continuous point and tangent at the junction
    e = 1e-9
    np.testing.assert_allclose(m.point(length - e), m.point(length + e), atol=1e-8)
    assert abs(float(m.tangent_angle(length + e) - m.tangent_angle(length - e))) < 1e-8


def test_manoeuvre_projection() -> None:
    m = ManoeuvrePath(radius=1.0, straight_length=1.5, direction=1)
    g = rng()
    # near the straight segment and closer to it than to the circle (centre (1.5, 1), leftmost x = 0.5):
    # s = x, e = y
    x = np.concatenate((g.uniform(-0.5, 0.4, 50), g.uniform(0.4, 1.3, 50)))
    y = np.concatenate((g.uniform(-0.2, 0.2, 50), g.uniform(-0.2, -0.01, 50)))
    pr = m.project(np.column_stack((x, y)))
    np.testing.assert_allclose(pr.s, x, atol=1e-15)
    np.testing.assert_allclose(pr.cross_track_error, y, atol=1e-15)
    np.testing.assert_allclose(pr.tangent_angle, 0.0)
    np.testing.assert_allclose(pr.curvature, 0.0)
    # near the far side of the circle (centre (1.5, 1)): polar projection, s = L + R * angle travelled
    a = g.uniform(0.2, math.pi + 0.4, 100)  # polar angle about the centre, measured from the start radius
    rho = g.uniform(0.8, 1.2, 100)
    c = np.array([1.5, 1.0])
    dirn = np.column_stack((np.sin(a), -np.cos(a)))  # a = 0 is the junction point (1.5, 0)
    pr = m.project(c + rho[:, None] * dirn)
    np.testing.assert_allclose(pr.point, c + dirn, atol=1e-12)
    np.testing.assert_allclose(pr.s, 1.5 + a, atol=1e-12)
    np.testing.assert_allclose(pr.cross_track_error, 1.0 - rho, atol=1e-12)
    np.testing.assert_allclose(pr.curvature, 1.0)


def test_batch_equals_loop() -> None:
    g = rng()
    q = g.uniform(-2, 3, (9, 2))
    s = g.uniform(-1, 10, 9)
    for p in (CirclePath(1.2, (0.5, -0.5), 0.4, -1), ManoeuvrePath(1.0, 1.0, 1), ManoeuvrePath(0.6, 0.0, -1)):
        pr = p.project(q)
        pt, th, k = p.point(s), p.tangent_angle(s), p.curvature(s)
        for i in range(9):
            one = p.project(q[i])
            for name in ("s", "point", "tangent_angle", "curvature", "cross_track_error"):
                np.testing.assert_array_equal(getattr(one, name), getattr(pr, name)[i], err_msg=name)
            np.testing.assert_array_equal(p.point(s[i]), pt[i])
            assert float(p.tangent_angle(s[i])) == th[i]
            assert float(p.curvature(s[i])) == k[i]
        # two leading axes
        np.testing.assert_array_equal(p.project(q.reshape(3, 3, 2)).s, pr.s.reshape(3, 3))


def test_wrap_angle() -> None:
    x = np.linspace(-20.0, 20.0, 1001)
    w = wrap_angle(x)
    assert np.all((w >= -math.pi) & (w < math.pi))
    _same_angle(w, x, atol=1e-13)
    assert float(wrap_angle(math.pi)) == pytest.approx(-math.pi)


def test_atan2_float() -> None:
    """``classic.atan2_float`` (the compiled step's ``atan2``) is within 2 ulp of ``math.atan2`` over random pairs of
    scales 1e-8 to 1e8, the signed zeros, infinities and NaN alike (two infinite arguments: NaN)."""
    from amigo_gym.paths.classic import atan2_float

    rng = np.random.default_rng(0)
    scales = 10.0 ** rng.uniform(-8.0, 8.0, (4000, 2))
    pairs = (rng.normal(size=(4000, 2)) * scales).tolist()
    for y, x in pairs:
        want = math.atan2(y, x)
        assert abs(atan2_float(y, x) - want) <= 2.0 * math.ulp(want), (y, x)
    special = (0.0, -0.0, 1.0, -1.0, 1e-300, 5e-324, math.inf, -math.inf, math.nan)
    for y in special:
        for x in special:
            got, want = atan2_float(y, x), math.atan2(y, x)
            if math.isinf(x) and math.isinf(y):
                assert math.isnan(got)
            elif math.isnan(want):
                assert math.isnan(got), (y, x)
            else:
                assert got == want and math.copysign(1.0, got) == math.copysign(1.0, want), (y, x, got, want)


def test_make_path_and_validation() -> None:
    c = TrackingParams.v0(radius=2.0, direction=-1).path
    assert isinstance(c, CirclePath)
    assert (c.radius, c.direction, c.start, c.start_angle) == (2.0, -1, (0.0, 0.0), 0.0)
    m = TrackingParams.v0(path="manoeuvre", straight_length=0.5).path
    assert isinstance(m, ManoeuvrePath)
    assert (m.radius, m.straight_length, m.direction) == (1.0, 0.5, 1)
    with pytest.raises(ValueError, match=r"CirclePath\.radius"):
        CirclePath(radius=0.0)
    with pytest.raises(ValueError, match=r"CirclePath\.direction"):
        CirclePath(direction=0)
    with pytest.raises(ValueError, match=r"CirclePath\.start\[1\]"):
        CirclePath(start=(0.0, math.nan))
    with pytest.raises(ValueError, match=r"ManoeuvrePath\.straight_length"):
        ManoeuvrePath(straight_length=-1.0)
    with pytest.raises(ValueError, match=r"ManoeuvrePath\.radius"):
        ManoeuvrePath(radius=math.inf)
