"""Where AmigoBot-v1's vector step spends its CPU time, function by function: Linux ``perf`` with the compiled
kernel's own symbols.

    NUMBA_NUM_THREADS=1 python experiments/perf_profile.py [defaults|training|hard] [N] [seconds]

numba's JIT code has no symbols ``perf`` can read, so this script runs the env in a child process with an empty numba
cache (the kernels compile there, a few minutes) and writes the address and size of every compiled function to
``/tmp/perf-<pid>.map``, the file ``perf report`` reads for JIT code. The child steps
``gym.make_vec("AmigoBot-v1", N, vectorization_mode="vector_entry_point", **kwargs)`` (N = 4096; the training
distribution's or ``V1_HARD``'s keywords) 300 times with uniform random actions (the steady state of restarts), then
``perf record -F 2000 -p <child>`` samples ``seconds`` (default 20) of further steps. Prints each function's share of
all samples (those of at least 0.3 %), grouped: the compiled kernel, the C math library, the rest (Python, numpy, the
garbage collector, the OS), and the CPU. Needs ``perf`` (Debian's ``linux-perf``) and the permission to sample
(``/proc/sys/kernel/perf_event_paranoid`` <= 1, or root).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import time


def child(config: str, n: int, seconds: float) -> None:
    import gymnasium as gym
    import numba
    import numpy as np

    import amigo_gym  # noqa: F401  (registers the envs)
    from amigo_gym.sim import _kernels_v1
    from amigo_gym.tools.bench.env import V1_HARD
    from amigo_gym.tools.training.benchmark import TRAINING_DISTRIBUTION

    kw = {"defaults": {}, "training": dict(TRAINING_DISTRIBUTION["env_kwargs"]), "hard": dict(V1_HARD)}[config]
    env = gym.make_vec("AmigoBot-v1", n, vectorization_mode="vector_entry_point", **kw)
    env.reset(seed=0)
    acts = np.random.default_rng(0).uniform(-1.0, 1.0, (10, n, 2))
    for k in range(300):
        env.step(acts[k % 10])
    functions = {}  # address -> name, of every function of every compiled kernel's library
    for d in vars(_kernels_v1).values():
        if isinstance(d, numba.core.registry.CPUDispatcher):
            for cres in d.overloads.values():
                ee = cres.library._codegen._engine._ee
                for fn in cres.library._final_module.functions:
                    if not fn.is_declaration and (address := ee.get_function_address(fn.name)):
                        functions[address] = fn.name
    starts = sorted(functions)
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as f:  # perf's JIT map: start, size (hex), name
        for a, b in zip(starts, [*starts[1:], starts[-1] + 4096], strict=True):
            f.write(f"{a:x} {min(b - a, 1 << 20):x} {functions[a]}\n")
    print("ready", flush=True)
    t = time.perf_counter()
    k = 0
    while time.perf_counter() - t < seconds + 3.0:
        env.step(acts[k % 10])
        k += 1


def short(symbol: str) -> str:
    """A numba symbol's qualified Python name (``_ZN9amigo_gym5paths8clothoid9pose_flatB3v64...`` ->
    ``amigo_gym.paths.clothoid.pose_flat``); other symbols as they are."""
    if not symbol.startswith("_ZN"):
        return symbol
    parts, rest = [], symbol[3:]
    while (m := re.match(r"(\d+)", rest)) and rest[len(m.group(1)) :][:1] != "B":
        size = int(m.group(1))
        parts.append(rest[len(m.group(1)) : len(m.group(1)) + size])
        rest = rest[len(m.group(1)) + size :]
    if m:
        size = int(m.group(1))
        parts.append(rest[len(m.group(1)) : len(m.group(1)) + size])
    return ".".join(parts) or symbol


def main() -> None:
    config = sys.argv[1] if len(sys.argv) > 1 else "training"
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 4096
    seconds = float(sys.argv[3]) if len(sys.argv) > 3 else 20.0
    if os.environ.get("_PERF_PROFILE_CHILD"):
        child(config, n, seconds)
        return
    from amigo_gym.tools.machine import machine_line

    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "_PERF_PROFILE_CHILD": "1", "NUMBA_CACHE_DIR": tmp}
        proc = subprocess.Popen([sys.executable, __file__, config, str(n), str(seconds)], env=env,
                                stdout=subprocess.PIPE, text=True)  # fmt: skip
        assert proc.stdout is not None
        if proc.stdout.readline().strip() != "ready":
            raise SystemExit(f"the child process did not start (status {proc.wait()})")
        data = os.path.join(tmp, "perf.data")
        subprocess.run(["perf", "record", "-q", "-F", "2000", "-o", data, "-p", str(proc.pid), "--", "sleep",
                        str(seconds)], check=True)  # fmt: skip
        proc.wait()
        report = subprocess.run(["perf", "report", "-i", data, "--no-children", "--sort", "dso,symbol", "-g", "none",
                                 "--stdio"], capture_output=True, text=True, check=True).stdout  # fmt: skip
        os.remove(f"/tmp/perf-{proc.pid}.map")
    groups: dict[str, list[tuple[float, str]]] = {"compiled kernel": [], "C math library": [], "the rest": []}
    for line in report.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+(\S.*?)\s+\[[.k]\]\s+(\S+)", line)
        if not m:
            continue
        share, dso, symbol = float(m.group(1)), m.group(2), m.group(3)
        group = "compiled kernel" if dso.startswith("[JIT]") else "C math library" if "libm" in dso else "the rest"
        groups[group].append((share, short(symbol)))
    print(f"AmigoBot-v1 {config}, N = {n}, {seconds:.0f} s of steps after 300: share of samples")
    for group, rows in groups.items():
        merged: dict[str, float] = {}
        for share, name in rows:  # a function compiled into several kernels' libraries: one line
            merged[name] = merged.get(name, 0.0) + share
        print(f"  {group}: {sum(merged.values()):.1f} %")
        for name, share in sorted(merged.items(), key=lambda kv: -kv[1]):
            if share >= 0.3:
                print(f"    {share:5.1f} %  {name}")
    print(machine_line())


if __name__ == "__main__":
    main()
