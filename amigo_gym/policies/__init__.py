"""Classical controllers with stable-baselines3's ``predict`` interface.

May import the core (params, kinematics, paths, task, inverse) and numpy; never envs' internals,
training, analysis or the CLI.
"""

from __future__ import annotations

from amigo_gym.policies.analytic import AnalyticPolicy, analytic_body_velocity, analytic_wheel_rates

__all__ = ["AnalyticPolicy", "analytic_body_velocity", "analytic_wheel_rates"]
