"""How long the first use of each compiled step takes with a cold numba cache (README, "Install").

    PYTHONPATH=. python experiments/cold_compile.py

For each env, a new Python process with an empty ``NUMBA_CACHE_DIR`` makes the env, resets it and takes one step;
printed: the wall time of that first use, the same in a second process on the now warm cache, the CPU and its load.
numba compiles a kernel once per install (per cache directory) and loads it afterwards. The processes run one after
another, so the figures include what the other processes of the machine take from it (the load is printed).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

from amigo_gym.tools.machine import machine_line

CASES = {
    "AmigoBot-v0": "e = gym.make('AmigoBot-v0'); e.reset(seed=0); e.step(np.zeros(2, np.float32))",
    "AmigoBot-v0 vector": "v = gym.make_vec('AmigoBot-v0', num_envs=4, vectorization_mode='vector_entry_point'); "
    "v.reset(seed=0); v.step(np.zeros((4, 2)))",
    "AmigoBot-v1": "e = gym.make('AmigoBot-v1'); e.reset(seed=0); e.step(np.zeros(2, np.float32))",
    "AmigoBot-v1 vector": "v = gym.make_vec('AmigoBot-v1', num_envs=4, vectorization_mode='vector_entry_point'); "
    "v.reset(seed=0); v.step(np.zeros((4, 2)))",
}


def first_use(code: str, cache: str) -> float:
    """Wall time [s] of ``code`` after the imports, in a new process with ``NUMBA_CACHE_DIR=cache``."""
    script = (
        "import time, gymnasium as gym, numpy as np, amigo_gym\n"
        f"t = time.perf_counter()\n{code}\nprint(time.perf_counter() - t)\n"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    out = subprocess.run([sys.executable, "-c", script], env=env, check=True, capture_output=True, text=True)
    return float(out.stdout.split()[-1])


def main() -> None:
    print(machine_line(), flush=True)
    print(f"load average at the start: {os.getloadavg()}", flush=True)
    print("| env | first use, cold cache [s] | first use, warm cache [s] |\n|---|---:|---:|", flush=True)
    for name, code in CASES.items():
        with tempfile.TemporaryDirectory() as cache:
            cold = first_use(code, cache)
            warm = first_use(code, cache)
        print(f"| {name} | {cold:.1f} | {warm:.2f} |", flush=True)
    print(f"load average at the end: {os.getloadavg()}", flush=True)


if __name__ == "__main__":
    main()
