"""The float paths of one robot give the bits of the column code on arrays (issue 12, part 2).

The single environments run the column code on Python floats (``task.v1.step_columns``, with v0's settings
AmigoBot-v0's reference; the float branches of ``ClothoidPath.locate``/``pose_columns``); the vector environments run
the column code on ``(N,)`` arrays. Each float result here must equal the array result of its row bit for bit (signs
of zeros included). ``fresnel.advance``, ``actuators.actuator_step``, ``randomization.step_noise`` and the v0 paths'
projections are one function for floats and columns since issue 19's ``h19-cols`` branch (the same code on both,
checked here all the same; the fresnel and manoeuvre tests also against the former column code, kept below as
independent references).
"""

from __future__ import annotations

import math
from typing import Any

import clothoid_columns
import numpy as np
import pytest
from v0_reference import Reference, start_pose

from amigo_gym.model import actuators, fresnel, numeric
from amigo_gym.model.actuators import ActuatorParams
from amigo_gym.model.params import EnvParams, RobotParams
from amigo_gym.model.randomization import make_randomization, step_noise
from amigo_gym.paths import make_family_path
from amigo_gym.task import v0 as task


def same(a: Any, b: Any) -> bool:
    """Bit for bit, the sign of a zero included (NaN equal to NaN)."""
    a = float(a)
    b = float(b)
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


def rows_equal(floats: Any, arrays: Any, i: int) -> None:
    """Row ``i`` of the columns ``arrays`` (a constant column: a scalar) equals ``floats`` bit for bit."""
    for name, f, a in zip(getattr(floats, "_fields", range(len(floats))), floats, arrays, strict=True):
        flat = np.asarray(a).reshape(-1)
        want = flat[i] if flat.size > 1 else flat[0]
        assert same(f, want), (name, f, want)


def _advance_all_nodes_at_once(*args: Any) -> tuple[Any, Any, Any]:
    """The former column form of ``fresnel.advance`` (all nodes as one array of shape ``(nodes, N)``, then the sums
    node by node in order), an independent reference for the node loop that ``fresnel.advance`` now runs on columns."""
    x, y, theta, v0, a, w0, alpha, t, n_sub = args
    table = fresnel.node_table(n_sub)
    nn = len(table) // 2
    u = np.asarray(table[:nn]).reshape(nn, 1)
    uw = np.asarray(table[nn:]).reshape(nn, 1)
    half_alpha = 0.5 * alpha
    tau = u * t
    phase = theta + tau * (w0 + half_alpha * tau)
    weight = (v0 + a * tau) * uw
    px = weight * np.cos(phase)
    py = weight * np.sin(phase)
    dx = 0.0 + px[0]
    dy = 0.0 + py[0]
    for k in range(1, nn):
        dx = dx + px[k]
        dy = dy + py[k]
    return x + dx * t, y + dy * t, theta + t * (w0 + half_alpha * t)


