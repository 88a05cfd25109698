"""User paths in AmigoBot-v1: the duck-typed protocol, NaN at the step, feasibility modes, goal tolerance."""

from __future__ import annotations

import json
import math
import re
import warnings
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers the environments)
from amigo_gym.paths import ClothoidPath, ClothoidSegment, UserPath, from_points


class _Pose(NamedTuple):
    x: Any
    y: Any
    theta: Any
    curvature: Any


class Circle:
    """A circle of radius r through the origin, heading +x, turning left: the protocol's three members only."""

    def __init__(self, r: float = 1.0, length: Any = None, closed: Any = True, bad_after: float | None = None) -> None:
        self.r = r
        self.length = 2.0 * math.pi * r if length is None else length
        self.closed = closed
        self.bad_after = bad_after

    def pose_columns(self, s: Any) -> _Pose:
        th = np.asarray(s, dtype=np.float64) / self.r
        k = np.full(np.shape(s), 1.0 / self.r)
        if self.bad_after is not None:
            k = np.where(np.asarray(s) > self.bad_after, np.nan, k)
        out = _Pose(self.r * np.sin(th), self.r * (1.0 - np.cos(th)), th, k)
        if not isinstance(s, np.ndarray):
            return _Pose(*(float(v) for v in out))
        return out


def test_three_members_are_enough_and_match_the_builtin_circle() -> None:
    """A path with only length, closed and pose_columns runs (the sampled closest-point search) and steps like
    the built-in circle family (the same geometry, an independent implementation)."""
    kw: dict[str, Any] = {"speed": 0.2, "randomize": "none", "max_episode_steps": 200, "kernel": "numpy"}
    e1 = gym.make("AmigoBot-v1", path=Circle(1.0), **kw)
    e2 = gym.make("AmigoBot-v1", path="circle", radius=1.0, **kw)
    assert isinstance(e1.unwrapped.params.path, UserPath)  # type: ignore[attr-defined]
    o1, i1 = e1.reset(seed=5)
    o2, _ = e2.reset(seed=5)
    assert i1["path"]["family"] == "Circle"
    np.testing.assert_allclose(o1, o2, atol=1e-6)
    rng = np.random.default_rng(2)
    for _ in range(40):
        a = rng.uniform(0.1, 0.3, 2)
        o1, r1, t1, _, _ = e1.step(a)
        o2, r2, t2, _, _ = e2.step(a)
        np.testing.assert_allclose(o1, o2, atol=1e-6)
        assert abs(r1 - r2) < 1e-6 and t1 == t2
    # rendering draws the path by the documented members only (no `point`)
    from amigo_gym.envs.rendering import path_polyline

    pts = path_polyline(e1.unwrapped.params.path, 40)  # type: ignore[attr-defined]
    np.testing.assert_allclose(np.hypot(pts[:, 0], pts[:, 1] - 1.0), 1.0, atol=1e-12)


class NoPose:
    length = 3.0
    closed = False


@pytest.mark.parametrize(
    ("path", "message"),
    [
        (NoPose(), r"path NoPose has no 'pose_columns'"),
        (object(), r"has no 'length', 'closed', 'pose_columns'"),
        (Circle(length=0.0), r"AmigoBot-v1: path Circle: length must be a finite number in \(0, 1e\+07\] m, got 0.0"),
        (Circle(length=-5.0), r"length must be .* got -5"),
        (Circle(length=float("nan")), r"length must be .* got nan"),
        (Circle(length="10"), r"length must be a finite number .* got '10'"),
        (Circle(closed="yes"), r"closed must be True or False, got 'yes'"),
        (Circle(bad_after=1.0), r"pose_columns\(s\).curvature must be finite, got nan"),
    ],
)
def test_bad_path_objects_are_refused_at_make_in_one_line(path: object, message: str) -> None:
    with pytest.raises(ValueError, match=message) as err:
        gym.make("AmigoBot-v1", path=path)
    assert "\n" not in str(err.value)


class WrongShape(Circle):
    def pose_columns(self, s: Any) -> _Pose:
        p = super().pose_columns(s)
        return p._replace(x=np.zeros(3)) if isinstance(s, np.ndarray) else p


def test_wrong_shapes_are_refused() -> None:
    with pytest.raises(ValueError, match=r"pose_columns\(s\).x must have the shape of s, \(7,\), got shape \(3,\)"):
        gym.make("AmigoBot-v1", path=WrongShape())


