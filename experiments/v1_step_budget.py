"""Where AmigoBot-v1's single step spends its time, beside AmigoBot-v0's whole step (docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v1_step_budget.py

Prints the CPU, then the least of 15 repeats (``time.thread_time``: a busy host's stolen time does not count) of:
``gym.make("AmigoBot-v0")``'s and ``gym.make("AmigoBot-v1")``'s step and the v1 env's own ``step`` (no wrappers), with
random actions and resets as ``amigo-gym bench-env`` steps them (``bench.env._single_stepper``); then, on the v1 env,
its compiled call (``StepKernel.run_record``: the step and its info record), an empty compiled function of the same 13
arguments (what numba's entry costs to unbox them), the info built from the record (``_kernel_info``), and a dict of
the same 18 entries built from a copy of the record with nothing else (the floor of that info).
"""

from __future__ import annotations

import time
import timeit
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numba

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.bench.env import _single_stepper
from amigo_gym.bench.machine import machine_line
from amigo_gym.sim import fast
from amigo_gym.sim import layout_v1 as L


def best(f: Callable[[], Any], number: int = 2000) -> float:
    """Least time of one call over 15 repeats [us]."""
    return min(timeit.repeat(f, number=number, repeat=15, timer=time.thread_time)) / number * 1e6


@numba.njit(cache=False)
def _empty(c: Any, pv: Any, ring: Any, ws: Any, obs: Any, k: Any, a1: Any, a2: Any, rec: Any, w: Any) -> None:
    return None


def main() -> None:
    print(machine_line(), flush=True)
    v0, v1 = gym.make("AmigoBot-v0"), gym.make("AmigoBot-v1")
    u = v1.unwrapped
    step_v0, step_v1, step_own = _single_stepper(v0, 0), _single_stepper(v1, 0), _single_stepper(u, 1)
    kern = u._kernel
    args = [kern.consts, kern.path, u._ring, kern.ws, kern.obs, u._ring_step, 0.5, 0.5, kern.record, kern.smooth_weight]
    empty = fast.direct_call(_empty, *args)
    rec = kern.record

    def floor() -> tuple[dict[str, Any], float]:
        r = rec.copy()
        v = r.tolist()
        e, progress, v_true, v_ref, heading, end, _term, track, speed, _, smooth, reward = v[L.R_ERROR :]
        info = {
            "pose": r[L.R_POSE], "h_position": r[L.R_H], "cross_track_error": e, "progress": progress,
            "speed": v_true, "reference_speed": v_ref, "speed_error": v_true - v_ref, "wheel_rates": r[L.R_RATES],
            "command": r[L.R_COMMAND], "wheel_angles": r[L.R_ANGLES], "measured_pose": r[L.R_MEASURED],
            "reward_terms": {"track": track, "speed": speed, "heading": heading, "smooth": smooth},
            "time": 0.1, "path": {}, "true_robot": {}, "delay": 0.0, "slip": r[L.R_SLIP], "end_of_path": end != 0.0,
        }  # fmt: skip
        return info, reward

    rows = [
        ("AmigoBot-v0 step (gym.make)", best(step_v0)),
        ("AmigoBot-v1 step (gym.make)", best(step_v1)),
        ("AmigoBot-v1 step (the env's own step)", best(step_own)),
        ("  its compiled call (run_record)", best(lambda: kern.run_record(*args))),
        ("  an empty compiled call of the same 13 arguments", best(lambda: empty(*args))),
        ("  its info from the record (_kernel_info)", best(lambda: u._kernel_info(False))),
        ("  the floor of that info (18 entries from a copy of the record)", best(floor)),
    ]
    print("| AmigoBot-v1's single step | [us] |\n|---|---:|")
    for label, t in rows:
        print(f"| {label} | {t:.2f} |", flush=True)


if __name__ == "__main__":
    main()
