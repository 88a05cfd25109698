"""A deployable delay compensator: the analytic controller acting on the observation predicted over the actuation
delay (a Smith predictor with the nominal model), the delay known or estimated online, on the validation cells.

    python experiments/smith_delay.py [--seeds 20] [--gains 1 2 3] [--cells val_delay_0.25 ...]
    python experiments/smith_delay.py --estimates     # the delay estimate step by step; the mismatch per cell

The prediction (:class:`Smith`): H's cross-track error ``e`` and heading error ``psi`` (from the observation) moved
over the delay ``d`` by the Frenet equations of H, ``de/dt = v sin psi + l3 omega cos psi``, ``dpsi/dt = omega -
kappa (v cos psi - l3 omega sin psi) / (1 - kappa e)`` (the path's curvature ``kappa`` held), with ``v``, ``omega``
of the nominal robot from the measured wheel rates, ramped by the firmware's limits towards the commands this
controller issued ``d`` before (episodes start at rest; the package's :func:`amigo_gym.model.actuators.ramp`); 5 ms
steps. :class:`SmithEstimated` estimates ``d`` among 0, 0.05, ..., 0.3 s: each candidate simulates the nominal
ramps' ``v``, ``omega`` from the commands issued so far under that delay, and the one with the least squared distance
to the measured ones so far wins.
Prints one Markdown row per cell: the mean H RMS [mm] over the validation seeds of the analytic controller
(``k = 1``), and the ratio to it of the compensator per gain (estimated delay; on the delay cells also known), and
the episodes ended early. Validation cells and seeds only (:mod:`amigo_gym.tools.training.protocol`).
"""

from __future__ import annotations

import argparse
import math
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym  # noqa: F401
from amigo_gym.model import actuators, kinematics
from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.task.v1 import obs_fields
from amigo_gym.tools.machine import machine_line
from amigo_gym.tools.training.protocol import VALIDATION_SEEDS, validation_cells

CANDIDATES = tuple(0.05 * i for i in range(7))  # delays the estimator chooses from [s]


class Smith:
    """The analytic controller (gain ``k``) on the observation predicted ``delay`` [s] ahead; ``h``: Euler step [s]."""

    def __init__(self, params: Any, delay: float, gain: float, h: float = 0.005) -> None:
        self.p, self.delay, self.h = params, delay, h
        self.pol = AnalyticTrackingPolicy(params, gain=gain)
        names = obs_fields(params)
        self.at = {n: names.index(n) for n in ("cross_track_error", "sin_heading_error", "cos_heading_error",
                                               "curvature", "wheel_rate_1", "wheel_rate_2")}  # fmt: skip
        self.issued: list[tuple[float, float]] = []  # the actions issued, step by step
        self.state: Any = None

    def body(self, a1: float, a2: float) -> tuple[float, float]:
        """``(v, omega)`` [m/s, rad/s] of the nominal robot for normalised wheel rates (the package's kinematics)."""
        r = self.p.robot
        return kinematics.body_velocity_of(a1 * r.max_wheel_rate, a2 * r.max_wheel_rate, r.r1, r.r2, 2.0 * r.l1)

    def ramp(self, v: float, om: float, a: tuple[float, float]) -> tuple[float, float]:
        """``v``, ``omega`` after one step ``h`` of the firmware's ramps towards the setpoint ``a``
        (:func:`amigo_gym.model.actuators.ramp`)."""
        act, h = self.p.actuators, self.h
        vc, oc = self.body(*a)
        v2 = actuators.ramp(v, vc, act.acceleration, act.deceleration, h).u_b
        om2 = actuators.ramp(om, oc, act.rot_acceleration, act.rot_deceleration, h).u_b
        return float(v2), float(om2)

    def command_at(self, t: float, delay: float) -> tuple[float, float]:
        """The setpoint acting at time ``t`` [s] since the reset: the action issued last at or before ``t - delay``."""
        m = math.floor((t - delay) / self.p.dt + 1e-9)
        return self.issued[m] if 0 <= m < len(self.issued) else (0.0, 0.0)

    def predicted(self, obs: np.ndarray) -> np.ndarray:
        """``obs`` with ``e`` and ``psi`` moved ``delay`` ahead."""
        p, r, at = self.p, self.p.robot, self.at
        e = float(obs[at["cross_track_error"]]) * p.error_scale
        psi = math.atan2(obs[at["sin_heading_error"]], obs[at["cos_heading_error"]])
        kappa = float(obs[at["curvature"]]) / r.l3
        v, om = self.body(float(obs[at["wheel_rate_1"]]), float(obs[at["wheel_rate_2"]]))
        now = len(self.issued) * p.dt
        for k in range(round(self.delay / self.h)):
            v2, om2 = self.ramp(v, om, self.command_at(now + k * self.h, self.delay))
            vm, omm = 0.5 * (v + v2), 0.5 * (om + om2)
            s_dot = (vm * math.cos(psi) - r.l3 * omm * math.sin(psi)) / max(1.0 - kappa * e, 0.05)
            e += self.h * (vm * math.sin(psi) + r.l3 * omm * math.cos(psi))
            psi += self.h * (omm - kappa * s_dot)
            v, om = v2, om2
        out = np.array(obs, dtype=np.float64)
        out[at["cross_track_error"]] = e / p.error_scale
        out[at["sin_heading_error"]], out[at["cos_heading_error"]] = math.sin(psi), math.cos(psi)
        return out

    def observe(self, obs: np.ndarray, start: bool) -> None:
        """Bookkeeping before acting on ``obs`` (the delay estimate here)."""
        if start:
            self.issued, self.state = [], None

    def act(self, obs: np.ndarray, start: bool) -> np.ndarray:
        self.observe(obs, start)
        seen = self.predicted(obs) if self.delay > 0.0 else obs
        a, self.state = self.pol.predict(seen[None], self.state, episode_start=np.array([start]), deterministic=True)
        a = np.asarray(a, dtype=np.float32).reshape(-1)
        self.issued.append((float(a[0]), float(a[1])))
        return a


