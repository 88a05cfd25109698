"""sbx (Stable-Baselines on JAX) timed like ``amigo-gym bench-train --offpolicy``: not a dependency, an experiment.

    python -m venv --system-site-packages /tmp/sbxenv && /tmp/sbxenv/bin/pip install sbx-rl jax
    XLA_FLAGS="--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1" PYTHONPATH=$PWD \\
        nice -n 10 /tmp/sbxenv/bin/python experiments/bench_sbx.py --json docs/figures/offpolicy/bench_sbx.json

The same function as the bench (:func:`amigo_gym.tools.bench.train.bench_offpolicy`: the same env, adapter,
configurations, 64x64 networks, warm-up/loop split; one round of updates after the warm-up (8 env-steps per env,
while JAX compiles) is left out of the loop's time), with sbx's classes in place of SB3's / sb3-contrib's, JAX on
the CPU (one XLA thread with the flags above). Budgets as the bench's defaults: 1024 env-steps after the warm-up in the
``shipped`` configuration, 16384 in ``ht``.
"""

from __future__ import annotations

import argparse
import sys

from amigo_gym.io import atomic_write_json
from amigo_gym.tools.bench import load_values
from amigo_gym.tools.bench import train as bench_train
from amigo_gym.tools.bench.train import cpu_model


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--algos", default="sac,td3,crossq,tqc")
    p.add_argument("--steps", type=int, default=1024)
    p.add_argument("--ht-steps", type=int, default=16384)
    p.add_argument("--json", default=None)
    a = p.parse_args()
    import jax
    import sbx

    bench_train.ALGOS.update(
        {k: ("sbx", v) for k, v in (("sac", "SAC"), ("td3", "TD3"), ("crossq", "CrossQ"), ("tqc", "TQC"))}
    )
    doc = {
        "cpu_model": cpu_model(),
        "sbx": sbx.__version__,
        "jax": jax.__version__,
        "devices": [str(d) for d in jax.devices()],
        "load_average_start": load_values(),
        "command": "python experiments/bench_sbx.py " + " ".join(sys.argv[1:]),
        "runs": {},
    }
    for algo in a.algos.split(","):
        for config, steps in (("shipped", a.steps), ("ht", a.ht_steps)):
            # the first updates compile (JIT): one training round after the warm-up is left out of the loop's time
            hp = bench_train.offpolicy_config(algo, config)
            r = bench_train.bench_offpolicy(algo, config, steps, threads=1, pre_steps=8 * int(hp.get("n_envs", 1)))
            doc["runs"][f"sbx_{algo}_{config}"] = r
            print(f"sbx_{algo}_{config}: {r['sps_loop']:,.0f} env-steps/s ({r['sps_loop_cpu']:,.0f} per CPU s), "
                  f"{r['gsps_loop']:,.1f} gradient steps/s ({r['gsps_loop_cpu']:,.1f} per CPU s)",
                  flush=True)  # fmt: skip
    doc["load_average_end"] = load_values()
    if a.json:
        atomic_write_json(a.json, doc, parents=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
