"""The reward's exponentials: AmigoBot-v0's third pass with them (issue 19, docs/architecture.md, "Speed").

    cd <tree> && PYTHONPATH=. NUMBA_CACHE_DIR=<own> python experiments/exp_speed.py <label>

Least ``time.thread_time_ns`` of 3000 calls, per robot at N = 4096: the exponentials of the ``(N, 3)`` block and the
third pass (:func:`amigo_gym.sim._kernels.finish`; on a tree whose ``finish`` takes numpy's ``exp`` first, that
``np.exp`` call included), less the copy of the arguments; then ``kinematics.col_exp`` of a float and of a column of
4096 (``timeit``). Run it on two trees alternately, with this CPU's code and with AVX2 code
(``NPY_DISABLE_CPU_FEATURES="X86_V4 AVX512_ICL AVX512_SPR" NUMBA_CPU_NAME=haswell NUMBA_CPU_FEATURES=""``: the name
alone keeps the host's AVX-512 features), to compare them.
"""

from __future__ import annotations

import inspect
import sys
import time
import timeit

import numpy as np

from amigo_gym.model import kinematics
from amigo_gym.model.params import EnvParams
from amigo_gym.paths import make_path
from amigo_gym.sim import fast
from amigo_gym.task import v0 as task


def main() -> None:
    k, p, n = fast.kernels(), EnvParams(), 4096
    ws = fast.workspace(task.task_constants(p), make_path(p), n)
    args = -np.random.default_rng(0).exponential(1.0, (n, 3))
    reward, record = np.zeros(n), np.zeros((n, 16))
    numpy_first = "col_exp" not in inspect.getsource(k.finish.py_func)  # the exponentials taken by np.exp before

    def copy() -> None:
        ws.exps[:] = args

    def run() -> None:
        ws.exps[:] = args
        if numpy_first:
            np.exp(ws.exps, out=ws.exps)
        k.finish(ws.consts, reward, record, ws.exps)

    def least(f: object) -> int:
        out = []
        for _ in range(3000):
            t = time.thread_time_ns()
            f()  # type: ignore[operator]
            out.append(time.thread_time_ns() - t)
        return min(out)

    run()
    label = sys.argv[1] if sys.argv[1:] else ""
    per_robot = (least(run) - least(copy)) / n
    x, xs = -0.37, args[:, 0].copy()
    one = min(timeit.repeat(lambda: kinematics.col_exp(x), number=20000, repeat=7, timer=time.thread_time)) / 20000
    col = min(timeit.repeat(lambda: kinematics.col_exp(xs), number=200, repeat=7, timer=time.thread_time)) / 200
    print(f"{label} exponentials and third pass, N={n}: {per_robot:.2f} ns/robot; col_exp of a float "
          f"{one * 1e6:.3f} us, of a column of {n} {col * 1e6:.1f} us")  # fmt: skip


if __name__ == "__main__":
    main()
