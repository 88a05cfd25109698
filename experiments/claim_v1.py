"""Write the claimed benchmark numbers of the shipped AmigoBot-v1 generalists into their manifests.

Reads the JSON of a full benchmark run (``amigo-gym benchmark --out docs/benchmark``) and, for every
model under ``agents/pretrained/v1/<folder>/`` (the SB3 TD3 with a low-pass actor ``td3lp``, the fast PPO's
``ppo_fast`` and its ``residual``, matched by the sha256 of the zip) that the run evaluated, stores its
per-scenario figures (``h_rms_m``, ``h_rms_settled_m``, ``speed_err_rms``, ``failure_rate``, ``return``,
``chatter_settled_rms``) under ``"claimed"`` in its manifest, with the suite version and the benchmark command.
``tests/test_agents_v1_pretrained.py`` re-runs some scenarios and asserts the same numbers: exactly on this machine
(the claim records :func:`amigo_gym.tools.machine.bits_key`), to 1 % relative on any other. Run it on the
machine that ran the benchmark.

    python experiments/claim_v1.py --benchmark docs/benchmark/benchmark.json
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

from amigo_gym.data import pretrained_dir
from amigo_gym.io import atomic_write_json
from amigo_gym.tools.machine import bits_key

KEYS = ("h_rms_m", "h_rms_settled_m", "speed_err_rms", "failure_rate", "return", "chatter_settled_rms", "episodes")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--benchmark", required=True, help="benchmark.json of a full run")
    a = p.parse_args()
    doc = json.loads(Path(a.benchmark).read_text())
    by_sha: dict[str, dict[str, dict[str, float]]] = {}
    shas = {ag["agent"] + "/" + str(ag["seed"]): ag.get("sha256") for ag in doc["agents"]}
    for r in doc["results"]:
        sha = shas.get(r["agent"] + "/" + str(r["seed"]))
        if sha:
            by_sha.setdefault(sha, {})[r["scenario"]] = {k: r[k] for k in KEYS}
    done = 0
    for manifest in sorted((pretrained_dir() / "v1").glob("*/*.json")):
        model = manifest.with_suffix(".zip")
        sha = hashlib.sha256(model.read_bytes()).hexdigest()
        if sha not in by_sha:
            print(f"{model}: not in {a.benchmark}; left unclaimed", file=sys.stderr)
            continue
        m = json.loads(manifest.read_text())
        m["claimed"] = {
            "suite_version": doc["suite_version"],
            "command": doc.get("command"),
            # the run of docs/benchmark used torch's default, one thread per core (2 on the 2-core machines)
            "torch_threads": int(doc.get("torch_threads", 2)),
            # the last bits are this machine's: compared exactly only where the key is the same
            "machine": bits_key(),
            "scenarios": by_sha[sha],
        }
        atomic_write_json(manifest, m)  # json.dumps(indent=2) + newline, via a temporary file and os.replace
        done += 1
    print(f"claimed numbers written for {done} models", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
