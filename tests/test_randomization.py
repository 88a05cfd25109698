"""Randomisation ranges as data: validation, presets, reproducible draws, the counter-based per-step noise."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy import stats

from amigo_gym.model import randomization
from amigo_gym.model.randomization import (
    PRESETS,
    Randomization,
    draw_key,
    make_randomization,
    sample,
    step_noise,
)


def counter_uniform(key: np.ndarray, step: int, channel: int) -> np.ndarray:
    """The counter generator's uniforms in ``(0, 1)`` of uint64 ``key`` ``(...)``, ``step`` and ``channel``."""
    with np.errstate(over="ignore"):  # uint64 wraps
        u: np.ndarray = randomization._counter_uniform_int(key, np.asarray(step, dtype=np.uint64), channel)
    return u


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"wheel_radius": (0.9, 1.6)}, "wheel_radius[1]"),
        ({"wheel_radius": (1.1, 1.0)}, "wheel_radius"),
        ({"track": "1"}, "track"),
        ({"slip": (0.0, math.nan)}, "slip[1]"),
        ({"delay": (0.0, 0.6)}, "delay[1]"),
        ({"position_noise": -1e-3}, "position_noise"),
        ({"heading_noise": math.inf}, "heading_noise"),
        ({"wheel_rate_noise": True}, "wheel_rate_noise"),
    ],
)
def test_bad_ranges_are_refused_naming_the_field(kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match="Randomization." + re.escape(field)):
        Randomization(**kwargs)  # type: ignore[arg-type]


def test_make_randomization_forms() -> None:
    assert make_randomization(None) == Randomization()
    assert make_randomization("none") == Randomization()
    assert make_randomization("hard") == PRESETS["hard"]
    r = make_randomization({"delay": [0.01, 0.02]})
    assert r.delay == (0.01, 0.02) and r.wheel_radius == (1.0, 1.0)
    with pytest.raises(ValueError, match="unknown field"):
        make_randomization({"dleay": (0, 1)})
    with pytest.raises(ValueError, match="randomize must be one of"):
        make_randomization("harder")


def test_presets_nest() -> None:
    """mild lies inside hard, and hard inside the allowed ranges (validated on construction)."""
    m, h = PRESETS["mild"], PRESETS["hard"]
    for name in ("wheel_radius", "track", "slip", "delay"):
        lo_m, hi_m = getattr(m, name)
        lo_h, hi_h = getattr(h, name)
        assert lo_h <= lo_m <= hi_m <= hi_h
    assert m.position_noise <= h.position_noise and m.wheel_rate_noise <= h.wheel_rate_noise


@pytest.mark.parametrize("seed", [0, 1, 12345])
def test_sample_is_reproducible_and_in_range(seed: int) -> None:
    r = PRESETS["hard"]
    draws = [sample(np.random.default_rng(seed), r) for _ in range(2)]
    assert draws[0] == draws[1]
    rng = np.random.default_rng(seed)
    many = [sample(rng, r) for _ in range(500)]
    for d in many:
        assert r.wheel_radius[0] <= d.r1_scale <= r.wheel_radius[1]
        assert r.wheel_radius[0] <= d.r2_scale <= r.wheel_radius[1]
        assert r.track[0] <= d.track_scale <= r.track[1]
        assert r.slip[0] <= d.slip_max <= r.slip[1]
        assert r.delay[0] <= d.delay <= r.delay[1]
    assert len({d.r1_scale for d in many}) == 500  # continuous draws differ


def test_fixed_ranges_do_not_touch_the_generator() -> None:
    rng = np.random.default_rng(3)
    state = rng.bit_generator.state
    d = sample(rng, Randomization())
    assert rng.bit_generator.state == state
    assert d == (1.0, 1.0, 1.0, 0.0, 0.0)


def test_counter_uniform_is_uniform_and_independent() -> None:
    keys = np.arange(50_000, dtype=np.uint64)
    u0 = counter_uniform(keys, 7, 0)
    u1 = counter_uniform(keys, 7, 1)
    u2 = counter_uniform(keys, 8, 0)
    for u in (u0, u1, u2):
        assert u.min() > 0.0 and u.max() < 1.0
        assert stats.kstest(u, "uniform").pvalue > 1e-3
    assert abs(np.corrcoef(u0, u1)[0, 1]) < 0.02
    assert abs(np.corrcoef(u0, u2)[0, 1]) < 0.02


def test_step_noise_scalar_equals_batch_rows_and_is_zero_when_off() -> None:
    r = PRESETS["hard"]
    rng = np.random.default_rng(0)
    keys = np.array([draw_key(rng) for _ in range(4)], dtype=np.uint64)
    steps = np.array([0, 5, 5, 399])
    slip = np.array([0.0, 0.05, 0.1, 0.02])
    batch = step_noise(keys, steps, r, slip)
    for i in range(4):
        one = step_noise(keys[i], steps[i], r, float(slip[i]))
        for b, o in zip(batch, one, strict=True):
            assert np.asarray(b)[i] == float(o)
    off = step_noise(keys, steps, Randomization(), 0.0)
    assert all(np.all(np.asarray(c) == 0.0) for c in off)
    assert np.all(np.asarray(batch.slip1) <= slip) and np.all(np.asarray(batch.slip1) >= 0.0)


def test_step_noise_normals_have_the_stated_levels_and_are_gaussian() -> None:
    # 2e5 draws: the sample std's relative standard error is 1/sqrt(2n) = 0.16 %, so 1 % is 6 of them; a Box-Muller
    # with sqrt(-ln u1) (std x 0.71) or a level off by 2 % fails, as does a channel reading another's level
    n = 200_000
    r = Randomization(position_noise=0.005, heading_noise=0.01, wheel_rate_noise=0.2)
    rng = np.random.default_rng(3)
    keys = rng.integers(0, 2**63, n, dtype=np.uint64) * np.uint64(2) + rng.integers(0, 2, n, dtype=np.uint64)
    draws = step_noise(keys, rng.integers(0, 1000, n), r, 0.0)
    columns = {"x": (draws.x, 0.005), "y": (draws.y, 0.005), "beta": (draws.beta, 0.01)}
    columns |= {"rate1": (draws.rate1, 0.2), "rate2": (draws.rate2, 0.2)}
    for name, (column, level) in columns.items():
        z = np.asarray(column) / level
        assert abs(z.std() - 1.0) < 0.01, (name, z.std())
        assert abs(z.mean()) < 5.0 / math.sqrt(n), (name, z.mean())
        assert stats.kstest(z, "norm").pvalue > 1e-3, name
    assert abs(np.corrcoef(draws.x, draws.y)[0, 1]) < 0.02 and abs(np.corrcoef(draws.rate1, draws.rate2)[0, 1]) < 0.02
    assert np.all(np.asarray(draws.slip1) == 0.0) and np.all(np.asarray(draws.slip2) == 0.0)
