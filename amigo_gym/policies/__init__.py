"""Classical and learned controllers with stable-baselines3's ``predict`` interface.

* :mod:`amigo_gym.policies.base`: the observation adapter :class:`~amigo_gym.policies.base.Fields` (either env's
  layout, read by field name) and the shared ``predict``.
* :mod:`amigo_gym.policies.analytic`: the analytic law (``analytic_tracking_command``) and :class:`AnalyticPolicy`
  (``AmigoBot-v0``'s baseline).
* :mod:`amigo_gym.policies.tracking`: :class:`AnalyticTrackingPolicy` (PI and feedforward, any path) and
  :class:`PurePursuitPolicy` (``AmigoBot-v1``'s preview points).
* :mod:`amigo_gym.policies.learned`: learned ``AmigoBot-v1`` policies in numpy and :func:`load_pretrained`.
"""

from __future__ import annotations

from amigo_gym.policies.analytic import AnalyticPolicy, analytic_body_velocity, analytic_wheel_rates
from amigo_gym.policies.learned import FastPolicy, load_pretrained
from amigo_gym.policies.tracking import AnalyticTrackingPolicy, PurePursuitPolicy

__all__ = [
    "AnalyticPolicy",
    "analytic_body_velocity",
    "analytic_wheel_rates",
    "AnalyticTrackingPolicy",
    "PurePursuitPolicy",
    "FastPolicy",
    "load_pretrained",
]
