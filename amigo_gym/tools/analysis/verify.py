"""``amigo-gym verify``: the project's exactness checks, measured against references, PASS/FAIL per row.

Each row is a residual against an independent reference and the bound it must meet; exit status 1 when a row fails.
The rows and values: docs/model.md, "Exactness, measured"."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np

from amigo_gym.model.kinematics import a_from_h, body_velocity, castor_rate, circle_steady_state, h_position, step_pose
from amigo_gym.model.params import RobotParams
from amigo_gym.paths import CirclePath
from amigo_gym.task.inverse import paper_circle
from amigo_gym.tools.options import run_command

#: the steady state of the default circle (R = 1 m, v_A = 0.2 m/s), to 6 decimals as docs/model.md tabulates it
STEADY_REFERENCE = {"betadot": 0.200643, "alpha1_dot": 4.481543, "alpha2_dot": 3.518457, "alpha3_dot": 6.714802}
ROBOT = RobotParams()
R, V = 1.0, 0.2
#: one lap of A's steady circle [s]
LAP = 2 * math.pi * math.sqrt(R * R - ROBOT.l3**2) / V


def _laps_error(dt: float, how: str) -> float:
    """Largest distance of H from the circle of eq. 6 [m] over 10 laps at the steady rates, H starting at the origin
    in the steady pose, stepped ``how``: ``"exact"`` (the arc step), ``"euler"``, ``"env"`` (AmigoBot-v0, dt 0.1 s)."""
    ss = circle_steady_state(R, V, ROBOT)
    beta, w = -float(ss.heading_lag), np.asarray(ss.wheel_rates)
    pose = np.array([*a_from_h(0.0, 0.0, math.cos(beta), math.sin(beta), ROBOT.l3), beta])
    v, bd = body_velocity(w, ROBOT)
    if how == "env":
        env = gym.make("AmigoBot-v0", max_episode_steps=None)
        env.reset(options={"pose": pose})
    err = 0.0
    for _ in range(math.ceil(10 * LAP / dt)):
        if how == "env":
            err = max(err, abs(env.step(w / ROBOT.max_wheel_rate)[4]["cross_track_error"]))
            continue
        if how == "euler":
            pose = pose + dt * np.array([v * math.cos(pose[2]), v * math.sin(pose[2]), bd])
        else:
            pose = step_pose(pose, w, dt, ROBOT)
        h = h_position(pose, ROBOT)
        err = max(err, abs(math.hypot(h[0], h[1] - R) - R))
    return err


def round_trip_error(dt: float) -> float:
    """Largest ``|e|`` of H [m] over one lap when the inverse solution's wheel-angle increments / dt are held."""
    path = CirclePath(radius=R)
    sol = paper_circle(radius=R, speed=V, duration=LAP, dt=dt)
    w = np.diff(sol.wheel_angles[:, :2], axis=0) / dt
    pose = sol.pose[0]
    err = 0.0
    for k in range(w.shape[0]):
        pose = step_pose(pose, w[k], dt, ROBOT)
        err = max(err, abs(float(path.project(h_position(pose, ROBOT)).cross_track_error)))
    return err


def _symbolic_residual(n: int = 1000, seed: int = 0) -> float:
    from amigo_gym.tools import symbolic as S

    d = S.derive()
    rng = np.random.default_rng(seed)
    x, y, b = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-math.pi, math.pi, n)
    w = rng.uniform(-15, 15, (n, 2))
    v, bd = body_velocity(w, ROBOT)
    values: dict[str, Any] = {"x_A": x, "y_A": y, "beta": b, "betadot": bd, "v_A": v, **S.robot_values(ROBOT)}
    values |= {"xdot_A": v * np.cos(b), "ydot_A": v * np.sin(b), "alphadot_1": w[:, 0], "alphadot_2": w[:, 1]}
    rolling = S.lambdify([d.eq11, d.eq12, d.eq19, d.eq20, d.eq27, d.eq28])(**values)
    # the castor's equation is written for forward motion: speed |v_A| and rolling rate |alpha3dot|
    castor = S.lambdify([d.eq_castor])(**{**values, "v_A": np.abs(v), "alphadot_3": np.abs(castor_rate(v, bd, ROBOT))})
    return float(max(np.max(np.abs(rolling)), np.max(np.abs(castor))))


