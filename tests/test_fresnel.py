"""amigo_gym.model.fresnel.advance against mpmath at 40 digits, closed forms of lines and arcs, bits of floats vs
arrays."""

from __future__ import annotations

import itertools
import math

import mpmath as mp
import numpy as np
import pytest
from numpy.typing import NDArray

from amigo_gym.model.fresnel import MAX_PHASE_PER_SUB, TIER_PHASE, advance, subintervals


def _reference(theta: float, v0: float, a: float, w0: float, alpha: float, t: float) -> tuple[float, float]:
    mp.mp.dps = 40
    th, v, acc, w, al = (mp.mpf(x) for x in (theta, v0, a, w0, alpha))

    def phase(s: mp.mpf) -> mp.mpf:
        return th + w * s + al * s * s / 2

    x = mp.quad(lambda s: (v + acc * s) * mp.cos(phase(s)), [0, t])
    y = mp.quad(lambda s: (v + acc * s) * mp.sin(phase(s)), [0, t])
    return float(x), float(y)


def test_against_mpmath_over_regimes() -> None:
    """Random speeds, ramps and turn rates, curvature rates from 1e-14 to 5 (the Fresnel formula's weak spot)."""
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(150):
        v0, a = rng.uniform(-1, 1), rng.uniform(-1, 1)
        w0 = rng.uniform(-6, 6)
        alpha = rng.uniform(-5, 5) * 10 ** rng.uniform(-14, 0)
        t, th = rng.uniform(0, 0.3), rng.uniform(-3, 3)
        n = subintervals(abs(w0) * t + 0.5 * abs(alpha) * t * t)
        x, y, b = advance(0.0, 0.0, th, v0, a, w0, alpha, t, n)
        rx, ry = _reference(th, v0, a, w0, alpha, t)
        worst = max(worst, abs(x - rx), abs(y - ry))
        assert b == th + t * (w0 + 0.5 * alpha * t)
    assert worst < 1e-15


def test_long_phase_needs_subintervals() -> None:
    """A 12 rad turn in one call: exact with the sub-intervals of ``subintervals``, not with one."""
    th, v0, a, w0, alpha, t = 0.2, 0.5, 0.1, 6.0, 0.0, 2.0
    rx, ry = _reference(th, v0, a, w0, alpha, t)
    n = subintervals(abs(w0) * t)
    assert n == math.ceil(12.0 / MAX_PHASE_PER_SUB)
    x, y, _ = advance(0.0, 0.0, th, v0, a, w0, alpha, t, n)
    assert abs(x - rx) < 1e-14 and abs(y - ry) < 1e-14
    x1, y1, _ = advance(0.0, 0.0, th, v0, a, w0, alpha, t, 1)
    assert max(abs(x1 - rx), abs(y1 - ry)) > 1e-10  # one 10-node rule over 12 rad: 1.7e-9 m off


def test_lines_and_arcs_in_closed_form() -> None:
    # a line with a speed ramp: v0 t + a t^2 / 2 along the heading
    x, y, b = advance(1.0, 2.0, 0.7, 0.3, 0.2, 0.0, 0.0, 1.5)
    d = 0.3 * 1.5 + 0.5 * 0.2 * 1.5**2
    assert x == pytest.approx(1.0 + d * math.cos(0.7), abs=1e-15)
    assert y == pytest.approx(2.0 + d * math.sin(0.7), abs=1e-15)
    assert b == 0.7
    # an arc at constant speed: the chord 2 (v/w) sin(w t / 2) in the direction theta + w t / 2
    v, w, t = 0.4, 1.3, 0.9
    x, y, b = advance(0.0, 0.0, 0.1, v, 0.0, w, 0.0, t)
    chord = 2.0 * v / w * math.sin(0.5 * w * t)
    assert x == pytest.approx(chord * math.cos(0.1 + 0.5 * w * t), abs=1e-15)
    assert y == pytest.approx(chord * math.sin(0.1 + 0.5 * w * t), abs=1e-15)


def test_each_rule_at_its_phase_limit() -> None:
    """Every rule (the smaller ones of ``tier`` and the 10-node one) at the largest phase change ``Phi`` it takes, in
    the worst directions (phase linear, quadratic, mixed; speed constant, from zero, through zero): error relative to
    ``int |v| dt`` below 4e-16 up to ``Phi = 1``, 5e-14 at ``MAX_PHASE_PER_SUB`` (the module docstring's bounds)."""
    shapes = [(1.0, 0.0), (0.0, 2.0), (0.5, 1.0), (-0.5, 1.0), (0.25, 1.5)]
    for phi, bound in [*((p, 4e-16) for p in TIER_PHASE), (1.0, 4e-16), (MAX_PHASE_PER_SUB, 5e-14)]:
        assert subintervals(phi) == 1
        worst = 0.0
        for (wa, wb), (v0, a) in itertools.product(shapes, [(1.0, 0.0), (0.0, 1.0), (1.0, -1.0), (-0.3, 1.0)]):
            w0, alpha = wa * phi, wb * phi  # |w0| t + |alpha| t^2 / 2 = phi at t = 1 s
            x, y, _ = advance(0.0, 0.0, 0.4, v0, a, w0, alpha, 1.0)
            rx, ry = _reference(0.4, v0, a, w0, alpha, 1.0)
            speed = float(mp.quad(lambda s: abs(v0 + a * s), [0, 0.3, 0.5, 1]))  # noqa: B023
            worst = max(worst, math.hypot(x - rx, y - ry) / speed)
        assert worst < bound, (phi, worst)


