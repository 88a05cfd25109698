"""Where AmigoBot-v1's compiled robot-step goes: jitted loops over the rows of a vector env calling the kernel's own
functions, CPU time per robot. Run it on two trees alternately to compare them.

    PYTHONPATH=<tree> NUMBA_NUM_THREADS=1 python experiments/v1_step_parts.py [defaults|training|hard] [N]

The env (``gym.make_vec("AmigoBot-v1", N)``, N = 4096, with the training distribution's or ``V1_HARD``'s keywords)
is reset with seed 0 and stepped 30 times with uniform random actions; its block is then copied before every repeat.
Prints the least of 7 repeats, ns a robot: the whole row step with its record (``step`` and ``fill_record``), the
actuator step alone (``_actuator_step``, setpoints from random actions), the evaluation alone (``_evaluate``, no
noise, no command change), H's projection alone (``_locate``), the three previews' poses alone (``pose``), and the
CPU.
"""

from __future__ import annotations

import math
import sys
import time

import gymnasium as gym
import numba
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.model import kinematics
from amigo_gym.sim import fast_v1
from amigo_gym.sim import layout_v1 as L
from amigo_gym.tools.bench.env import V1_HARD
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

config = sys.argv[1] if len(sys.argv) > 1 else "defaults"
kw = {"defaults": {}, "training": dict(TRAINING_DISTRIBUTION["env_kwargs"]), "hard": dict(V1_HARD)}[config]
n = int(sys.argv[2]) if len(sys.argv) > 2 else 4096
env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", **kw)
env.reset(seed=0)
rng = np.random.default_rng(0)
for _ in range(30):
    env.step(rng.uniform(-1.0, 1.0, (n, 2)))
u = env.unwrapped
b, kv = u._batch, fast_v1.kernels()  # type: ignore[attr-defined]
c, a, ws0, rings0, ring_step = b.consts, b.arena, b.ws.copy(), u._ring.copy(), u._ring_step  # type: ignore[attr-defined]
a1, a2 = rng.uniform(-1.0, 1.0, n), rng.uniform(-1.0, 1.0, n)
setpoints = np.stack([a1, a2]) * float(c[L.C_W_MAX])
obs = np.empty((n, u._obs.shape[1]), dtype=np.float32)  # type: ignore[attr-defined]
rec = np.empty((n, L.RECORD_WIDTH))
PROGRESS, L3 = L.Rows._fields.index("progress"), float(c[L.C_L3])
step, act, evaluate, fill, locate, pose = kv.step, kv._actuator_step, kv._evaluate, kv.fill_record, kv._locate, kv.pose


@numba.njit
def whole(c, flat, starts, stops, rings, ws, obs, ring_step, a1, a2, keys, rec):  # type: ignore[no-untyped-def]
    for i in range(ws.shape[1]):
        step(c, flat[starts[i] : stops[i]], rings[i], ws, i, obs[i], rec[i], ring_step, a1[i], a2[i], keys[i])
        fill(rec[i], 0.2)


@numba.njit
def actuator(c, ws, w):  # type: ignore[no-untyped-def]
    for i in range(ws.shape[1]):
        act(c, ws, i, w[0, i], w[1, i], w[0, i], w[1, i], 0.0, 0.0)


@numba.njit
def evaluation(c, flat, starts, stops, ws, obs, rec):  # type: ignore[no-untyped-def]
    for i in range(ws.shape[1]):
        cb, sb = math.cos(ws[2, i]), math.sin(ws[2, i])
        pv = flat[starts[i] : stops[i]]
        evaluate(c, pv, ws, i, obs[i], rec[i], 0.1, cb, sb, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@numba.njit
def projection(c, flat, starts, stops, ws):  # type: ignore[no-untyped-def]
    for i in range(ws.shape[1]):
        hx, hy = kinematics.h_from_a(ws[0, i], ws[1, i], math.cos(ws[2, i]), math.sin(ws[2, i]), L3)
        locate(c, flat[starts[i] : stops[i]], hx, hy, ws[PROGRESS, i])


@numba.njit
def previews(c, flat, starts, stops, ws):  # type: ignore[no-untyped-def]
    for i in range(ws.shape[1]):
        for j in range(int(c[L.C_N_PREVIEW])):
            pose(c, flat[starts[i] : stops[i]], ws[PROGRESS, i] + c[L.C_TAIL + j])


def least(f, *args) -> float:  # type: ignore[no-untyped-def]
    """The least CPU time of 7 repeats [ns a robot], the block and rings copied before each."""
    best = math.inf
    for _ in range(8):  # the first compiles
        ws, rings = ws0.copy(), rings0.copy()
        fresh = [ws if x is ws0 else rings if x is rings0 else x for x in args]
        t = time.thread_time_ns()
        f(*fresh)
        best = min(best, (time.thread_time_ns() - t) / n)
    return best


parts = {
    "row step": least(whole, c, a.flat, a.starts, a.stops, rings0, ws0, obs, ring_step, a1, a2, b.keys, rec),
    "actuator": least(actuator, c, ws0, setpoints),
    "evaluation": least(evaluation, c, a.flat, a.starts, a.stops, ws0, obs, rec),
    "projection": least(projection, c, a.flat, a.starts, a.stops, ws0),
    "previews": least(previews, c, a.flat, a.starts, a.stops, ws0),
}
print(f"{config} N={n}: " + ", ".join(f"{k} {v:.0f}" for k, v in parts.items()) + f" ns a robot [{machine_line()}]")
