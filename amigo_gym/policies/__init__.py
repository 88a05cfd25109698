"""Classical and learned controllers with stable-baselines3's ``predict`` interface: :class:`AnalyticPolicy`
(``AmigoBot-v0``'s baseline), :class:`AnalyticTrackingPolicy` (PI and feedforward, any path),
:class:`PurePursuitPolicy`, :class:`DelayCompensatedPolicy` (the analytic controller over the estimated actuation
delay), and learned ``AmigoBot-v1`` policies (:class:`FastPolicy`, :func:`load_pretrained`)."""

from __future__ import annotations

from amigo_gym.policies.analytic import AnalyticPolicy, analytic_body_velocity, analytic_wheel_rates
from amigo_gym.policies.compensator import DelayCompensatedPolicy
from amigo_gym.policies.learned import FastPolicy, load_pretrained
from amigo_gym.policies.tracking import AnalyticTrackingPolicy, PurePursuitPolicy

__all__ = [
    "AnalyticPolicy",
    "analytic_body_velocity",
    "analytic_wheel_rates",
    "AnalyticTrackingPolicy",
    "PurePursuitPolicy",
    "DelayCompensatedPolicy",
    "FastPolicy",
    "load_pretrained",
]
