"""AmigoBot-v0's compiled step, timed by CPU time: the vector step's evaluate pass per robot at N = 4096 and the single
robot's compiled step (docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v0_step_speed.py [label]

Prints, for the circle and the manoeuvre path, the least of 400 repeats (``time.thread_time_ns``, which a busy host's
stolen time does not count) of the evaluate pass (:func:`amigo_gym.sim._kernels.evaluate`) over 4096 robots in
random states with random actions, per robot, and the least of 50 batches of 1000 calls of
:meth:`amigo_gym.sim.fast.SingleStep.step` per call. Run it on two trees alternately (``PYTHONPATH``) to compare them.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from amigo_gym.model.params import EnvParams
from amigo_gym.paths import make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task


def main() -> None:
    out = []
    kernels = fast.kernels()
    n = 4096
    for path_name in ("circle", "manoeuvre"):
        p = EnvParams(path=path_name)
        k = task.task_constants(p)
        path = make_path(p)
        ws = fast.workspace(k, path, n)
        g = np.random.default_rng(0)
        state = np.zeros((n, 8))
        state[:, 0] = g.uniform(-0.5, 2.0, n)
        state[:, 1] = g.uniform(-0.3, 2.0, n)
        state[:, 2] = g.uniform(-3.0, 3.0, n)
        state[:, 6:] = 10.0
        actions = g.uniform(-1.0, 1.0, (n, 2))
        restart = np.zeros(n, bool)
        obs = np.zeros((n, ws.obs_dim), np.float32)
        terminated = np.zeros(n, bool)
        record = np.zeros((n, 16))
        s0 = state.copy()
        kernels.move_arguments(ws.consts, state, actions, restart, ws.tans, ws.turn)
        np.tan(ws.tans, out=ws.tans)
        args = [ws.consts, ws.preview, state, actions, restart, ws.tans, ws.turn, obs, terminated, record, ws.exps]
        if hasattr(ws, "block_cols"):  # the blocked pass's scratch (absent before it)
            args.append(ws.block_cols)
        best = 1 << 62
        for _ in range(400):
            state[:] = s0
            t0 = time.thread_time_ns()
            kernels.evaluate(*args)
            best = min(best, time.thread_time_ns() - t0)
        out.append(f"evaluate {path_name} N={n}: {best / n:.1f} ns/robot")
        one = fast.SingleStep(k, path)
        for _ in range(1000):
            one.step(0.3, 0.5)
        single = float("inf")
        for _ in range(50):
            t0 = time.thread_time_ns()
            for _ in range(1000):
                one.step(0.3, 0.5)
            single = min(single, (time.thread_time_ns() - t0) / 1000)
        out.append(f"single {path_name}: {single:.0f} ns")
    label = sys.argv[1] if len(sys.argv) > 1 else ""
    print(f"{label} " + " | ".join(out), flush=True)


if __name__ == "__main__":
    main()
