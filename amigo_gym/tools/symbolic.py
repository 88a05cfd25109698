r"""Symbolic Denavit–Hartenberg derivation of the AmigoBot kinematics (SymPy), from the transforms to system (29).

The steps, the equations and the paper's misprints: docs/derivation.md.
"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp
from numpy.typing import ArrayLike, NDArray

from amigo_gym.io import atomic_write
from amigo_gym.model.params import RobotParams
from amigo_gym.tools.options import cli, run_command

Array = NDArray[np.float64]

#: time [s]
t = sp.Symbol("t", real=True)


# each coordinate q: its time function q(t) (the paper's Maple variables) and plain symbols q, qdot at one instant
_NAMES = ("x_A", "y_A", "beta", "alpha_1", "alpha_2", "alpha_3", "phi", "s", "gamma")
_COORDS: tuple[tuple[Any, Any, Any], ...] = tuple(
    (sp.Function(n, real=True)(t), *sp.symbols([n, n.replace("_", "dot_") if "_" in n else n + "dot"], real=True))
    for n in _NAMES
)
xA_t, yA_t, beta_t, alpha1_t, alpha2_t, alpha3_t, phi_t, s_t, gamma_t = (c[0] for c in _COORDS)
x_A, y_A, beta, alpha_1, alpha_2, alpha_3, phi, s, gamma = (c[1] for c in _COORDS)
xdot_A, ydot_A, betadot, alphadot_1, alphadot_2, alphadot_3, phidot, sdot, gammadot = (c[2] for c in _COORDS)
_TO_PLAIN: dict[Any, Any] = {k: v for f, p, pd in _COORDS for k, v in ((sp.Derivative(f, t), pd), (f, p))}

# constants: lengths [m] and the speed of A [m/s]; the path tangent angle at H [rad], the heading lag theta - beta
l1, l3, l4, l5, r1, r2, r3, R = sp.symbols("l_1 l_3 l_4 l_5 r_1 r_2 r_3 R", positive=True)
v_A, theta, delta = sp.symbols("v_A theta delta", real=True)

#: every plain symbol an expression of :func:`derive` may contain, by name (the keyword names of :func:`lambdify`)
PLAIN_SYMBOLS: dict[str, Any] = {str(x): x for c in _COORDS for x in c[1:]}
PLAIN_SYMBOLS |= {str(x): x for x in (l1, l3, l4, l5, r1, r2, r3, R, v_A, theta, delta)}


def to_plain(expr: Any) -> Any:
    """Replace the time functions ``q(t)`` and ``dq/dt`` by the plain symbols ``q``, ``qdot`` (a matrix: immutable)."""
    return sp.sympify(expr).xreplace(_TO_PLAIN)


def _simp(expr: Any) -> Any:
    """Trigonometric simplification to an expanded canonical form (expressions or matrices)."""
    if isinstance(expr, sp.MatrixBase):
        return sp.ImmutableMatrix(expr.applyfunc(_simp))
    return sp.expand(sp.trigsimp(sp.expand(expr)))


def _frame(angle: Any, x: Any, y: Any, z: Any) -> Any:
    """Homogeneous transform: rotation ``angle`` about z, then translation ``(x, y, z)``."""
    c, si = sp.cos(angle), sp.sin(angle)
    return sp.ImmutableMatrix([[c, -si, 0, x], [si, c, 0, y], [0, 0, 1, z], [0, 0, 0, 1]])


def _wheel(alpha: Any, radius: Any) -> tuple[Any, Any]:
    """A wheel turned by ``alpha``: its D–H transform into the vehicle frame (eqs 15, 23) and its contact point in
    its frame, ``(-r cos alpha, r sin alpha, 0, 1)`` (eqs 16, 24)."""
    c, si = sp.cos(alpha), sp.sin(alpha)
    transform = sp.ImmutableMatrix([[si, c, 0, 0], [0, 0, 1, 0], [c, -si, 0, 0], [0, 0, 0, 1]])
    return transform, sp.ImmutableMatrix([-radius * c, radius * si, 0, 1])


@dataclass(frozen=True)
class Transforms:
    """The paper's homogeneous transforms (4x4) and point vectors (4x1), coordinates as functions of ``t``.

    Attributes:
        T40H, rho_H: eqs 2, 3: vehicle frame 4 placed at H's vertical, into frame 0; H in it, ``(0, 0, -l4, 1)``.
        T40K, T14, rho_K: eqs 14, 15, 16: frame 4 placed at the centre of wheel 1 (right), into frame 0; the frame
            of wheel 1 (turned by ``alpha1``) into frame 4; the contact point K in the frame of wheel 1.
        T40L, T24, rho_L: eqs 22, 23, 24: the same for wheel 2 (left, ``alpha2``) and its contact point L.
        T40S, TSw, T3S, rho_C: the castor (not printed in the paper): frame 4 placed at its swivel, ``l5`` behind A
            at height ``r3``; the swivel's rotation ``gamma`` about the vertical; the castor wheel's frame
            (``alpha3``) and contact point, as eqs 15, 16 with ``r3``.
    """

    T40H: Any
    rho_H: Any
    T40K: Any
    T14: Any
    rho_K: Any
    T40L: Any
    T24: Any
    rho_L: Any
    T40S: Any
    TSw: Any
    T3S: Any
    rho_C: Any


@functools.lru_cache(maxsize=1)
def transforms() -> Transforms:
    """Build the transforms of the paper (eqs 2, 3, 14, 15, 16, 22, 23, 24) and the castor's, in time-function form."""
    b = beta_t
    cb, sb = sp.cos(b), sp.sin(b)
    return Transforms(  # in the order of the fields
        _frame(b, xA_t + l3 * cb, yA_t + l3 * sb, r1),
        sp.ImmutableMatrix([0, 0, -l4, 1]),
        _frame(b, xA_t + l1 * sb, yA_t - l1 * cb, r1),
        *_wheel(alpha1_t, r1),
        _frame(b, xA_t - l1 * sb, yA_t + l1 * cb, r2),
        *_wheel(alpha2_t, r2),
        _frame(b, xA_t - l5 * cb, yA_t - l5 * sb, r3),
        _frame(gamma_t, 0, 0, 0),
        *_wheel(alpha3_t, r3),
    )


