"""AmigoBot-v0's compiled step, timed by CPU time: the vector step's evaluate pass per robot at N = 4096 and the single
robot's compiled step (docs/architecture.md, "Speed").

    PYTHONPATH=. NUMBA_NUM_THREADS=1 python experiments/v0_step_speed.py [label]

Prints, for the circle and the manoeuvre path, the evaluate pass (:func:`amigo_gym.sim._kernels.evaluate`) over 4096
robots in random states with random actions, per robot (``experiments/v0_vector_speed.py``'s ``evaluate_pass``: the
least of 40 repeats by ``time.thread_time_ns``, which a busy host's stolen time does not count), and the least of 50
batches of 1000 calls of
:meth:`amigo_gym.sim.fast.SingleStep.step` per call. Run it on two trees alternately (``PYTHONPATH``) to compare them.
"""

from __future__ import annotations

import sys
import time

from v0_vector_speed import N, evaluate_pass  # the evaluate pass's measurement, written once (this folder)

from amigo_gym.model.params import EnvParams
from amigo_gym.paths import make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task


def main() -> None:
    out = []
    for path_name in ("circle", "manoeuvre"):
        p = EnvParams(path=path_name)
        per_robot = evaluate_pass(path_name, 40)  # least of 40 repeats of 10 passes, less the state's reset
        out.append(f"evaluate {path_name} N={N}: {per_robot:.1f} ns/robot")
        one = fast.SingleStep(task.task_constants(p), make_path(p))
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
