"""Classical controllers with stable-baselines3's ``predict`` interface.

* :mod:`amigo_gym.policies.analytic`: the analytic inverse solution for ``AmigoBot-v0``.
* :mod:`amigo_gym.policies.tracking`: ``AmigoBot-v1``'s baselines: :class:`AnalyticTrackingPolicy` (the exact
  inverse solution on any path with integral action) and :class:`PurePursuitPolicy`.

May import the core (params, kinematics, paths, task, tracking, inverse) and numpy; never envs' internals,
training, analysis or the CLI.
"""

from __future__ import annotations

from amigo_gym.policies.analytic import AnalyticPolicy, analytic_body_velocity, analytic_wheel_rates
from amigo_gym.policies.tracking import AnalyticTrackingPolicy, PurePursuitPolicy

__all__ = [
    "AnalyticPolicy",
    "analytic_body_velocity",
    "analytic_wheel_rates",
    "AnalyticTrackingPolicy",
    "PurePursuitPolicy",
]
