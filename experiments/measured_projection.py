"""The measured H's projection of the compiled step (``_kernels_v1._evaluate``: Newton from H's foot, no coarse
search) against an alternative not kept (Newton from the first step, taken with that foot's known pose: one pose
fewer, but ``project_flat``'s Newton step written a second time), CPU time a robot of both projections.

    NUMBA_NUM_THREADS=1 python experiments/measured_projection.py

The training distribution's vector env (N = 4096) after 30 steps of random actions; each row's H projected, then a
point 2 mm (normal, per axis) from it projected without the coarse search from either start where the kernel does so
(H's foot interior, ``|kappa e| <= 0.5``). Prints the least of 9 repeats, twice, and the largest difference of the two
feet [m].
"""

from __future__ import annotations

import math
import time

import gymnasium as gym
import numba
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.model import kinematics
from amigo_gym.paths import clothoid as C
from amigo_gym.sim import fast_v1
from amigo_gym.sim import layout_v1 as L
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

kv = fast_v1.kernels()
n = 4096
env = gym.make_vec(
    "AmigoBot-v1", n, vectorization_mode="vector_entry_point", **dict(TRAINING_DISTRIBUTION["env_kwargs"])
)
env.reset(seed=0)
rng = np.random.default_rng(0)
for _ in range(30):
    env.step(rng.uniform(-1, 1, (n, 2)))
b = env.unwrapped._batch  # type: ignore[attr-defined]
c = b.consts
a = b.arena
ws = b.ws
PROG = L.Rows._fields.index("progress")
L3 = float(c[L.C_L3])
loc = kv._locate
noise = rng.normal(0, 0.002, (2, n))


@numba.njit
def run(c, flat, starts, stops, ws, noise, new, out):  # type: ignore[no-untyped-def]
    """Both projections of every row (the second from H's foot, or ``new``: from the first step) into ``out``."""
    for i in range(ws.shape[1]):
        pv = flat[starts[i] : stops[i]]
        hx, hy = kinematics.h_from_a(ws[0, i], ws[1, i], math.cos(ws[2, i]), math.sin(ws[2, i]), L3)
        s_h, kappa, e, ct, st, status = loc(c, pv, hx, hy, ws[PROG, i])
        if len(pv) == 0 or status != 0 or abs(kappa * e) > 0.5:
            continue
        mhx, mhy = hx + noise[0, i], hy + noise[1, i]
        h = pv[C.P_SPACING]
        s_m = s_h
        if new:
            _dx, _dy, g, e0 = C.foot_terms(mhx, mhy, hx + e * st, hy - e * ct, ct, st)
            s_m = s_h + min(max(g / max(1.0 - kappa * e0, C.MIN_NEWTON_DENOMINATOR), -h), h)
        out[i] = loc(c, pv, mhx, mhy, s_m, False)[0]


def least(new: bool) -> tuple[float, np.ndarray]:
    """The least CPU time of 9 repeats [ns a robot] and the measured feet [m]."""
    out = np.zeros(n)
    run(c, a.flat, a.starts, a.stops, ws, noise, new, out)
    best = 1e18
    for _ in range(9):
        t = time.thread_time_ns()
        run(c, a.flat, a.starts, a.stops, ws, noise, new, out)
        best = min(best, time.thread_time_ns() - t)
    return best / n, out


for _ in range(2):
    (t0, o0), (t1, o1) = least(False), least(True)
    ds = np.abs(o0 - o1).max()
    print(f"H's and the measured H's projections: {t0:.0f} ns a robot from H's foot, {t1:.0f} from the first step;")
    print(f"  largest difference of the measured feet {ds:.2e} m [{machine_line()}]")
