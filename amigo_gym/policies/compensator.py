r"""The delay compensator: the analytic controller acting on the observation predicted over the actuation delay (a
Smith predictor with the nominal robot), the delay estimated online from the measured wheel rates.

Prediction: H's cross-track error ``e`` and heading error ``psi`` moved over the delay ``d`` by H's Frenet equations,
:math:`\dot e = v \sin\psi + l_3 \omega \cos\psi`, :math:`\dot\psi = \omega - \kappa (v \cos\psi - l_3 \omega
\sin\psi) / (1 - \kappa e)` (the path's curvature ``kappa`` held, the divisor floored at 0.05), Euler steps of ``h``
= 5 ms, with the nominal robot's ``v``, ``omega`` from the measured wheel rates ramped by the firmware's limits
(:func:`amigo_gym.model.actuators.ramp`) towards the commands issued ``d`` before (read from the observations'
``previous_command`` fields; the episode starts at rest). Estimate: each candidate delay of :data:`CANDIDATES`
simulates the nominal ``v``, ``omega`` from the commands issued so far; the one with the least summed squared
distance :math:`(v_c - v)^2 + (l_1 (\omega_c - \omega))^2` to the measurements wins. Gain: ``k = gain`` while that
distance per step is at most ``quiet`` [(m/s)^2] (measurements the nominal model explains), else ``k = 1`` (the
analytic controller's: a higher gain amplifies noise). Validated in docs/experiments.md, "Delay compensation"."""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model import actuators, kinematics
from amigo_gym.model.params import check_real
from amigo_gym.policies.base import Fields, Policy
from amigo_gym.policies.tracking import AnalyticTrackingPolicy, limit_wheel_rates
from amigo_gym.sim import fast_v1
from amigo_gym.sim.layout import kernel_cache
from amigo_gym.task.v1 import TrackingParams

Array = NDArray[np.float64]
#: the delays the estimator chooses from [s]
CANDIDATES: tuple[float, ...] = tuple(0.05 * i for i in range(7))
#: commands kept per row (the estimator looks back at most ``max(CANDIDATES) / dt + 1`` steps)
RING = 8
#: the prediction's Euler step [s]
STEP = 0.005
#: observation fields read: ``e``, sin and cos ``psi``, curvature, wheel rates, previous commands
COLUMNS = ("cross_track_error", "sin_heading_error", "cos_heading_error", "curvature", "wheel_rate_1",
           "wheel_rate_2", "previous_command_1", "previous_command_2")  # fmt: skip


def _ramped(s: Array, m: int, count: int, v: float, om: float, rob: Array) -> tuple[Any, Any]:
    """``(v, omega)`` after :data:`STEP` of the nominal ramps towards the ring's command ``m`` (0 outside [0, count))"""
    on = (m >= 0) * (m < count)  # 1 or 0, not a conditional expression (numba's inlining warned of its phi)
    a1 = on * s[1 + 2 * (m % RING)]
    a2 = on * s[2 + 2 * (m % RING)]
    vc, omc = kinematics.body_velocity_of(a1 * rob[4], a2 * rob[4], rob[0], rob[1], 2.0 * rob[2])
    return actuators.ramp(v, vc, rob[5], rob[6], STEP).u_b, actuators.ramp(om, omc, rob[7], rob[8], STEP).u_b


def predict_rows(
    obs: Array, starts: NDArray[np.bool_], st: Array, col: NDArray[np.int64], cand: Array, rob: Array, dt: float,
    error_scale: float,
) -> tuple[Array, Array, Array]:  # fmt: skip
    """Per row of ``obs`` ``(N, d)``: the estimated delay [s], the chosen candidate's distance per step [(m/s)^2] (0
    before the first measurement) and ``(e [m], psi [rad])`` moved over the delay. ``st`` ``(N, 1 + 2 RING + 3 C)``
    is updated: ``[steps, ring of commands (RING, 2), candidates' (v, omega) (C, 2), their summed distance (C,)]``;
    ``col``: the indices of :data:`COLUMNS`; ``rob``: ``r1, r2, l1, l3, max_wheel_rate, acceleration, deceleration,
    rot_acceleration, rot_deceleration``."""
    n, nc, r1, r2, l1, l3, w_max = obs.shape[0], cand.size, rob[0], rob[1], rob[2], rob[3], rob[4]
    delay, dist, pred = np.zeros(n), np.zeros(n), np.zeros((n, 2))
    sim0, err0 = 1 + 2 * RING, 1 + 2 * RING + 2 * nc
    n_dt = round(dt / STEP)
    for i in range(n):
        s = st[i]
        if starts[i]:
            s[:] = 0.0
        else:  # the command issued a step ago (ring from index 1), then each candidate's ramps over the last step
            c = int(s[0])
            s[1 + 2 * (c % RING)], s[2 + 2 * (c % RING)] = obs[i, col[6]], obs[i, col[7]]
            s[0] = c + 1
        count = int(s[0])
        v, om = kinematics.body_velocity_of(obs[i, col[4]] * w_max, obs[i, col[5]] * w_max, r1, r2, 2.0 * l1)
        if count > 0:
            t0, best, j = (count - 1) * dt, np.inf, 0
            for k in range(nc):
                sv, so = s[sim0 + 2 * k], s[sim0 + 2 * k + 1]
                for q in range(n_dt):
                    sv, so = _ramped(s, math.floor((t0 + q * STEP - cand[k]) / dt + 1e-9), count, sv, so, rob)
                s[sim0 + 2 * k], s[sim0 + 2 * k + 1] = sv, so
                s[err0 + k] += (sv - v) ** 2 + (l1 * (so - om)) ** 2
                if s[err0 + k] < best:
                    best, j = s[err0 + k], k
            delay[i], dist[i] = cand[j], best / count
        e = obs[i, col[0]] * error_scale
        psi = math.atan2(obs[i, col[1]], obs[i, col[2]])
        kappa = obs[i, col[3]] / l3
        now, d = count * dt, delay[i]
        for q in range(round(d / STEP)):
            v2, om2 = _ramped(s, math.floor((now + q * STEP - d) / dt + 1e-9), count, v, om, rob)
            vm, omm = 0.5 * (v + v2), 0.5 * (om + om2)
            s_dot = (vm * math.cos(psi) - l3 * omm * math.sin(psi)) / max(1.0 - kappa * e, 0.05)
            e += STEP * (vm * math.sin(psi) + l3 * omm * math.cos(psi))
            psi += STEP * (omm - kappa * s_dot)
            v, om = v2, om2
        pred[i, 0], pred[i, 1] = e, psi
    return delay, dist, pred


