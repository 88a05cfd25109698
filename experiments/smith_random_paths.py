"""The delay compensator of ``experiments/smith_delay.py`` as chosen on the validation cells (``k = 2``, the delay
estimated online, ``--quiet``) against the analytic controller (``k = 1``) on the published random paths (Cao et al.,
Sensors 2024; :mod:`amigo_gym.tools.training.random_paths`, AmigoBot-v1's firmware condition): does the higher gain
fail tight paths?

    python experiments/smith_random_paths.py [--paths 200] [--quiet 1e-6] [--json out.json]

The benchmark's own run (:func:`~amigo_gym.tools.training.random_paths.run_random_paths`: one episode per path from
the protocol's start offset, a failure a peak |e| of H at or above the tolerance) with the two controllers as its
agents; prints the protocol's tables (all paths, the paths within the wheel-rate limits, per curvature bin, Wilson
95 % intervals).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from smith_delay import Smith, SmithEstimated
from smith_test_cells import GAIN, Rows

import amigo_gym  # noqa: F401
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.random_paths import markdown_random_paths, path_set, run_random_paths


@dataclass(frozen=True)
class Controller:
    """A controller as the benchmark's agent spec: ``make(params)`` per episode row, one seed."""

    name: str
    make: Callable[[Any], Any]
    seed: int = 0

    def instantiate(self, env: Any) -> Rows:
        return Rows(lambda q=env.unwrapped.params: self.make(q), 1)

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "seed": self.seed}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--paths", type=int, default=200)
    p.add_argument("--quiet", type=float, default=1e-6, help="SmithEstimated's quiet threshold [(m/s)^2]")
    p.add_argument("--json", default=None)
    a = p.parse_args()
    agents = [Controller("analytic", lambda q: Smith(q, 0.0, 1.0)),
              Controller("compensator", lambda q: SmithEstimated(q, GAIN, a.quiet))]  # fmt: skip
    doc = run_random_paths(agents, path_set(a.paths, "firmware"), progress=False)
    print(machine_line())
    print(markdown_random_paths(doc))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(doc, f)


if __name__ == "__main__":
    main()