@pytest.mark.parametrize("n_sub", [1, 3])
def test_fresnel_float_paths_equal_the_node_loop_on_arrays(n_sub: int) -> None:
    g = np.random.default_rng(1)
    n = 300
    cols = [g.normal(size=n) for _ in range(7)]
    cols[4][::5] = 0.0  # constant speed
    cols[6][::4] = 0.0  # arcs
    cols[5][::7] = 0.0  # lines
    t = np.abs(g.normal(size=n)) * 0.3
    t[::11] = 0.0
    ref = fresnel.advance(*cols, t, n_sub)
    for got, want in zip(ref, _advance_all_nodes_at_once(*cols, t, n_sub), strict=True):
        assert got.tobytes() == want.tobytes()
    for i in range(n):
        args = [float(c[i]) for c in cols]
        rows_equal(fresnel.advance(*args, float(t[i]), n_sub), ref, i)
    # unit speed: a path piece, with the cosine and sine of the end heading
    ref = fresnel.advance(cols[0], cols[1], cols[2], 1.0, 0.0, cols[5], cols[6], t, 1)
    for i in range(n):
        x, y, th, c, s = fresnel.unit_speed_pose(
            *(float(v[i]) for v in (cols[0], cols[1], cols[2], cols[5], cols[6])), float(t[i])
        )
        rows_equal((x, y, th), ref, i)
        assert same(c, np.cos(ref[2])[i]) and same(s, np.sin(ref[2])[i])
    # a chain of pieces: advance after advance
    for i in range(0, n - 4, 5):
        pieces = [
            (float(cols[3][j]), float(cols[4][j]), float(cols[5][j]), float(cols[6][j]), float(t[j]))
            for j in range(i, i + 4)
        ]
        x, y, th = float(cols[0][i]), float(cols[1][i]), float(cols[2][i])
        want = (x, y, th)
        for p in pieces:
            want = fresnel.advance(np.array([want[0]]), np.array([want[1]]), np.array([want[2]]), *p, n_sub)
        got = fresnel.advance_chain_float(x, y, th, pieces, n_sub)
        rows_equal(got, want, 0)


def test_actuator_step_float_equals_the_column_code() -> None:
    g = np.random.default_rng(2)
    nominal = RobotParams()
    limits = ActuatorParams()
    n = 400
    w = nominal.max_wheel_rate
    x, y, beta = g.normal(size=n), g.normal(size=n), g.normal(size=n) * 3
    w1, w2 = g.uniform(-w, w, n), g.uniform(-w, w, n)
    w1[::6] = 0.0
    c = [g.uniform(-1.3 * w, 1.3 * w, n) for _ in range(4)]
    c[0][::5] = w1[::5]  # already at the command
    t_s = g.uniform(0.0, 0.1, n)
    t_s[::3] = 0.0
    r1, r2, l1 = g.uniform(0.04, 0.06, n), g.uniform(0.04, 0.06, n), g.uniform(0.1, 0.14, n)
    s1, s2 = g.uniform(0.0, 0.2, n), g.uniform(0.0, 0.2, n)
    ref = actuators.actuator_step(x, y, beta, w1, w2, *c, t_s, 0.1, nominal, limits, r1, r2, l1, s1, s2)
    for i in range(n):
        got = actuators.actuator_step(
            float(x[i]), float(y[i]), float(beta[i]), float(w1[i]), float(w2[i]), *(float(v[i]) for v in c),
            float(t_s[i]), 0.1, nominal, limits, float(r1[i]), float(r2[i]), float(l1[i]), float(s1[i]), float(s2[i]),
        )  # fmt: skip
        assert all(type(v) is float for v in got)
        rows_equal(got, ref, i)
    ring = actuators.make_ring(4, 1.5, -2.0)
    actuators.ring_write(ring, 7, 3.0, 4.0)
    batch = actuators.make_ring(4, np.array([1.5]), np.array([-2.0]))
    actuators.ring_write(batch, 7, np.array([3.0]), np.array([4.0]))
    for lag in (0, 1, 2):
        rows_equal(actuators.ring_read(ring, 7, lag), actuators.ring_read(batch, 7, np.array([lag])), 0)
    with pytest.raises(ValueError, match="lag"):
        actuators.ring_read(ring, 7, 3)


PATHS = [
    ("circle", {"radius": 0.7, "direction": -1}),
    ("figure8", {"size": 4.0}),
    ("lane_change", {"offset": 0.6, "length": 3.5}),
    ("manoeuvre", {"radius": 1.0, "direction": 1}),
    ("random", {}),
]


