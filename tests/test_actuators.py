"""The actuator model of AmigoBot-v1 (:mod:`amigo_gym.model.actuators`) against independent facts.

Closed-form motion from rest, step-halving and time-shift invariants (with and without delay), an
mpmath reference at 40 digits with its own event-by-event ramp, rate limits, the bits of one robot
versus a batch, clipping, and the true robot's scale.
"""

from __future__ import annotations

import ast
import importlib.util
import itertools
import math
import sys
from pathlib import Path

import mpmath
import numpy as np
import pytest

from amigo_gym.model.actuators import (
    MAX_DELAY,
    PIECES,
    ActuatorParams,
    ActuatorStep,
    actuator_step,
    delay_split,
    ramp,
    ring_length,
    ring_read,
    ring_write,
    step_subintervals,
    turn_rate_bound,
)
from amigo_gym.model.kinematics import body_velocity_columns
from amigo_gym.model.params import RobotParams

ROBOT = RobotParams()
LIM = ActuatorParams()
W_MAX = ROBOT.max_wheel_rate


def clip_setpoints(w1c: object, w2c: object, nominal: RobotParams) -> tuple:
    """Setpoints [rad/s] (columns) clipped to ``[-w_max, w_max]``, ``w_max = nominal.max_wheel_rate``."""
    w_max = nominal.max_wheel_rate
    return np.clip(w1c, -w_max, w_max), np.clip(w2c, -w_max, w_max)


NOMINAL_TRUE = (ROBOT.r1, ROBOT.r2, ROBOT.l1)
Array = np.ndarray


def _step(state: tuple, old: tuple, new: tuple, t_s: object, dt: float, true: tuple = NOMINAL_TRUE,
          slip: tuple = (0.0, 0.0)) -> ActuatorStep:  # fmt: skip
    """``actuator_step`` with the state ``(x, y, beta, w1, w2)`` and commands as pairs."""
    return actuator_step(*state, *old, *new, t_s, dt, ROBOT, LIM, *true, *slip)


def _state(s: ActuatorStep) -> tuple:
    return s.x, s.y, s.beta, s.w1, s.w2


