"""Paths for point H: the AmigoBot-v0 paths (:mod:`~amigo_gym.paths.classic`), the clothoid paths of AmigoBot-v1
(:mod:`~amigo_gym.paths.clothoid`), their families, batches, fits to points, paths of your own and their analysis.
"""

from __future__ import annotations

from amigo_gym.paths.analysis import Feasibility, LagProfile, Preview, feasibility, heading_lag_profile, preview
from amigo_gym.paths.batch import PathBatch
from amigo_gym.paths.classic import CirclePath, ClosestPoint, ManoeuvrePath, PathPoint, PathPose, Projection, wrap_angle
from amigo_gym.paths.clothoid import (
    STATUS_END,
    STATUS_INTERIOR,
    STATUS_START,
    STATUS_WINDOW,
    ClothoidPath,
    ClothoidSegment,
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
    "CirclePath",
    "ManoeuvrePath",
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
