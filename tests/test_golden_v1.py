"""AmigoBot-v1 reproduces its golden episodes (tests/data/golden_v1.npz, make_golden_v1.py).

The shipped v1 generalists and their claimed benchmark numbers rest on these numbers. Across machines
the comparison allows a few ulps of each quantity's scale (tests/golden_compare.py says why and how
much); a faster implementation must give the same bits as the reference on the same machine (the native
vector env against the single env in tests/test_vector_v1*.py, the compiled step against the numpy one
in tests/test_kernel_v1.py).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from golden_compare import mismatches

DATA = Path(__file__).resolve().parent / "data"
spec = importlib.util.spec_from_file_location("make_golden_v1", DATA / "make_golden_v1.py")
assert spec is not None and spec.loader is not None
golden = importlib.util.module_from_spec(spec)
spec.loader.exec_module(golden)
GOLDEN = np.load(DATA / "golden_v1.npz")


@pytest.mark.parametrize("name", list(golden.CONFIGS))
@pytest.mark.parametrize("seed", golden.SEEDS)
@pytest.mark.parametrize("kind", ["noisy", "analytic"])
def test_v1_reproduces_golden_episode(name: str, seed: int, kind: str) -> None:
    got = golden.episode(name, seed, kind)
    prefix = f"{name}/{seed}/{kind}/"
    keys = sorted(k[len(prefix) :] for k in GOLDEN.files if k.startswith(prefix))
    problems = mismatches(got, {key: GOLDEN[prefix + key] for key in keys})
    assert not problems, f"{prefix}: " + "; ".join(problems)
