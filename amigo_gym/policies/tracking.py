r"""Classical path trackers for ``AmigoBot-v1``: the exact inverse solution with integral action, and pure pursuit.

Both read only the observation, by field name (:class:`amigo_gym.policies.base.Fields`), and the constant settings
:class:`~amigo_gym.task.v1.TrackingParams` (:class:`AnalyticTrackingPolicy` also ``AmigoBot-v0``'s
:class:`~amigo_gym.model.params.EnvParams`), use the **nominal** robot (``params.robot``), and have
stable-baselines3's ``predict`` interface for one observation ``(d,)`` or a batch ``(N, d)``.

Fields used: ``e``, ``psi`` (here from ``sin_heading_error``, ``cos_heading_error`` as they are), ``kappa`` and
``v_ref`` as in :mod:`amigo_gym.policies.analytic`, whose docstring also derives the velocity of H in the path
frame: ``edot = Hdot . n = v sin psi + l3 omega cos psi`` for a speed ``v`` of A and turn rate ``omega`` on any
smooth path, a map ``(v, omega) -> Hdot`` of determinant ``l3 != 0`` (H is steered directly, and the error
dynamics do not depend on the path's curvature). Besides (module table of :mod:`amigo_gym.task.v1`,
``v_max = robot.max_speed``):

* ``v_ahead = reference_speed_ahead * v_max``: the reference speed 1 s later [m/s];
* ``(x_d, y_d) = preview_{x,y}_<d> * preview_scale``: the path point ``d`` [m] of arc length ahead of H's
  closest point, in the robot frame (origin A, x along the heading) [m].

Analytic law (:func:`analytic_tracking_command`)
------------------------------------------------
Ask for ``Hdot = sdot t + c n`` with ``c = -k e - k_i z``, ``z = int e dt``, and keep ``v = v_ref``:

.. math::
    v = v_{ref}, \qquad \dot s = \frac{v_{ref} - c\sin\psi}{\cos\psi}, \qquad
    \omega = \frac{-\dot s\sin\psi + c\cos\psi}{l_3} = \frac{c - v_{ref}\sin\psi}{l_3\cos\psi}.

Then ``edot = -k e - k_i z`` exactly in continuous time, on every path and speed profile. On the path
(``e = z = 0``) this *is* the paper's exact inverse solution: with the lag ``theta - beta = -psi``,
``sdot = v_A / cos(theta - beta)`` and ``betadot = v_A tan(theta - beta) / l3``. ``cos psi`` is floored at
:data:`COS_MIN` (the law is singular when the robot faces across the path, like the paper's ODE).

Gains (the default ``k = 1 1/s``, ``k_i = k^2/4 = 0.25 1/s^2``). The error obeys ``e'' + k e' + k_i e = 0``:

* critically damped, ``k_i = k^2 / 4``: the fastest decay without overshoot, double pole at ``-k/2``;
* sampling: the command is held over ``dt``; the discrete loop (:func:`closed_loop_impulse_response`) has
  both poles at about ``exp(-k dt / 2) = 0.905`` for ``k dt = 0.2``, far inside its stability limit (the
  discrete loop becomes unstable near ``k dt = 2``); its behaviour is within a few per cent of the continuous one;
* actuator ramps: correcting an error ``e`` at rate ``~k`` needs turn-rate changes of ``~k^2 e / l3`` per
  second; the firmware ramps the turn rate at ``a_w = 0.87 rad/s^2``, so the loop stays linear for
  ``|e| <= a_w l3 / k^2 = 1.7 cm`` at ``k = 2``, the size of the env's start offsets (2 cm). Larger gains
  shrink that range as ``1/k^2`` (the ramp then rate-limits the turn); smaller gains slow the settling
  (``|e| < 1e-6 m`` after about 13 s at ``k = 2`` from a 2 cm start, 25 s at ``k = 1``);
* delay: a command acts ``tau`` late (up to 0.15 s in the ``"hard"`` preset) and is held over ``dt``, a phase
  lag of about ``k (tau + dt/2)`` at the loop's bandwidth; together with the rate-limited turn this pushed
  the loop into a limit cycle at ``k = 2`` (figure-8 at 0.3 m/s, ``randomize="hard"``, seed 0: H 0.25 m off
  the path, saturated bang-bang wheel commands), while ``k = 1`` kept H within 11 mm on seeds 0–5 (and the
  linear range above grows to 7 cm). The default is therefore ``k = 1``: robustness to the robot as it is
  over settling speed on the ideal one. This was found by rendering the ``"hard"`` figure-8 with ``amigo-gym
  gallery``; it is a design choice of the controller, not a fit to a benchmark score.

Anti-windup: ``k_i |z|`` is clamped at ``integral_limit`` (default 0.1 m/s, the correction speed a 25 %
mismatch of wheel radii or track needs at 0.4 m/s). A constant mismatch (true wheel radii or track off)
leaves a constant ``c`` in steady state; the integral supplies it, so ``e -> 0``.

Limits: the wheel-rate setpoints ``r1 w1 = v + l1 omega``, ``r2 w2 = v - l1 omega`` are divided by
``max(1, |w1| / w_max, |w2| / w_max)``: within ``+-w_max`` with the ratio ``omega / v`` (the path's
curvature of A) kept.

Feedforward (``feedforward=True``, default). The command is held over a step while the exact solution's turn
rate changes; ``Hdot . n = v sin psi + l3 omega cos psi`` then drifts by ``sdot psidot t``. Evaluating the law at
the predicted heading error of mid-step, ``psi + psidot dt / 2``, i.e. adding

.. math::
    \Delta\omega = \frac{\partial \omega}{\partial \psi}\,\dot\psi\,\frac{dt}{2}
    = -\frac{\dot s}{l_3\cos\psi}\Bigl(\omega - \frac{\kappa\,\dot s}{1 - \kappa e}\Bigr)\frac{dt}{2},

removes the first-order hold error (``psidot = omega - kappa sdot / (1 - kappa e)`` uses the curvature at H,
observed). On a circle in steady state ``psidot = 0``: the term vanishes. The reference speed is fed forward
too: ``v`` is the reference predicted for the end of the step (:meth:`AnalyticTrackingPolicy.next_reference_speed`,
from the 1 s preview), so that a trapezoid's ramp is met at each step's end rather than one step late.

Tracking error on paths whose curvature changes (:func:`zoh_error_bound`)
--------------------------------------------------------------------------
On the path the exact solution's turn rate is ``omega*(t)``. For H on the path and ``v_A = v`` constant, the
heading lag ``psi = theta - beta`` obeys ``dpsi/ds = u``, ``u = kappa - sin(psi) / l3``
(:func:`amigo_gym.paths.heading_lag_profile`), and ``omega* = v tan(psi) / l3``, so
``omegadot* = v^2 u / (l3 cos^3 psi)``. Two first-order low passes in arc length bound it:
``d(sin psi)/ds = (cos psi / l3) (l3 kappa - sin psi)`` keeps ``|sin psi| <= l3 kappa_max``, and
``du/ds = (cos psi / l3) (l3 kappa' / cos psi - u)`` keeps ``|u| <= l3 K / cos psi`` (``K = max |dkappa/ds|``;
``u`` is continuous where ``kappa'`` jumps), hence, with ``cos^2 psi >= 1 - (l3 kappa_max)^2``,

.. math:: |\dot\omega^*| \le \dot W = \frac{v^2 K}{(1 - (l_3\kappa_{max})^2)^2}

(the tests check ``Wdot`` against the exact peak of :func:`amigo_gym.paths.feasibility`). Two effects make the
held command miss ``omega*`` within a step:

1. zero-order hold: ``omega_cmd = omega*(t_k)`` while ``omega*(t_k + t) = omega*(t_k) + omegadot* t``: ``Hdot . n``
   is off by ``l3 cos(psi) omegadot* t``; over a step, ``e`` loses up to ``l3 Wdot dt^2 / 2``;
2. the firmware's ramp: successive commands differ by ``Delta omega = omegadot* dt``, reached after
   ``|Delta omega| / a_w`` (``a_w = rot_acceleration`` 0.87 rad/s^2, the slower of the two rates); the turn rate
   lags by the triangle ``Delta omega^2 / (2 a_w)``: ``e`` loses up to another ``l3 Wdot^2 dt^2 / (2 a_w)``.

So each step adds at most ``delta = l3 Wdot dt^2 (1/2 + Wdot / (2 a_w))`` to the error dynamics
``e_{k+1} = e_k + dt c_k + delta_k`` (with ``z_k = z_{k-1} + dt e_k``, ``c_k = -k e_k - k_i z_k``, as implemented).
A sequence of disturbances bounded by ``delta`` gives ``|e| <= ||h||_1 delta``, with ``h`` the impulse response of
this loop (:func:`closed_loop_impulse_response`; ``||h||_1 = 7.50`` for ``k = 2``, ``k_i = 1``, ``dt = 0.1``, close
to the continuous loop's ``4 / (e k dt) = 7.36``: its response to a unit velocity impulse, ``(1 - k t / 2)
exp(-k t / 2)``, has L1 norm ``4 / (e k)``).
The bound is ``O(dt)``: ``|e| <= ||h||_1 delta ~ (4 / (e k)) l3 Wdot dt (1/2 + Wdot / (2 a_w))``. With the
feedforward the first term is cancelled to first order; the same bound then holds with room to spare.

Measured (``dt = 0.1``, randomisation off, no start offsets, max ``|e|`` after 5 s; ``tests/test_policies_v1.py``)::

    path          v [m/s]  K [1/m^2]  bound [mm]  plain [mm]  feedforward [mm]  pure pursuit [mm]
    figure8       0.1      2.95       0.093       0.034       0.0040            42
    figure8       0.4      2.95       2.24        0.94        0.49              41
    lane_change   0.1      0.563      0.017       0.013       0.0004            17
    lane_change   0.4      0.563      0.30        0.23        0.015             16
    random (id)   0.4      1.0        0.58        0.22        0.045             27

On circles (radii 0.5-2 m, both directions, 0.1-0.4 m/s, from the env's 2 cm / 0.1 rad start offsets) H is within
3e-8 m of the path at 20-25 s and still converging; with true wheel radii and track 5 % larger, within 3e-8 m too.

Pure pursuit (:class:`PurePursuitPolicy`)
-----------------------------------------
Coulter (1992), "Implementation of the Pure Pursuit Path Tracking Algorithm", CMU-RI-TR-92-01: the reference
point A drives on the circular arc through the goal point ``(x_L, y_L)`` (robot frame) tangent to its heading,

.. math:: \kappa = \frac{2 y_L}{L^2}, \qquad L^2 = x_L^2 + y_L^2, \qquad v = v_{ref}, \qquad \omega = v\kappa.

The goal point is the observation's preview point at the chosen arc-length distance ``d`` ahead of H's closest
point (no interpolation: a chord between preview points would put the goal off the path); its distance from A
is ``L ~ l3 + d`` on a straight. On a circle of radius ``R`` the steady state has A on a circle of radius
``R_A`` concentric with the path and the goal on the path: ``y_L = (R_A^2 + L^2 - R^2) / (2 R_A)``, and
``1 / R_A = 2 y_L / L^2`` gives ``R_A = R`` for every ``L``. A tracks the circle exactly and H, ``l3`` ahead on
the tangent, runs outside it at ``sqrt(R^2 + l3^2)``: the steady cross-track error of H is

.. math:: e_{ss} = -\mathrm{direction}\,\bigl(\sqrt{R^2 + l_3^2} - R\bigr) \approx -\mathrm{direction}\,\frac{l_3^2}{2R}

(3.2 mm on R = 1 m, 6.4 mm on 0.5 m), whatever the lookahead: the offset is the price of tracking A, not H.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.model.actuators import wheel_rates_columns
from amigo_gym.model.params import check_range
from amigo_gym.policies.analytic import COS_MIN, analytic_tracking_command
from amigo_gym.policies.base import Fields, Params, Policy
from amigo_gym.task.v1 import SPEED_LOOKAHEAD, TrackingParams

__all__ = [
    "COS_MIN",
    "DEFAULT_TRACKING_GAIN",
    "DEFAULT_INTEGRAL_LIMIT",
    "AnalyticTrackingPolicy",
    "PurePursuitPolicy",
    "analytic_tracking_command",
    "pure_pursuit_command",
    "limit_wheel_rates",
    "closed_loop_impulse_response",
    "zoh_error_bound",
    "pure_pursuit_circle_offset",
]

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
    r"""Pure pursuit (Coulter 1992) towards the goal point ``(x_L, y_L)`` in the frame of A.

    .. math:: \kappa = \frac{2 y_L}{L^2}, \quad L^2 = x_L^2 + y_L^2, \quad v = v_{ref}, \quad \omega = v\kappa.

    Args:
        x_l, y_l: the goal point in the frame of A (x along the heading) [m], ``(N,)``; ``L`` is floored at 1 mm.
        v_ref: speed of A [m/s], ``(N,)``.

    Returns:
        ``(v [m/s], omega [rad/s])``, each ``(N,)``.
    """
    x = np.asarray(x_l, dtype=np.float64)
    y = np.asarray(y_l, dtype=np.float64)
    v = np.asarray(v_ref, dtype=np.float64)
    l2 = np.maximum(x * x + y * y, 1e-6)
    kappa = 2.0 * y / l2
    return v + 0.0 * kappa, v * kappa


def closed_loop_impulse_response(gain: float, integral_gain: float, dt: float, steps: int = 20000) -> Array:
    r"""Response ``h_n`` [m per m] of the sampled error loop to one disturbance ``delta_0 = 1`` m.

    ``z_k = z_{k-1} + dt e_k``, ``c_k = -k e_k - k_i z_k``, ``e_{k+1} = e_k + dt c_k + delta_k`` (the analytic
    policy's update, module docstring); ``h_0 = 0``, ``h_1 = 1``. Returns ``(steps,)``.
    """
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
    """The exact inverse solution along any path and speed profile, with PI feedback on H (module docstring).

    ``predict`` keeps the integral ``z`` [m s] of H's cross-track error per batch row, SB3-recurrent style:

    * ``state`` given: an ``(N, 1)`` array (``(1, 1)`` for a single observation) of ``z``; rows where
      ``episode_start`` is True are reset to 0 before the update; the new ``(N, 1)`` state is returned (the input
      is not modified).
    * ``state=None``: the policy's own internal state (one row per batch row) is used and updated, reset where
      ``episode_start`` is True, and reset to zeros whenever the batch size changes; call :meth:`reset` at the
      start of new episodes if ``episode_start`` is not passed. The returned state is a copy of it.

    Args:
        params: the task's settings (nominal robot, ``dt``, observation layout): ``AmigoBot-v1``'s
            :class:`~amigo_gym.task.v1.TrackingParams`, or ``AmigoBot-v0``'s :class:`~amigo_gym.model.params.EnvParams`
            (its observation has no speed preview: the reference speed is constant, and is fed forward as it is).
        gain: ``k`` [1/s], in (0, 1/dt]; default 1.
        integral_gain: ``k_i`` [1/s^2] >= 0; default ``k^2/4`` (critically damped); 0 disables the integral.
        integral_limit: clamp of ``k_i |z|`` [m/s] (anti-windup), > 0; default 0.1.
        feedforward: mid-step feedforward of the turn rate and the reference speed (module docstring); default True.
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
    """Pure pursuit (Coulter 1992) towards a preview point of the observation, in the textbook's variants.

    Args:
        params: the task's settings.
        lookahead: arc length ahead of H's closest point of the goal point [m]; must be one of ``params.preview``
            (the goal is that preview point, module docstring). Default 0.5 (or the preview distance nearest it).
        origin: the point that pursues the goal: ``"axle"`` (default; the axle midpoint A, Coulter's rear-axle
            form: the arc from A tangent to the heading through the goal) or ``"H"`` (the arc from H, ``l3``
            ahead of A on the heading: the goal in H's frame, ``x_L - l3``, ``y_L``; the turn rate
            ``omega = v kappa_H`` with ``kappa_H = 2 y_L / ((x_L - l3)^2 + y_L^2)``).
        max_turn_rate: the turn rate is clipped to ``[-max_turn_rate, max_turn_rate]`` [rad/s] (> 0), as a
            published controller's rate limit; None (default): no limit but the wheels' (:func:`limit_wheel_rates`).
        lookahead_time: speed-scaled look-ahead [s] (> 0): per robot the goal is the preview point nearest to
            ``lookahead_time * v_ref`` ahead (the preview distances are the only goal points the observation
            holds); None (default): the fixed ``lookahead``.

    ``predict`` is stateless: it returns ``state`` unchanged. The benchmark's ``pure_pursuit`` is the default form
    (``origin="axle"``, fixed look-ahead 0.5 m, no turn-rate limit; docs/benchmark.md).
    """

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
        self.max_turn_rate = (
            None if max_turn_rate is None else check_range(o, "max_turn_rate", max_turn_rate, 0.0, 1e3, low_open=True)
        )
        self.lookahead_time = (
            None
            if lookahead_time is None
            else check_range(o, "lookahead_time", lookahead_time, 0.0, 60.0, low_open=True)
        )
        self.lookahead = la
        self._prev = np.asarray(prev, dtype=np.float64)
        self._fixed = list(prev).index(la)
        self._ix, self._iy = (np.array([self._fields.index[f"preview_{c}_{d:g}m"] for d in prev]) for c in "xy")

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