class Check(NamedTuple):
    """One row of the table: what is measured, the value, the bound it must meet and the verdict."""

    what: str
    value: float
    bound: str
    passed: bool


def _check(what: str, value: float, bound: str, ok: Callable[[float], bool]) -> Check:
    return Check(what, value, bound, bool(math.isfinite(value) and ok(value)))


def rows(quick: bool = False) -> list[Check]:
    """Every check with its verdict (``quick``: skip the slow ones)."""
    ss = circle_steady_state(R, V, ROBOT)
    got = dict(zip(STEADY_REFERENCE, (ss.betadot, *ss.wheel_rates, ss.castor_rate), strict=True))
    out = []
    for k, ref in STEADY_REFERENCE.items():
        what = f"steady {k} [rad/s] - docs/model.md's {ref}"
        out.append(_check(what, float(got[k]) - ref, "abs < 5e-7 (6 decimals)", lambda v: abs(v) < 5e-7))
    for dt in (0.01, 0.1, 0.5):
        what = f"step, 10 laps, dt = {dt} s: max H off circle [m]"
        out.append(_check(f"exact {what}", _laps_error(dt, "exact"), "<= 1e-9", lambda v: v <= 1e-9))
        out.append(_check(f"Euler {what}", _laps_error(dt, "euler"), "> 1e-4: not exact", lambda v: v > 1e-4))
    what = "AmigoBot-v0, 10 laps, dt = 0.1 s: max abs(e) [m]"
    out.append(_check(what, _laps_error(0.1, "env"), "<= 1e-9", lambda v: v <= 1e-9))
    if not quick:
        sol = paper_circle(radius=R, speed=V, duration=60.0, dt=0.1)
        e = np.hypot(sol.x_H, sol.y_H - R) - R
        what = "inverse solution, 60 s: max abs(e) of H [m]"
        out.append(_check(what, float(np.max(np.abs(e))), "<= 1e-8", lambda v: v <= 1e-8))
        e1, e2 = round_trip_error(0.1), round_trip_error(0.05)
        out.append(_check("round trip, 1 lap, dt = 0.1 s: max abs(e) [m]", e1, "<= 1e-4", lambda v: v <= 1e-4))
        out.append(_check("round trip, 1 lap, dt = 0.05 s: max abs(e) [m]", e2, "<= 1e-4", lambda v: v <= 1e-4))
        what = "round trip ratio dt 0.1 / 0.05 (second order)"
        out.append(_check(what, e1 / e2, "in [3.5, 4.5]", lambda v: 3.5 <= v <= 4.5))
        what = "symbolic system 29 on 1000 random states: max residual"
        out.append(_check(what, _symbolic_residual(), "<= 1e-12", lambda v: v <= 1e-12))
    return out


@dataclass(frozen=True)
class VerifySettings:
    """Options of ``amigo-gym verify``.

    Attributes:
        quick: skip the inverse solution, the round trip and the symbolic check.
    """

    quick: bool = False


def _report(args: VerifySettings) -> int:
    checks = rows(args.quick)
    print("| check | measured | bound | verdict |\n|---|---:|---|---|")
    for c in checks:
        print(f"| {c.what} | {c.value:.3g} | {c.bound} | {'PASS' if c.passed else 'FAIL'} |")
    failed = [c for c in checks if not c.passed]
    print(f"{len(checks) - len(failed)} of {len(checks)} checks passed" + (": FAIL" if failed else ""))
    return 1 if failed else 0


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym verify [--quick]``: print the table of residuals with PASS/FAIL; status 1 if one fails."""
    return run_command(VerifySettings, _report, argv, "amigo-gym verify", __doc__.splitlines()[0])
