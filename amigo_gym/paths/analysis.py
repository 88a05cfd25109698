"""What a path asks of the robot: the path ahead in the robot's frame (:func:`preview`) and the wheel rates and
accelerations the exact inverse solution needs (:func:`feasibility`), for any
:class:`~amigo_gym.paths.clothoid.PathSpec`."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import NDArray

from amigo_gym.model.kinematics import Real, wheel_rates_of
from amigo_gym.model.params import RobotParams, check_real
from amigo_gym.paths.clothoid import PathSpec

Array = NDArray[np.float64]


class Preview(NamedTuple):
    """The path at ``K`` distances ahead in the robot's frame, arrays ``(..., K)``: coordinates ``forward`` along
    the robot's heading and ``left`` of it [m], the signed ``curvature`` there [1/m], the arc lengths ``s`` [m]."""

    forward: Array
    left: Array
    curvature: Array
    s: Array


def preview(path: PathSpec, x: Real, y: Real, heading: Real, s: Real, distances: Sequence[float]) -> Preview:
    r"""The :class:`Preview` ``(..., K)`` of the path points at arc lengths ``s + d_i`` [m] (``s`` [m] a column
    ``(...)``, ``distances`` ``d_i`` [m] ``K`` finite numbers, negative behind) in the frame of the pose ``x, y``
    [m], ``heading`` ``beta`` [rad] (columns ``(...)``): with ``(dx, dy) = c(s + d_i) - (x, y)``,

    .. math:: f_i = \cos\beta\,dx + \sin\beta\,dy, \qquad l_i = -\sin\beta\,dx + \cos\beta\,dy.
    """
    d = np.asarray([check_real("preview", f"distances[{i}]", v) for i, v in enumerate(distances)], dtype=np.float64)
    sk = np.asarray(s, dtype=np.float64)[..., None] + d
    p = path.pose_columns(sk)
    dx = np.asarray(p.x) - np.asarray(x, dtype=np.float64)[..., None]
    dy = np.asarray(p.y) - np.asarray(y, dtype=np.float64)[..., None]
    b = np.asarray(heading, dtype=np.float64)[..., None]
    cb, sb = np.cos(b), np.sin(b)
    kappa = np.broadcast_to(np.asarray(p.curvature, dtype=np.float64), sk.shape).copy()
    return Preview(cb * dx + sb * dy, cb * dy - sb * dx, kappa, sk)


#: largest arc-length step of the heading-lag integration, as a fraction of ``l3``
STEP_FRACTION = 1.0 / 64.0
#: arc length of the warm-up of a closed path [l3] (the lag forgets its start as ``exp(-s cos(psi) / l3)``)
WARMUP_L3 = 60.0


class LagProfile(NamedTuple):
    """The heading lag along a path (:func:`heading_lag_profile`), arrays ``(M,)``: arc lengths ``s`` [m],
    increasing (a sample at each side of every breakpoint), the lag ``psi = theta - beta`` [rad],
    ``dpsi_ds = kappa - sin(psi) / l3`` [rad/m] and the path ``curvature`` [1/m]."""

    s: Array
    psi: Array
    dpsi_ds: Array
    curvature: Array


def _grid(path: PathSpec, start: float, stop: float, h_max: float) -> tuple[Array, Array]:
    # step ends (s_i, s_i+1) of at most h_max covering [start, stop], aligned with the path's breakpoints if any
    brk = getattr(path, "breakpoints", None)
    pts = [start, stop]
    if callable(brk):
        length = path.length
        base = [float(b) for b in brk()]
        lap0 = math.floor(start / length) if path.closed else 0
        lap1 = math.ceil(stop / length) if path.closed else 0
        for lap in range(lap0, lap1 + 1):
            pts.extend(b + lap * length for b in base)
    knots = np.unique(np.clip(np.asarray(pts, dtype=np.float64), start, stop))
    edges = [knots[:1]]
    for a, b in itertools.pairwise(knots):
        n = max(1, math.ceil((b - a) / h_max))
        e = a + (b - a) * np.arange(1, n + 1) / n
        e[-1] = b
        edges.append(e)
    e = np.concatenate(edges)
    return e[:-1], e[1:]