def material_velocity(chain: Sequence[Any], rho: Any) -> Any:
    r"""Velocity of the material point at ``rho``, fixed in the last frame of ``chain``, by the product rule.

    .. math:: \bar v = \frac{d}{dt}\Big(\prod_i T_i\Big)\bar\rho
              = \sum_i T_1 \cdots \dot T_i \cdots T_n\,\bar\rho

    ``rho`` is *frozen*: it is not differentiated (it names the point currently in contact, and the velocity
    wanted is that of the wheel's material point there). Time-function form in, time-function form out.
    """
    factors = [[sp.diff(m, t) if i == j else m for j, m in enumerate(chain)] for i in range(len(chain))]
    return sp.ImmutableMatrix(sum((math.prod(f, start=sp.eye(4)) * rho for f in factors), sp.zeros(4, 1)))


#: labels of the seven equations of system (29): the paper's numbers, and the castor's
SYSTEM_29_LABELS: tuple[str, ...] = ("9", "10", "11", "12", "19", "27", "castor")


@dataclass(frozen=True)
class Misprints:
    """The paper's misprinted forms, as printed (plain symbols), for showing that they are not identities.

    Attributes:
        eq17, eq25: ``Tdot_{4,0,K} Tdot_{1,4} rho_K``, ``Tdot_{4,0,L} Tdot_{2,4} rho_L`` (products of derivatives).
        eq18, eq26: eqs 18, 26's right-hand sides with ``x_A``, ``y_A`` (positions) in place of velocities.
        eq28: eq. 28, ``y_A - r2 alpha2dot sin b - l1 betadot sin b``.
        contact_point_velocity_K: full derivative of ``r_K`` (``rho_K`` differentiated too): the velocity of the
            geometric contact point, not of the wheel's material point; it is not zero when the wheel rolls.
    """

    eq17: Any
    eq25: Any
    eq18: Any
    eq26: Any
    eq28: Any
    contact_point_velocity_K: Any