def _is_module(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:  # a name inside a module that is not a package
        return False


def test_imports_are_restricted() -> None:
    """numpy, the standard library and four amigo_gym modules only (the module docstring's promise)."""
    import amigo_gym.model.actuators as mod

    allowed = {
        "numpy",
        "amigo_gym.model.params",
        "amigo_gym.model.numeric",
        "amigo_gym.model.kinematics",
        "amigo_gym.model.fresnel",
    }
    names: set[str] = set()
    for node in ast.walk(ast.parse(Path(str(mod.__file__)).read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            # ``from amigo_gym.model import fresnel`` imports the module amigo_gym.model.fresnel
            names.update(
                f"{node.module}.{a.name}" if _is_module(f"{node.module}.{a.name}") else node.module for a in node.names
            )
    bad = {n for n in names if n.split(".")[0] not in sys.stdlib_module_names and n not in allowed}
    bad -= {n for n in names if n.startswith("numpy.")}
    assert not bad, bad


# -- parameters and helpers ---------------------------------------------------------------------------


def test_params_defaults_are_the_manufacturers() -> None:
    p = ActuatorParams()
    # shared/MODEL.md: acceleration 0.3 m/s^2 (0.87 rad/s^2), deceleration 0.75 m/s^2 (2.5 rad/s^2)
    assert (p.acceleration, p.deceleration, p.rot_acceleration, p.rot_deceleration) == (0.3, 0.75, 0.87, 2.5)
    assert (p.acceleration, p.deceleration) == (ROBOT.max_acceleration, ROBOT.max_deceleration)
    assert p.delay == 0.0
    assert W_MAX == 15.0


@pytest.mark.parametrize(
    "kw",
    [{"acceleration": 0.0}, {"deceleration": -1.0}, {"rot_acceleration": math.nan}, {"rot_deceleration": math.inf},
     {"delay": -0.01}, {"delay": MAX_DELAY + 1e-9}, {"acceleration": "fast"}],
)  # fmt: skip
def test_params_are_validated(kw: dict) -> None:
    with pytest.raises(ValueError, match="ActuatorParams"):
        ActuatorParams(**kw)


def test_clip_setpoints() -> None:
    assert clip_setpoints(100.0, -100.0, ROBOT) == (15.0, -15.0)
    assert clip_setpoints(3.0, -14.0, ROBOT) == (3.0, -14.0)
    c1, c2 = clip_setpoints(np.array([20.0, -1.0]), np.array([-16.0, 15.0]), ROBOT)
    assert c1.tolist() == [15.0, -1.0] and c2.tolist() == [-15.0, 15.0]


def test_setpoints_beyond_the_limit_act_as_the_limit() -> None:
    rng = np.random.default_rng(1)
    state = (0.1, -0.2, 0.3, 4.0, -7.0)
    for _ in range(20):
        big = rng.uniform(15.0, 1e3, 2) * rng.choice([-1.0, 1.0], 2)
        clipped = np.sign(big) * 15.0
        a = _step(state, tuple(big), tuple(-big), 0.04, 0.1)
        b = _step(state, tuple(clipped), tuple(-clipped), 0.04, 0.1)
        assert a == b


def test_delay_split_and_ring() -> None:
    assert delay_split(0.0, 0.1) == (0, 0.0)
    m, f = delay_split(0.03, 0.1)
    assert m == 0 and f == 0.03
    m, f = delay_split(0.25, 0.1)
    assert m == 2 and abs(f - 0.05) < 1e-15
    ma, fa = delay_split(np.array([0.03, 0.25, 0.5]), 0.1)
    assert ma.tolist() == [0, 2, 4] or ma.tolist() == [0, 2, 5]  # 0.5 = 5 x 0.1 up to rounding
    assert np.all((fa >= 0) & (fa < 0.1)) and np.allclose(ma * 0.1 + fa, [0.03, 0.25, 0.5], atol=1e-15, rtol=0)
    assert ring_length(0.1) == 6 and ring_length(0.1, 0.05) == 2 and ring_length(0.125, 0.5) == 6  # 0.5 = 4.99.. x 0.1
    for dt in (0.02, 0.05, 0.1, 0.3):
        for d in np.linspace(0.0, MAX_DELAY, 26):
            m, _ = delay_split(float(d), dt)
            assert m + 2 <= ring_length(dt)
    # the ring: slot j % length holds the command of step j
    ring = np.array([[1.0, 2.0]] * 4)
    for k in range(10):
        ring_write(ring, k, 10.0 + k, -10.0 - k)
        assert ring_read(ring, k, 0) == ((1.0, 2.0) if k == 0 else (9.0 + k, -9.0 - k)) + (10.0 + k, -10.0 - k)
        if k >= 3:
            assert ring_read(ring, k, 2) == (7.0 + k, -7.0 - k, 8.0 + k, -8.0 - k)
    with pytest.raises(ValueError, match="lag"):
        ring_read(ring, 5, 3)
    batch = np.zeros((2, 3, 2))
    batch[..., 1] = 1.0
    ring_write(batch, 0, np.array([5.0, 6.0]), np.array([7.0, 8.0]))
    o1, o2, n1, n2 = ring_read(batch, 0, np.array([0, 1]))
    assert o1.tolist() == [0.0, 0.0] and o2.tolist() == [1.0, 1.0]
    assert n1.tolist() == [5.0, 0.0] and n2.tolist() == [7.0, 1.0]


def test_subintervals_from_parameters_only() -> None:
    assert turn_rate_bound(ROBOT) == pytest.approx(1.25**2 * 2 * 0.75 / 0.12)
    assert step_subintervals(0.1, ROBOT) == 1
    assert step_subintervals(1.0, ROBOT) == 10


# -- the ramp -------------------------------------------------------------------------------------------


def test_ramp_reaches_targets_at_closed_form_times() -> None:
    a, d, ra, rd = 0.3, 0.75, 0.87, 2.5
    r = ramp(0.0, 0.75, a, d, 10.0)
    assert (r.t_a, r.t_b, r.u_b, r.s_b) == (0.0, 0.75 / a, 0.75, a)  # 2.5 s to full speed
    r = ramp(0.75, 0.0, a, d, 10.0)
    assert (r.t_b, r.u_b, r.s_b) == (1.0, 0.0, -d)  # 1 s to stop
    r = ramp(0.5, -0.3, a, d, 10.0)  # reversing: stop at D, then speed up at A
    assert (r.t_a, r.u_a, r.s_a, r.s_b) == (0.5 / d, 0.0, -d, -a)
    assert r.t_b == pytest.approx(0.5 / d + 0.3 / a, abs=1e-15) and r.u_b == -0.3
    r = ramp(-2.0, -0.5, ra, rd, 10.0)  # slowing down, same sign
    assert (r.t_a, r.t_b, r.u_b, r.s_b) == (0.0, 1.5 / rd, -0.5, rd)
    r = ramp(0.0, 6.25, ra, rd, 1.0)  # not reached within T
    assert (r.t_b, r.u_b) == (1.0, ra)
    r = ramp(1.0, -1.0, ra, rd, 0.2)  # zero not reached within T
    assert (r.t_a, r.t_b) == (0.2, 0.2) and r.u_a == pytest.approx(1.0 - rd * 0.2, abs=1e-16) and r.u_b == r.u_a
    r = ramp(0.4, 0.4, a, d, 0.0)
    assert r.u_b == 0.4


def test_rates_are_respected() -> None:
    """|v| never grows faster than A nor shrinks faster than D, sampled every 10 ms under random commands."""
    rng = np.random.default_rng(2)
    n, dt = 64, 0.01
    state = (np.zeros(n), np.zeros(n), np.zeros(n), rng.uniform(-15, 15, n), rng.uniform(-15, 15, n))
    cmd = rng.uniform(-20, 20, (2, n))
    grow_v = grow_w = shrink_v = shrink_w = 0.0
    for k in range(400):
        if k % 37 == 0:
            cmd = rng.uniform(-20, 20, (2, n)) * rng.choice([0.0, 1.0], (2, n), p=[0.1, 0.9])
        v0, w0 = body_velocity_columns(state[3], state[4], ROBOT)
        s = _step(state, tuple(cmd), tuple(cmd), 0.0, dt)
        v1, w1 = body_velocity_columns(s.w1, s.w2, ROBOT)
        grow_v = max(grow_v, float(np.max(np.abs(v1) - np.abs(v0))) / dt)
        shrink_v = max(shrink_v, float(np.max(np.abs(v0) - np.abs(v1))) / dt)
        grow_w = max(grow_w, float(np.max(np.abs(w1) - np.abs(w0))) / dt)
        shrink_w = max(shrink_w, float(np.max(np.abs(w0) - np.abs(w1))) / dt)
        state = _state(s)
    assert grow_v <= 0.3 * (1 + 1e-9) and shrink_v <= 0.75 * (1 + 1e-9)
    assert grow_w <= 0.87 * (1 + 1e-9) and shrink_w <= 2.5 * (1 + 1e-9)
    # and the limits are used: the fastest changes are the limits themselves
    assert grow_v > 0.3 * 0.999 and shrink_v > 0.75 * 0.999 and grow_w > 0.87 * 0.999 and shrink_w > 2.5 * 0.999
    # all commands are eventually reached (wheel rates within the clipped setpoints)
    for _ in range(100):
        state = _state(_step(state, tuple(cmd), tuple(cmd), 0.0, 0.1))
    c1, c2 = clip_setpoints(cmd[0], cmd[1], ROBOT)
    assert np.max(np.abs(state[3] - c1)) < 1e-12 and np.max(np.abs(state[4] - c2)) < 1e-12


# -- closed-form motion ---------------------------------------------------------------------------------


@pytest.mark.parametrize("dt", [0.1, 0.07, 0.25, 0.5, 1.3])
def test_from_rest_full_forward(dt: float) -> None:
    """x = 0.3 t^2 / 2 until 0.75 m/s at t = 2.5 s, then 0.9375 + 0.75 (t - 2.5); straight, wheels at 15 rad/s."""
    state: tuple = (0.0, 0.0, 0.0, 0.0, 0.0)
    worst = 0.0
    for k in range(1, int(6.0 / dt) + 1):
        s = _step(state, (15.0, 15.0), (15.0, 15.0), 0.0, dt)
        t = k * dt
        x_ref = 0.15 * t * t if t <= 2.5 else 0.9375 + 0.75 * (t - 2.5)
        v_ref = min(0.3 * t, 0.75)
        worst = max(worst, abs(s.x - x_ref))
        assert s.y == 0.0 and s.beta == 0.0 and s.w1 == s.w2
        assert abs(s.w1 - v_ref / 0.05) < 1e-12 and abs(s.v_true - v_ref) < 1e-14
        assert abs(s.dalpha1 - s.distance / 0.05) < 1e-12 and abs(s.distance - (s.x - state[0])) < 1e-14
        state = _state(s)
    assert worst < 1e-12
    assert state[3] == 15.0 and state[4] == 15.0


def test_true_radius_larger_makes_the_robot_faster() -> None:
    """A true radius 5% larger (both wheels): 5% faster at steady state; slip s: (1 - s) slower."""
    for true, slip, factor in [((0.0525, 0.0525, 0.12), (0.0, 0.0), 1.05), ((0.05, 0.05, 0.12), (0.1, 0.1), 0.9)]:
        s_nom = s_true = None
        st_nom: tuple = (0.0, 0.0, 0.0, 0.0, 0.0)
        st_true: tuple = st_nom
        for _ in range(40):
            s_nom = _step(st_nom, (10.0, 10.0), (10.0, 10.0), 0.0, 0.1)
            s_true = _step(st_true, (10.0, 10.0), (10.0, 10.0), 0.0, 0.1, true, slip)
            st_nom, st_true = _state(s_nom), _state(s_true)
        assert s_nom is not None and s_true is not None
        assert s_nom.v_true == pytest.approx(0.5, abs=1e-15)
        assert s_true.v_true == pytest.approx(0.5 * factor, abs=1e-15)
        assert s_true.distance == pytest.approx(factor * 0.05, abs=1e-15)
        assert s_true.w1 == s_nom.w1 == 10.0  # the wheels turn as the firmware commands
    # a larger right wheel (wheel 1) turns the robot left: w_true = (r1t - r2t) w / (2 l1)
    st: tuple = (0.0, 0.0, 0.0, 10.0, 10.0)
    s = _step(st, (10.0, 10.0), (10.0, 10.0), 0.0, 0.1, (0.0525, 0.05, 0.12))
    assert s.w_true == pytest.approx(0.0025 * 10.0 / 0.24, abs=1e-15) and s.beta > 0


# -- invariants -------------------------------------------------------------------------------------------


def _random_cases(rng: np.random.Generator, n: int) -> tuple[tuple, Array, tuple, tuple]:
    """Random starting states (with special rows), commands, true robots and slips, as (n,) columns."""
    w1, w2 = rng.uniform(-16, 16, n), rng.uniform(-16, 16, n)
    c1, c2 = rng.uniform(-18, 18, n), rng.uniform(-18, 18, n)
    q = n // 8
    w2[:q] = -w1[:q]  # pure rotation now
    c2[q : 2 * q] = -c1[q : 2 * q]  # pure rotation commanded
    w2[2 * q : 3 * q] = w1[2 * q : 3 * q]  # equal wheels
    c2[2 * q : 3 * q] = c1[2 * q : 3 * q]
    c1[3 * q : 4 * q], c2[3 * q : 4 * q] = -w1[3 * q : 4 * q], -w2[3 * q : 4 * q]  # reversing through zero
    w1[4 * q : 5 * q] = w2[4 * q : 5 * q] = 0.0  # from rest
    c1[5 * q : 6 * q], c2[5 * q : 6 * q] = w1[5 * q : 6 * q], w2[5 * q : 6 * q]  # steady
    state = (rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(-4, 4, n), w1, w2)
    true = (0.05 * rng.uniform(0.95, 1.05, n), 0.05 * rng.uniform(0.95, 1.05, n), 0.12 * rng.uniform(0.95, 1.05, n))
    slip = (rng.uniform(0, 0.2, n), rng.uniform(0, 0.2, n))
    return state, np.stack([c1, c2]), true, slip


def _max_diff(a: ActuatorStep, b: ActuatorStep) -> dict[str, float]:
    return {f: float(np.max(np.abs(np.asarray(getattr(a, f)) - getattr(b, f)))) for f in ("x", "y", "beta", "w1", "w2")}


@pytest.mark.parametrize("dt", [0.1, 0.3, 1.0])
@pytest.mark.parametrize("nominal", [True, False])
def test_one_step_equals_two_half_steps(dt: float, nominal: bool) -> None:
    """Without delay and with the command held: one step of dt is two of dt/2 (slip and true robot held too)."""
    rng = np.random.default_rng(3)
    n = 400
    state, cmd, true, slip = _random_cases(rng, n)
    if nominal:
        true, slip = tuple(np.full(n, v) for v in NOMINAL_TRUE), (np.zeros(n), np.zeros(n))
    c = (cmd[0], cmd[1])
    one = _step(state, c, c, 0.0, dt, true, slip)
    h1 = _step(state, c, c, 0.0, dt / 2, true, slip)
    h2 = _step(_state(h1), c, c, 0.0, dt / 2, true, slip)
    d = _max_diff(one, h2)
    assert d["x"] < 1e-12 and d["y"] < 1e-12 and d["beta"] < 1e-12 and d["w1"] < 1e-11 and d["w2"] < 1e-11, d
    for f in ("dalpha1", "dalpha2", "distance"):
        assert np.max(np.abs(getattr(one, f) - getattr(h1, f) - getattr(h2, f))) < 1e-12


def _run_delayed(state: tuple, cmds: Array, init: Array, delay: Array, dt: float, repeat: int,
                 true: tuple, slip: tuple) -> ActuatorStep:  # fmt: skip
    """Issue ``cmds[k]`` ((K, 2, n)) at steps of ``dt``, each held for ``repeat`` steps of ``dt / repeat``."""
    h = dt / repeat
    lag, f = delay_split(delay, h)
    ring = np.repeat(np.stack((init[0], init[1]), -1)[:, None], ring_length(h), axis=1)  # (n, length, 2)
    s: ActuatorStep | None = None
    for k in range(len(cmds) * repeat):
        ring_write(ring, k, cmds[k // repeat][0], cmds[k // repeat][1])
        o1, o2, n1, n2 = ring_read(ring, k, lag)
        s = actuator_step(*state, o1, o2, n1, n2, f, h, ROBOT, LIM, *true, *slip)
        state = _state(s)
    assert s is not None
    return s


@pytest.mark.parametrize("delays", [(0.03,), (0.15,), (0.1,), "random"])
def test_halving_with_delay(delays: tuple[float, ...] | str) -> None:
    """With a delay in seconds, the setpoint in effect at time t is the same function of t whatever the step:
    commands issued every dt, each repeated at two steps of dt/2, give the same motion (to rounding)."""
    rng = np.random.default_rng(4)
    n, dt, k = 96, 0.1, 12
    state, _, true, slip = _random_cases(rng, n)
    delay = rng.uniform(0, MAX_DELAY, n) if delays == "random" else np.full(n, delays[0])
    cmds = rng.uniform(-18, 18, (k, 2, n))
    cmds[3:6, 1] = -cmds[3:6, 0]
    init = np.stack([state[3], state[4]])  # before the first step the robot was doing what it does
    a = _run_delayed(state, cmds, init, delay, dt, 1, true, slip)
    b = _run_delayed(state, cmds, init, delay, dt, 2, true, slip)
    d = _max_diff(a, b)
    assert d["x"] < 1e-12 and d["y"] < 1e-12 and d["beta"] < 1e-12 and d["w1"] < 1e-11 and d["w2"] < 1e-11, d


def test_delay_shifts_the_motion_in_time() -> None:
    """From rest with nothing commanded before, a delay d shifts the whole motion by d: the pose at k dt with
    the delay is the pose at k dt - d without it (reached by k - 1 steps of dt and one of dt - f)."""
    rng = np.random.default_rng(5)
    n, dt, k = 64, 0.1, 9
    zeros = np.zeros(n)
    state = (rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(-4, 4, n), zeros, zeros)
    true, slip = tuple(np.full(n, v) for v in NOMINAL_TRUE), (zeros, zeros)
    cmds = rng.uniform(-18, 18, (k, 2, n))
    for d in (0.03, 0.07, 0.15, 0.3, 0.42):
        delayed = _run_delayed(state, cmds, np.zeros((2, n)), np.full(n, d), dt, 1, true, slip)
        m, f = delay_split(d, dt)
        st = state
        for j in range(k - m):  # the commands that took effect, each for dt, the last for dt - f
            last = j == k - m - 1
            c = (cmds[j][0], cmds[j][1])
            s = actuator_step(*st, *c, *c, 0.0, dt - f if last else dt, ROBOT, LIM, *true, *slip)
            st = _state(s)
        diff = _max_diff(delayed, s)
        assert diff["x"] < 1e-12 and diff["y"] < 1e-12 and diff["beta"] < 1e-12, (d, diff)


# -- one robot versus a batch -------------------------------------------------------------------------------


def _bits(x: object) -> int:
    return int(np.float64(x).view(np.int64))


def test_floats_and_arrays_agree() -> None:
    """A batch of heterogeneous robots (true radii, half track, slip, switch time per row) is row by row (to
    1e-12 of each quantity's scale)."""
    rng = np.random.default_rng(6)
    n, dt = 64, 0.1
    state, cmd, true, slip = _random_cases(rng, n)
    old = rng.uniform(-18, 18, (2, n))
    t_s = rng.uniform(0, dt, n)
    t_s[:8] = 0.0
    batch = actuator_step(*state, *old, *cmd, t_s, dt, ROBOT, LIM, *true, *slip)
    for i in range(n):
        row = actuator_step(
            *(float(c[i]) for c in state), *(float(c) for c in old[:, i]), *(float(c) for c in cmd[:, i]),
            float(t_s[i]), dt, ROBOT, LIM, *(float(c[i]) for c in true), *(float(c[i]) for c in slip),
        )  # fmt: skip
        for f, col in zip(ActuatorStep._fields, batch, strict=True):
            value = float(getattr(row, f))
            assert abs(value - col[i]) <= 1e-12 * max(1.0, float(np.max(np.abs(col)))), (i, f, value, col[i])
    # a scalar setting (nominal robot, no slip) broadcast against array states: the same
    mixed = actuator_step(*state, *old, *cmd, t_s, dt, ROBOT, LIM, 0.05, 0.05, 0.12)
    full = actuator_step(*state, *old, *cmd, t_s, dt, ROBOT, LIM, *(np.full(n, v) for v in NOMINAL_TRUE))
    for a, b in zip(mixed, full, strict=True):
        assert np.array_equal(a, b)


# -- against mpmath -----------------------------------------------------------------------------------------


def _mp_channel(u: mpmath.mpf, targets: list[tuple[mpmath.mpf, mpmath.mpf]], acc: float, dec: float) -> list:
    """The firmware's ramp, event by event: ``[(t_start, u_start, slope)]`` for targets ``[(t_end, c)]``."""
    segs: list = []
    t = mpmath.mpf(0)
    for t_end, c in targets:
        while t < t_end:
            if u == c:
                segs.append((t, u, mpmath.mpf(0)))
                t = t_end
                break
            if u != 0 and (mpmath.sign(c) != mpmath.sign(u) or abs(c) < abs(u)):  # slowing down
                stop = c if mpmath.sign(c) == mpmath.sign(u) else mpmath.mpf(0)
                slope = -mpmath.sign(u) * dec
            else:  # speeding up
                stop, slope = c, mpmath.sign(c) * acc
            reach = t + abs(stop - u) / abs(slope)
            segs.append((t, u, slope))
            if reach <= t_end:
                t, u = reach, stop
            else:
                u = u + slope * (t_end - t)
                t = t_end
    return segs


def _mp_at(segs: list, t: mpmath.mpf) -> tuple[mpmath.mpf, mpmath.mpf]:
    for t0, u0, s in reversed(segs):
        if t >= t0:
            return u0 + s * (t - t0), s
    raise AssertionError


def _mp_reference(state: tuple, old: tuple, new: tuple, t_s: float, dt: float, true: tuple, slip: tuple) -> tuple:
    mp = mpmath.mpf
    r1, r2, l1 = mp(ROBOT.r1), mp(ROBOT.r2), mp(ROBOT.l1)
    x0, y0, b0, w1, w2 = (mp(v) for v in state)
    ts, T = mp(t_s), mp(dt)

    def speeds(a: float, b: float, clip: bool) -> tuple[mpmath.mpf, mpmath.mpf]:
        a, b = (mp(min(max(c, -W_MAX), W_MAX)) if clip else mp(c) for c in (a, b))
        return (r1 * a + r2 * b) / 2, (r1 * a - r2 * b) / (2 * l1)

    (v0, om0), (vo, wo), (vn, wn) = speeds(w1, w2, False), speeds(*old, True), speeds(*new, True)
    sv = _mp_channel(v0, [(ts, vo), (T, vn)], LIM.acceleration, LIM.deceleration)
    sw = _mp_channel(om0, [(ts, wo), (T, wn)], LIM.rot_acceleration, LIM.rot_deceleration)
    g1, g2, l1t = (1 - mp(slip[0])) * mp(true[0]), (1 - mp(slip[1])) * mp(true[1]), mp(true[2])

    def rates(t: mpmath.mpf) -> tuple[mpmath.mpf, mpmath.mpf]:
        v, _ = _mp_at(sv, t)
        om, _ = _mp_at(sw, t)
        return (v + l1 * om) / r1, (v - l1 * om) / r2

    def v_true(t: mpmath.mpf) -> mpmath.mpf:
        a, b = rates(t)
        return (g1 * a + g2 * b) / 2

    def w_true(t: mpmath.mpf) -> mpmath.mpf:
        a, b = rates(t)
        return (g1 * a - g2 * b) / (2 * l1t)

    knots = sorted({*(s[0] for s in sv), *(s[0] for s in sw), T})
    # the heading: piecewise quadratic, exact from the linear turn rate on each piece
    starts, beta = [], b0
    for a, b in itertools.pairwise(knots):
        starts.append((a, beta, w_true(a), (w_true(b) - w_true(a)) / (b - a)))
        beta = beta + (b - a) * (w_true(a) + w_true(b)) / 2

    def heading(t: mpmath.mpf) -> mpmath.mpf:
        for a, h, w0, al in reversed(starts):
            if t >= a:
                return h + w0 * (t - a) + al * (t - a) ** 2 / 2
        raise AssertionError

    x = x0 + mpmath.quad(lambda t: v_true(t) * mpmath.cos(heading(t)), knots)
    y = y0 + mpmath.quad(lambda t: v_true(t) * mpmath.sin(heading(t)), knots)
    a_end, b_end = rates(T)
    da1 = mpmath.quad(lambda t: rates(t)[0], knots)
    return x, y, beta, a_end, b_end, da1


def test_against_mpmath() -> None:
    """Random steps (delay switch, reversal, clipping, slip, true robot) against the 40-digit reference."""
    rng = np.random.default_rng(7)
    worst = dict.fromkeys(("x", "y", "beta", "w", "dalpha"), 0.0)
    with mpmath.workdps(40):  # restores the caller's precision (another test module may rely on its own)
        for i in range(24):
            dt = float(rng.choice([0.1, 0.25, 1.0, 2.0]))
            state = (*rng.uniform(-1, 1, 2), rng.uniform(-4, 4), *rng.uniform(-15, 15, 2))
            old, new = tuple(rng.uniform(-18, 18, 2)), tuple(rng.uniform(-18, 18, 2))
            if i % 4 == 0:
                new = (-state[3], -state[4])
            t_s = 0.0 if i % 3 == 0 else float(rng.uniform(0, dt))
            true = (0.05 * rng.uniform(0.95, 1.05), 0.05 * rng.uniform(0.95, 1.05), 0.12 * rng.uniform(0.95, 1.05))
            slip = tuple(rng.uniform(0, 0.3, 2))
            s = _step(state, old, new, t_s, dt, true, slip)
            x, y, beta, w1, w2, da1 = _mp_reference(state, old, new, t_s, dt, true, slip)
            worst["x"] = max(worst["x"], abs(float(x - s.x)))
            worst["y"] = max(worst["y"], abs(float(y - s.y)))
            worst["beta"] = max(worst["beta"], abs(float(beta - s.beta)))
            worst["w"] = max(worst["w"], abs(float(w1 - s.w1)), abs(float(w2 - s.w2)))
            worst["dalpha"] = max(worst["dalpha"], abs(float(da1 - s.dalpha1)))
    assert worst["x"] < 1e-13 and worst["y"] < 1e-13 and worst["beta"] < 1e-13, worst
    assert worst["w"] < 1e-12 and worst["dalpha"] < 1e-12, worst


def test_piece_count_is_enough() -> None:
    """9 inner breakpoints: both channels reverse before the switch and again after it, all in one step
    (v: 0.5 -> -0.5 -> 0.5 m/s, w: 25/12 -> -25/12 -> 25/12 rad/s), as 700 steps of 10 ms."""
    assert PIECES == 10
    start: tuple = (0.0, 0.0, 0.0, 15.0, 5.0)
    one = _step(start, (-15.0, -5.0), (15.0, 5.0), 3.5, 7.0)
    kv = [ramp(0.5, -0.5, 0.3, 0.75, 3.5), ramp(-0.5, 0.5, 0.3, 0.75, 3.5)]
    assert all(0 < r.t_a < r.t_b < 3.5 for r in kv)
    st = start
    for k in range(700):
        c = (-15.0, -5.0) if k < 350 else (15.0, 5.0)
        st = _state(_step(st, c, c, 0.0, 0.01))
    assert abs(st[0] - one.x) < 1e-12 and abs(st[1] - one.y) < 1e-12 and abs(st[2] - one.beta) < 1e-12
    assert abs(st[3] - one.w1) < 1e-12 and abs(st[4] - one.w2) < 1e-12
