"""The classical controllers on either env: one implementation, the observation read through the adapter
(amigo_gym/policies/base.py: :class:`~amigo_gym.policies.base.Fields`).

References: the error dynamics the laws impose in continuous time (docstrings of amigo_gym.policies.analytic and
amigo_gym.policies.tracking): ``e'' + k e' + k_i e = 0`` for the PI law (critically damped at ``k_i = k^2 / 4``:
``e(t) = (a + b t) exp(-k t / 2)``), ``e(t) = e0 exp(-k t)`` for v0's law; H's true cross-track error comes from
the environment's ``info``.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the envs)
from amigo_gym.envs.amigobot_v1 import AmigoBotV1Env
from amigo_gym.policies import AnalyticPolicy, AnalyticTrackingPolicy, PurePursuitPolicy, analytic_body_velocity
from amigo_gym.task import v1


def errors(env: Any, policy: Any, steps: int) -> np.ndarray:
    """|H's true cross-track error| [m] after each step of one episode (state threaded through)."""
    obs, _ = env.reset(seed=0)
    state, out = None, []
    for _ in range(steps):
        a, state = policy.predict(obs, state)
        obs, _, term, trunc, info = env.step(a)
        out.append(abs(float(info["cross_track_error"])))
        if term or trunc:
            break
    return np.array(out)


def test_pi_tracker_on_v0_decays_at_the_sampled_loops_slow_pole() -> None:
    """AnalyticTrackingPolicy reads v0's observation (no speed preview): the error decays at the rate of the slow
    pole of the sampled loop ``e_{n+1} = e_n + dt c_n``, ``c_n = -k e_n - k_i z_n``, ``z_n = z_{n-1} + dt e_n``."""
    env = gym.make("AmigoBot-v0")
    p = env.unwrapped.params  # type: ignore[attr-defined]
    k, ki, dt = 1.0, 0.25, p.dt
    loop = np.array([[1.0 - dt * k - dt * dt * ki, -dt * ki], [dt, 1.0]])  # (e_n, z_{n-1}) -> (e_{n+1}, z_n)
    rate = math.log(float(np.abs(np.linalg.eigvals(loop)).max())) / dt  # -0.408 1/s (continuous: -k/2 = -0.5)
    for feedforward in (True, False):
        e = errors(env, AnalyticTrackingPolicy(p, gain=k, integral_gain=ki, feedforward=feedforward), 300)
        i15, i30 = round(15.0 / dt) - 1, round(30.0 / dt) - 1
        assert math.log(e[i30] / e[i15]) / 15.0 == pytest.approx(rate, abs=0.03)
        assert e[-1] < 1e-4 * e[0]


def test_v0_law_on_v1_tracks_a_circle() -> None:
    """AnalyticPolicy reads v1's observation (its fields are a superset): H converges onto the circle."""
    env = AmigoBotV1Env(path="circle")
    e = errors(env, AnalyticPolicy(env.params), 200)
    assert e[0] > 1e-3 and e[-1] < 1e-6  # started off the path (the env's start offsets), ends on it


def test_v0_law_reads_v1_fields_by_name() -> None:
    """The same law on the same quantities laid out by v0 and by v1 gives the same command."""
    p1 = v1.make_tracking_params("test", None, path="circle")
    names = v1.obs_fields(p1)
    o1 = np.zeros(len(names))
    vals = {"cross_track_error": 0.4, "sin_heading_error": math.sin(0.3), "cos_heading_error": math.cos(0.3)}
    vals |= {"curvature": 0.2, "reference_speed": 0.5}
    for k, x in vals.items():
        o1[names.index(k)] = x
    p0 = v1.TrackingParams.v0(robot=p1.robot, dt=p1.dt, error_scale=p1.error_scale)
    from amigo_gym.task.v0 import obs_names

    n0 = obs_names(p0)
    o0 = np.zeros(len(n0))
    for k, x in vals.items():
        o0[n0.index(k)] = x
    e = 0.4 * p1.error_scale
    v_ref = 0.5 * p1.robot.max_speed
    want = (-3.0 * e - v_ref * math.sin(0.3)) / (p1.robot.l3 * math.cos(0.3))  # module docstring, law "A"
    for p, o in ((p0, o0), (p1, o1)):
        v, bd = analytic_body_velocity(o, p, 3.0)
        assert v == pytest.approx(v_ref, rel=1e-15) and bd == pytest.approx(want, rel=1e-12)


def test_bad_settings_and_layouts() -> None:
    p0, p1 = v1.TrackingParams.v0(), v1.make_tracking_params("test", None)
    with pytest.raises(
        ValueError,
        match=r"PurePursuitPolicy\.params must be TrackingParams with observation='v1', got observation='v0'",
    ):
        PurePursuitPolicy(p0)
    with pytest.raises(ValueError, match=r"AnalyticPolicy\.params must be TrackingParams, got dict"):
        AnalyticPolicy({})  # type: ignore[arg-type]
    obs1 = np.zeros(len(v1.obs_fields(p1)))
    with pytest.raises(ValueError, match=r"AnalyticTrackingPolicy: observation must have shape \(\d+,\)"):
        AnalyticTrackingPolicy(p0).predict(obs1)  # v1's observation given to a policy made for v0
    with pytest.raises(ValueError, match=r"AnalyticTrackingPolicy: state must have shape \(1, 1\)"):
        AnalyticTrackingPolicy(p1).predict(obs1, np.zeros((2, 1)))