def heading_lag_profile(
    path: PathSpec, robot: RobotParams, initial_lag: float | None = None, step_fraction: float = STEP_FRACTION
) -> LagProfile:
    r"""The heading lag ``psi = theta - beta`` of the exact inverse solution along a path (H on the path).

    From ``v_A (cos, sin)(beta) + l3 betadot (-sin, cos)(beta) = v_H (cos, sin)(theta)``: ``v_A = v_H cos psi``,
    ``l3 betadot = v_H sin psi`` and, per unit arc length of H,

    .. math:: \frac{d\psi}{ds} = \kappa(s) - \frac{\sin\psi}{l_3},

    by classical Runge–Kutta with steps of at most ``step_fraction l3`` (in [1e-3, 0.5]) aligned with
    ``path.breakpoints()`` if present. An open path from its start to its end, from ``initial_lag`` [rad] (None:
    ``asin(kappa(0) l3)``, clipped); a closed one over one lap after a warm-up of whole laps of at least
    :data:`WARMUP_L3` ``l3`` (the periodic solution)."""
    l3, o = robot.l3, "heading_lag_profile"
    frac = check_real(o, "step_fraction", step_fraction, 1e-3, 0.5)
    h_max = frac * l3
    length = path.length
    warm = length * math.ceil(WARMUP_L3 * l3 / length) if path.closed else 0.0
    a, b = _grid(path, 0.0 - warm, length, h_max)  # (+0.0 when open)
    mid = 0.5 * (a + b)
    b_left = np.nextafter(b, a)
    k_a, k_m, k_b = (
        np.asarray(path.pose_columns(u).curvature, dtype=np.float64) * np.ones_like(a) for u in (a, mid, b_left)
    )
    if initial_lag is None:
        psi = math.asin(min(max(float(k_a[0]) * l3, -1.0), 1.0))
    else:
        psi = check_real(o, "initial_lag", initial_lag, -math.pi / 2, math.pi / 2, low_open=True, high_open=True)
    inv = 1.0 / l3
    n = len(a)
    psi_a, psi_b = np.empty(n), np.empty(n)
    hs = (b - a).tolist()
    ka, km, kb = k_a.tolist(), k_m.tolist(), k_b.tolist()
    sin = math.sin
    for i in range(n):
        h = hs[i]
        psi_a[i] = psi
        f1 = ka[i] - sin(psi) * inv
        f2 = km[i] - sin(psi + 0.5 * h * f1) * inv
        f3 = km[i] - sin(psi + 0.5 * h * f2) * inv
        f4 = kb[i] - sin(psi + h * f3) * inv
        psi = psi + h * (f1 + 2.0 * f2 + 2.0 * f3 + f4) / 6.0
        psi_b[i] = psi
    keep = a >= 0.0
    s, ps, kk = (np.concatenate((u[keep], w[keep])) for u, w in ((a, b), (psi_a, psi_b), (k_a, k_b)))
    order = np.argsort(s, kind="stable")
    s, ps, kk = s[order], ps[order], kk[order]
    return LagProfile(s, ps, kk - np.sin(ps) * inv, kk)


#: the quantities of :func:`feasibility`: unit and keyword of the limit
QUANTITIES = {
    "wheel_rate": ("rad/s", "max_wheel_rate"),
    "wheel_acceleration": ("rad/s^2", "max_wheel_acceleration"),
    "acceleration": ("m/s^2", "max_acceleration"),
    "rotation_rate": ("rad/s", "max_rotation_rate"),
    "rotational_acceleration": ("rad/s^2", "max_rotational_acceleration"),
}


