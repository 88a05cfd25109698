"""The symbolic D–H derivation (amigo_gym.tools.symbolic) against the numeric core, docs/model.md and the paper's
misprints.

References: the numeric kinematics of :mod:`amigo_gym.model.kinematics` (an independent implementation), the equations
of ``docs/model.md`` typed here by hand, rigid-body velocities computed here with numpy, and docs/model.md's
steady-state figures for the circle (v_A = 0.2 m/s, R = 1 m).
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from amigo_gym.model import kinematics as K
from amigo_gym.model.params import RobotParams
from amigo_gym.tools import symbolic as S
from amigo_gym.tools.cli import main as cli_main

Array = np.ndarray[Any, np.dtype[np.float64]]

#: the paper's robot, and an asymmetric one so that swapped r1/r2 or l-lengths cannot pass unnoticed
ROBOTS = [RobotParams(), RobotParams(l1=0.13, l3=0.09, l4=0.02, l5=0.11, r1=0.052, r2=0.047, r3=0.031)]
TOL = 1e-12

l1, l3, l5, r1, r2, r3, R, v_A = (S.PLAIN_SYMBOLS[n] for n in ("l_1", "l_3", "l_5", "r_1", "r_2", "r_3", "R", "v_A"))
x_A, y_A, beta, phi, theta = (S.PLAIN_SYMBOLS[n] for n in ("x_A", "y_A", "beta", "phi", "theta"))
xdot_A, ydot_A, betadot, phidot, sdot = (S.PLAIN_SYMBOLS[n] for n in ("xdot_A", "ydot_A", "betadot", "phidot", "sdot"))
ad1, ad2, ad3 = (S.PLAIN_SYMBOLS[n] for n in ("alphadot_1", "alphadot_2", "alphadot_3"))


@pytest.fixture(scope="module")
def d() -> S.Derivation:
    return S.derive()


def _is_zero(expr: Any) -> bool:
    return bool(sp.simplify(sp.expand(expr)) == 0)


def _motion_values(pose: Array, v: Array, bd: Array, w: Array, robot: RobotParams) -> dict[str, Array]:
    """Symbol values of a rolling motion: pose, A's velocity (eqs 11-12), turn rate, wheel and castor rates."""
    b = pose[:, 2]
    return {
        "x_A": pose[:, 0],
        "y_A": pose[:, 1],
        "beta": b,
        "xdot_A": v * np.cos(b),
        "ydot_A": v * np.sin(b),
        "betadot": bd,
        "v_A": v,
        "alphadot_1": w[:, 0],
        "alphadot_2": w[:, 1],
        "alphadot_3": K.castor_rate(v, bd, robot),
        "pose": pose,
        "w": w,
    }


def rolling_states(robot: RobotParams, n: int, seed: int) -> dict[str, Array]:
    """Random poses and random wheel rates; the motion of A from the core's ``body_velocity`` (docs/model.md)."""
    rng = np.random.default_rng(seed)
    pose = np.column_stack((rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(-math.pi, math.pi, n)))
    pose[:4, 2] = (math.pi / 2, -math.pi / 2, 0.0, math.pi)  # headings along the axes are included
    w = rng.uniform(-robot.max_wheel_rate, robot.max_wheel_rate, (n, 2))
    v, bd = K.body_velocity(w, robot)
    return _motion_values(pose, v, bd, w, robot)


def circle_states(robot: RobotParams, n: int, seed: int) -> dict[str, Array]:
    """Random states with H on the circle of eq. 6, moving along it; turn rate and phidot solved here with numpy.

    H is placed by eq. 6 (typed here); A = H - l3 (cos b, sin b) for a random heading lag; the velocity of H is the
    rigid-body velocity ``v_A e + betadot k x (H - A)``, and (betadot, phidot) make it equal ``R phidot (cos phi,
    sin phi)`` (H stays on the path).
    """
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.3, 3.0, n)
    ph = rng.uniform(-2 * math.pi, 2 * math.pi, n)
    lag = rng.uniform(-1.0, 1.0, n)
    v = rng.uniform(0.05, robot.max_speed, n)
    b = ph - lag
    h = np.column_stack((radius * np.sin(ph), radius * (1 - np.cos(ph))))
    pose = np.column_stack((h[:, 0] - robot.l3 * np.cos(b), h[:, 1] - robot.l3 * np.sin(b), b))
    rel = K.h_position(pose, robot) - pose[:, :2]
    mat = np.stack(
        (np.column_stack((-rel[:, 1], rel[:, 0])), np.column_stack((-radius * np.cos(ph), -radius * np.sin(ph)))),
        axis=-1,
    )
    rhs = -v[:, None] * np.column_stack((np.cos(b), np.sin(b)))
    bd, phd = np.linalg.solve(mat, rhs[..., None])[..., 0].T
    w = K.wheel_rates(v, bd, robot)
    return {
        **_motion_values(pose, v, bd, w, robot),
        "R": radius,
        "phi": ph,
        "phidot": phd,
        "theta": ph,
        "sdot": radius * phd,
        "h": h,
    }


