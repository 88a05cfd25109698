"""Old module names of amigo_gym 0.1, kept for one version: importing one warns and gives the moved module.

The layout of 0.2 (docs/architecture.md) grouped the root modules into subpackages: the robot model in
:mod:`amigo_gym.model`, the tasks in :mod:`amigo_gym.task`, the compiled step in :mod:`amigo_gym.sim`, the
command line in :mod:`amigo_gym.tools.cli`. ``import amigo_gym.kinematics`` (or unpickling an object saved under an
old name) still works: a finder on ``sys.meta_path`` maps the old name to the new module, the *same* module
object, and warns once with a :class:`DeprecationWarning` naming the new place. The names go in 0.3.

Standard library only; installed by ``amigo_gym/__init__.py``.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import types
import warnings
from collections.abc import Sequence

__all__ = ["MOVED", "install"]

#: old module name -> the module it moved to (0.2)
MOVED: dict[str, str] = {
    "amigo_gym.params": "amigo_gym.model.params",
    "amigo_gym.kinematics": "amigo_gym.model.kinematics",
    "amigo_gym.actuators": "amigo_gym.model.actuators",
    "amigo_gym.fresnel": "amigo_gym.model.fresnel",
    "amigo_gym.symbolic": "amigo_gym.tools.symbolic",
    "amigo_gym.inverse": "amigo_gym.task.inverse",
    "amigo_gym.randomization": "amigo_gym.model.randomization",
    "amigo_gym.tracking": "amigo_gym.task.v1",
    "amigo_gym._kernels": "amigo_gym.sim._kernels",
    "amigo_gym._kernels_v1": "amigo_gym.sim._kernels_v1",
    "amigo_gym.fast": "amigo_gym.sim.fast",
    "amigo_gym.fast_v1": "amigo_gym.sim.fast_v1",
    "amigo_gym.fast_v1_batch": "amigo_gym.sim.fast_v1_batch",
    "amigo_gym.cli_inverse": "amigo_gym.tools.cli.inverse",
    "amigo_gym.rendering": "amigo_gym.envs.rendering",
    "amigo_gym.envs.vector": "amigo_gym.envs.amigobot",
}


class _MovedFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: types.ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        new = MOVED[spec.name]
        warnings.warn(
            f"{spec.name} moved to {new} in amigo_gym 0.2; the old name goes in 0.3",
            DeprecationWarning,
            stacklevel=2,  # warnings skips the frames of importlib's bootstrap: this names the importer
        )
        return importlib.import_module(new)

    def exec_module(self, module: types.ModuleType) -> None:
        """Nothing to run: the module is the moved one, already imported."""


def install() -> None:
    """Put the finder on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.append(_MovedFinder())