class SmithEstimated(Smith):
    """:class:`Smith` with the delay chosen among :data:`CANDIDATES` by the measured wheel rates (module docstring).
    ``quiet`` [(m/s)^2]: if given, the gain ``k`` only while the chosen candidate's mean squared distance per step to
    the measured ``v``, ``l1 omega`` stays at or below it (measurements that the nominal model explains), else the
    analytic controller's ``k = 1`` (noisy measurements: a higher gain amplifies them)."""

    def __init__(self, params: Any, gain: float, quiet: float | None = None) -> None:
        super().__init__(params, 0.0, gain)
        self.quiet, self.fast, self.slow = quiet, self.pol, AnalyticTrackingPolicy(params, gain=1.0)

    def observe(self, obs: np.ndarray, start: bool) -> None:
        super().observe(obs, start)
        if start:
            self.sim, self.err = [(0.0, 0.0)] * len(CANDIDATES), np.zeros(len(CANDIDATES))
            self.delay = 0.0
            self.pol = self.fast
            return
        t0 = (len(self.issued) - 1) * self.p.dt
        v, om = self.body(float(obs[self.at["wheel_rate_1"]]), float(obs[self.at["wheel_rate_2"]]))
        for i, d in enumerate(CANDIDATES):
            sv, so = self.sim[i]
            for k in range(round(self.p.dt / self.h)):
                sv, so = self.ramp(sv, so, self.command_at(t0 + k * self.h, d))
            self.sim[i] = (sv, so)
            self.err[i] += (sv - v) ** 2 + (self.p.robot.l1 * (so - om)) ** 2
        self.delay = CANDIDATES[int(np.argmin(self.err))]
        if self.quiet is not None:
            steps = len(self.issued)
            self.pol = self.fast if self.err.min() / steps <= self.quiet else self.slow