@pytest.mark.parametrize(("name", "kw"), PATHS)
def test_locate_and_pose_float_equal_arrays(name: str, kw: dict[str, Any]) -> None:
    g = np.random.default_rng(3)
    path = make_family_path(name, np.random.default_rng(5) if name == "random" else None, **kw)
    n = 300
    length = path.length
    s = g.uniform(-0.3 * length, 1.3 * length, n)
    s[:4] = (0.0, length, -0.0, 0.5 * length)
    q = path.pose_columns(s)
    x = q.x + g.normal(size=n) * 0.1
    y = q.y + g.normal(size=n) * 0.1
    hint = s + g.normal(size=n) * 0.2
    ref = path.locate(x, y, hint, 0.475, 0.3)
    ref_default = path.locate(x, y, hint, 0.475)
    ref_global = path.locate(x, y)
    # the arrays (the float functions row by row) against the former vectorised code (an independent reference)
    for got_cols, want_cols in (
        (q, clothoid_columns.pose(path, s)),
        (ref, clothoid_columns.locate(path, x, y, hint, 0.475, 0.3)),
        (ref_default, clothoid_columns.locate(path, x, y, hint, 0.475)),
        (ref_global, clothoid_columns.locate(path, x, y)),
    ):
        for i in range(n):
            rows_equal([np.asarray(v)[i] for v in got_cols], want_cols, i)
    for i in range(n):
        rows_equal(path.pose_columns(float(s[i])), q, i)
        got = path.locate(float(x[i]), float(y[i]), float(hint[i]), 0.475, 0.3)
        assert type(got.status) is int
        rows_equal(got, ref, i)
        rows_equal(path.locate(float(x[i]), float(y[i]), float(hint[i]), 0.475), ref_default, i)
        rows_equal(path.locate(float(x[i]), float(y[i])), ref_global, i)
    for i in range(0, n - 3, 3):
        for j, got_pose in enumerate(path.pose_floats([float(v) for v in s[i : i + 3]])):
            rows_equal(got_pose, q, i + j)
    with pytest.raises(ValueError, match="max_advance"):
        path.locate(0.0, 0.0, 0.0, -1.0)


@pytest.mark.parametrize("preset", ["none", "mild", "hard"])
def test_step_noise_float_equals_arrays(preset: str) -> None:
    r = make_randomization(preset)
    keys = [0, 1, 2**63 - 1, 2**64 - 1, 12345678901234567]
    steps = [0, 1, 599, 2**40]
    for key in keys:
        for st in steps:
            for slip in (0.0, 0.07):
                got = step_noise(key, st, r, slip)
                assert all(type(v) is float for v in got)
                ref = step_noise(np.array([key], dtype=np.uint64), np.array([st]), r, np.array([slip]))
                rows_equal(got, ref, 0)


@pytest.mark.parametrize("path_name", ["circle", "manoeuvre"])
def test_v0_reference_step_on_floats_equals_the_columns(path_name: str) -> None:
    """AmigoBot-v0's reference step (AmigoBot-v1's ideal step with v0's settings, what the single env runs with
    ``kernel="numpy"``) on one robot's Python floats gives its row of the ``(N,)`` columns, every field."""
    p = EnvParams(path=path_name, dt=0.2)
    g = np.random.default_rng(4)
    n = 200
    pose = start_pose(p, g.uniform(-1, 1, (n, 3)))
    pose[:, 0] += g.uniform(0.0, 2.0, n)
    angles = g.normal(size=(n, 3))
    prev = g.uniform(-15, 15, (n, 2))
    action = g.uniform(-1.3, 1.3, (n, 2))
    action[::5, 0] = action[::5, 1]  # straight lines: a zero turn
    action[::7] = 0.0
    state = np.column_stack((pose, angles, prev))
    ref = Reference(p, state)
    _, _, out = ref.step(action)
    for i in range(n):
        one = Reference(p, state[i])
        _, _, got = one.step(action[i])
        rows_equal(one.st, ref.st, i)
        rows_equal((one.castor,), (ref.castor,), i)
        rows_equal(got.obs, out.obs, i)
        rows_equal(got.terms, out.terms, i)
        rows_equal(got[2:], out[2:], i)  # reward, terminated, H, the error, speeds, measurements, end of path


