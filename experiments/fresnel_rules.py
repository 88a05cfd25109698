"""The error of an n-node Gauss–Legendre rule on one piece of linear speed and turn rate, against mpmath at 30 digits:
the figures behind ``amigo_gym.model.fresnel``'s rules (``TIER_NODES``, ``TIER_PHASE``) and its docstring's bounds.

    python experiments/fresnel_rules.py

For each rule and phase change ``Phi = |w0| h + |alpha| h^2 / 2`` [rad], the worst error relative to ``int |v| dt`` of
``int_0^1 (v0 + a u) exp(i (w0 u + alpha u^2 / 2)) du`` over 45 directions of ``(w0, alpha)`` (phase linear,
quadratic, mixed, 40 random) and four speeds (constant, from zero, through zero, ramping up); a Markdown table.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np

mp.mp.dps = 30
rng = np.random.default_rng(3)
DIRECTIONS = [(1.0, 0.0), (0.0, 2.0), (-1.0, 0.0), (0.5, 1.0), (0.5, -1.0), *map(tuple, rng.uniform(-1, 1, (40, 2)))]
SPEEDS = [(1.0, 0.0), (0.0, 1.0), (1.0, -1.0), (-0.3, 1.0)]
CASES = {6: (1 / 16, 1 / 8), 8: (1 / 4, 1 / 2), 10: (1.0, 2.0)}


def worst(phi: float, n: int) -> float:
    x, w = np.polynomial.legendre.leggauss(n)
    u, w = 0.5 * (x + 1.0), 0.5 * w
    out = 0.0
    for a, b in DIRECTIONS:
        s = abs(a) + abs(b) / 2
        a, b = a / s * phi, b / s * phi
        for v0, acc in SPEEDS:
            exact = complex(mp.quad(lambda t: (v0 + acc * t) * mp.expj(a * t + b * t * t / 2), [0, 0.5, 1]))  # noqa: B023
            zero = -v0 / acc if acc and 0 < -v0 / acc < 1 else 0.5
            scale = float(mp.quad(lambda t: abs(v0 + acc * t), [0, zero, 1]))  # noqa: B023
            quad = np.sum(w * (v0 + acc * u) * np.exp(1j * (a * u + b * u * u / 2)))
            out = max(out, abs(quad - exact) / scale)
    return out


print("| nodes | Phi [rad] | worst error / int |v| dt |")
print("|---:|---:|---:|")
for n, phis in CASES.items():
    for phi in phis:
        print(f"| {n} | {phi:g} | {worst(phi, n):.1e} |", flush=True)