class GoesBad(Circle):
    """Finite on the probes at make, NaN once the robot has driven 0.3 m (a user path's bug)."""

    name = "my-track"

    def __init__(self) -> None:
        super().__init__(1.0)
        self.armed = False

    def pose_columns(self, s: Any) -> _Pose:
        p = super().pose_columns(s)
        if self.armed and not isinstance(s, np.ndarray) and s > 0.3:
            return p._replace(theta=float("nan"))
        return p


@pytest.mark.parametrize("vector", [False, True])
def test_nan_from_a_user_path_is_caught_at_the_step_naming_it(vector: bool) -> None:
    path = GoesBad()
    if vector:
        env: Any = gym.make_vec("AmigoBot-v1", 2, vectorization_mode="vector_entry_point", path=path, kernel="numpy")
    else:
        env = gym.make("AmigoBot-v1", path=path, kernel="numpy")
    env.reset(seed=0)
    path.armed = True
    a = np.full((2, 2), 0.4) if vector else np.array([0.4, 0.4])
    with pytest.raises(ValueError, match=r"path my-track: pose_columns\(s\).theta must be finite, got nan") as err:
        for _ in range(200):
            env.step(a)
    assert "\n" not in str(err.value)


# --------------------------------------------------------------------------- feasibility


def test_feasibility_modes() -> None:
    """A circle of 0.5 m at 0.74 m/s needs more wheel rate than 15 rad/s everywhere on it."""
    kw: dict[str, Any] = {"path": "circle", "radius": 0.5, "speed": 0.74}
    with pytest.raises(ValueError, match="above the robot's limit of 15 rad/s"):
        gym.make("AmigoBot-v1", **kw)
    with pytest.warns(UserWarning, match="running it"):
        gym.make("AmigoBot-v1", feasibility="warn", **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = gym.make("AmigoBot-v1", feasibility="off", **kw)
    _, info = env.reset(seed=0)
    rep = info["feasibility"]
    assert rep["feasible"] is False and rep["binding"] == "wheel_rate"
    # the closed form: steady state on the circle, R_A = sqrt(R^2 - l3^2), wheel rate (v + l1 v / R_A) / r
    r_a = math.sqrt(0.5**2 - 0.08**2)
    assert rep["peaks"]["wheel_rate"] == pytest.approx((0.74 + 0.12 * 0.74 / r_a) / 0.05, rel=1e-6)
    (start, stop), *rest = rep["exceeded"]["wheel_rate"]
    assert not rest and start == 0.0 and stop == pytest.approx(math.pi, rel=1e-9)  # the whole lap
    assert env.unwrapped.feasibility == rep  # type: ignore[attr-defined]
    for _ in range(5):
        env.step(np.array([1.0, 0.5]))  # it runs
    venv = gym.make_vec("AmigoBot-v1", 2, vectorization_mode="vector_entry_point", feasibility="off", **kw)
    assert venv.unwrapped.feasibility["exceeded"]["wheel_rate"]  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match="feasibility must be one of"):
        gym.make("AmigoBot-v1", feasibility="maybe")


def test_an_infeasible_fitted_path_reports_where() -> None:
    """A path from points: a straight, a tight arc (0.15 m), a straight; at 0.2 m/s only the arc exceeds."""
    line = ClothoidSegment.line(1.0)
    ref = ClothoidPath((line, ClothoidSegment.transition(0.1, 0.0, 1 / 0.15), ClothoidSegment.arc(0.3, 1 / 0.15),
                        ClothoidSegment.transition(0.1, 1 / 0.15, 0.0), line))  # fmt: skip
    path = from_points(ref.point(np.arange(0.0, ref.length, 0.02)))
    env = gym.make("AmigoBot-v1", path=path, speed=0.2, feasibility="off")
    _, info = env.reset(seed=0)
    ex = info["feasibility"]["exceeded"]
    assert not info["feasibility"]["feasible"]
    assert ex["wheel_rate"] or ex["rotational_acceleration"]
    for name, intervals in ex.items():
        for a, b in intervals:  # around the arc, not on the straights far from it
            assert 0.7 < a <= b < 1.8, (name, a, b)


# --------------------------------------------------------------------------- goal tolerance


