"""Where one ``gym.make`` step of AmigoBot-v1 spends the time AmigoBot-v0's does not (issue 35's "single step").

    NUMBA_NUM_THREADS=1 python experiments/single_step_parts.py [repeats]

For each env: the whole ``env.step`` through ``gym.make``'s wrappers (``bench-env``'s stepper: a pool of 16
``action_space.sample()`` actions, seed 0, cycled), the env's own ``step`` (no wrappers, the same actions), and its
parts on the compiled route: the compiled step with its record (``run_record``), the info dict from the record
(``_record_info``) and the end-of-episode check with ``info["end_condition"]`` (``_end``). A reset when an episode
ends (with these actions about one in 400 steps for either env; a pool that drives AmigoBot-v0 off its circle every
50 steps would time its resets too). Least CPU time (``time.thread_time``) per call over ``repeats`` (default 9)
repeats of 3000 calls, in µs; the CPU is printed.
"""

from __future__ import annotations

import sys

import gymnasium as gym
from env_step_speed import least  # beside this file: the least CPU time [ns] of a call

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.tools.bench import stepper
from amigo_gym.tools.machine import machine_line


def parts(env_id: str, repeats: int) -> dict[str, float]:
    env = gym.make(env_id)
    env.reset(seed=0)
    u = env.unwrapped
    env.action_space.seed(0)
    pool = [env.action_space.sample() for _ in range(16)]
    i = [0]

    def bare() -> None:
        i[0] = (i[0] + 1) % 16
        _, _, terminated, _, _ = u.step(pool[i[0]])
        if terminated:
            u.reset()

    k = u._kernel

    def kernel() -> None:
        u._ring_step += 1
        k.run_record(u._ring_step, 0.3, 0.31, *k.args)

    def info() -> None:
        u._record_info(k.record.copy(), k.scalars.tolist())

    def end() -> None:
        u._end(False, u._record_info(k.record.copy(), k.scalars.tolist()))

    wrapped = stepper(gym.make(env_id), 0)
    for _ in range(500):
        wrapped()
        bare()
    out = {name: least(fn, 3000, repeats) / 1e3 for name, fn in
           (("gym.make step", wrapped), ("env.step", bare), ("compiled step", kernel), ("info", info),
            ("info and end", end))}  # fmt: skip
    env.close()
    return out


def main() -> None:
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 9
    print(machine_line())
    v0, v1 = parts("AmigoBot-v0", repeats), parts("AmigoBot-v1", repeats)
    print("| part [µs] | AmigoBot-v0 | AmigoBot-v1 | v1 - v0 |\n|---|---:|---:|---:|")
    for name in v0:
        print(f"| {name} | {v0[name]:.2f} | {v1[name]:.2f} | {v1[name] - v0[name]:+.2f} |")
    print(f"v1 / v0, gym.make step: {v1['gym.make step'] / v0['gym.make step']:.2f}")


if __name__ == "__main__":
    main()
