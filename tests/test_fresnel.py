"""amigo_gym.model.fresnel.advance against mpmath at 40 digits, closed forms of lines and arcs, bits of floats vs
arrays."""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from amigo_gym.model.fresnel import MAX_PHASE_PER_SUB, advance, subintervals


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


def test_floats_and_arrays_give_the_same_bits() -> None:
    rng = np.random.default_rng(3)
    cols = [rng.uniform(-1, 1, 64) for _ in range(6)]
    t = rng.uniform(0, 0.2, 64)
    xs, ys, bs = advance(cols[0], cols[1], cols[2], cols[3], cols[4], cols[5], 0.3 * cols[0], t)
    for i in range(64):
        x, y, b = advance(*(float(c[i]) for c in cols), 0.3 * float(cols[0][i]), float(t[i]))
        assert isinstance(x, float)
        assert (x, y, b) == (xs[i], ys[i], bs[i])


def test_subintervals_refuses_bad_input() -> None:
    for bad in (math.nan, -1.0, math.inf):
        with pytest.raises(ValueError, match="max_phase_change"):
            subintervals(bad)