def test_path_batch_locate_rows_equal_each_path_on_floats() -> None:
    """Newton's method on the rows still moving only (PathBatch, ClothoidPath on arrays): every row's bits."""
    from amigo_gym.paths import PathBatch

    g = np.random.default_rng(6)
    family = [make_family_path(n, np.random.default_rng(5) if n == "random" else None, **kw) for n, kw in PATHS]
    n = 240
    paths = [family[i % len(family)] for i in range(n)]
    batch = PathBatch(paths)
    length = np.array([p.length for p in paths])
    s = g.uniform(-0.2, 1.2, n) * length
    x = np.empty(n)
    y = np.empty(n)
    for i, p in enumerate(paths):
        q = p.pose_columns(float(s[i]))
        x[i], y[i] = float(q.x) + g.normal() * 0.1, float(q.y) + g.normal() * 0.1
    hint = s + g.normal(size=n) * 0.2
    got = batch.locate(x, y, hint, 0.475, 0.475)
    for i, p in enumerate(paths):
        rows_equal(p.locate(float(x[i]), float(y[i]), float(hint[i]), 0.475, 0.475), got, i)


@pytest.mark.parametrize("direction", [1, -1])
def test_circle_projection_of_one_point_is_the_column_projection(direction: int) -> None:
    """``CirclePath.project_xy`` on one point of floats (its own float branch) equals its row of the columns."""
    from amigo_gym.paths import CirclePath

    path = CirclePath(radius=0.7, start=(0.3, -0.2), start_angle=0.4, direction=direction)
    rng = np.random.default_rng(7)
    xs = np.concatenate([rng.uniform(-3, 3, 300), [path.center[0], -0.0, 0.0]])
    ys = np.concatenate([rng.uniform(-3, 3, 300), [path.center[1], 0.0, -0.0]])
    cols = path.project_xy(xs, ys, True)
    for i, (x, y) in enumerate(zip(xs.tolist(), ys.tolist(), strict=True)):
        rows_equal(path.project_xy(x, y, True), cols, i)


def test_action_pair_is_validate_action() -> None:
    """``task.action_pair`` (the single env's check) gives ``validate_action``'s values and refuses the same."""
    rng = np.random.default_rng(3)
    for dtype in (np.float32, np.float64):
        for a in rng.uniform(-3, 3, (200, 2)).astype(dtype):
            assert task.action_pair(a) == tuple(task.validate_action(a).tolist())
        for bad in ((np.nan, 0.0), (0.0, np.inf), (-np.inf, 1.0)):
            with pytest.raises(ValueError, match="finite"):
                task.action_pair(np.array(bad, dtype=dtype))
    assert task.action_pair([0.5, -1]) == (0.5, -1.0)  # other inputs take validate_action's route
    with pytest.raises(ValueError, match="shape"):
        task.action_pair(np.zeros(3, dtype=np.float32))
    with pytest.raises(TypeError):
        task.action_pair(np.array(["a", "b"]))


def _search_cases(path: Any) -> tuple[list[float], list[tuple[float, float, float]]]:
    """Arc lengths for the piece search (piece starts exactly, between them, outside [0, L], -0.0, NaN) and points
    with hints for the coarse search (exact ties between two samples, NaN, hints before, beyond and laps away)."""
    t = path._t
    g = np.random.default_rng(11)
    length = path.length
    us = [*t.s0, *(g.uniform(-0.2, 1.2, 200) * length).tolist(), 0.0, -0.0, length, -1.0, 2.0 * length, math.nan]
    h = t.spacing
    cases = []
    for _ in range(150):
        s = float(g.uniform(-0.3, 1.3) * length)
        p = path.pose_columns(s)
        cases.append((float(p.x + g.normal() * 0.2), float(p.y + g.normal() * 0.2), s + float(g.normal() * 0.3)))
    for j in (0, 3, len(t.sample_x) - 3):  # midway between two samples: d2 ties when the geometry is exact
        x = float(0.5 * (t.sample_x[j] + t.sample_x[j + 1]))
        y = float(0.5 * (t.sample_y[j] + t.sample_y[j + 1]))
        cases += [(x, y, (j + 0.5) * h), (x, y, -0.7), (x, y, length + 0.9), (x, y, 5.0 * length + j * h)]
    cases += [(math.nan, 0.0, 0.3), (0.0, math.nan, 0.3), (math.inf, 0.0, 0.3), (1e6, -1e6, 0.3)]
    cases += [(0.1, 0.2, 1e17), (0.1, 0.2, -3e16), (0.1, 0.2, 1e300)]  # sample numbers beyond 2^53
    return us, cases