@dataclass(frozen=True)
class Derivation:
    """Everything derived from the transforms, in plain symbols (``x_A``, ``xdot_A``, ``alphadot_1``, ...).

    Vectors are 4x1 immutable matrices in homogeneous coordinates of frame 0; every ``eq*`` is a left-hand side
    whose equation is ``eq = 0``.

    Attributes:
        r_H: eq. 4, ``T_{4,0,H} rho_H``.
        r_K, r_L: contact points of wheels 1 and 2, ``T_{4,0,K} T_{1,4} rho_K``, ``T_{4,0,L} T_{2,4} rho_L``.
        v_K, v_L: velocities of the wheels' material points at K and L (eqs 18, 26 corrected), product rule, ``rho``
            frozen.
        v_S, v_C: velocities of the castor's swivel S (a body point) and of its wheel's material point in contact.
        eq7, eq8: H on the path of eq. 6 (``r_H - path = 0``), x and y.
        eq9, eq10: their time derivatives.
        eq11, eq12: ``xdot_A - v_A cos b``, ``ydot_A - v_A sin b``.
        eq19, eq20, eq27, eq28: ``v_K = 0`` and ``v_L = 0``, x and y.
        eq_castor: ``sqrt(l5^2 betadot^2 + v_A^2) - r3 alphadot_3`` (forward motion).
        system_29: the seven equations (9, 10, 11, 12, 19, 27, castor), left-hand sides.
        slip_K, slip_L: the components of ``v_K``, ``v_L`` across the heading after eqs 11–12 (identically 0).
        roll_K, roll_L: their components along the heading after eqs 11–12.
        wheel_rates: ``{alphadot_1: ..., alphadot_2: ...}`` solving ``roll_K = roll_L = 0``.
        body_velocity: ``{v_A: ..., betadot: ...}`` solving the same for the motion.
        castor_swivel: the castor's swivel angle ``gamma`` relative to the body that makes it roll.
        castor_rate: ``alphadot_3`` from rolling of the castor (forward motion).
        eq9_path, eq10_path: eqs 9–10 for a general path with tangent angle ``theta`` and arc rate ``sdot``.
        inverse_ode: ``{sdot: ..., betadot: ...}`` from eqs 9–12 for a general path.
        heading_lag_rate: ``d(theta - beta)/dt`` on a circle of radius ``R`` as a function of ``delta``.
        steady_lag: steady heading lag ``delta`` on the circle (``asin(l3/R)``).
        steady: steady-state values on the circle: ``{betadot, sdot, alphadot_1, alphadot_2, alphadot_3}``.
        misprints: the paper's misprinted forms.
    """

    r_H: Any
    r_K: Any
    r_L: Any
    v_K: Any
    v_L: Any
    v_S: Any
    v_C: Any
    eq7: Any
    eq8: Any
    eq9: Any
    eq10: Any
    eq11: Any
    eq12: Any
    eq19: Any
    eq20: Any
    eq27: Any
    eq28: Any
    eq_castor: Any
    system_29: tuple[Any, ...]
    slip_K: Any
    slip_L: Any
    roll_K: Any
    roll_L: Any
    wheel_rates: dict[Any, Any]
    body_velocity: dict[Any, Any]
    castor_swivel: Any
    castor_rate: Any
    eq9_path: Any
    eq10_path: Any
    inverse_ode: dict[Any, Any]
    heading_lag_rate: Any
    steady_lag: Any
    steady: dict[str, Any]
    misprints: Misprints


def _solve_one(eqs: Sequence[Any], unknowns: Sequence[Any]) -> dict[Any, Any]:
    sols = sp.solve(list(eqs), list(unknowns), dict=True)
    if len(sols) != 1:  # pragma: no cover - a property of the derivation, checked by the tests
        raise RuntimeError(f"expected one solution for {unknowns}, got {sols}")
    return {k: sp.simplify(v) for k, v in sols[0].items()}


