"""Validation metrics of the analytic controller and fast-PPO models on a run's validation seeds (not benchmark cells).

    python experiments/fast_validation.py runs/fast/var_base runs/fast/var_filter0.5 [--eval-envs 64]

For each run folder: its ``settings.json`` gives the distribution (``env_kwargs``) and the validation seeds
(``eval_seed + i``); the analytic controller (:class:`amigo_gym.policies.AnalyticTrackingPolicy`, nominal robot)
and the run's ``model.zip`` (else ``best.zip``) are evaluated with
:func:`amigo_gym.tools.training.fastppo.evaluate_policy` on ``--eval-envs`` episodes. Prints one Markdown row per agent:
H cross-track RMS (whole episode and settled, t >= 5 s) [mm], settled chatter [rad/s], settled speed error [mm/s],
failure rate.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.policies.learned import FastPolicy
from amigo_gym.tools.training.fastppo import FastPPOSettings, evaluate_policy


def row(name: str, m: dict[str, float]) -> str:
    return (
        f"| {name} | {1e3 * m['h_rms_m']:.2f} | {1e3 * m['h_rms_settled_m']:.2f} | {m['chatter_settled_rms']:.2f} | "
        f"{1e3 * m['speed_err_settled_rms']:.1f} | {m['failure']:.2f} |"
    )


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", help="fast-PPO run folders")
    p.add_argument("--eval-envs", type=int, default=64, help="episodes per agent (default 64)")
    a = p.parse_args()
    print("| agent | H RMS [mm] | H RMS settled [mm] | chatter settled [rad/s] | speed err settled [mm/s] | failure |")
    print("|---|---|---|---|---|---|")
    done_analytic: set[str] = set()
    for run in map(Path, a.runs):
        s = FastPPOSettings.from_json(json.loads((run / "settings.json").read_text()))
        s = dataclasses.replace(s, eval_envs=a.eval_envs)
        key = json.dumps(dict(s.env_kwargs), sort_keys=True)
        if key not in done_analytic:
            done_analytic.add(key)
            print(
                row(
                    f"analytic ({run.name}'s distribution)",
                    evaluate_policy(AnalyticTrackingPolicy(s.spec().params()), s),
                )
            )
        model = run / "model.zip" if (run / "model.zip").is_file() else run / "best.zip"
        print(row(f"{run.name} ({model.name})", evaluate_policy(FastPolicy.load(model), s)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
