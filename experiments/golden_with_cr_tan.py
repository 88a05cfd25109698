"""The golden tests with the reference's ``tan`` replaced by the correctly rounded one of ``experiments/cr_tan.py``.

    AMIGO_GYM_KERNEL=numpy PYTHONPATH=. python experiments/golden_with_cr_tan.py [--perturb]

In this process only, :func:`amigo_gym.model.kinematics.col_tan` becomes ``cr_tan.tan_cr`` (``AMIGO_GYM_KERNEL=numpy``:
the reference route, which calls ``col_tan``; the compiled steps call numpy's ``tan`` loop and are not changed), then
``tests/test_golden.py``, ``tests/test_golden_v1.py`` and ``tests/test_golden_tolerance.py`` run (pytest's exit code is
this script's). The evidence of docs/architecture.md ("Speed": "A correctly rounded ``tan``") that the golden episodes
keep their tolerance with it. ``--perturb`` multiplies that ``tan`` by ``1 + 2**-50`` (a few ulp), to show that the
golden tests then fail (that the run can fail).
"""

from __future__ import annotations

import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))

if __name__ == "__main__":
    if os.environ.get("AMIGO_GYM_KERNEL") != "numpy":
        sys.exit("run with AMIGO_GYM_KERNEL=numpy (the reference route, which calls col_tan)")
    sys.path.insert(0, HERE)
    import cr_tan

    from amigo_gym.model import kinematics

    scale = 1.0 + 2.0**-50 if "--perturb" in sys.argv[1:] else 1.0
    kinematics.col_tan = lambda x: cr_tan.tan_cr(x) * scale  # type: ignore[assignment]
    root = os.path.dirname(HERE)
    names = ("test_golden.py", "test_golden_v1.py", "test_golden_tolerance.py")
    files = [os.path.join(root, "tests", f) for f in names]
    sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", "-p", "no:xdist", *files]))