@functools.lru_cache(maxsize=1)
def derive() -> Derivation:
    """Carry out the whole derivation (a few seconds; cached); the steps: docs/derivation.md."""
    T = transforms()
    cb, sb = sp.cos(beta), sp.sin(beta)
    motion_of_a = {xdot_A: v_A * cb, ydot_A: v_A * sb}  # eqs 11-12 solved

    def along(v: Any, angle: Any) -> Any:  # the component of v along the direction ``angle``, with eqs 11-12
        return (sp.cos(angle) * v[0] + sp.sin(angle) * v[1]).subs(motion_of_a)

    # 1-2: positions
    r_H_t = T.T40H * T.rho_H
    r_H = _simp(to_plain(r_H_t))
    r_K = _simp(to_plain(T.T40K * T.T14 * T.rho_K))
    r_L = _simp(to_plain(T.T40L * T.T24 * T.rho_L))

    # 3: material-point velocities (product rule, rho frozen)
    v_K = _simp(to_plain(material_velocity([T.T40K, T.T14], T.rho_K)))
    v_L = _simp(to_plain(material_velocity([T.T40L, T.T24], T.rho_L)))
    v_S = _simp(to_plain(material_velocity([T.T40S], sp.ImmutableMatrix([0, 0, -r3, 1]))))
    v_C = _simp(to_plain(material_velocity([T.T40S, T.TSw, T.T3S], T.rho_C)))

    # 4: rolling constraints, reduced with the motion of A
    slip_K, slip_L, roll_K, roll_L = (_simp(along(v, a)) for a in (beta + sp.pi / 2, beta) for v in (v_K, v_L))
    wheel_rates = _solve_one([roll_K, roll_L], [alphadot_1, alphadot_2])
    body_velocity = _solve_one([roll_K, roll_L], [v_A, betadot])

    # 5: castor: v_C = 0 <=> v_S = r3 alphadot_3 (cos(b + gamma), sin(b + gamma))
    c_across = _simp(along(v_C, beta + gamma + sp.pi / 2))  # = -v_A sin g - l5 betadot cos g
    castor_swivel = sp.atan2(-l5 * betadot, v_A)
    c_along = along(v_C, beta + gamma)
    castor_rate = _solve_one([sp.simplify(c_along.subs(gamma, castor_swivel))], [alphadot_3])[alphadot_3]
    if sp.simplify(c_across.subs(gamma, castor_swivel)) != 0:  # pragma: no cover
        raise RuntimeError("castor swivel angle does not cancel the lateral slip")
    eq_castor = r3 * castor_rate - r3 * alphadot_3

    # 6: H on the circle (eq 6), eqs 7-10
    eq7_t, eq8_t = r_H_t[0] - R * sp.sin(phi_t), r_H_t[1] - R * (1 - sp.cos(phi_t))
    eq7, eq8 = to_plain(eq7_t), to_plain(eq8_t)
    eq9, eq10 = _simp(to_plain(sp.diff(eq7_t, t))), _simp(to_plain(sp.diff(eq8_t, t)))
    eq11, eq12 = xdot_A - v_A * cb, ydot_A - v_A * sb

    # a general path: d/dt path(s(t)) = sdot (cos theta, sin theta)
    eq9_path = _simp(to_plain(sp.diff(r_H_t[0], t)) - sdot * sp.cos(theta))
    eq10_path = _simp(to_plain(sp.diff(r_H_t[1], t)) - sdot * sp.sin(theta))
    ode = _solve_one([eq9_path.subs(motion_of_a), eq10_path.subs(motion_of_a)], [sdot, betadot])
    inverse_ode = {k: sp.trigsimp(v) for k, v in ode.items()}

    # steady state on a circle (curvature 1/R): d(theta - beta)/dt = sdot / R - betadot = 0
    in_lag = {theta: beta + delta}
    heading_lag_rate = sp.simplify((inverse_ode[sdot] / R - inverse_ode[betadot]).subs(in_lag))
    roots = [d for d in sp.solve(sp.simplify(heading_lag_rate * sp.cos(delta)), delta) if not d.has(sp.pi)]
    if len(roots) != 1:  # pragma: no cover
        raise RuntimeError(f"expected one steady heading lag in (-pi/2, pi/2), got {roots}")
    steady_lag = roots[0]
    bd_ss = sp.simplify(inverse_ode[betadot].subs(in_lag).subs(delta, steady_lag))
    forward = sp.Symbol("v_A", positive=True)  # the steady state is driven forward: |v_A| = v_A

    def steady_value(e: Any) -> Any:
        return sp.simplify(e.subs(v_A, forward)).subs(forward, v_A)

    steady = {
        "betadot": bd_ss,
        "sdot": steady_value(inverse_ode[sdot].subs(in_lag).subs(delta, steady_lag)),
        "alphadot_1": steady_value(wheel_rates[alphadot_1].subs(betadot, bd_ss)),
        "alphadot_2": steady_value(wheel_rates[alphadot_2].subs(betadot, bd_ss)),
        "alphadot_3": steady_value(castor_rate.subs(betadot, bd_ss)),
    }

    eq19, eq20, eq27, eq28 = v_K[0], v_K[1], v_L[0], v_L[1]
    system_29 = (eq9, eq10, eq11, eq12, eq19, eq27, eq_castor)

    def printed(r: Any, alphadot: Any, sign: int) -> list[Any]:  # eqs 18, 26 as printed: positions for velocities
        return [x_A - r * alphadot * cb + sign * l1 * betadot * cb, y_A - r * alphadot * sb + sign * l1 * betadot * sb]

    misprints = Misprints(
        eq17=_simp(to_plain(sp.diff(T.T40K, t) * sp.diff(T.T14, t) * T.rho_K)),
        eq25=_simp(to_plain(sp.diff(T.T40L, t) * sp.diff(T.T24, t) * T.rho_L)),
        eq18=sp.ImmutableMatrix([*printed(r1, alphadot_1, 1), 0, 0]),
        eq26=sp.ImmutableMatrix([*printed(r2, alphadot_2, -1), 0, 0]),
        eq28=printed(r2, alphadot_2, -1)[1],
        contact_point_velocity_K=_simp(to_plain(sp.diff(T.T40K * T.T14 * T.rho_K, t))),
    )
    # every field of Derivation is a local variable of the same name
    return Derivation(**{k: v for k, v in locals().items() if k in Derivation.__dataclass_fields__})