# ---------------------------------------------------------------------------------------------------------------------
# (a) the derivation against the numeric kinematics and docs/model.md
# ---------------------------------------------------------------------------------------------------------------------


def test_contact_point_velocity_is_model_md_eq_18_with_velocities(d: S.Derivation) -> None:
    cb, sb = sp.cos(beta), sp.sin(beta)
    model_k = [xdot_A - r1 * ad1 * cb + l1 * betadot * cb, ydot_A - r1 * ad1 * sb + l1 * betadot * sb, 0, 0]
    model_l = [xdot_A - r2 * ad2 * cb - l1 * betadot * cb, ydot_A - r2 * ad2 * sb - l1 * betadot * sb, 0, 0]
    assert all(_is_zero(a - b) for a, b in zip(d.v_K, model_k, strict=True))
    assert all(_is_zero(a - b) for a, b in zip(d.v_L, model_l, strict=True))
    # the product-rule sum is the derivative of the product of the transforms, applied to the frozen rho
    T = S.transforms()
    by_product = sp.diff(T.T40K * T.T14, S.t) * T.rho_K
    assert all(_is_zero(a) for a in S.to_plain(by_product - S.material_velocity([T.T40K, T.T14], T.rho_K)))
    # the wheel frame maps rho_K to the bottom of the wheel whatever alpha1: T14 rho_K = (0, 0, -r1, 1)
    assert all(_is_zero(a - b) for a, b in zip(S.to_plain(T.T14 * T.rho_K), [0, 0, -r1, 1], strict=True))