SEARCH_PATHS = [*PATHS, ("line", {})]


def _search_path(name: str, kw: dict[str, Any]) -> Any:
    from amigo_gym.paths import ClothoidPath, ClothoidSegment

    if name == "line":  # samples 1/64 m apart exactly: the points midway between two tie exactly
        return ClothoidPath((ClothoidSegment.line(1.0),), sample_spacing=1.0 / 64.0)
    return make_family_path(name, np.random.default_rng(5) if name == "random" else None, **kw)


@pytest.mark.parametrize(("name", "kw"), SEARCH_PATHS)
def test_flat_piece_and_coarse_search_equal_the_column_code(name: str, kw: dict[str, Any]) -> None:
    """The projection's shared loops on the flat path (run by the float path, compiled by v1's kernel) against the
    column code: piece_index is bisect_right - 1 clamped (numpy's searchsorted in the column code), coarse_start
    the column code's coarse search (np.mod / np.clip of the sample numbers, np.argmin's first minimum and NaN), and
    the whole projection with and without a hint on these ties, NaN and far points (tests/clothoid_columns.py)."""
    from amigo_gym.paths import clothoid

    path = _search_path(name, kw)
    t = path._t
    pv = path._flat_list
    assert pv == t.flat.tolist() and t.flat[clothoid.P_CLOSED] == float(path.closed)
    us, cases = _search_cases(path)
    n = len(t.s0)
    col = np.clip(np.searchsorted(t.s0_a, np.array(us), side="right") - 1, 0, n - 1)
    for u, want in zip(us, col, strict=True):
        assert clothoid.piece_index(pv, u) == int(want), u
    for s in us[:-1]:  # the pose's piece, wrap and placement: the column code's (NaN: the wrap's error, as before)
        rows_equal(clothoid._pose_float(pv, s), clothoid_columns.pose(path, np.array([s])), 0)
    ties = 0
    for x, y, hint in cases:
        for ahead, behind in ((0.475, 0.475), (0.475, 0.3), (0.05, 1.3)):
            s_col, lo, hi = clothoid_columns.coarse(path, np.array(x), np.array(y), np.array(hint), ahead, behind)
            got = numeric.clip_float(clothoid.coarse_start(pv, x, y, hint, ahead, behind), float(lo), float(hi))
            assert same(got, s_col), (x, y, hint, ahead, behind, got, s_col)
            want = clothoid_columns.locate(path, np.array([x]), np.array([y]), np.array([hint]), ahead, behind)
            rows_equal(path.locate(x, y, hint, ahead, behind), want, 0)
            d2 = (t.sample_x - x) ** 2 + (t.sample_y - y) ** 2
            ties += int(np.sum(d2 == d2.min()) > 1)
        rows_equal(path.locate(x, y), clothoid_columns.locate(path, np.array([x]), np.array([y])), 0)
    if name == "line":
        assert ties > 0  # the tie rule was exercised


