"""Ship fast PPO's residual on the delay compensator: each run folder's ``model.zip`` (``amigo-gym train-fast ...
--residual-base compensator --residual-gain 2.0``, trained with the correction everywhere) written with
``FeatureSpec.gate = True`` (it acts with the correction only where the compensator's quiet flag is on: the choice made
on the validation cells, experiments/candidates/README.md, "sr_s1, sr_s2 and the test cells") to
``agents/pretrained/v1/compensator_residual/compensator_residual_s<seed>.zip``, with its manifest (the run's
``run.json``, the zip's sha256, the training command, the weights' sha256 and that of the candidate they equal).

    python experiments/ship_compensator_residual.py /work/runs/cr_s0 /work/runs/cr_s1 /work/runs/cr_s2
    python experiments/ship_compensator_residual.py runs/cr_k3_s0 --out experiments/candidates --agent cr_k3
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import zipfile
from pathlib import Path

from amigo_gym.data import pretrained_dir
from amigo_gym.io import atomic_write_json, sha256_file
from amigo_gym.policies.learned import FastPolicy

AGENT = "compensator_residual"
CANDIDATES = Path(__file__).resolve().parent / "candidates"


def weights_digest(path: Path) -> str:
    """The sha256 of a fast-PPO zip's ``weights.npz`` (the network and normalisation, not the settings)."""
    with zipfile.ZipFile(path) as z:
        return hashlib.sha256(z.read("weights.npz")).hexdigest()


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path, help="train-fast run folders")
    p.add_argument("--out", type=Path, default=pretrained_dir() / "v1" / AGENT, help="folder of the zips")
    p.add_argument("--agent", default=AGENT, help="the zips' stem before _s<seed>")
    a = p.parse_args()
    out = a.out
    for run in a.runs:
        meta = json.loads((run / "run.json").read_text())
        policy = FastPolicy.load(run / "model.zip")
        if policy.spec.base != "compensator" or not meta.get("finished"):
            raise SystemExit(f"{run}: not a finished run of a residual on the compensator")
        policy.spec = dataclasses.replace(policy.spec, gate=True)
        zip_path = out / f"{a.agent}_s{meta['seed']}.zip"
        policy.save(zip_path)
        w = weights_digest(zip_path)
        same = [c.stem for c in sorted(CANDIDATES.glob("sr_s*.zip")) if weights_digest(c) == w]
        atomic_write_json(
            zip_path.with_suffix(".json"),
            {
                **meta,
                "sha256": sha256_file(zip_path),
                "weights_sha256": w,
                "same_weights_as": [f"experiments/candidates/{s}.zip" for s in same],
                "agent": a.agent,
                "env_id": "AmigoBot-v1",
                "env_kwargs": policy.spec.env_kwargs,
                "training_command": meta["command"],
                "acting": "FeatureSpec.gate = True set after training (experiments/ship_compensator_residual.py)",
                "loader": "amigo_gym.policies.load_pretrained",
            },
        )
        print(f"{zip_path}: seed {meta['seed']}, weights {w[:12]} (= {', '.join(same) or 'no candidate'})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
