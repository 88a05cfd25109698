"""Paths for point H: the AmigoBot-v0 paths and the clothoid path families of AmigoBot-v1.

* :mod:`amigo_gym.paths.classic`: :class:`CirclePath` and :class:`ManoeuvrePath` of AmigoBot-v0, unchanged
  (the env's behaviour is bit for bit that of the former module ``amigo_gym/paths.py``).
* :mod:`amigo_gym.paths.clothoid`: :class:`ClothoidPath`, exact clothoid geometry and a projection that keeps
  progress (:meth:`ClothoidPath.locate`); :class:`PathSpec`, what AmigoBot-v1 needs of a path.
* :mod:`amigo_gym.paths.families`: the path families (circle, manoeuvre, figure-8, lane change, random) and
  their registry :data:`FAMILIES`.
* :mod:`amigo_gym.paths.batch`: :class:`PathBatch`, ``N`` paths (one per sub-environment) behind the column
  interface of one path on ``(N,)`` columns, row ``i`` bit-identical to path ``i``.
* :mod:`amigo_gym.paths.points`: :func:`from_points` and :func:`from_file`, a :class:`ClothoidPath` with
  continuous curvature fitted to points of your own (an array, a CSV or a JSON file).
* :mod:`amigo_gym.paths.user`: the duck-typed protocol of a path object of your own (``length``, ``closed``,
  ``pose_columns``), :func:`check_path` and :class:`UserPath`, which checks it at ``gym.make`` and every result.
* :mod:`amigo_gym.paths.analysis`: :func:`preview` (path ahead in the robot frame) and :func:`feasibility`
  (wheel rates and accelerations the exact inverse solution needs).

This package may import numpy (and, in :mod:`amigo_gym.paths.points`, the standard library's csv and json),
:mod:`amigo_gym.model.params`, :mod:`amigo_gym.model.kinematics` and
:mod:`amigo_gym.model.fresnel` only.
"""

from __future__ import annotations

from amigo_gym.paths.analysis import Feasibility, LagProfile, Preview, feasibility, heading_lag_profile, preview
from amigo_gym.paths.batch import PathBatch
from amigo_gym.paths.classic import (
    CirclePath,
    ClosestPoint,
    ManoeuvrePath,
    Path,
    Projection,
    make_path,
    wrap_angle,
)
from amigo_gym.paths.clothoid import (
    STATUS_END,
    STATUS_INTERIOR,
    STATUS_START,
    STATUS_WINDOW,
    ClothoidPath,
    ClothoidSegment,
    PathPoint,
    PathPose,
    PathSpec,
)
from amigo_gym.paths.families import (
    FAMILIES,
    Family,
    ParamRange,
    circle,
    figure8,
    lane_change,
    make_family_path,
    manoeuvre,
    random_path,
)
from amigo_gym.paths.points import PointsFit, fit_points, from_file, from_points, load_points
from amigo_gym.paths.user import UserPath, check_path

__all__ = [
    "Projection",
    "ClosestPoint",
    "Path",
    "CirclePath",
    "ManoeuvrePath",
    "make_path",
    "wrap_angle",
    "STATUS_END",
    "STATUS_INTERIOR",
    "STATUS_START",
    "STATUS_WINDOW",
    "ClothoidPath",
    "ClothoidSegment",
    "PathPoint",
    "PathPose",
    "PathSpec",
    "PathBatch",
    "FAMILIES",
    "Family",
    "ParamRange",
    "circle",
    "figure8",
    "lane_change",
    "make_family_path",
    "manoeuvre",
    "random_path",
    "Feasibility",
    "LagProfile",
    "Preview",
    "feasibility",
    "heading_lag_profile",
    "preview",
    "PointsFit",
    "fit_points",
    "from_points",
    "from_file",
    "load_points",
    "UserPath",
    "check_path",
]
