"""The sweep's objective for any models: IQM of H RMS over the protocol's v1 validation cells (5 episodes each).

The number ``amigo-gym sweep --env AmigoBot-v1`` minimises (:func:`amigo_gym.tools.training.sweep.validation_cells`,
:func:`~amigo_gym.tools.training.sweep.validate_agent`: :mod:`amigo_gym.tools.training.protocol`'s validation cells
on validation seeds, never a test cell or seed), computed for models trained outside the sweep, e.g. the shipped
seeds against the sweep's trials, which ran a shorter budget:

    python experiments/sweep_objective.py 'agents/pretrained/v1/ppo_fast/*.zip'

One line per model, in mm.
"""

from __future__ import annotations

import argparse
import glob
import sys


def main(argv: list[str] | None = None) -> int:
    from amigo_gym.policies import load_pretrained
    from amigo_gym.tools.training.sweep import validate_agent, validation_cells

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="*", help="model zips or glob patterns (quoted)")
    ap.add_argument("--episodes", type=int, default=5, help="validation episodes per cell (default 5, the sweep's)")
    a = ap.parse_args(argv)
    if not 1 <= a.episodes <= 100:
        print(f"sweep_objective: error: --episodes {a.episodes}: must be in [1, 100]", file=sys.stderr)
        return 2
    paths = [p for pattern in a.models for p in (sorted(glob.glob(pattern)) or [pattern])]
    cells = validation_cells("AmigoBot-v1", a.episodes, 0)
    status = 0
    for p in paths:
        try:
            agent = load_pretrained(p)
        except (OSError, ValueError) as e:
            print(f"sweep_objective: error: {p}: {e}", file=sys.stderr)
            status = 1
            continue
        value, _ = validate_agent(agent, cells)
        print(f"{p}: {1e3 * value:.3f} mm", flush=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
