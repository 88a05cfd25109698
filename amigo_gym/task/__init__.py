"""The tasks: where H must go, what the agent sees and what it is rewarded for, as pure batched functions.

``v0``       AmigoBot-v0's task: the ideal robot on the paper's circle (or manoeuvre), its observation and reward
``v1``       AmigoBot-v1's task: the real robot on any path (:mod:`amigo_gym.paths`), actuators, noise, delays
``inverse``  the analytic inverse solution: the wheel angles and rates that drive H along a circle or manoeuvre

Both import :mod:`amigo_gym.model` and :mod:`amigo_gym.paths`; the envs, policies and the compiled step
(:mod:`amigo_gym.sim`) import them.

The names of ``amigo_gym.task`` of 0.1 (now :mod:`amigo_gym.task.v0`) are still found here, with a
:class:`DeprecationWarning`, until 0.3; those removed in 0.2 (:data:`amigo_gym.task.v0.REMOVED`) raise an
``AttributeError`` naming their replacement.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any


def __getattr__(name: str) -> Any:
    if name.startswith("__"):
        raise AttributeError(name)
    v0 = importlib.import_module("amigo_gym.task.v0")
    if name in v0.REMOVED:  # removed, not moved: v0's AttributeError names the replacement
        return getattr(v0, name)
    if not hasattr(v0, name):
        raise AttributeError(f"module 'amigo_gym.task' has no attribute {name!r}")
    warnings.warn(
        f"amigo_gym.task.{name} moved to amigo_gym.task.v0.{name} in amigo_gym 0.2; the old name goes in 0.3",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(v0, name)
