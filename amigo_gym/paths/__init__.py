"""Paths for point H: the AmigoBot-v0 paths (:mod:`.classic`) and the clothoid paths of AmigoBot-v1.

* :mod:`amigo_gym.paths.classic`: :class:`CirclePath` and :class:`ManoeuvrePath` of AmigoBot-v0, unchanged
  (the env's behaviour is bit for bit that of the former module ``amigo_gym/paths.py``).

This package may import numpy, :mod:`amigo_gym.params`, :mod:`amigo_gym.kinematics` and
:mod:`amigo_gym.fresnel` only.
"""

from __future__ import annotations

from amigo_gym.paths.classic import (
    CirclePath,
    ClosestPoint,
    ManoeuvrePath,
    Path,
    Projection,
    make_path,
    wrap_angle,
)

__all__ = ["Projection", "ClosestPoint", "Path", "CirclePath", "ManoeuvrePath", "make_path", "wrap_angle"]
