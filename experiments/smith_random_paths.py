"""The delay compensator of ``experiments/smith_delay.py`` as chosen on the validation cells (``k = 2``, the delay
estimated online, ``--quiet``) against the analytic controller (``k = 1``) on the published random paths (Cao et al.,
Sensors 2024; :mod:`amigo_gym.tools.training.random_paths`, AmigoBot-v1's firmware condition): does the higher gain
fail tight paths?

    python experiments/smith_random_paths.py [--paths 200] [--quiet 1e-6] [--json out.json]

One episode per path from the protocol's start offset (:func:`~amigo_gym.tools.training.task_metrics.run_scenario`);
a failure is a peak |e| of H at or above the tolerance. Prints the protocol's tables
(:func:`~amigo_gym.tools.training.random_paths.markdown_random_paths`: all paths, the paths within the wheel-rate
limits, per curvature bin), with Wilson 95 % intervals.
"""

from __future__ import annotations

import argparse
import json
import time

import gymnasium as gym
from smith_delay import Smith, SmithEstimated
from smith_test_cells import GAIN, Rows

import amigo_gym  # noqa: F401
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.random_paths import failure_table, markdown_random_paths, path_set
from amigo_gym.tools.training.task_metrics import run_scenario


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--paths", type=int, default=200)
    p.add_argument("--quiet", type=float, default=1e-6, help="SmithEstimated's quiet threshold [(m/s)^2]")
    p.add_argument("--json", default=None)
    a = p.parse_args()
    t0 = time.perf_counter()
    ps = path_set(a.paths, "firmware")
    agents = {"analytic": lambda q: Smith(q, 0.0, 1.0), "compensator": lambda q: SmithEstimated(q, GAIN, a.quiet)}
    episodes = []
    for sc in ps.scenarios:
        env = gym.make(sc.env_id, **dict(sc.env_kwargs))
        params, feasible = env.unwrapped.params, bool(env.unwrapped.feasibility["feasible"])  # type: ignore[attr-defined]
        env.close()
        for name, make in agents.items():
            m = run_scenario(Rows(lambda q=params, f=make: f(q), 1), sc)[0].metrics()
            episodes.append({"agent": name, "seed": 0, "scenario": sc.name, **ps.tags[sc.name], "feasible": feasible,
                             "peak_m": round(m["h_max_m"], 5), "steps": int(m.get("steps", 0))})  # fmt: skip
    doc = {
        "protocol": {**ps.settings, "failure": "peak |cross-track error| of H over the episode >= tolerance"},
        "agents": [{"name": n} for n in agents],
        "accepted": sum(e["feasible"] for e in episodes) // len(agents),
        "skipped": list(ps.skipped),
        "table": failure_table(episodes, ps.settings["tolerances"]),
        "episodes": episodes,
        "unavailable": [],
        "wall_time_s": round(time.perf_counter() - t0, 2),
    }
    print(machine_line())
    print(markdown_random_paths(doc))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(doc, f)


if __name__ == "__main__":
    main()