def robot_values(robot: RobotParams) -> dict[str, float]:
    """The lengths of ``robot`` [m] by symbol name, for :func:`lambdify`'s keyword arguments."""
    return {f"{n[0]}_{n[1]}": float(getattr(robot, n)) for n in ("l1", "l3", "l4", "l5", "r1", "r2", "r3")}


def lambdify(exprs: Sequence[Any]) -> Callable[..., Array]:
    """Batched numpy function ``f(**values)`` of ``n`` expressions in plain symbols (:data:`PLAIN_SYMBOLS`): keyword
    arguments named after their symbols (e.g. ``x_A``, ``l_1``; extra names ignored), finite scalars or arrays that
    broadcast; the result has shape ``(..., n)``. ``f`` raises ``ValueError`` for a missing or non-finite value."""
    exprs = [sp.sympify(e) for e in exprs]
    syms = sorted(set().union(*(e.free_symbols for e in exprs)), key=str)
    if unknown := [str(x) for x in syms if str(x) not in PLAIN_SYMBOLS]:
        raise ValueError(f"expressions contain symbols outside PLAIN_SYMBOLS: {unknown}")
    fn = sp.lambdify(syms, exprs, modules="numpy")
    names = [str(x) for x in syms]

    def call(**values: ArrayLike) -> Array:
        args = []
        for name in names:
            if name not in values:
                raise ValueError(f"missing value for {name!r} (needed: {', '.join(names)})")
            a = np.asarray(values[name], dtype=np.float64)
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name} must be finite, got {values[name]!r}")
            args.append(a)
        out = [np.asarray(o, dtype=np.float64) for o in fn(*args)]
        return np.stack(np.broadcast_arrays(*out, *args), axis=-1)[..., : len(out)]

    return call


def system_29_latex() -> list[str]:
    """System (29) as LaTeX, one string ``"<lhs> = 0"`` per equation, in the order of :data:`SYSTEM_29_LABELS`."""
    return [f"{sp.latex(e)} = 0" for e in derive().system_29]