@pytest.mark.parametrize("kernel", ["auto", "numpy"])
@pytest.mark.parametrize(("tol", "step", "condition"), [(0.5, 129, "goal"), (0.0, 154, "end_of_path")])
def test_goal_tolerance_on_a_straight_line(kernel: str, tol: float, step: int, condition: str) -> None:
    """Closed form: from rest, equal setpoints of 0.2 m/s, the firmware ramp 0.3 m/s^2: H (starting at 0) is at
    0.2^2 / (2 0.3) + 0.2 (t - 0.2 / 0.3) for t >= 2/3 s; it comes within 0.5 m of the end of a 3 m line at
    t = 12.83 s (step 129 at dt = 0.1) and passes the end at t = 15.33 s (step 154)."""
    line = ClothoidPath((ClothoidSegment.line(3.0),))
    kw: dict[str, Any] = {
        "path": line,
        "goal_tolerance": tol,
        "init_position_noise": 0.0,
        "init_heading_noise": 0.0,
        "randomize": "none",
        "kernel": kernel,
    }
    env = gym.make("AmigoBot-v1", max_episode_steps=400, **kw)
    p = env.unwrapped.params  # type: ignore[attr-defined]
    a = 0.2 / (p.robot.max_wheel_rate * p.robot.r1)
    env.reset(seed=0)
    ended = 0
    for k in range(1, 400):
        _, _, term, trunc, info = env.step(np.array([a, a]))
        assert info["end_condition"] == (condition if term else "")
        if term or trunc:
            ended = k
            break
    assert term and ended == step and info["end_of_path"]
    venv: Any = gym.make_vec("AmigoBot-v1", 3, vectorization_mode="vector_entry_point", max_episode_steps=400, **kw)
    venv.reset(seed=0)
    ended = 0
    for k in range(1, 400):
        _, _, term, _, info = venv.step(np.full((3, 2), a))
        if term.any():
            ended = k
            break
    assert ended == step and term.all() and list(info["end_condition"]) == [condition] * 3
    _, _, term, _, info = venv.step(np.full((3, 2), a))  # autoreset: new episodes, no end condition
    assert not term.any() and list(info["end_condition"]) == [""] * 3


@pytest.mark.parametrize("kernel", ["auto", "numpy"])
def test_leaving_the_path_ends_off_path(kernel: str) -> None:
    """One wheel at full rate, the other still: the robot turns on a 0.14 m circle and leaves the default path; the
    step that terminates says ``"off_path"`` (not the end of the path), every step before it ``""``; so do the
    vector env's rows."""
    env = gym.make("AmigoBot-v1", kernel=kernel, max_episode_steps=400)
    env.reset(seed=0)
    for _ in range(400):
        _, _, term, trunc, info = env.step(np.array([1.0, 0.0]))
        assert info["end_condition"] == ("off_path" if term else "")
        if term or trunc:
            break
    assert term and not info["end_of_path"]
    venv: Any = gym.make_vec("AmigoBot-v1", 2, vectorization_mode="vector_entry_point", max_episode_steps=400)
    venv.reset(seed=0)
    for _ in range(400):
        _, _, term, _, info = venv.step(np.tile([1.0, 0.0], (2, 1)))
        assert list(info["end_condition"]) == ["off_path" if t else "" for t in term]
        if term.any():
            break
    assert term.any()


def test_goal_tolerance_is_checked() -> None:
    with pytest.raises(ValueError, match="goal_tolerance"):
        gym.make("AmigoBot-v1", goal_tolerance=-1.0)


# --------------------------------------------------------------------------- files and the command line


def _tight_csv(folder: Any) -> Any:
    """Points of a straight, a 0.15 m arc (beyond the robot at 0.2 m/s), a straight, as a CSV."""
    line = ClothoidSegment.line(1.0)
    ref = ClothoidPath((line, ClothoidSegment.transition(0.1, 0.0, 1 / 0.15), ClothoidSegment.arc(0.3, 1 / 0.15),
                        ClothoidSegment.transition(0.1, 1 / 0.15, 0.0), line))  # fmt: skip
    f = folder / "tight.csv"
    pts = ref.point(np.arange(0.0, ref.length, 0.02)).tolist()
    f.write_text("x,y\n" + "".join(f"{x!r},{y!r}\n" for x, y in pts))
    return f