@dataclass(frozen=True)
class Feasibility:
    """What tracking a path at the reference ``speed`` [m/s] of ``speed_of`` (``"A"``, AmigoBot-v0's, or ``"H"``)
    needs: the ``peaks`` over the path of the :data:`QUANTITIES` (units there; ``acceleration`` of A along its
    heading) at arc lengths ``peak_s`` [m], ``peak_wheel`` ``"outer"``, ``"inner"`` or ``"each"`` for the wheel
    ones, the ``limits`` checked; ``binding``: the quantity of the largest need over limit (``"heading lag"`` if the
    lag reaches 90 degrees: H cannot follow), its ``needed`` and ``limit``, the path ``radius`` ``1/|kappa|`` [m]
    there (``inf`` on a straight); ``feasible``: all within the limits and the lag below 90 degrees;
    ``max_heading_lag`` ``max |theta - beta|`` [rad]; ``exceeded``: per quantity (and ``"heading lag"``) the
    arc-length intervals ``(s_from, s_to)`` [m] over the limit (at most :data:`MAX_INTERVALS`, the rest merged)."""

    speed: float
    speed_of: str
    peaks: dict[str, float]
    peak_s: dict[str, float]
    peak_wheel: dict[str, str]
    limits: dict[str, float]
    binding: str
    needed: float
    limit: float
    radius: float
    feasible: bool
    max_heading_lag: float
    exceeded: dict[str, tuple[tuple[float, float], ...]] = field(default_factory=dict)

    def report(self) -> dict[str, Any]:
        """A JSON-able summary: ``feasible``, ``message`` (:meth:`message`), ``speed`` [m/s], ``speed_of``,
        ``binding``, ``peaks``, ``peak_s`` [m], ``limits`` and ``exceeded`` (intervals as ``[s_from, s_to]`` lists)."""
        out = {"feasible": self.feasible, "message": self.message(), "speed": self.speed, "speed_of": self.speed_of}
        out |= {"binding": self.binding, "peaks": dict(self.peaks), "peak_s": dict(self.peak_s)}
        exceeded = {k: [list(iv) for iv in v] for k, v in self.exceeded.items()}
        return out | {"limits": dict(self.limits), "exceeded": exceeded}

    def message(self) -> str:
        """One line, e.g. ``path: speed 0.74 m/s on radius 1 m needs 16.6 rad/s on the outer wheel, above the
        robot's limit of 15 rad/s``."""
        where = "on a straight line" if math.isinf(self.radius) else f"on radius {self.radius:.3g} m"
        of = "" if self.speed_of == "A" else f" of {self.speed_of}"
        head = f"path: speed {self.speed:.3g} m/s{of} {where}"
        if self.binding == "heading lag":
            return f"{head} turns the heading 90 degrees away from the path: H cannot follow it"
        unit = QUANTITIES[self.binding][0]
        need = f"{self.needed:.3g} {unit}" + ("" if self.binding == "wheel_rate" else f" of {self.binding}")
        if self.binding.startswith("wheel"):
            wheel = self.peak_wheel[self.binding]
            need += " on each wheel" if wheel == "each" else f" on the {wheel} wheel"
        need = need.replace("_", " ")
        verdict = "above" if self.needed > self.limit else "within"
        return f"{head} needs {need}, {verdict} the robot's limit of {self.limit:.3g} {unit}"


