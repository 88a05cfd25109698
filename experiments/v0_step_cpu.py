"""CPU time of AmigoBot-v0's step and reset (``time.process_time``, so other processes' load counts less).

Prints one line per measurement: the single env's unwrapped ``env.step`` (20 000 steps with
``termination_distance=10``: no episode ends, resets not timed; 3 000 with ``kernel="numpy"``), ``env.reset``
(2 000), and the vector env at N = 4096 (50 steps, autoresets inside), each the best and the median of 5 repeats.
To compare two versions of the package on a loaded machine, run it alternately with each on ``PYTHONPATH``::

    for i in 1 2 3; do PYTHONPATH=/path/to/old python experiments/v0_step_cpu.py --label old
                       PYTHONPATH=. python experiments/v0_step_cpu.py --label new; done

``--steps-only --repeats 3`` runs in about 3 s: alternate it many times for the step alone.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)


def _single(kernel: str, repeats: int = 5) -> tuple[float, float]:
    env = gym.make("AmigoBot-v0", kernel=kernel, termination_distance=10.0).unwrapped
    n = 3000 if kernel == "numpy" else 20_000
    g = np.random.default_rng(0)
    acts = (g.normal(size=(n, 2)) * 0.02 + np.array([0.2933, 0.2400])).astype(np.float32)
    env.reset(seed=0)
    for a in acts[:300]:
        env.step(a)
    us = []
    for rep in range(repeats):
        env.reset(seed=rep)
        t0 = time.process_time()
        for a in acts:
            env.step(a)
        us.append((time.process_time() - t0) / n * 1e6)
    us.sort()
    return us[0], us[len(us) // 2]


def _reset(kernel: str) -> tuple[float, float]:
    env = gym.make("AmigoBot-v0", kernel=kernel).unwrapped
    env.reset(seed=0)
    us = []
    for _ in range(5):
        t0 = time.process_time()
        for _ in range(2000):
            env.reset()
        us.append((time.process_time() - t0) / 2000 * 1e6)
    us.sort()
    return us[0], us[2]


def _vector(kernel: str, n: int = 4096) -> tuple[float, float]:
    env = gym.make_vec("AmigoBot-v0", num_envs=n, kernel=kernel)
    env.reset(seed=0)
    g = np.random.default_rng(0)
    acts = (g.normal(size=(50, n, 2)) * 0.05 + np.array([0.2933, 0.2400])).astype(np.float32)
    for a in acts[:5]:
        env.step(a)
    rates = []
    for _ in range(5):
        t0 = time.process_time()
        for a in acts:
            env.step(a)
        rates.append(len(acts) * n / (time.process_time() - t0) / 1e6)
    rates.sort()
    return rates[-1], rates[2]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--label", default="", help="a name printed before each line")
    p.add_argument("--kernels", nargs="+", default=["auto"], help="kernel= values to measure")
    p.add_argument("--vector", action="store_true", help="also the vector env at N = 4096")
    p.add_argument("--steps-only", action="store_true", help="only the single env's step")
    p.add_argument("--repeats", type=int, default=5, help="repeats of the single env's step")
    a = p.parse_args()
    for k in a.kernels:
        best, med = _single(k, a.repeats)
        print(f"{a.label} single step, kernel={k}: CPU {best:.2f} us best, {med:.2f} us median")
        if a.steps_only:
            continue
        best, med = _reset(k)
        print(f"{a.label} single reset, kernel={k}: CPU {best:.1f} us best, {med:.1f} us median")
        if a.vector:
            best, med = _vector(k)
            print(f"{a.label} vector N=4096, kernel={k}: CPU {best:.2f} M robot-steps/s best, {med:.2f} median")


if __name__ == "__main__":
    main()
