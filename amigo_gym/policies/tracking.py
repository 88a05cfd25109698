r"""Classical path trackers for ``AmigoBot-v1``: the exact inverse solution with integral action, and pure pursuit.

Both read the observation by field name (as :mod:`amigo_gym.policies.analytic`; ``v_ahead`` the reference 1 s
later; preview points ``(x_d, y_d)`` [m] in the frame of A).

:class:`AnalyticTrackingPolicy`: H's normal speed ``c = -k e - k_i z``, ``z = int e dt`` (``k_i |z| <=
integral_limit``), ``v = v_ref``: ``e'' + k e' + k_i e = 0`` on any path; defaults ``k = 1 1/s``, ``k_i = k^2/4``
(critically damped); setpoints scaled into ``+-w_max`` keeping ``omega / v`` (:func:`limit_wheel_rates`). A held
command with the ramp ``a_w`` [rad/s^2] adds per step at most ``delta = l3 Wdot dt^2 (1/2 + Wdot / (2 a_w))``,
``Wdot = v^2 K / (1 - (l3 kappa_max)^2)^2`` (``K = max |dkappa/ds|``): ``|e| <= ||h||_1 delta``, ``h`` the loop's
impulse response (``zoh_error_bound`` in tests/test_policies_v1.py).

:class:`PurePursuitPolicy` (Coulter 1992, CMU-RI-TR-92-01): A drives on the arc through the goal point
``(x_L, y_L)`` (the preview point ``d`` ahead) tangent to its heading,

.. math:: \kappa = \frac{2 y_L}{L^2}, \qquad L^2 = x_L^2 + y_L^2, \qquad v = v_{ref}, \qquad \omega = v\kappa;

on a circle of radius ``R`` H runs outside it: ``e_ss = -direction (sqrt(R^2 + l3^2) - R)``."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.actuators import wheel_rates_columns
from amigo_gym.model.params import check_real
from amigo_gym.policies.analytic import analytic_tracking_command
from amigo_gym.policies.base import Fields, Policy
from amigo_gym.task.v1 import SPEED_LOOKAHEAD, TrackingParams

Array = NDArray[np.float64]

#: default proportional gain ``k`` on H's cross-track error [1/s]
DEFAULT_TRACKING_GAIN = 1.0
#: default clamp of the integral term ``k_i |z|`` [m/s]
DEFAULT_INTEGRAL_LIMIT = 0.1
#: default pure-pursuit goal distance, arc length ahead of H's closest point [m]
DEFAULT_LOOKAHEAD = 0.5


def limit_wheel_rates(v: ArrayLike, omega: ArrayLike, params: TrackingParams) -> Array:
    """The action ``(..., 2)`` in [-1, 1] for speeds ``v`` [m/s] and turn rates ``omega`` [rad/s]: the wheel rates
    ``(v +- l1 omega) / r_i`` divided by ``max(1, |w1| / w_max, |w2| / w_max)``, then by ``w_max``."""
    r = params.robot
    w1, w2 = wheel_rates_columns(np.asarray(v, dtype=np.float64), np.asarray(omega, dtype=np.float64), r)
    w_max = r.max_wheel_rate
    m = np.maximum(1.0, np.maximum(np.abs(w1), np.abs(w2)) / w_max)
    out: Array = np.stack((w1 / m, w2 / m), axis=-1) / w_max
    return np.clip(out, -1.0, 1.0)


class AnalyticTrackingPolicy(Policy):
    """The exact inverse solution with PI feedback on H (module docstring), for AmigoBot-v0's or v1's
    ``TrackingParams``: ``gain`` ``k`` [1/s] in (0, 1/dt], ``integral_gain`` ``k_i`` [1/s^2] >= 0 (default ``k^2/4``),
    ``integral_limit`` [m/s] > 0, ``feedforward``: of the mid-step turn rate and the reference speed.

    ``predict`` keeps the integral ``z`` [m s] per batch row as its state ``(N, 1)``, reset where ``episode_start``."""

    def __init__(
        self,
        params: TrackingParams,
        gain: float = DEFAULT_TRACKING_GAIN,
        integral_gain: float | None = None,
        integral_limit: float = DEFAULT_INTEGRAL_LIMIT,
        feedforward: bool = True,
    ) -> None:
        o = "AnalyticTrackingPolicy"
        self._fields, self.params = Fields(o, params), params
        self.gain = check_real(o, "gain", gain, 0.0, 1.0 / params.dt, low_open=True)
        ki = self.gain * self.gain / 4.0 if integral_gain is None else integral_gain
        self.integral_gain = check_real(o, "integral_gain", ki, 0.0, 1.0 / params.dt**2)
        self.integral_limit = check_real(o, "integral_limit", integral_limit, 0.0, 10.0, low_open=True)
        self.feedforward = bool(feedforward)

    name = "analytic_v1"

    def command(self, obs: Array, z: Array) -> tuple[Array, Array, Array]:
        """``(v [m/s], omega [rad/s], z_new [m s])`` for observations ``(N, d)`` and integrals ``(N,)``:
        ``z_new = clip(z + dt e, +-integral_limit / k_i)``, ``c = -k e - k_i z_new``. With ``feedforward``, ``v`` is
        the reference at the step's end: ``min(v_ref + profile_accel dt, v_ahead)`` when rising, else the chord
        ``v_ref + (v_ahead - v_ref) dt / 1 s``."""
        p, r, d = self.params, self.params.robot, self._fields
        e = d(obs, "cross_track_error") * p.error_scale
        sp, cp = d(obs, "sin_heading_error"), d(obs, "cos_heading_error")
        kappa = d(obs, "curvature") / r.l3
        v_ref = d(obs, "reference_speed") * r.max_speed
        if self.feedforward and "reference_speed_ahead" in d.index:
            assert isinstance(p, TrackingParams)
            v_ahead = d(obs, "reference_speed_ahead") * r.max_speed
            rise = np.minimum(v_ref + p.profile_accel * p.dt, v_ahead)
            chord = v_ref + (v_ahead - v_ref) * (p.dt / SPEED_LOOKAHEAD)
            v_ref = np.maximum(np.where(v_ahead > v_ref, rise, chord), 0.0)
        z_max = math.inf if self.integral_gain == 0.0 else self.integral_limit / self.integral_gain
        z_new = np.clip(z + p.dt * e, -z_max, z_max)
        c = -self.gain * e - self.integral_gain * z_new
        v, om = analytic_tracking_command(e, sp, cp, kappa, v_ref, c, r.l3, p.dt, self.feedforward)
        return v, om, z_new

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, Array]:
        z, starts = self._rows(obs.shape[0], state, episode_start, 1)
        v, om, z_new = self.command(obs, np.where(starts, 0.0, z[:, 0]))
        return limit_wheel_rates(v, om, self.params), self._keep(state, z_new[:, None])

    def __repr__(self) -> str:
        return (
            f"AnalyticTrackingPolicy(gain={self.gain:g}, integral_gain={self.integral_gain:g}, "
            f"integral_limit={self.integral_limit:g}, feedforward={self.feedforward})"
        )


class PurePursuitPolicy(Policy):
    """Pure pursuit (Coulter 1992) towards the preview point ``lookahead`` [m] ahead (one of ``params.preview``,
    default the nearest to 0.5), or with ``lookahead_time`` [s] the one nearest ``lookahead_time v_ref``; from A
    (``origin="axle"``) or H (``"H"``: ``(x_L - l3, y_L)``); the turn rate clipped to ``max_turn_rate`` [rad/s]
    when given. ``predict`` is stateless."""

    max_turn_rate: float | None
    lookahead_time: float | None

    def __init__(
        self,
        params: TrackingParams,
        lookahead: float | None = None,
        *,
        origin: str = "axle",
        max_turn_rate: float | None = None,
        lookahead_time: float | None = None,
    ) -> None:
        o = "PurePursuitPolicy"
        self._fields, self.params = Fields(o, params, v1_only=True), params
        prev = params.preview
        if lookahead is None:
            lookahead = min(prev, key=lambda d: abs(d - DEFAULT_LOOKAHEAD))
        la = check_real(o, "lookahead", lookahead, 0.0, 5.0, low_open=True)
        if la not in prev:
            raise ValueError(f"{o}.lookahead must be one of the preview distances {list(prev)} m, got {lookahead!r}")
        if origin not in ("axle", "H"):
            raise ValueError(f"{o}.origin must be 'axle' or 'H', got {origin!r}")
        self.origin = origin
        opt = {"max_turn_rate": (max_turn_rate, 1e3), "lookahead_time": (lookahead_time, 60.0)}
        for k, (v, top) in opt.items():
            setattr(self, k, None if v is None else check_real(o, k, v, 0.0, top, low_open=True))
        self.lookahead = la
        self._prev = np.asarray(prev, dtype=np.float64)
        self._fixed = list(prev).index(la)
        self._ix, self._iy = (np.array([self._fields.index[f"preview_{c}_{d:g}m"] for d in prev]) for c in "xy")

    @classmethod
    def textbook(cls, params: TrackingParams) -> PurePursuitPolicy:
        """The preset of Cao et al., Sensors 24(2) 561 (2024), Sec. 3.1: the goal 0.2 m ahead (in
        ``params.preview``), pursued from A, the turn rate clipped to 1 rad/s."""
        return cls(params, 0.2, origin="axle", max_turn_rate=1.0)

    name = "pure_pursuit"

    def command(self, obs: Array) -> tuple[Array, Array]:
        """``(v [m/s], omega [rad/s])`` for observations ``(N, d)`` (``L`` floored at 1 mm)."""
        p = self.params
        v_ref = self._fields(obs, "reference_speed") * p.robot.max_speed
        if self.lookahead_time is None:
            x, y = obs[:, self._ix[self._fixed]], obs[:, self._iy[self._fixed]]
        else:  # per row the preview point nearest to lookahead_time * v_ref ahead
            pick = np.argmin(np.abs(self._prev[None, :] - (self.lookahead_time * v_ref)[:, None]), axis=1)
            rows = np.arange(len(obs))
            x, y = obs[rows, self._ix[pick]], obs[rows, self._iy[pick]]
        x, y = x * p.preview_scale, y * p.preview_scale
        if self.origin == "H":
            x = x - p.robot.l3
        om = v_ref * (2.0 * y / np.maximum(x * x + y * y, 1e-6))
        if self.max_turn_rate is not None:
            om = np.clip(om, -self.max_turn_rate, self.max_turn_rate)
        return v_ref, om

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, Any]:
        v, om = self.command(obs)
        return limit_wheel_rates(v, om, self.params), state

    def __repr__(self) -> str:
        extra = "" if self.origin == "axle" else f", origin={self.origin!r}"
        if self.max_turn_rate is not None:
            extra += f", max_turn_rate={self.max_turn_rate:g}"
        if self.lookahead_time is not None:
            extra += f", lookahead_time={self.lookahead_time:g}"
        return f"PurePursuitPolicy(lookahead={self.lookahead:g}{extra})"
