"""A prototype not kept: H's coarse scan skipping whole blocks of samples by a bounding circle per block, against the
kernel's scan (``clothoid.nearest_sample``), on the open clothoid paths of a training-distribution env.

    NUMBA_NUM_THREADS=1 python experiments/scan_bound.py

The env (N = 4096, ``TRAINING_DISTRIBUTION``'s keywords) after 300 steps of random actions; for every row on an open
clothoid path, H's window (``+-window`` around the row's progress, as ``_locate`` scans it). The bounded scan: a circle
``(cx, cy, r)`` around each block of 8 samples (side arrays here; in a real change they would lie in the flat vector),
a first pass over the 4 samples in the window's middle for a small best distance ``b``, then the samples in order,
a whole block skipped where ``|H - c| > r + b`` (no sample of it can be nearer: the same sample is found, ties to the
first, checked on every row). Prints the samples read a row, and the least CPU time a row of 15 repeats of each scan
(3 rounds), warm and with the caches flushed before each repeat (a 64 MB array written), and the CPU.
"""

from __future__ import annotations

import math
import time
from typing import Any

import gymnasium as gym
import numba
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.model import kinematics
from amigo_gym.paths import clothoid as C
from amigo_gym.sim import layout_v1 as L
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

B = 8  # samples a block


@numba.njit
def bounds_of(flat, starts, stops, boff, bb):  # type: ignore[no-untyped-def]
    """Each open path's blocks: centre of the bounding box and radius (inflated by rounding's worth) into bb."""
    for i in range(starts.shape[0]):
        pv = flat[starts[i] : stops[i]]
        m = int(pv[C.P_M])
        sx = C.P_TAIL + 6 * int(pv[C.P_N])
        for blk in range((m + B - 1) // B):
            lo, hi = blk * B, min(m, blk * B + B)
            xs, ys = pv[sx + lo : sx + hi], pv[sx + m + lo : sx + m + hi]
            cx, cy = 0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max())
            r = np.sqrt((xs - cx) ** 2 + (ys - cy) ** 2).max()
            q = 3 * (boff[i] + blk)
            bb[q], bb[q + 1], bb[q + 2] = cx, cy, r * (1.0 + 1e-12) + 1e-15


@numba.njit
def bounded(pv, x, y, j0, count, bb, o, reads):  # type: ignore[no-untyped-def]
    """``nearest_sample`` of an open path with the blocks' bounds at ``bb[3 o:]``; counts the samples read."""
    m = int(pv[C.P_M])
    sx = C.P_TAIL + 6 * int(pv[C.P_N])
    sy = sx + m
    i0 = int(min(max(j0, 0.0), m - 1.0))
    i1 = int(min(max(j0 + float(count - 1), 0.0), m - 1.0)) + 1
    mid = (i0 + i1) // 2
    best, at = C.nearest_in_run(pv, sx, sy, x, y, max(i0, mid - 2), min(i1, mid + 2), math.inf, max(i0, mid - 2))
    sb = math.sqrt(best)
    j = i0
    while j < i1:
        stop = min(i1, (j // B + 1) * B)
        if stop - j == B:
            q = 3 * (o + j // B)
            dx, dy, rr = x - bb[q], y - bb[q + 1], bb[q + 2] + sb
            if dx * dx + dy * dy > rr * rr:
                j = stop
                continue
        for k in range(j, stop):
            reads[0] += 1
            d2 = (pv[sx + k] - x) ** 2 + (pv[sy + k] - y) ** 2
            if d2 < best or (d2 == best and k < at) or (d2 != d2 and best == best):
                best, at = d2, k
                sb = math.sqrt(best)
        j = stop
    return float(at) * pv[C.P_SPACING]


@numba.njit
def scan_all(flat, starts, stops, hx, hy, sp, window, mode, boff, bb, out, reads):  # type: ignore[no-untyped-def]
    for i in range(starts.shape[0]):
        pv = flat[starts[i] : stops[i]]
        h = pv[C.P_SPACING]
        j0, count = float(np.floor((sp[i] - window) / h)), math.ceil(2.0 * window / h) + 2
        if mode == 0:
            out[i] = C.nearest_sample(pv, hx[i], hy[i], j0, count)
        else:
            out[i] = bounded(pv, hx[i], hy[i], j0, count, bb, boff[i], reads)


def main() -> None:
    n = 4096
    env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", **TRAINING_DISTRIBUTION["env_kwargs"])
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(300):
        env.step(rng.uniform(-1.0, 1.0, (n, 2)))
    b: Any = env.unwrapped._batch  # type: ignore[attr-defined]
    a, ws, rows = b.arena, b.ws, {f: i for i, f in enumerate(L.Rows._fields)}
    flat = a.flat
    keep = np.array([flat[s + C.P_CIRCLE_K] == 0.0 and flat[s + C.P_CLOSED] == 0.0 for s in a.starts])
    starts, stops = a.starts[keep].copy(), a.stops[keep].copy()
    beta = ws[rows["beta"]][keep]
    hx, hy = kinematics.h_from_a(ws[rows["x"]][keep], ws[rows["y"]][keep], np.cos(beta), np.sin(beta),
                                 ws[rows["l3"]][keep])  # fmt: skip
    sp = ws[rows["progress"]][keep].copy()
    blocks = np.array([(int(flat[s + C.P_M]) + B - 1) // B for s in starts])
    boff = np.concatenate([[0], np.cumsum(blocks)[:-1]]).astype(np.int64)
    bb = np.zeros(3 * int(blocks.sum()))
    bounds_of(flat, starts, stops, boff, bb)
    window, m = float(b.consts[L.C_WINDOW]), len(starts)
    outs, reads = [np.empty(m), np.empty(m)], np.zeros(1, dtype=np.int64)
    for mode in (0, 1):
        scan_all(flat, starts, stops, hx, hy, sp, window, mode, boff, bb, outs[mode], reads)
    assert np.array_equal(outs[0], outs[1]), "the bounded scan found another sample"
    print(f"{m} rows on open clothoid paths of {n}; samples read a row: {2 * window / 0.02 + 2:.0f} (window "
          f"+-{window} m, spacing 0.02 m) against {reads[0] / m + 4:.1f} (4 in the first pass)")  # fmt: skip
    junk = np.zeros(8 << 20)
    for cold in (False, True):
        least = [math.inf, math.inf]
        for _ in range(3):
            for mode in (0, 1):
                for _ in range(15):
                    if cold:
                        junk += 1.0
                    t = time.thread_time_ns()
                    scan_all(flat, starts, stops, hx, hy, sp, window, mode, boff, bb, outs[mode], reads)
                    least[mode] = min(least[mode], (time.thread_time_ns() - t) / m)
        print(
            f"{'caches flushed' if cold else 'warm'}: the kernel's scan {least[0]:.0f} ns a row, bounded {least[1]:.0f}"
        )
    print(machine_line())


if __name__ == "__main__":
    main()