def test_a_points_file_in_one_line(tmp_path: Any) -> None:
    f = _tight_csv(tmp_path)
    with pytest.raises(ValueError, match="rotational acceleration"):
        gym.make("AmigoBot-v1", path=str(f))
    env = gym.make("AmigoBot-v1", path=str(f), feasibility="off")
    path = env.unwrapped.params.path  # type: ignore[attr-defined]
    assert type(path) is ClothoidPath and not path.closed
    venv = gym.make_vec("AmigoBot-v1", 2, vectorization_mode="vector_entry_point", path=str(f), feasibility="off")
    assert venv.unwrapped.paths[0] is path  # type: ignore[attr-defined]  # fitted once per file
    if env.unwrapped._kernel is not None:  # type: ignore[attr-defined]  # numba installed: the compiled steps
        assert venv.unwrapped._batch is not None  # type: ignore[attr-defined]
        env.reset(seed=0)
        assert env.unwrapped._in_kernel  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match=r"a points file \(.csv, .json\)"):
        gym.make("AmigoBot-v1", path="points.txt")
    with pytest.raises(FileNotFoundError, match="no such points file"):
        gym.make("AmigoBot-v1", path=str(tmp_path / "missing.csv"))


def test_benchmark_on_a_points_file_reports_the_limits(tmp_path: Any) -> None:
    from amigo_gym.tools.training import benchmark

    f = _tight_csv(tmp_path)
    out = tmp_path / "bench"
    args = ["--path", str(f), "--agents", "analytic", "--quick", "--no-plots", "--no-progress", "--out", str(out)]
    assert benchmark.main([*args, "--reps", "20", "--profile-reps", "10"]) == 0
    doc = json.loads((out / "benchmark.json").read_text())
    rep = doc["feasibility"]["path:tight"]
    assert not rep["feasible"] and rep["exceeded"]["rotational_acceleration"]
    assert [r["scenario"] for r in doc["results"]] == ["path:tight"]
    md = (out / "benchmark.md").read_text()
    assert "path:tight" in md and "exceeded: rotational acceleration at s = [" in md


class Forwarding:
    """A user class with its own locate (all four members forwarded to a ClothoidPath)."""

    def __init__(self, path: ClothoidPath) -> None:
        self._p = path
        self.length = path.length
        self.closed = path.closed

    def pose_columns(self, s: Any) -> Any:
        return self._p.pose_columns(s)

    def locate(self, *args: Any) -> Any:
        return self._p.locate(*args)


def test_a_users_own_locate_is_used_and_checked() -> None:
    ref = from_points(np.c_[np.cos(np.linspace(0, 6, 60)), np.sin(np.linspace(0, 6, 60))])
    kw: dict[str, Any] = {"speed": 0.2, "randomize": "none", "kernel": "numpy"}
    e1 = gym.make("AmigoBot-v1", path=Forwarding(ref), **kw)
    e2 = gym.make("AmigoBot-v1", path=ref, **kw)
    o1, _ = e1.reset(seed=1)
    o2, _ = e2.reset(seed=1)
    for _ in range(30):
        o1, r1, *_ = e1.step(np.array([0.3, 0.25]))
        o2, r2, *_ = e2.step(np.array([0.3, 0.25]))
    np.testing.assert_allclose(o1, o2, atol=1e-6)  # cos/sin of theta by numpy instead of the path's own
    assert abs(r1 - r2) < 1e-9

    class BadLocate(Forwarding):
        def locate(self, *args: Any) -> Any:
            got = self._p.locate(*args)
            return got._replace(cross_track_error=float("inf")) if isinstance(args[0], float) else got

    with pytest.raises(ValueError, match=r"path BadLocate: locate\(x, y, ...\).cross_track_error must be finite"):
        gym.make("AmigoBot-v1", path=BadLocate(ref))


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("bad.csv", "x,z\n0,0\n1,1\n", r"--path .*bad.csv: missing column\(s\) \['y'\]"),
        ("bad.txt", "x,y\n0,0\n1,1\n", "a points file must end in .csv or .json"),
        ("missing.csv", None, "no such points file"),
    ],
)
def test_benchmark_refuses_a_bad_points_file(
    tmp_path: Any, capsys: pytest.CaptureFixture[str], name: str, text: str | None, message: str
) -> None:
    from amigo_gym.tools.training import benchmark

    f = tmp_path / name
    if text is not None:
        f.write_text(text)
    out = tmp_path / "bench"
    assert benchmark.main(["--path", str(f), "--agents", "analytic", "--no-progress", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(message, err), err
    assert not out.exists()  # nothing written