def feasibility(
    path: PathSpec, speed: float, robot: RobotParams | None = None, speed_of: Literal["A", "H"] = "A", *,
    max_wheel_rate: float | None = None, max_wheel_acceleration: float | None = None,
    max_acceleration: float | None = None, max_rotation_rate: float | None = None,
    max_rotational_acceleration: float | None = None, initial_lag: float | None = None,
) -> Feasibility:  # fmt: skip
    r"""Peak wheel rate, accelerations and turn rates the exact inverse solution needs to track ``path`` at ``speed``.

    From the heading lag ``psi(s)`` (:func:`heading_lag_profile`), at every sample, with ``v_H = speed``
    (``speed_of="H"``) or ``speed / cos psi`` (``"A"``) and ``psi_t = v_H dpsi/ds``:

    .. math::
        v_A = v_H \cos\psi,\quad \dot\beta = \frac{v_H \sin\psi}{l_3},\quad
        \dot\alpha_{1,2} = \frac{v_A \pm l_1 \dot\beta}{r_{1,2}};

    constant ``v_H``: ``dv_A/dt = -v_H sin(psi) psi_t``, ``betaddot = v_H cos(psi) psi_t / l3``; constant
    ``v_A``: ``dv_A/dt = 0``, ``betaddot = v_A psi_t / (l3 cos^2 psi)``; then
    ``alphaddot_{1,2} = (dv_A/dt +- l1 betaddot) / r_{1,2}``.
    Peaks are over the samples (both sides of every breakpoint): a smooth maximum between samples ``h`` apart is
    underestimated by at most ``h^2/8 max|f''|``.

    ``speed`` [m/s] in (0, 10]; ``robot`` default :class:`RobotParams`; ``max_wheel_rate`` [rad/s] default
    ``robot.max_wheel_rate``; the other limits (units of :data:`QUANTITIES`) None: not checked (peaks reported);
    ``initial_lag`` as :func:`heading_lag_profile`."""
    robot = RobotParams() if robot is None else robot
    v = check_real("feasibility", "speed", speed, 0.0, 10.0, low_open=True)
    if speed_of not in ("A", "H"):
        raise ValueError(f"feasibility.speed_of must be 'A' or 'H', got {speed_of!r}")
    w_max = robot.max_wheel_rate if max_wheel_rate is None else max_wheel_rate
    given = (w_max, max_wheel_acceleration, max_acceleration, max_rotation_rate, max_rotational_acceleration)
    limits = {  # in the order of QUANTITIES
        k: check_real("feasibility", QUANTITIES[k][1], x, 0.0, low_open=True)
        for k, x in zip(QUANTITIES, given, strict=True)
        if x is not None
    }
    prof = heading_lag_profile(path, robot, initial_lag)
    psi, kappa = prof.psi, prof.curvature
    cos_p, sin_p = np.cos(psi), np.sin(psi)
    l1, l3 = robot.l1, robot.l3
    max_lag = float(np.max(np.abs(psi)))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        on_h = speed_of == "H"
        v_h = np.full_like(psi, v) if on_h else v / cos_p
        v_a = v * cos_p if on_h else np.full_like(psi, v)
        psi_t = v_h * prof.dpsi_ds
        acc = -v * sin_p * psi_t if on_h else np.zeros_like(psi)
        bdd = v * cos_p * psi_t / l3 if on_h else v * psi_t / (l3 * cos_p * cos_p)
        bd = v_h * sin_p / l3
        w1, w2 = wheel_rates_of(v_a, bd, l1, robot.r1, robot.r2)
        wd1, wd2 = wheel_rates_of(acc, bdd, l1, robot.r1, robot.r2)
    wheels = (np.maximum(np.abs(w1), np.abs(w2)), np.maximum(np.abs(wd1), np.abs(wd2)))
    series = dict(zip(QUANTITIES, (*wheels, np.abs(acc), np.abs(bd), np.abs(bdd)), strict=True))
    arg = {name: int(np.argmax(np.where(np.isfinite(f), f, np.inf))) for name, f in series.items()}
    peaks = {name: float(f[arg[name]]) for name, f in series.items()}
    peak_s = {name: float(prof.s[i]) for name, i in arg.items()}
    peak_wheel: dict[str, str] = {}
    for name, (a1, a2) in (("wheel_rate", (w1, w2)), ("wheel_acceleration", (wd1, wd2))):
        i = arg[name]
        # wheel 1 (right) is outer on a left turn (betadot > 0)
        outer = (abs(a1[i]) > abs(a2[i])) == (bd[i] > 0.0)
        peak_wheel[name] = "each" if abs(a1[i]) == abs(a2[i]) or bd[i] == 0.0 else "outer" if outer else "inner"
    singular = not max_lag < math.pi / 2 - 1e-9
    exceeded = {q: _intervals(prof.s, ~(series[q] <= lim)) for q, lim in limits.items()}
    if singular:
        exceeded["heading lag"] = _intervals(prof.s, ~(np.abs(psi) < math.pi / 2 - 1e-9))
        i = int(np.argmax(np.abs(psi)))
        binding, needed, limit, k = "heading lag", max_lag, math.pi / 2, float(kappa[i])
    else:
        binding = max(limits, key=lambda q: peaks[q] / limits[q])
        needed, limit, k = peaks[binding], limits[binding], float(kappa[arg[binding]])
    radius = math.inf if k == 0.0 else 1.0 / abs(k)
    feasible = not singular and all(peaks[q] <= limits[q] for q in limits)
    return Feasibility(v, speed_of, peaks, peak_s, peak_wheel, limits, binding, needed, limit, radius, feasible,
                       max_lag, exceeded)  # fmt: skip


#: most intervals listed per quantity in :attr:`Feasibility.exceeded`
MAX_INTERVALS = 64


def _intervals(s: Array, over: NDArray[np.bool_]) -> tuple[tuple[float, float], ...]:
    """The arc-length intervals ``(s_from, s_to)`` of the runs of consecutive samples ``s`` (sorted) with ``over``."""
    idx = np.flatnonzero(over)
    if idx.size == 0:
        return ()
    cut = np.flatnonzero(np.diff(idx) > 1)
    first = np.r_[idx[0], idx[cut + 1]]
    last = np.r_[idx[cut], idx[-1]]
    if len(first) > MAX_INTERVALS:
        first, last = first[:MAX_INTERVALS], np.r_[last[: MAX_INTERVALS - 1], last[-1]]
    return tuple((float(s[a]), float(s[b])) for a, b in zip(first.tolist(), last.tolist(), strict=True))