def _sections(latex: bool) -> dict[str, list[tuple[str | None, str, str]]]:  # rows: (label or None, lhs, rhs)
    d, mp, lag = derive(), derive().misprints, {theta: beta + delta}

    def f(e: Any) -> str:
        if latex:
            return str(sp.latex(e))
        return "(" + ", ".join(sp.sstr(x) for x in e) + ")" if isinstance(e, sp.MatrixBase) else str(sp.sstr(e))

    def eq(label: str | None, lhs: Any, rhs: Any, tex: str | None = None) -> tuple[str | None, str, str]:
        return (label, f(lhs) if tex is None else tex if latex else lhs, f(rhs))  # tex: the LaTeX of a named lhs

    return {
        "Positions (eqs 4, 13, 21): H, and the contact points K (wheel 1, right) and L (wheel 2, left)": [
            eq("4", "r_H", d.r_H, r"\bar r_H"),
            eq("13", "r_K", d.r_K, r"\bar r_K"),
            eq("21", "r_L", d.r_L, r"\bar r_L"),
        ],
        "Velocities of the wheels' material points in contact (eqs 18, 26 corrected): d/dt(T40 T14) rho with rho "
        "frozen": [eq("18", "v_K", d.v_K, r"\bar v_K"), eq("26", "v_L", d.v_L, r"\bar v_L")],
        "System (29), corrected: seven equations": [
            eq(lab, e, 0) for lab, e in zip(SYSTEM_29_LABELS, d.system_29, strict=True)
        ],
        "Solution of v_K = v_L = 0 with eqs 11-12: no side slip, and the differential-drive relations": [
            eq(None, "v_K across the heading", d.slip_K, r"\bar v_K \cdot \bar e_\perp"),
            eq(None, "v_L across the heading", d.slip_L, r"\bar v_L \cdot \bar e_\perp"),
            *[eq(None, k, v) for k, v in (d.wheel_rates | d.body_velocity).items()],
        ],
        "Castor: rolling of its material contact point (swivel gamma relative to the body, trail neglected)": [
            eq(None, gamma, d.castor_swivel),
            eq(None, alphadot_3, d.castor_rate),
        ],
        "Inverse kinematics from eqs 9-12: H on a path with tangent angle theta(s), delta = theta - beta": [
            eq(None, k, sp.simplify(v.subs(lag))) for k, v in sorted(d.inverse_ode.items(), key=str, reverse=True)
        ],
        "Steady state of H on a circle of radius R": [
            eq(None, delta, d.steady_lag),
            *[eq(None, PLAIN_SYMBOLS[k], v) for k, v in d.steady.items()],
        ],
        "The paper's misprinted forms (not identities)": [
            eq("17", "Tdot40K Tdot14 rho_K", mp.eq17, r"\dot T_{4,0,K}\,\dot T_{1,4}\,\bar\rho_K"),
            eq("18", "printed v_K", mp.eq18, r"\text{printed } \bar v_K"),
            eq("26", "printed v_L", mp.eq26, r"\text{printed } \bar v_L"),
            eq("28", mp.eq28, 0),
        ],
    }


def render(latex: bool = False) -> str:
    """The derivation as text (``latex``: a LaTeX fragment, amsmath ``align`` environments, eq. numbers as tags)."""
    head = "Symbolic D-H derivation of the AmigoBot kinematics (amigo-gym derive"
    out = [f"% {head} --latex); needs amsmath" if latex else f"{head})"]
    for title, rows in _sections(latex).items():
        if latex:
            lines = [f"{lhs} &= {rhs} " + (f"\\tag{{{lab}}}" if lab else r"\notag") for lab, lhs, rhs in rows]
            out += [f"% {title}", r"\begin{align}", " \\\\\n".join(lines), r"\end{align}"]
        else:
            out += ["", title + ":", *(f"  {f'({lab})' if lab else '':<9}{lhs} = {rhs}" for lab, lhs, rhs in rows)]
    return "\n".join(out) + "\n"


@dataclass(frozen=True)
class DeriveSettings:
    """Options of ``amigo-gym derive``, each the option of the same name.

    Attributes:
        latex: emit LaTeX (amsmath align environments).
        out: write to FILE, atomically [file] (default: standard output; '-' too).
    """

    latex: bool = False
    out: str | None = field(default=None, metadata=cli(metavar="FILE"))


def _derive(args: DeriveSettings) -> None:
    text = render(latex=args.latex)
    if args.out is None or args.out == "-":
        sys.stdout.write(text)
    else:
        atomic_write(args.out, text)
        print(f"wrote {args.out}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym derive [--latex] [--out FILE]``: print (or write) the symbolic derivation and system (29)."""
    return run_command(DeriveSettings, _derive, argv, "amigo-gym derive", __doc__.splitlines()[0])