@pytest.mark.parametrize("robot", ROBOTS)
def test_positions_equal_core(d: S.Derivation, robot: RobotParams) -> None:
    st = rolling_states(robot, 64, seed=1)
    vals = {**st, **S.robot_values(robot)}
    h = S.lambdify(list(d.r_H))(**vals)
    k = S.lambdify(list(d.r_K))(**vals)
    lp = S.lambdify(list(d.r_L))(**vals)
    k_ref, l_ref = K.contact_points(st["pose"], robot)
    np.testing.assert_allclose(h[:, :2], K.h_position(st["pose"], robot), rtol=0, atol=TOL)
    np.testing.assert_allclose(h[:, 2:], np.tile([robot.r1 - robot.l4, 1.0], (64, 1)), rtol=0, atol=TOL)
    np.testing.assert_allclose(k[:, :2], k_ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(lp[:, :2], l_ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(k[:, 2:], np.tile([0.0, 1.0], (64, 1)), rtol=0, atol=TOL)
    np.testing.assert_allclose(lp[:, 2:], np.tile([0.0, 1.0], (64, 1)), rtol=0, atol=TOL)


@pytest.mark.parametrize("robot", ROBOTS)
def test_rolling_constraints_hold_for_core_kinematics(d: S.Derivation, robot: RobotParams) -> None:
    st = rolling_states(robot, 200, seed=2)
    vals = {**st, **S.robot_values(robot)}
    # v_K = 0, v_L = 0 in full (eqs 19, 20, 27, 28) and eqs 11, 12 of system (29)
    res = S.lambdify([*d.v_K, *d.v_L, d.eq11, d.eq12, *d.system_29[2:6]])(**vals)
    assert np.max(np.abs(res)) <= TOL
    # the castor (seventh equation) for forward motion; |alpha3dot| in general
    fwd = st["v_A"] > 0
    assert fwd.sum() > 20 and (~fwd).sum() > 20
    castor = S.lambdify([d.eq_castor])(**vals)[..., 0]
    assert np.max(np.abs(castor[fwd])) <= TOL
    speed = np.hypot(robot.l5 * st["betadot"], st["v_A"])
    assert np.max(np.abs(robot.r3 * np.abs(st["alphadot_3"]) - speed)) <= TOL


@pytest.mark.parametrize("robot", ROBOTS)
def test_castor_rolls_when_aligned_with_its_swivel_velocity(d: S.Derivation, robot: RobotParams) -> None:
    st = rolling_states(robot, 100, seed=3)
    st = {k: v[st["v_A"] > 0] for k, v in st.items()}
    # swivel velocity by the rigid-body formula from the core's castor position
    rel = K.castor_position(st["pose"], robot) - st["pose"][:, :2]
    e = np.column_stack((np.cos(st["beta"]), np.sin(st["beta"])))
    v_s = st["v_A"][:, None] * e + st["betadot"][:, None] * np.column_stack((-rel[:, 1], rel[:, 0]))
    gamma = np.arctan2(v_s[:, 1], v_s[:, 0]) - st["beta"]
    vals = {**st, **S.robot_values(robot), "gamma": gamma}
    np.testing.assert_allclose(S.lambdify(list(d.v_S[:2]))(**vals), v_s, rtol=0, atol=TOL)
    assert np.max(np.abs(S.lambdify(list(d.v_C))(**vals))) <= TOL
    swivel = S.lambdify([d.castor_swivel])(**vals)[..., 0]
    np.testing.assert_allclose(np.angle(np.exp(1j * (swivel - gamma))), 0.0, atol=TOL)


@pytest.mark.parametrize("robot", ROBOTS)
def test_wheel_rate_solution_equals_core(d: S.Derivation, robot: RobotParams) -> None:
    # symbolically: docs/model.md's differential-drive relations
    assert _is_zero(d.wheel_rates[ad1] - (v_A + l1 * betadot) / r1)
    assert _is_zero(d.wheel_rates[ad2] - (v_A - l1 * betadot) / r2)
    assert _is_zero(d.body_velocity[v_A] - (r1 * ad1 + r2 * ad2) / 2)
    assert _is_zero(d.body_velocity[betadot] - (r1 * ad1 - r2 * ad2) / (2 * l1))
    assert d.slip_K == 0 and d.slip_L == 0
    # numerically against the core
    rng = np.random.default_rng(4)
    v, bd = rng.uniform(-0.75, 0.75, 50), rng.uniform(-3.0, 3.0, 50)
    vals = {"v_A": v, "betadot": bd, **S.robot_values(robot)}
    got = S.lambdify([d.wheel_rates[ad1], d.wheel_rates[ad2]])(**vals)
    np.testing.assert_allclose(got, K.wheel_rates(v, bd, robot), rtol=0, atol=TOL)
    w = rng.uniform(-15, 15, (50, 2))
    got_vb = S.lambdify([d.body_velocity[v_A], d.body_velocity[betadot]])(
        alphadot_1=w[:, 0], alphadot_2=w[:, 1], **S.robot_values(robot)
    )
    np.testing.assert_allclose(got_vb, np.column_stack(K.body_velocity(w, robot)), rtol=0, atol=TOL)
    got_c = S.lambdify([d.castor_rate])(**vals)[..., 0]
    fwd = v > 0
    np.testing.assert_allclose(got_c[fwd], K.castor_rate(v, bd, robot)[fwd], rtol=0, atol=TOL)


@pytest.mark.parametrize("robot", ROBOTS)
def test_path_equations_and_inverse_ode_on_the_circle(d: S.Derivation, robot: RobotParams) -> None:
    st = circle_states(robot, 200, seed=5)
    np.testing.assert_allclose(K.h_position(st["pose"], robot), st["h"], rtol=0, atol=TOL)
    vals = {**st, **S.robot_values(robot)}
    res = S.lambdify([d.eq7, d.eq8, d.eq9, d.eq10, *d.system_29])(**vals)
    assert np.max(np.abs(res)) <= TOL
    ode = S.lambdify([d.inverse_ode[sdot], d.inverse_ode[betadot]])(**vals)
    np.testing.assert_allclose(ode, np.column_stack((st["sdot"], st["betadot"])), rtol=0, atol=TOL)


def test_inverse_ode_is_model_md_form(d: S.Derivation) -> None:
    assert _is_zero(d.inverse_ode[sdot] - v_A / sp.cos(theta - beta))
    assert _is_zero(d.inverse_ode[betadot] - v_A * sp.tan(theta - beta) / l3)
    # eqs 9-10 are the general path's with theta = phi and sdot = R phidot
    on_circle = {theta: phi, sdot: R * phidot}
    assert _is_zero(d.eq9_path.subs(on_circle) - d.eq9)
    assert _is_zero(d.eq10_path.subs(on_circle) - d.eq10)
    # and paper's printed eqs 9-10
    assert _is_zero(d.eq9 - (xdot_A - l3 * betadot * sp.sin(beta) - R * phidot * sp.cos(phi)))
    assert _is_zero(d.eq10 - (ydot_A + l3 * betadot * sp.cos(beta) - R * phidot * sp.sin(phi)))


def test_steady_state_on_circle_gives_model_md_numbers(d: S.Derivation) -> None:
    robot = RobotParams()
    vals = {"v_A": 0.2, "R": 1.0, **S.robot_values(robot)}
    names = ("betadot", "alphadot_1", "alphadot_2", "alphadot_3")
    got = S.lambdify([d.steady[n] for n in names])(**vals)
    # docs/model.md, "The path of H and the inverse problem", printed to 6 decimals
    np.testing.assert_allclose(got, [0.200643, 4.481543, 3.518457, 6.714802], rtol=0, atol=6e-7)
    ref = K.circle_steady_state(1.0, 0.2, robot)
    lag = S.lambdify([d.steady_lag])(**vals)[0]
    np.testing.assert_allclose(lag, ref.heading_lag, rtol=0, atol=TOL)
    np.testing.assert_allclose(got[0], ref.betadot, rtol=0, atol=TOL)
    np.testing.assert_allclose(got[1:3], ref.wheel_rates, rtol=0, atol=TOL)
    np.testing.assert_allclose(got[3], ref.castor_rate, rtol=0, atol=TOL)


def test_inverse_ode_integrated_on_circle_settles_to_steady_state(d: S.Derivation) -> None:
    robot = RobotParams()
    radius, speed = 1.0, 0.2
    rhs = S.lambdify([d.inverse_ode[sdot], d.inverse_ode[betadot]])

    def f(_t: float, y: Array) -> Array:
        return rhs(theta=y[0] / radius, beta=y[1], v_A=speed, **S.robot_values(robot))

    # start on the path at its start point, heading along the tangent (beta = theta = 0)
    sol = solve_ivp(f, (0.0, 20.0), [0.0, 0.0], rtol=1e-11, atol=1e-12)
    assert sol.success
    s_end, b_end = sol.y[:, -1]
    ref = K.circle_steady_state(radius, speed, robot)
    np.testing.assert_allclose(s_end / radius - b_end, ref.heading_lag, rtol=0, atol=1e-8)
    np.testing.assert_allclose(f(0.0, sol.y[:, -1])[1], ref.betadot, rtol=0, atol=1e-8)


# ---------------------------------------------------------------------------------------------------------------------
# (b) the paper's misprinted forms are not identities
# ---------------------------------------------------------------------------------------------------------------------


def steady_circle_motion(robot: RobotParams, phases: Array) -> dict[str, Array]:
    """The steady rolling motion of docs/model.md's example (v_A = 0.2, R = 1) at the given path phases of H."""
    radius, speed = 1.0, 0.2
    ss = K.circle_steady_state(radius, speed, robot)
    b = phases - ss.heading_lag
    h = np.column_stack((radius * np.sin(phases), radius * (1 - np.cos(phases))))
    n = len(phases)
    return {
        "x_A": h[:, 0] - robot.l3 * np.cos(b),
        "y_A": h[:, 1] - robot.l3 * np.sin(b),
        "beta": b,
        "xdot_A": speed * np.cos(b),
        "ydot_A": speed * np.sin(b),
        "betadot": np.full(n, ss.betadot),
        "v_A": np.full(n, speed),
        "alphadot_1": np.full(n, ss.wheel_rates[0]),
        "alphadot_2": np.full(n, ss.wheel_rates[1]),
        "alphadot_3": np.full(n, ss.castor_rate),
        "R": np.full(n, radius),
        "phi": phases,
        "phidot": np.full(n, ss.speed_h / radius),
    }


def test_misprinted_forms_are_not_satisfied_by_rolling(d: S.Derivation) -> None:
    robot = RobotParams()
    vals = {**steady_circle_motion(robot, np.array([0.7, 1.9, 3.1, 4.4, 5.6])), **S.robot_values(robot)}
    # the motion does roll: the corrected system holds
    assert np.max(np.abs(S.lambdify([*d.system_29, *d.v_K, *d.v_L])(**vals))) <= TOL
    mp = d.misprints

    def norm2(vec: Any) -> Array:
        return np.asarray(np.linalg.norm(S.lambdify(list(vec[:2]))(**vals), axis=-1))

    # eqs 17/25: the product of derivatives is r alphadot betadot (sin b, -cos b), not zero
    assert np.all(norm2(mp.eq17) > 1e-3) and np.all(norm2(mp.eq25) > 1e-3)
    # eqs 18/26 with positions, eq 28 with y_A
    assert np.all(norm2(mp.eq18) > 1e-3) and np.all(norm2(mp.eq26) > 1e-3)
    assert np.all(np.abs(S.lambdify([mp.eq28])(**vals)) > 1e-3)
    # the velocity of the geometric contact point (rho differentiated too) is not the rolling condition
    assert np.all(norm2(mp.contact_point_velocity_K) > 1e-3)
    # symbolically too: none is the product-rule result
    assert not _is_zero(mp.eq17[0] - d.v_K[0])
    assert not _is_zero(mp.eq18[0] - d.v_K[0])


def test_printed_x_components_say_nothing_when_heading_along_y(d: S.Derivation) -> None:
    # system 29 keeps only the x-components of v_K = 0: at beta = pi/2 (so xdot_A = 0 by eq. 11) eq. 19 holds for
    # any alpha1dot, while the component along the heading still fixes it
    at = {beta: sp.pi / 2, xdot_A: 0}
    assert d.eq19.subs(at) == 0 and d.eq27.subs(at) == 0
    assert d.roll_K.has(ad1) and not d.roll_K.has(beta)


# ---------------------------------------------------------------------------------------------------------------------
# (c) LaTeX, (d) CLI and import weight
# ---------------------------------------------------------------------------------------------------------------------


def test_latex_emitter_gives_the_seven_equations() -> None:
    cb, sb = sp.cos(beta), sp.sin(beta)
    model_md = [  # docs/model.md / the paper's system 29, typed here
        xdot_A - l3 * betadot * sb - R * phidot * sp.cos(phi),
        ydot_A + l3 * betadot * cb - R * phidot * sp.sin(phi),
        xdot_A - v_A * cb,
        ydot_A - v_A * sb,
        xdot_A - r1 * ad1 * cb + l1 * betadot * cb,
        xdot_A - r2 * ad2 * cb - l1 * betadot * cb,
        sp.sqrt(l5**2 * betadot**2 + v_A**2) - r3 * ad3,
    ]
    lines = S.system_29_latex()
    assert len(lines) == 7 == len(S.SYSTEM_29_LABELS)
    assert lines == [f"{sp.latex(sp.expand(e))} = 0" for e in model_md]
    joined = "\n".join(lines)
    # velocities, never the positions x_A, y_A (as the paper's eqs 18, 26, 28 print them)
    assert joined.count(r"\dot{x}_{A}") == 4 and joined.count(r"\dot{y}_{A}") == 2
    assert "x_{A}" not in joined and "y_{A}" not in joined
    assert "y_{A}" in sp.latex(S.derive().misprints.eq28)
    doc = S.render(latex=True)
    block = doc.split("System (29)")[1].split(r"\end{align}")[0]
    tags = [line.rsplit(r"\tag{", 1)[1].rstrip("} \\") for line in block.splitlines() if r"\tag{" in line]
    assert tags == list(S.SYSTEM_29_LABELS)
    assert doc.count(r"\begin{align}") == doc.count(r"\end{align}") and doc.count("{") == doc.count("}")


def test_cli_prints_plain_and_latex(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert cli_main(["derive"]) == 0
    out = capsys.readouterr().out
    section = out.split("System (29), corrected: seven equations:")[1].split("\n\n")[0]
    assert len([ln for ln in section.splitlines() if ln.strip().endswith("= 0")]) == 7
    assert "alphadot_1 = (betadot*l_1 + v_A)/r_1" in out
    target = tmp_path / "derivation.tex"
    assert cli_main(["derive", "--latex", "--out", str(target)]) == 0
    assert target.read_text(encoding="utf-8") == S.render(latex=True)
    assert [p.name for p in tmp_path.iterdir()] == ["derivation.tex"]  # no temporary file left


def test_cli_bad_input_is_one_line_error(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert S.main(["--out", str(tmp_path / "missing" / "x.tex")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "does not exist" in err
    with pytest.raises(SystemExit) as exc:
        S.main(["--no-such-option"])
    assert exc.value.code == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_lambdify_refuses_missing_and_nonfinite_values(d: S.Derivation) -> None:
    f = S.lambdify([d.eq11])
    with pytest.raises(ValueError, match="missing value for 'v_A'"):
        f(xdot_A=1.0, beta=0.0)
    with pytest.raises(ValueError, match="v_A must be finite"):
        f(xdot_A=1.0, beta=0.0, v_A=float("nan"))


def test_import_amigo_gym_does_not_import_sympy() -> None:
    code = (
        "import sys, gymnasium as gym, amigo_gym, amigo_gym.model.kinematics, amigo_gym.paths, amigo_gym.task.v0\n"
        "env = gym.make('AmigoBot-v0'); env.reset(seed=0); env.step(env.action_space.sample())\n"
        "print('sympy' in sys.modules, 'amigo_gym.tools.symbolic' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False"]
