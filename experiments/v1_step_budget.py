"""Where AmigoBot-v1's single step spends its time, beside AmigoBot-v0's whole step (docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v1_step_budget.py

Prints the CPU, then the least of 15 repeats (``time.thread_time``: a busy host's stolen time does not count) of:
``gym.make("AmigoBot-v0")``'s and ``gym.make("AmigoBot-v1")``'s step and the v1 env's own ``step`` (no wrappers), with
random actions and resets as ``amigo-gym bench-env`` steps them (``bench.env._single_stepper``); then the pieces of the
v1 env's step (``AmigoBotV1Env._step_kernel`` and ``AmigoBotBase.step``), each timed alone: the action's check, the
compiled call (``StepKernel.run_record``: the step and its info record) and an empty compiled function of the same 13
arguments (what numba's entry costs to unbox them), the copy of the record and its scalars' floats, the info built from
them (``record_info``), the new ``true_robot`` and ``path`` dicts, the end condition, the observation's copy (the rest
of the env's own step: the calls between them); last a dict of the same 18 entries built from a copy of the record with
nothing else (the floor of that info); and AmigoBot-v0's compiled call (``fast.SingleStep.step``, with its record's
floats) beside v1's, both with the same random actions (v1's compiled step does more: actuator ramps integrated piece
by piece, a projection onto a clothoid path and three preview poses by quadrature), and v0's info from its record.
"""

from __future__ import annotations

import time
import timeit
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numba
import numpy as np

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.envs.amigobot_v1 import record_info
from amigo_gym.sim import fast
from amigo_gym.sim import layout_v1 as L
from amigo_gym.task import v0 as task
from amigo_gym.task import v1 as tracking
from amigo_gym.tools.bench.env import _single_stepper
from amigo_gym.tools.machine import machine_line


def best(f: Callable[[], Any], number: int = 2000) -> float:
    """Least time of one call over 15 repeats [us]."""
    return min(timeit.repeat(f, number=number, repeat=15, timer=time.thread_time)) / number * 1e6


@numba.njit(cache=False)
def _empty(k: Any, a1: Any, a2: Any, c: Any, pv: Any, ring: Any, ws: Any, obs: Any, rec: Any, w: Any) -> None:
    return None


def main() -> None:
    print(machine_line(), flush=True)
    v0, v1 = gym.make("AmigoBot-v0"), gym.make("AmigoBot-v1")
    u = v1.unwrapped
    step_v0, step_v1, step_own = _single_stepper(v0, 0), _single_stepper(v1, 0), _single_stepper(u, 1)
    kern = u._kernel
    empty = fast.direct_call(_empty, 0, 0.5, 0.5, *kern.args)
    rec, scalars, action = kern.record, kern.scalars, v1.action_space.sample()
    r, v = rec.copy(), scalars.tolist()
    true_robot, path_info, goal = u._true_robot, u._path_info, u._goal
    end_condition, action_pair = tracking.end_condition, task.action_pair
    fs = v0.unwrapped._v0
    pool = np.random.default_rng(0).uniform(-1.0, 1.0, (16, 2)).tolist()  # random actions, as bench-env's
    k = [0]

    v0_rec = fs.record.tolist()

    def call_v0() -> None:
        i = k[0] = (k[0] + 1) % 16
        fs.step(*pool[i])

    def call_v1() -> None:
        i = k[0] = (k[0] + 1) % 16
        a1, a2 = pool[i]
        kern.run_record(u._ring_step, a1, a2, *kern.args)

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

    def end() -> str:
        gx, _ = goal
        return "" if gx == gx else end_condition(False, False, False)

    rows = [
        ("AmigoBot-v0 step (gym.make)", best(step_v0)),
        ("AmigoBot-v1 step (gym.make)", best(step_v1)),
        ("AmigoBot-v1 step (the env's own step)", best(step_own)),
        ("  the action's check (task.action_pair, as v0's)", best(lambda: action_pair(action))),
        ("  its compiled call (run_record), random actions", best(call_v1)),
        ("    an empty compiled call of the same 13 arguments", best(lambda: empty(0, 0.5, 0.5, *kern.args))),
        ("  the record's copy and its scalars' floats", best(lambda: (rec.copy(), scalars.tolist()))),
        ("  the info from them (record_info)", best(lambda: record_info(r, v, 0.1, true_robot, 0.0, False, path_info))),
        ("  new true_robot and path dicts", best(lambda: (true_robot.copy(), path_info.copy()))),
        ("  the end condition (no goal)", best(end)),
        ("  the observation's copy", best(lambda: kern.obs.copy())),
        ("the floor of the info (18 entries from a copy of the record)", best(floor)),
        ("AmigoBot-v0's compiled call and its record's floats (SingleStep.step), random actions", best(call_v0)),
        (
            "AmigoBot-v0's info: its record's copy and task.record_info",
            best(lambda: task.record_info(fs.head.copy(), v0_rec, 0.1)),
        ),
    ]
    print("| AmigoBot-v1's single step | [us] |\n|---|---:|")
    for label, t in rows:
        print(f"| {label} | {t:.2f} |", flush=True)


if __name__ == "__main__":
    main()