def test_floats_and_arrays_agree() -> None:
    """Columns take each piece's rule by the largest phase change of their rows: within rounding of the floats (two
    units in the last place at 1 m: numpy's cosines and sines of columns may differ from libm's in the last bit)."""
    rng = np.random.default_rng(3)
    cols = [rng.uniform(-1, 1, 64) for _ in range(6)]
    t = rng.uniform(0, 0.2, 64)
    xs, ys, bs = advance(cols[0], cols[1], cols[2], cols[3], cols[4], cols[5], 0.3 * cols[0], t)
    for i in range(64):
        x, y, b = advance(*(float(c[i]) for c in cols), 0.3 * float(cols[0][i]), float(t[i]))
        assert type(x) is float and type(y) is float
        assert abs(x - xs[i]) <= 2 * np.spacing(1.0) and abs(y - ys[i]) <= 2 * np.spacing(1.0) and b == bs[i]


def test_subintervals_refuses_bad_input() -> None:
    for bad in (math.nan, -1.0, math.inf):
        with pytest.raises(ValueError, match="max_phase_change"):
            subintervals(bad)


def test_compiled_nodes_against_mpmath() -> None:
    """The compiled quadrature (its smaller rules; its node cosines by angle addition and Taylor polynomials) and the
    compiled path pose (arcs in closed form) against mpmath: 1e-15 m over the actuator's and the path's regimes."""
    import numba

    from amigo_gym.model import fresnel
    from amigo_gym.sim.fast_v1 import kernels

    kernels()  # registers the compiled forms (fresnel.cos_sin_nodes's overload)
    table = np.array(fresnel.step_table(1))
    nn = fresnel.NODES

    @numba.njit
    def advance_one(th: float, v0: float, a: float, w0: float, alpha: float, t: float) -> tuple[float, float]:
        buf = np.zeros(3 * nn)
        x, y, _ = fresnel.advance_nodes(buf, 0, nn, 0.0, 0.0, th, np.array([v0, a, w0, alpha, t]), 0, 1, table, 0, nn)
        return x, y

    @numba.njit
    def unit_one(th: float, w0: float, alpha: float, t: float) -> tuple[float, float, float, float, float]:
        return fresnel.unit_speed_nodes(np.zeros(3 * (nn + 1)), 0.0, 0.0, th, w0, alpha, t, table, 0, nn)

    @numba.njit
    def cos_sin(phases: NDArray[np.float64]) -> NDArray[np.float64]:
        n = len(phases)
        buf = np.zeros(3 * n)
        buf[:n] = phases
        fresnel.cos_sin_nodes(buf, 0, n, n)
        return buf

    # the nodes' cosines and sines themselves: within 3e-16 of the C library's, near the first phase and far
    for p0, spread in ((0.3, 0.5), (-2.9, 0.5), (1e3, 0.49), (0.3, 3.0)):
        phases = p0 + np.linspace(-spread, spread, 41) * np.array([0.0 if i == 0 else 1.0 for i in range(41)])
        buf = cos_sin(phases)
        assert np.abs(buf[41:82] - np.cos(phases)).max() < 3e-16
        assert np.abs(buf[82:] - np.sin(phases)).max() < 3e-16

    rng = np.random.default_rng(5)
    worst = 0.0
    for k in range(120):
        th, t = rng.uniform(-3, 3), rng.uniform(0, 0.3)
        w0 = rng.uniform(-6, 6) if k % 3 else rng.uniform(-1, 1)  # a third within the polynomials' 0.5 rad
        alpha = 0.0 if k % 4 == 0 else rng.uniform(-5, 5)
        v0, a = rng.uniform(-1, 1), rng.uniform(-1, 1)
        rx, ry = _reference(th, v0, a, w0, alpha, t)
        x, y = advance_one(th, v0, a, w0, alpha, t)
        worst = max(worst, abs(x - rx), abs(y - ry))
        # a path piece of 4 t <= 1.2 m, curvature w0 / 4 and its rate alpha / 16: the same phase (<= 2 rad, as
        # the path's pieces, clothoid.chain_pieces)
        ux, uy, ub, uc, us = unit_one(th, w0 / 4, alpha / 16, 4 * t)
        rx, ry = _reference(th, 1.0, 0.0, w0 / 4, alpha / 16, 4 * t)
        worst = max(worst, abs(ux - rx), abs(uy - ry), abs(uc - math.cos(ub)), abs(us - math.sin(ub)))
    assert worst < 1e-15
