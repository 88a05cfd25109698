"""AmigoBot-v0's native vector env at N = 4096 against Gymnasium's ``CartPoleVectorEnv``, by CPU time, one core
(issue 19's target: >= 1.0 x CartPole's throughput), with its compiled evaluate pass per robot and the single env's
step against ``Pendulum-v1`` (docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v0_vector_speed.py [label] [--repeats R]

Prints the CPU model, then the least (``time.thread_time_ns``: a busy host's stolen time does not count) over ``R``
repeats (default 9) of: the evaluate pass (:func:`amigo_gym.sim._kernels.evaluate`) over 4096 robots in random states
with random actions, per robot, on the circle (the default path) and the manoeuvre path; one ``step`` of
``gym.make_vec("AmigoBot-v0", num_envs=4096, vectorization_mode="vector_entry_point")`` and of
``CartPoleVectorEnv(num_envs=4096)`` (random actions, autoreset inside; the two interleaved in each repeat, 20 steps a
repeat) and their ratio; one ``step`` of ``gym.make("AmigoBot-v0")`` and of ``gym.make("Pendulum-v1")`` (2000 steps a
repeat). Runs on a tree without the evaluate pass's scratch (``Workspace.block_cols``) too: run it on two trees
alternately (``PYTHONPATH``) to compare them.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np
from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.model.params import EnvParams
from amigo_gym.paths import make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task
from amigo_gym.tools.bench.env import _single_stepper, _vector_stepper
from amigo_gym.tools.machine import cpu_model

N = 4096


def least_ns(fns: dict[str, Callable[[], object]], calls: int, repeats: int) -> dict[str, float]:
    """The least CPU time [ns] per call of each function over ``repeats`` repeats of ``calls`` calls, interleaved."""
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeats):
        for name, fn in fns.items():
            t0 = time.thread_time_ns()
            for _ in range(calls):
                fn()
            best[name] = min(best[name], (time.thread_time_ns() - t0) / calls)
    return best


def evaluate_pass(path_name: str, repeats: int) -> float:
    """The evaluate pass over ``N`` robots, least CPU time per robot [ns]."""
    kernels = fast.kernels()
    p = EnvParams(path=path_name)
    ws = fast.workspace(task.task_constants(p), make_path(p), N)
    g = np.random.default_rng(0)
    state = np.zeros((N, 8))
    state[:, 0] = g.uniform(-0.5, 2.0, N)
    state[:, 1] = g.uniform(-0.3, 2.0, N)
    state[:, 2] = g.uniform(-3.0, 3.0, N)
    state[:, 6:] = 10.0
    actions = g.uniform(-1.0, 1.0, (N, 2))
    restart = np.zeros(N, bool)
    obs = np.zeros((N, ws.obs_dim), np.float32)
    terminated = np.zeros(N, bool)
    record = np.zeros((N, 16))
    s0 = state.copy()
    kernels.move_arguments(ws.consts, state, actions, restart, ws.tans, ws.turn)
    np.tan(ws.tans, out=ws.tans)
    args = [ws.consts, ws.preview, state, actions, restart, ws.tans, ws.turn, obs, terminated, record, ws.exps]
    if hasattr(ws, "block_cols"):  # the blocked pass's scratch (absent before it)
        args.append(ws.block_cols)

    def run() -> None:
        state[:] = s0
        kernels.evaluate(*args)

    run()
    copy = least_ns({"copy": lambda: state.__setitem__(slice(None), s0)}, 10, repeats)["copy"]
    return (least_ns({"evaluate": run}, 10, repeats)["evaluate"] - copy) / N


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("label", nargs="?", default="")
    ap.add_argument("--repeats", type=int, default=9)
    a = ap.parse_args()
    r = a.repeats
    print(f"{a.label} CPU: {cpu_model()}, numpy {np.__version__}", flush=True)
    for path_name in ("circle", "manoeuvre"):
        per_robot = evaluate_pass(path_name, 5 * r)
        print(f"{a.label} evaluate pass, {path_name}, N={N}: {per_robot:.2f} ns/robot", flush=True)
    amigo = gym.make_vec("AmigoBot-v0", num_envs=N, vectorization_mode="vector_entry_point")
    cart = CartPoleVectorEnv(num_envs=N)
    cart.action_space.seed(0)
    t = least_ns({"amigo": _vector_stepper(amigo, 0), "cartpole": _vector_stepper(cart, 0)}, 20, r)
    print(
        f"{a.label} vector step, N={N}: AmigoBot-v0 {t['amigo'] / 1e3:.1f} us, CartPoleVectorEnv "
        f"{t['cartpole'] / 1e3:.1f} us, throughput AmigoBot / CartPole {t['cartpole'] / t['amigo']:.3f}",
        flush=True,
    )
    one, pend = gym.make("AmigoBot-v0"), gym.make("Pendulum-v1")
    s = least_ns({"amigo": _single_stepper(one, 0), "pendulum": _single_stepper(pend, 0)}, 2000, r)
    print(
        f"{a.label} single step: AmigoBot-v0 {s['amigo'] / 1e3:.2f} us, Pendulum-v1 {s['pendulum'] / 1e3:.2f} us, "
        f"ratio {s['amigo'] / s['pendulum']:.3f}",
        flush=True,
    )


if __name__ == "__main__":
    main()
