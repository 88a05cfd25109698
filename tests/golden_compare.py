"""The comparison of golden episodes (tests/test_golden.py, tests/test_golden_v1.py): the stated tolerance.

The golden files (tests/data/golden_v0.npz, golden_v1.npz) keep AmigoBot-v0's and AmigoBot-v1's behaviour. They
are compared within a tolerance, not bit for bit: the same closed-form physics runs on several routes (Python
floats and numpy columns, numba's compiled step) whose transcendental functions (``sin``, ``cos``, ``tan``,
``exp``) are not the same code (numpy's SIMD loops, chosen at run time per CPU, or the C library's), so results
differ by ulps that the feedback of a closed-loop episode can grow. Bits are equal only for determinism: one
install, one seed, one route (``tests/test_env.py::test_determinism_under_seed``,
``tests/test_env_v1.py``, the serial and parallel loops and pickled copies of ``tests/test_vector_v1_kernel.py``).

The rule, per recorded array ``want`` and its counterpart ``got``:

- same dtype and shape (an episode that ends at another step fails), booleans and integers exact;
- floats: ``|got - want| <= max(RTOL * scale, 2 spacing(scale))`` elementwise, where ``scale`` is the largest
  magnitude of that quantity in the episode (per column for arrays of several columns, e.g. ``x``, ``y`` and
  ``beta`` of a pose each have their own) and ``spacing`` the distance to the next number of the array's dtype
  (two float32 ulp for v0's float32 observation, whose rounding may fall either side).
- A quantity that is a small difference of large ones takes the scale of what it is computed from
  (:data:`DERIVED_SCALE`: the cross-track error is a difference of positions of H).

``RTOL = 1e-9``: this machine's episodes differ from the recordings by at most 1.5e-16 of the scale for v0 and
4.2e-14 for v1 (its cross-track error) on an AMD EPYC (AVX-512), 2026-12-01 (``python tests/golden_compare.py``
prints the figures), so the bound leaves over four decades for other CPUs and libraries; and 1e-9 of a position is
a nanometre, of a reward a billionth of its range, far below
anything a policy, a benchmark interval or a figure can see. A relative change of 1e-7 of a physical or reward
constant moves the episodes beyond it (tests/test_golden_tolerance.py).

May import numpy only (loaded by the tests as a plain module).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

#: tolerance relative to the quantity's scale
RTOL = 1e-9
#: the least tolerance, in units in the last place of the scale (float32 roundings)
ULPS = 2

#: quantity -> the quantity whose magnitude is its scale as well (a difference of larger numbers)
DERIVED_SCALE = {"cross_track_error": "h_position"}


def _scale(want: np.ndarray) -> np.ndarray:
    """Largest magnitude of ``want``: a scalar for one column, per column (last axis) otherwise."""
    a = np.abs(want)
    if a.size == 0:
        return np.zeros(a.shape[1:] if a.ndim > 1 else ())
    return a.max(axis=tuple(range(a.ndim - 1))) if a.ndim > 1 else a.max()


def mismatch(name: str, got: object, want: np.ndarray, rtol: float = RTOL, scale: float | None = None) -> str | None:
    """``None`` if ``got`` equals ``want`` within the rule of this module, else one line saying where.

    Args:
        name: the quantity's name, for the message.
        got: the value computed now (array-like).
        want: the recorded array.
        rtol: tolerance relative to the scale.
        scale: a lower bound of the scale (see :data:`DERIVED_SCALE`), or ``None``.
    """
    g = np.asarray(got)
    if g.dtype != want.dtype:
        return f"{name}: dtype {g.dtype}, recorded {want.dtype}"
    if g.shape != want.shape:
        return f"{name}: shape {g.shape}, recorded {want.shape}"
    if want.dtype.kind not in "fc":
        if not np.array_equal(g, want):
            bad = np.argwhere(g != want)[0]
            return f"{name}: differs at {tuple(int(i) for i in bad)}: {g[tuple(bad)]!r}, recorded {want[tuple(bad)]!r}"
        return None
    if not np.array_equal(np.isnan(g), np.isnan(want)):
        return f"{name}: NaN where the recording has none (or the reverse)"
    s = _scale(np.nan_to_num(want))
    if scale is not None:
        s = np.maximum(s, scale)
    tol = np.maximum(rtol * s, ULPS * np.spacing(np.asarray(s, dtype=want.dtype)).astype(np.float64))
    err = np.abs(np.nan_to_num(g).astype(np.float64) - np.nan_to_num(want).astype(np.float64))
    ratio = err / np.broadcast_to(tol, err.shape) if err.size else err
    if err.size and np.any(err > tol):
        i = np.unravel_index(int(np.argmax(ratio)), err.shape)
        at_scale = float(s if np.ndim(s) == 0 else s[i[-1]])
        return (
            f"{name}: {err[i]:.3g} off at {tuple(int(k) for k in i)} ({g[i]!r}, recorded {want[i]!r}), "
            f"{err[i] / at_scale if at_scale else err[i]:.3g} of the scale {at_scale:.3g} (tolerance {rtol:g})"
        )
    return None


def mismatches(got: Mapping[str, object], want: Mapping[str, np.ndarray], rtol: float = RTOL) -> list[str]:
    """Every mismatch between two episodes (dicts name -> array with the same names); [] if they agree."""
    out = []
    if sorted(got) != sorted(want):
        out.append(f"names differ: {sorted(got)} against the recorded {sorted(want)}")
    for key in sorted(set(got) & set(want)):
        base = DERIVED_SCALE.get(key)
        scale = float(np.abs(want[base]).max()) if base in want and want[base].size else None
        line = mismatch(key, got[key], want[key], rtol, scale)
        if line:
            out.append(line)
    return out


def relative_distance(got: Mapping[str, object], want: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The largest error of each quantity relative to its scale (inf if shape or an exact value differs)."""
    out = {}
    for key in sorted(set(got) & set(want)):
        g, w = np.asarray(got[key]), want[key]
        if g.shape != w.shape or w.dtype.kind not in "fc" or w.size == 0:
            out[key] = 0.0 if g.shape == w.shape and np.array_equal(g, w) else float("inf")
            continue
        s = _scale(w)
        base = DERIVED_SCALE.get(key)
        if base in want:
            s = np.maximum(s, np.abs(want[base]).max())
        tol = np.broadcast_to(np.asarray(s, dtype=np.float64), w.shape)
        err = np.abs(g.astype(np.float64) - w.astype(np.float64))
        ratio = np.where(err == 0, 0.0, np.divide(err, tol, out=np.full(err.shape, np.inf), where=tol > 0))
        out[key] = float(ratio.max())
    return out