def _manoeuvre_points(path: Any, g: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, slice]:
    """Points around a manoeuvre path: random ones, the circle's centre, exact ties between the line and the circle
    (``x = L``, ``|y|`` in ``[r/2, r)`` on the circle's side: ``d_line = |e_circle| = |y|``; returned as a slice), the
    segment's end and an ulp past it, signed zeros, NaN and infinities."""
    big_l, r, d = path.straight_length, path.radius, path.direction
    cx, cy, _, _ = path.circle._frame
    x = g.uniform(-2.0, big_l + 2.5 * r, n)
    y = g.uniform(-2.5 * r, 2.5 * r, n)
    ties = slice(0, 40)
    x[ties] = big_l
    y[ties] = d * g.uniform(0.5 * r, r, 40)
    x[40:44], y[40:44] = cx, cy
    x[44:50] = np.nextafter(big_l, np.inf)
    x[50:56] = big_l
    y[50:53], y[53:56] = 0.0, -0.0
    x[56], x[57], y[58], y[59] = -0.0, math.nan, math.nan, math.inf
    x[60], y[61] = -math.inf, -math.inf
    x[62:70], y[62:70] = -0.0, d * g.uniform(0.5 * r, r, 8)  # ties where L = 0 (np.minimum(-0.0, 0.0) is 0.0)
    return x, y, ties


def _manoeuvre_columns(path: Any, x: Any, y: Any) -> tuple[Any, ...]:
    """The former column form of ``ManoeuvrePath.project_xy`` (numpy's ``minimum``, ``hypot``, ``sign``, ``where``
    and the circle's projection written on arrays), an independent reference for ``classic.manoeuvre_foot``, which
    now runs on columns too: ``(s, x, y, tangent_angle, curvature, e, cos_theta, sin_theta)``."""
    c, big_l, d, r = path.circle, path.straight_length, path.direction, path.radius
    cx, cy, r0x, r0y = c._frame
    ux, uy = x - cx, y - cy
    rho = np.sqrt(ux * ux + uy * uy)
    at_centre = rho == 0.0
    ux, uy, norm = np.where(at_centre, r0x, ux), np.where(at_centre, r0y, uy), np.where(at_centre, 1.0, rho)
    nx, ny = ux / norm, uy / norm
    e = r - rho if d > 0 else rho - r
    cos_theta, sin_theta = (-ny, nx) if d > 0 else (ny, -nx)
    cross = r0x * uy - r0y * ux
    a = np.arctan2(cross if d > 0 else -cross, r0x * ux + r0y * uy)
    s = r * (a + 2.0 * math.pi * (a < 0.0))
    s_line = np.minimum(x, big_l)
    d_line = np.hypot(x - s_line, y)
    line = d_line <= np.abs(e)
    e_line = np.where(x <= big_l, y, np.sign(y) * d_line)
    theta = c.start_angle + (s if d > 0 else -s) / r
    return (
        np.where(line, s_line, big_l + s), np.where(line, s_line, cx + r * nx), np.where(line, 0.0, cy + r * ny),
        np.where(line, 0.0, theta), np.where(line, 0.0, d / r), np.where(line, e_line, e),
        np.where(line, 1.0, cos_theta), np.where(line, 0.0, sin_theta),
    )  # fmt: skip


