"""Classical controllers with stable-baselines3's ``predict`` interface, each written once for both envs.

* :mod:`amigo_gym.policies.base`: the observation adapter :class:`~amigo_gym.policies.base.Fields` (v0's or v1's
  layout, read by field name) and the ``predict`` every policy shares.
* :mod:`amigo_gym.policies.analytic`: the analytic inverse solution (``analytic_tracking_command``, the one law)
  and :class:`AnalyticPolicy` (``AmigoBot-v0``'s baseline: proportional feedback, no state).
* :mod:`amigo_gym.policies.tracking`: ``AmigoBot-v1``'s baselines: :class:`AnalyticTrackingPolicy` (the same law on
  any path with integral action and mid-step feedforward; reads v0's observation too) and :class:`PurePursuitPolicy`
  (needs v1's preview points).
* :mod:`amigo_gym.policies.learned`: learned ``AmigoBot-v1`` policies in numpy (the fast PPO's models, the residual
  policy on the analytic controller) and :func:`load_pretrained` (a shipped zip, its manifest's sha256 checked).

May import the core (params, kinematics, paths, task, tracking, inverse) and numpy; never envs' internals,
training, analysis or the CLI.
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