def main() -> None:
    """Print how far this machine's episodes are from the recordings, per quantity, relative to its scale.

    ``python tests/golden_compare.py`` from the repository root (with e.g. ``NPY_DISABLE_CPU_FEATURES``
    set to see another dispatch level); the figures in docs/development.md come from it.
    """
    import sys
    import tempfile
    from pathlib import Path

    data = Path(__file__).resolve().parent / "data"
    sys.path.insert(0, str(data))
    import make_golden
    import make_golden_v1

    with tempfile.TemporaryDirectory() as tmp:
        for recorder, name in ((make_golden, "golden_v0.npz"), (make_golden_v1, "golden_v1.npz")):
            recorder.record(Path(tmp) / name)
            with np.load(Path(tmp) / name) as new, np.load(data / name) as old:
                worst: dict[str, float] = {}
                prefixes = sorted({k.rsplit("/", 1)[0] for k in old.files})
                for p in prefixes:
                    keys = [k for k in old.files if k.startswith(p + "/")]
                    d = relative_distance({k: new[k] for k in keys}, {k: old[k] for k in keys})
                    for k, v in d.items():
                        q = k.rsplit("/", 1)[1]
                        worst[q] = max(worst.get(q, 0.0), v)
            print(f"{name}: largest error relative to the quantity's scale (tolerance {RTOL:g})")
            for q, v in sorted(worst.items()):
                print(f"  {q:20s} {v:g}")


if __name__ == "__main__":
    main()