@pytest.mark.parametrize("shape", [(1.0, 1.0, 1), (0.6, 0.0, -1), (1.7, 2.5, -1), (0.25, 0.75, 1)])
def test_manoeuvre_projection_on_floats_equals_the_column_code(shape: tuple[float, float, int]) -> None:
    """``ManoeuvrePath.project_xy`` runs ``classic.manoeuvre_foot`` (what AmigoBot-v0's compiled step compiles) on one
    point of floats and on columns: every field the same bits as the former column code (numpy's ``minimum``,
    ``hypot``, ``where`` and the circle's column projection), ties between the line and the circle (to the line), the
    centre, NaN and infinities included."""
    from amigo_gym.paths import ManoeuvrePath

    path = ManoeuvrePath(*shape)
    x, y, ties = _manoeuvre_points(path, np.random.default_rng(7), 3000)
    with np.errstate(invalid="ignore"):
        want = _manoeuvre_columns(path, x, y)
        got_cols = path.project_xy(x, y)
    for got_col, want_col in zip(got_cols, want, strict=True):
        assert np.asarray(got_col).tobytes() == np.asarray(want_col).tobytes()
    for minimal in (False, True):
        with np.errstate(invalid="ignore"):  # NaN and infinite points
            ref = path.project_xy(x, y, minimal)
        for i in range(x.size):
            got = path.project_xy(float(x[i]), float(y[i]), minimal)
            assert all(type(v) is float for v in got)
            rows_equal(got, ref, i)
    assert np.all(np.asarray(ref.curvature)[ties] == 0.0)  # the ties took the line
    with np.errstate(invalid="ignore"):
        loc = path.locate(x, y, x)
    for i in range(0, x.size, 7):
        rows_equal(path.locate(float(x[i]), float(y[i]), float(x[i])), loc, i)
    s = np.concatenate((np.random.default_rng(8).uniform(-1.0, 2.0 * path.length, 500), [path.straight_length]))
    s[:3] = (-0.0, math.nan, np.nextafter(path.straight_length, np.inf))
    k = path.curvature_columns(s)
    for i in range(s.size):
        rows_equal((path.curvature_columns(float(s[i])),), (k,), i)


def test_observation_and_reward_pieces_on_floats_equal_columns() -> None:
    """``task/v0.py``'s observation pieces (``observe_head``, ``curvature_feature``, ``observe_tail``, what
    ``observe_columns`` and the compiled step call) and ``reward_arguments`` on floats give their columns' bits, the
    clips active (values beyond every bound, infinities, signed zeros); the reward's arguments are ``-x / sigma``.
    (Not NaN: on a float the clip, ``clip_float``, gives the upper bound for NaN where ``np.clip`` keeps NaN.)"""
    g = np.random.default_rng(9)
    n = 2000
    cols = [g.normal(size=n) * 3.0 for _ in range(8)]
    for j, c in enumerate(cols):  # the infinities of two columns never meet (inf - inf: NaN, below)
        c[:2] = (0.0, -0.0)
        c[2 + 2 * j : 4 + 2 * j] = (math.inf, -math.inf)
    e, sin_psi, cos_psi, kappa, w1, w2, v, v_ref = cols
    head = task.observe_head(e, sin_psi, cos_psi, kappa, 0.3, 0.25, 1.6)
    tail = task.observe_tail(w1, w2, v, v_ref, 1.7, 0.8)
    feature = task.curvature_feature(kappa, 0.3)
    assert np.all(np.abs(head[0]) <= 1.6) and np.any(np.abs(head[0]) == 1.6)  # the clips do clip
    assert np.any(np.abs(tail[0]) == 1.0) and np.any(np.abs(tail[2]) == 2.0)
    args = task.reward_arguments(np.abs(e), np.abs(v), w1 * w1 + w2 * w2, 0.2, 0.4, 3.5)
    np.testing.assert_array_equal(args[0], -(np.abs(e) / 0.2))
    np.testing.assert_array_equal(args[1], -(np.abs(v) / 0.4))
    np.testing.assert_array_equal(args[2], -((w1 * w1 + w2 * w2) / 3.5))
    for i in range(n):
        f = [float(c[i]) for c in cols]
        rows_equal(task.observe_head(f[0], f[1], f[2], f[3], 0.3, 0.25, 1.6), head, i)
        rows_equal(task.observe_tail(f[4], f[5], f[6], f[7], 1.7, 0.8), tail, i)
        rows_equal((task.curvature_feature(f[3], 0.3),), (feature,), i)
        got = task.reward_arguments(abs(f[0]), abs(f[6]), f[4] * f[4] + f[5] * f[5], 0.2, 0.4, 3.5)
        rows_equal(got, args, i)