@lru_cache(maxsize=1)
def _predictor() -> Any:
    """:func:`predict_rows` compiled (numba, cached with the step's kernels), or as it is without numba."""
    if not fast_v1.use_fast_path():
        return predict_rows
    fast_v1.kernels()  # registers the model's functions (actuators.ramp) with numba
    import numba
    from numba.extending import register_jitable

    register_jitable(inline="always")(_ramped)
    with kernel_cache():
        return numba.njit(cache=True, nogil=True)(predict_rows)


class DelayCompensatedPolicy(Policy):
    """The analytic controller (:class:`AnalyticTrackingPolicy`, gain ``gain`` [1/s] while quiet, else 1) on the
    observation predicted over the estimated actuation delay (module docstring); ``quiet`` [(m/s)^2] in [0, 1].
    ``predict``'s state per row ``(N, 2 + 2 RING + 3 C)``: the integral ``z`` [m s], then the predictor's."""

    name = "delay_compensated"

    def __init__(self, params: TrackingParams, gain: float = 2.0, quiet: float = 1e-6) -> None:
        o = "DelayCompensatedPolicy"
        self._fields = f = Fields(o, params, v1_only=True)
        self.params, self.quiet = params, check_real(o, "quiet", quiet, 0.0, 1.0)
        if max(CANDIDATES) / params.dt + 2 > RING:
            raise ValueError(f"{o}: params.dt = {params.dt} s is too short for the {max(CANDIDATES):g} s delays")
        self.gain = check_real(o, "gain", gain, 0.0, 1.0 / params.dt, low_open=True)
        self.fast, self.slow = AnalyticTrackingPolicy(params, gain), AnalyticTrackingPolicy(params, 1.0)
        self._col = np.array([f.index[c] for c in COLUMNS], dtype=np.int64)
        r, a = params.robot, params.actuators
        self._rob = np.array([r.r1, r.r2, r.l1, r.l3, r.max_wheel_rate, a.acceleration, a.deceleration,
                              a.rot_acceleration, a.rot_deceleration])  # fmt: skip
        self.state_dim = 2 + 2 * RING + 3 * len(CANDIDATES)

    def compensate(self, obs: Array, state: Array, starts: NDArray[np.bool_]) -> tuple[Array, Array, Array, Array]:
        """``(actions (N, 2), estimated delays [s] (N,), quiet flags (N,) as 0/1, new state)`` for checked
        observations ``(N, d)`` and the state ``(N, state_dim)``; rows with ``starts`` begin an episode."""
        st = np.array(state[:, 1:], dtype=np.float64)
        delay, dist, pred = _predictor()(obs, starts, st, self._col, np.array(CANDIDATES), self._rob, self.params.dt,
                                         self.params.error_scale)  # fmt: skip
        quiet = dist <= self.quiet
        seen = np.array(obs, dtype=np.float64)
        seen[:, self._col[0]] = pred[:, 0] / self.params.error_scale
        seen[:, self._col[1]], seen[:, self._col[2]] = np.sin(pred[:, 1]), np.cos(pred[:, 1])
        z = np.where(starts, 0.0, state[:, 0])
        v_f, om_f, z_f = self.fast.command(seen, z)
        v_s, om_s, z_s = self.slow.command(seen, z)
        v, om = np.where(quiet, v_f, v_s), np.where(quiet, om_f, om_s)
        new_state = np.concatenate([np.where(quiet, z_f, z_s)[:, None], st], axis=1)
        return limit_wheel_rates(v, om, self.params), delay, quiet.astype(np.float64), new_state

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, Array]:
        s, starts = self._rows(obs.shape[0], state, episode_start, self.state_dim)
        a, _, _, s_new = self.compensate(obs, s, starts)
        return a, self._keep(state, s_new)

    def __repr__(self) -> str:
        return f"DelayCompensatedPolicy(gain={self.gain:g}, quiet={self.quiet:g})"
