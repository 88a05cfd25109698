r"""Classical path trackers for ``AmigoBot-v1``: the exact inverse solution with integral action, and pure pursuit.

Both read the observation by field name (:class:`amigo_gym.policies.base.Fields`) and the nominal robot of
:class:`~amigo_gym.task.v1.TrackingParams` (:class:`AnalyticTrackingPolicy` also ``AmigoBot-v0``'s
:class:`~amigo_gym.model.params.EnvParams`), with stable-baselines3's ``predict`` for ``(d,)`` or ``(N, d)``.
Fields: ``e``, ``psi``, ``kappa``, ``v_ref`` as in :mod:`amigo_gym.policies.analytic` (which derives
``edot = v sin psi + l3 omega cos psi``), ``v_ahead = reference_speed_ahead * v_max`` (the reference speed 1 s
later) and the preview points ``(x_d, y_d)`` [m] in the robot frame (origin A, x along the heading).

Analytic law (:func:`analytic_tracking_command`, derived in :mod:`amigo_gym.policies.analytic`)
------------------------------------------------------------------------------------------------
H's normal speed ``c = -k e - k_i z``, ``z = int e dt``, and ``v = v_ref``: ``e'' + k e' + k_i e = 0`` on every
path and speed profile. Defaults ``k = 1 1/s``, ``k_i = k^2/4`` (critically damped); a larger ``k`` may enter a
limit cycle with the firmware's turn-rate ramp (``a_w = 0.87 rad/s^2``) and the ``"hard"`` preset's delays.
Anti-windup: ``k_i |z| <= integral_limit``. The wheel-rate setpoints are scaled into ``+-w_max`` keeping
``omega / v`` (:func:`limit_wheel_rates`). Feedforward (``feedforward=True``): the law at the mid-step heading
error, and ``v`` the reference predicted for the step's end (:meth:`AnalyticTrackingPolicy.next_reference_speed`).

Error bound with a held command (:func:`zoh_error_bound`)
---------------------------------------------------------
With ``K = max |dkappa/ds|``, the exact turn rate changes at most at
``Wdot = v^2 K / (1 - (l3 kappa_max)^2)^2``. Holding the command over ``dt`` and the firmware's ramp add at most
``delta = l3 Wdot dt^2 (1/2 + Wdot / (2 a_w))`` per step to ``e_{k+1} = e_k + dt c_k + delta_k``, so
``|e| <= ||h||_1 delta`` with ``h`` the loop's impulse response (:func:`closed_loop_impulse_response`;
``||h||_1 ~ 4 / (e k dt)``). ``tests/test_policies_v1.py`` checks the bound on the path families.

Pure pursuit (:class:`PurePursuitPolicy`)
-----------------------------------------
Coulter (1992), CMU-RI-TR-92-01: A drives on the arc through the goal point ``(x_L, y_L)`` (robot frame)
tangent to its heading,

.. math:: \kappa = \frac{2 y_L}{L^2}, \qquad L^2 = x_L^2 + y_L^2, \qquad v = v_{ref}, \qquad \omega = v\kappa,

the goal being the preview point at arc length ``d`` ahead of H's closest point. On a circle of radius ``R``
A tracks the circle and H runs outside it, for every look-ahead:

.. math:: e_{ss} = -d\,\bigl(\sqrt{R^2 + l_3^2} - R\bigr) \approx -d\,\frac{l_3^2}{2R}, \qquad d = \mathrm{direction}.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.actuators import wheel_rates_columns
from amigo_gym.model.params import check_range
from amigo_gym.policies.analytic import analytic_tracking_command
from amigo_gym.policies.base import Fields, Params, Policy
from amigo_gym.task.v1 import SPEED_LOOKAHEAD, TrackingParams

Array = NDArray[np.float64]

#: default proportional gain ``k`` on H's cross-track error [1/s] (module docstring: "Gains")
DEFAULT_TRACKING_GAIN = 1.0
#: default clamp of the integral term ``k_i |z|`` [m/s]
DEFAULT_INTEGRAL_LIMIT = 0.1
#: default pure-pursuit goal distance, arc length ahead of H's closest point [m] (one of the preview distances)
DEFAULT_LOOKAHEAD = 0.5


def limit_wheel_rates(v: ArrayLike, omega: ArrayLike, params: Params) -> Array:
    r"""Normalised wheel-rate setpoints ``(..., 2)`` for speeds ``v`` [m/s] and turn rates ``omega`` [rad/s].

    ``w1 = (v + l1 omega) / r1``, ``w2 = (v - l1 omega) / r2`` (nominal robot), both divided by
    ``max(1, |w1| / w_max, |w2| / w_max)`` (within ``+-w_max``, the ratio ``omega / v`` kept), then by ``w_max``:
    the action in ``[-1, 1]``.
    """
    r = params.robot
    v_a = np.asarray(v, dtype=np.float64)
    om = np.asarray(omega, dtype=np.float64)
    w1, w2 = wheel_rates_columns(v_a, om, r)  # the firmware's inverse, one home: amigo_gym.model.actuators
    w_max = r.max_wheel_rate
    m = np.maximum(1.0, np.maximum(np.abs(w1), np.abs(w2)) / w_max)
    out: Array = np.stack((w1 / m, w2 / m), axis=-1) / w_max
    return np.clip(out, -1.0, 1.0)


def pure_pursuit_command(x_l: ArrayLike, y_l: ArrayLike, v_ref: ArrayLike) -> tuple[Array, Array]:
    """Pure pursuit (module docstring) towards the goal point ``(x_L, y_L)`` [m] in the frame of A (``L`` floored
    at 1 mm) at the speed ``v_ref`` [m/s] of A: ``(v [m/s], omega [rad/s])``, columns ``(N,)``."""
    x = np.asarray(x_l, dtype=np.float64)
    y = np.asarray(y_l, dtype=np.float64)
    v = np.asarray(v_ref, dtype=np.float64)
    l2 = np.maximum(x * x + y * y, 1e-6)
    kappa = 2.0 * y / l2
    return v + 0.0 * kappa, v * kappa


def closed_loop_impulse_response(gain: float, integral_gain: float, dt: float, steps: int = 20000) -> Array:
    """Response ``h_n`` [m per m] of the sampled error loop to one disturbance ``delta_0 = 1`` m:
    ``z_k = z_{k-1} + dt e_k``, ``c_k = -k e_k - k_i z_k``, ``e_{k+1} = e_k + dt c_k + delta_k``; ``h_0 = 0``,
    ``h_1 = 1``. Returns ``(steps,)``."""
    h = np.zeros(steps)
    e, z = 0.0, 0.0
    for n in range(1, steps):
        z += dt * e
        c = -gain * e - integral_gain * z
        e = e + dt * c + (1.0 if n == 1 else 0.0)
        h[n] = e
    return h


def zoh_error_bound(
    params: TrackingParams,
    speed: float,
    max_curvature: float,
    max_curvature_rate: float,
    gain: float = DEFAULT_TRACKING_GAIN,
    integral_gain: float | None = None,
) -> float:
    r"""Bound [m] on H's settled cross-track error on a path with ``|kappa| <= max_curvature`` and
    ``|dkappa/ds| <= max_curvature_rate`` at constant ``speed`` of A (module docstring).

    .. math::
        \dot W = \frac{v^2 K}{(1 - (l_3\kappa_{max})^2)^2}, \qquad
        \delta = l_3 \dot W dt^2 \Bigl(\frac12 + \frac{\dot W}{2 a_w}\Bigr), \qquad |e| \le \|h\|_1\,\delta,

    ``a_w = params.actuators.rot_acceleration``, ``h`` from :func:`closed_loop_impulse_response`.
    """
    ki = gain * gain / 4.0 if integral_gain is None else integral_gain
    l3 = params.robot.l3
    dt = params.dt
    w_dot = speed * speed * max_curvature_rate / (1.0 - (l3 * max_curvature) ** 2) ** 2
    delta = l3 * w_dot * dt * dt * (0.5 + w_dot / (2.0 * params.actuators.rot_acceleration))
    h1 = float(np.abs(closed_loop_impulse_response(gain, ki, dt)).sum())
    return h1 * delta


def pure_pursuit_circle_offset(radius: float, l3: float, direction: int = 1) -> float:
    """Steady signed cross-track error of H under pure pursuit on a circle of radius ``R`` [m].

    ``e_ss = -direction (sqrt(R^2 + l3^2) - R)`` (module docstring): A on the circle, H ``l3`` ahead on the tangent.
    """
    return -direction * (math.hypot(radius, l3) - radius)


class AnalyticTrackingPolicy(Policy):
    """The exact inverse solution with PI feedback on H (module docstring).

    ``predict`` keeps the integral ``z`` [m s] of H's cross-track error per batch row, SB3-recurrent style: a given
    ``state`` ``(N, 1)`` is reset where ``episode_start`` is True and the new state returned (the input is not
    modified); with ``state=None`` the policy's own state is used (reset where ``episode_start`` is True or when the
    batch size changes; :meth:`reset` otherwise) and a copy returned.

    Args:
        params: :class:`~amigo_gym.task.v1.TrackingParams`, or ``AmigoBot-v0``'s
            :class:`~amigo_gym.model.params.EnvParams` (no speed preview: the reference speed is fed forward as is).
        gain: ``k`` [1/s], in (0, 1/dt]; default 1.
        integral_gain: ``k_i`` [1/s^2] >= 0; default ``k^2/4``; 0 disables the integral.
        integral_limit: clamp of ``k_i |z|`` [m/s], > 0; default 0.1.
        feedforward: mid-step feedforward of the turn rate and the reference speed; default True.
    """

    def __init__(
        self,
        params: Params,
        gain: float = DEFAULT_TRACKING_GAIN,
        integral_gain: float | None = None,
        integral_limit: float = DEFAULT_INTEGRAL_LIMIT,
        feedforward: bool = True,
    ) -> None:
        o = "AnalyticTrackingPolicy"
        self._fields = Fields(o, params)
        self.params = params
        self.gain = check_range(o, "gain", gain, 0.0, 1.0 / params.dt, low_open=True)
        ki = self.gain * self.gain / 4.0 if integral_gain is None else integral_gain
        self.integral_gain = check_range(o, "integral_gain", ki, 0.0, 1.0 / params.dt**2)
        self.integral_limit = check_range(o, "integral_limit", integral_limit, 0.0, 10.0, low_open=True)
        self.feedforward = bool(feedforward)

    @property
    def name(self) -> str:
        """Short label: ``analytic_v1``."""
        return "analytic_v1"

    def _z_max(self) -> float:
        return math.inf if self.integral_gain == 0.0 else self.integral_limit / self.integral_gain

    def next_reference_speed(self, v_ref: Array, v_ahead: Array) -> Array:
        """The reference speed at the end of the step [m/s], predicted from now and 1 s ahead (``AmigoBot-v1``).

        Rising (``v_ahead > v_ref``): ``min(v_ref + a_up dt, v_ahead)`` with ``a_up = profile_accel`` (exact on a
        trapezoid's ramp and at its corner). Otherwise the chord ``v_ref + (v_ahead - v_ref) dt / 1 s`` (exact on a
        constant speed; within 1 s of the stop the preview reads 0 both while cruising and while braking, so the
        chord is off by at most ``profile_decel dt`` there).
        """
        p = self.params
        assert isinstance(p, TrackingParams)
        rise = np.minimum(v_ref + p.profile_accel * p.dt, v_ahead)
        chord = v_ref + (v_ahead - v_ref) * (p.dt / SPEED_LOOKAHEAD)
        out: Array = np.maximum(np.where(v_ahead > v_ref, rise, chord), 0.0)
        return out

    def command(self, obs: Array, z: Array) -> tuple[Array, Array, Array]:
        """``(v [m/s], omega [rad/s], z_new [m s])`` for observations ``(N, d)`` and integrals ``(N,)``.

        ``z_new = clip(z + dt e, -z_max, z_max)`` with ``z_max = integral_limit / k_i``; ``c = -k e - k_i z_new``;
        then :func:`analytic_tracking_command`.
        """
        p = self.params
        r = p.robot
        d = self._fields
        e = d(obs, "cross_track_error") * p.error_scale
        sp = d(obs, "sin_heading_error")
        cp = d(obs, "cos_heading_error")
        kappa = d(obs, "curvature") / r.l3
        v_ref = d(obs, "reference_speed") * r.max_speed
        if self.feedforward and "reference_speed_ahead" in d.index:
            v_ref = self.next_reference_speed(v_ref, d(obs, "reference_speed_ahead") * r.max_speed)
        z_max = self._z_max()
        z_new = np.clip(z + p.dt * e, -z_max, z_max)
        c = -self.gain * e - self.integral_gain * z_new
        v, om = analytic_tracking_command(e, sp, cp, kappa, v_ref, c, r.l3, p.dt, self.feedforward)
        return v, om, z_new

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, Array]:
        n = obs.shape[0]
        z, _ = self._rows(n, state, 1)
        z = np.where(self._starts(episode_start, n), 0.0, z[:, 0])
        v, om, z_new = self.command(obs, z)
        if state is None:
            self._state = z_new.reshape(n, 1)
        return limit_wheel_rates(v, om, self.params), z_new.reshape(n, 1).copy()

    def __repr__(self) -> str:
        return (
            f"AnalyticTrackingPolicy(gain={self.gain:g}, integral_gain={self.integral_gain:g}, "
            f"integral_limit={self.integral_limit:g}, feedforward={self.feedforward})"
        )


class PurePursuitPolicy(Policy):
    """Pure pursuit (Coulter 1992) towards a preview point of the observation.

    Args:
        params: the task's settings.
        lookahead: arc length [m] of the goal point ahead of H's closest point, one of ``params.preview``.
            Default 0.5 (or the preview distance nearest it).
        origin: the pursuing point: ``"axle"`` (default, A) or ``"H"`` (goal in H's frame, ``(x_L - l3, y_L)``).
        max_turn_rate: clip of the turn rate [rad/s] (> 0); None (default): only the wheels' limit.
        lookahead_time: speed-scaled look-ahead [s] (> 0): the preview point nearest to
            ``lookahead_time * v_ref`` ahead; None (default): the fixed ``lookahead``.

    ``predict`` is stateless. The benchmark's ``pure_pursuit`` is the default form (docs/benchmark.md).
    """

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
        self._fields = Fields(o, params, (TrackingParams,))
        self.params = params
        prev = params.preview
        if lookahead is None:
            lookahead = min(prev, key=lambda d: abs(d - DEFAULT_LOOKAHEAD))
        la = check_range(o, "lookahead", lookahead, 0.0, 5.0, low_open=True)
        if la not in prev:
            raise ValueError(f"{o}.lookahead must be one of the preview distances {list(prev)} m, got {lookahead!r}")
        if origin not in ("axle", "H"):
            raise ValueError(f"{o}.origin must be 'axle' or 'H', got {origin!r}")
        self.origin = origin
        opt = {"max_turn_rate": (max_turn_rate, 1e3), "lookahead_time": (lookahead_time, 60.0)}
        for k, (v, top) in opt.items():
            setattr(self, k, None if v is None else check_range(o, k, v, 0.0, top, low_open=True))
        self.lookahead = la
        self._prev = np.asarray(prev, dtype=np.float64)
        self._fixed = list(prev).index(la)
        self._ix, self._iy = (np.array([self._fields.index[f"preview_{c}_{d:g}m"] for d in prev]) for c in "xy")

    @classmethod
    def textbook(cls, params: TrackingParams) -> PurePursuitPolicy:
        """The textbook preset of Cao et al., Sensors 24(2) 561 (2024), Sec. 3.1 and the authors' code: the goal 0.2 m
        of arc length ahead of the closest point, pursued from the axle midpoint A, the turn rate clipped to 1 rad/s.
        Needs 0.2 among ``params.preview``. On their 1000 random paths at 0.2 m/s it fails 26.8 % [24.1, 29.6] at
        0.1 m (published: 27.6 %; ``amigo-gym benchmark --random-paths 1000``, docs/benchmark.md)."""
        return cls(params, 0.2, origin="axle", max_turn_rate=1.0)

    @property
    def name(self) -> str:
        """Short label: ``pure_pursuit``."""
        return "pure_pursuit"

    def command(self, obs: Array) -> tuple[Array, Array]:
        """``(v [m/s], omega [rad/s])`` for observations ``(N, d)`` (:func:`pure_pursuit_command`)."""
        p = self.params
        v_ref = self._fields(obs, "reference_speed") * p.robot.max_speed
        if self.lookahead_time is None:  # the fixed preview point: two columns
            x, y = obs[:, self._ix[self._fixed]], obs[:, self._iy[self._fixed]]
        else:  # per row the preview point nearest to lookahead_time * v_ref ahead
            pick = np.argmin(np.abs(self._prev[None, :] - (self.lookahead_time * v_ref)[:, None]), axis=1)
            rows = np.arange(len(obs))
            x, y = obs[rows, self._ix[pick]], obs[rows, self._iy[pick]]
        x, y = x * p.preview_scale, y * p.preview_scale
        if self.origin == "H":
            x = x - p.robot.l3
        v, om = pure_pursuit_command(x, y, v_ref)
        if self.max_turn_rate is not None:
            om = np.clip(om, -self.max_turn_rate, self.max_turn_rate)
        return v, om

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
