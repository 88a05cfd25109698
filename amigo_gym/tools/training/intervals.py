"""rliable's aggregate estimators (Agarwal et al., NeurIPS 2021; ``rliable`` v1.2.0), vectorised in numpy, and the
Wilson interval of a failure rate.

Scores are matrices ``(num_runs, num_tasks)``: training seeds by benchmark scenarios. The bootstrap is rliable's
``StratifiedBootstrap`` (``task_bootstrap=False``): each replication resamples the runs of every task with
replacement; with one run per task the interval has zero width. Why not rliable itself: docs/benchmark.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
Stat = Callable[[Array], Array]

#: largest number of resampled scores held in memory at once
_CHUNK = 4_000_000


def iqm(scores: ArrayLike) -> Array:
    """Interquartile mean over the last two axes ``(..., runs, tasks)`` (``trim_mean(x, 0.25, axis=None)``)."""
    x = np.asarray(scores, dtype=np.float64)
    flat = np.sort(x.reshape(*x.shape[:-2], -1), axis=-1)
    n = flat.shape[-1]
    cut = int(0.25 * n)
    return np.asarray(np.mean(flat[..., cut : n - cut], axis=-1), dtype=np.float64)


def optimality_gap(scores: ArrayLike, gamma: float = 1.0) -> Array:
    """rliable's optimality gap over the last two axes: ``gamma - mean(min(scores, gamma))`` (for a lower-is-better
    ``x`` with target ``g``, applied to ``-x`` with ``gamma = -g``: ``mean(max(x - g, 0))``)."""
    x = np.asarray(scores, dtype=np.float64)
    return np.asarray(gamma - np.mean(np.minimum(x, gamma), axis=(-2, -1)), dtype=np.float64)


def score_distribution(scores: ArrayLike, taus: ArrayLike) -> Array:
    """Fraction of scores ``> tau`` over the last two axes, for each ``tau``: shape ``(..., len(taus))``."""
    x = np.asarray(scores, dtype=np.float64)
    t = np.asarray(taus, dtype=np.float64).reshape(-1)
    flat = x.reshape(*x.shape[:-2], -1)
    return np.asarray(np.mean(flat[..., None, :] > t[:, None], axis=-1), dtype=np.float64)


def stratified_bootstrap(scores: ArrayLike, stat: Stat, *, reps: int = 10_000, seed: int = 0) -> tuple[Array, Array]:
    """``(stat(scores), interval (2, ...))`` under rliable's stratified bootstrap: ``scores`` ``(num_runs,
    num_tasks)``, ``stat`` vectorised from ``(..., num_runs, num_tasks)`` to ``(...)`` or ``(..., k)``, ``reps``
    replications, the percentile 95 % interval, resampling seeded by ``seed``."""
    x = np.asarray(scores, dtype=np.float64)
    if x.ndim != 2 or x.size == 0:
        raise ValueError(f"scores must be a non-empty matrix (num_runs, num_tasks), got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("scores must be finite (drop or replace NaN before aggregating)")
    if isinstance(reps, bool) or not isinstance(reps, int) or reps < 1:
        raise ValueError(f"reps must be an integer >= 1, got {reps!r}")
    rng = np.random.default_rng(seed)
    n, m = x.shape
    point = np.asarray(stat(x), dtype=np.float64)
    chunk = max(1, _CHUNK // (n * m))
    cols = np.arange(m)
    out: list[Array] = []
    for done in range(0, reps, chunk):
        idx = rng.integers(0, n, size=(min(chunk, reps - done), n, m))
        out.append(np.asarray(stat(x[idx, cols]), dtype=np.float64))
    tail = 100.0 * (1.0 - 0.95) / 2.0  # each tail of the 95 % interval [%]
    interval = np.percentile(np.concatenate(out, axis=0), [tail, 100.0 - tail], axis=0)
    return point, np.asarray(interval, dtype=np.float64)


#: the 95 % normal quantile
Z95 = 1.959963984540054


def wilson_interval(failures: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion ``p = f / n``, ``(p + z^2/(2n) +- z sqrt(p (1 - p) / n +
    z^2 / (4 n^2))) / (1 + z^2 / n)``; ``(nan, nan)`` for ``n = 0``. ``z`` = 1.96 gives the 95 % interval."""
    if n <= 0:
        return math.nan, math.nan
    if not 0 <= failures <= n:
        raise ValueError(f"wilson_interval: failures must be in [0, n = {n}], got {failures}")
    p = failures / n
    zz = z * z
    centre = p + zz / (2 * n)
    half = z * math.sqrt(p * (1 - p) / n + zz / (4 * n * n))
    den = 1 + zz / n
    return max(0.0, (centre - half) / den), min(1.0, (centre + half) / den)


def failure_rate(failures: int, n: int) -> dict[str, Any]:
    """``n``, ``failures``, ``rate`` and its Wilson ``ci95`` (both ``None`` for ``n = 0``)."""
    lo, hi = wilson_interval(failures, n)
    return {"n": n, "failures": failures, "rate": failures / n if n else None, "ci95": [lo, hi] if n else None}