def h_rms(make: Any, env_id: str, kwargs: dict[str, Any], seed: int, steps: int) -> tuple[float, bool]:
    """H's cross-track RMS [m] of one episode of the controller ``make(params)`` and whether it ended early."""
    env = gym.make(env_id, **kwargs)
    ctl = make(env.unwrapped.params)  # type: ignore[attr-defined]
    obs, _ = env.reset(seed=seed)
    e = []
    for t in range(steps):
        obs, _, terminated, truncated, info = env.step(ctl.act(obs, t == 0))
        e.append(info["cross_track_error"])
        if terminated or truncated:
            break
    return float(np.sqrt(np.mean(np.square(e)))), len(e) < steps


def run(sc: Any, make: Any) -> tuple[float, int]:
    """The mean H RMS [mm] of ``make``'s controller over the cell ``sc``'s seeds, and the episodes ended early."""
    rs = [h_rms(make, sc.env_id, dict(sc.env_kwargs), s, sc.max_steps) for s in sc.seeds]
    return 1e3 * float(np.mean([r[0] for r in rs])), sum(r[1] for r in rs)


def estimates(seed: int) -> None:
    """Print :class:`SmithEstimated`'s delay after steps 1-10 and 100 on the circle R 1 m at 0.2 m/s (``k = 2``),
    then on each validation cell the chosen delay's mean squared mismatch per step after 60 steps (``--quiet``'s
    measure)."""
    for true in (0.0, 0.1, 0.25, 0.3):
        env = gym.make("AmigoBot-v1", path="circle", speed=0.2, dt=0.1, randomize={"delay": (true, true)})
        ctl = SmithEstimated(env.unwrapped.params, 2.0)  # type: ignore[attr-defined]
        obs, _ = env.reset(seed=seed)
        got = []
        for t in range(101):
            obs = env.step(ctl.act(obs, t == 0))[0]
            got.append(ctl.delay)
        first = [round(d, 2) for d in got[1:11]]
        print(f"true delay {true:.2f} s: estimates after steps 1-10 {first}, after 100 {got[100]:.2f}")
    for sc in validation_cells("AmigoBot-v1", 1):
        env = gym.make(sc.env_id, **dict(sc.env_kwargs))
        ctl = SmithEstimated(env.unwrapped.params, 2.0)  # type: ignore[attr-defined]
        obs, _ = env.reset(seed=seed)
        for t in range(61):
            obs = env.step(ctl.act(obs, t == 0))[0]
        per_step = ctl.err.min() / (len(ctl.issued) - 1)
        print(f"{sc.name}: mismatch {per_step:.1e} (m/s)^2 a step, delay {ctl.delay:.2f} s")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--gains", type=float, nargs="+", default=[1.0, 2.0, 3.0])
    p.add_argument("--cells", nargs="*", default=None, help="validation cells (default: every AmigoBot-v1 one)")
    p.add_argument("--estimates", action="store_true", help="print the delay estimate step by step, then stop")
    p.add_argument("--quiet", type=float, default=None, help="SmithEstimated's quiet threshold [(m/s)^2]")
    a = p.parse_args()
    if a.estimates:
        estimates(VALIDATION_SEEDS[0])
        return
    cells = [sc for sc in validation_cells("AmigoBot-v1", a.seeds) if a.cells is None or sc.name in a.cells]
    print(machine_line())
    heads = [f"estimated, k = {g:g}" for g in a.gains] + [f"known, k = {g:g}" for g in a.gains]
    print("| cell | analytic [mm] | " + " | ".join(heads) + " |")
    print("|---" * (2 + len(heads)) + "|")
    for sc in cells:
        base, base_end = run(sc, lambda q: Smith(q, 0.0, 1.0))
        rz = dict(sc.env_kwargs).get("randomize", {})
        known = rz["delay"][0] if isinstance(rz, dict) and "delay" in rz else None
        row = [f"{base:.2f}" + (f" ({base_end} end)" if base_end else "")]
        makers = [lambda q, g=g: SmithEstimated(q, g, a.quiet) for g in a.gains]
        makers += [None if known is None else (lambda q, g=g, d=known: Smith(q, d, g)) for g in a.gains]
        for make in makers:
            if make is None:
                row.append("–")
                continue
            m, ended = run(sc, make)
            row.append(f"{m / base:.2f}" + (f" ({ended} end)" if ended else ""))
        print(f"| {sc.name} | " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    main()
