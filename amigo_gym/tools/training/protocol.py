"""The benchmark protocol 2.0: validation cells for every decision, test cells that no decision sees.

Every decision taken while building an agent (the sweep's objective, the curriculum, the choice between agents,
early stopping) evaluates :func:`validation_cells` only; the benchmark reports suite ``"2.0"`` (:data:`TEST`,
``amigo-gym benchmark --suite 2.0``) on :data:`TEST_SEEDS`. No test cell has a validation cell's ``(env_id,
env_kwargs)`` and the seed ranges are disjoint (docs/benchmark.md, "Protocol 2.0"). A released suite is never edited:
a change is a new version beside it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from amigo_gym.tools.training.task_metrics import Scenario

__all__ = ["TEST", "TEST_SEEDS", "VALIDATION", "VALIDATION_SEEDS", "VERSION", "cell", "validation_cells"]

VERSION = "2.0"
#: the test seeds: 30 episodes per cell (``reset(seed=s)``)
TEST_SEEDS: tuple[int, ...] = tuple(range(7_000, 7_030))
#: the validation seeds (a decision may use any number of them, from the first)
VALIDATION_SEEDS: tuple[int, ...] = tuple(range(2_000_000, 2_000_100))

_R, _L = 0.05, 0.12  # the nominal wheel radius and track [m] (RobotParams)


def cell(
    name: str,
    desc: str,
    env_id: str = "AmigoBot-v1",
    held_out: bool = True,
    *,
    seeds: tuple[int, ...] = TEST_SEEDS,
    version: str = VERSION,
    duration: float = 40.0,
    **kw: Any,
) -> Scenario:
    """A suite's scenario: AmigoBot-v0 with ``kw`` for 400 steps, or AmigoBot-v1 with ``dt`` (0.1 s),
    ``randomize="none"`` and ``kw`` for ``duration`` [s]; ``max_steps`` in ``kw`` sets the length."""
    dt = kw.get("dt", 0.1)
    steps = kw.pop("max_steps", 400 if env_id == "AmigoBot-v0" else round(duration / dt))
    kwargs = kw if env_id == "AmigoBot-v0" else {"dt": dt, "randomize": "none", **kw}
    return Scenario(name, env_id, kwargs, seeds, steps, held_out, desc, version)


def _delay(s: float) -> dict[str, Any]:
    return {"delay": (s, s)}


# fmt: off
#: the validation cells (seeds: :data:`VALIDATION_SEEDS`, chosen by :func:`validation_cells`)
VALIDATION: tuple[Scenario, ...] = (
    cell("v0_paper_circle", "v0: the paper's circle R = 1 m, 0.2 m/s, dt 0.1 s", "AmigoBot-v0", False),
    cell("val_circle_r1_ccw", "circle R 1 m, left, 0.2 m/s", held_out=False, path="circle", radius=1.0, speed=0.2),
    cell("val_circle_r0.5_cw", "circle R 0.5 m, right, 0.2 m/s", held_out=False, path="circle", radius=0.5,
          direction=-1, speed=0.2),
    cell("val_figure8", "figure-8 size 4 m, 0.2 m/s", held_out=False, path="figure8", speed=0.2),
    cell("val_lane_change", "lane change, 0.3 m/s", held_out=False, path="lane_change", speed=0.3),
    cell("val_random", "random paths of the default pool, 0.2 m/s", held_out=False, path="random", speed=0.2),
    cell("val_mixed", "path family per episode, speed in [0.1, 0.4]", held_out=False, path="mixed",
          speed=(0.1, 0.4)),
    cell("val_delay_0.1", "delay 0.1 s, circle R 1 m", path="circle", speed=0.2, randomize=_delay(0.1)),
    cell("val_delay_0.25", "delay 0.25 s, figure-8", path="figure8", speed=0.2, randomize=_delay(0.25)),
    cell("val_wheels_plus5", "radii and track +5 %, circle R 1 m", path="circle", speed=0.2,
          true_robot={"r1": 1.05 * _R, "r2": 1.05 * _R, "l1": 1.05 * _L}),
    cell("val_wheels_unequal5", "right wheel +5 %, left -5 %, figure-8", path="figure8", speed=0.2,
          true_robot={"r1": 1.05 * _R, "r2": 0.95 * _R}),
    cell("val_noise", "noise 5 mm, 0.01 rad, 0.2 rad/s, circle R 1 m", path="circle", speed=0.2,
          randomize={"position_noise": 0.005, "heading_noise": 0.01, "wheel_rate_noise": 0.2}),
)

#: the test cells, suite 2.0: what the benchmark reports, on :data:`TEST_SEEDS`
TEST: tuple[Scenario, ...] = (
    cell("v0_speed_0.1", "v0: paper circle at 0.1 m/s", "AmigoBot-v0", speed=0.1),
    cell("v0_speed_0.4", "v0: paper circle at 0.4 m/s", "AmigoBot-v0", speed=0.4),
    cell("v0_dt_0.2", "v0: paper circle, dt 0.2 s", "AmigoBot-v0", dt=0.2, max_steps=200),
    cell("circle_r0.75_cw", "circle R 0.75 m, right, 0.25 m/s", held_out=False, path="circle", radius=0.75,
          direction=-1, speed=0.25),
    cell("circle_r2_ccw", "circle R 2 m, left, 0.3 m/s", held_out=False, path="circle", radius=2.0, speed=0.3),
    cell("figure8_5m", "figure-8 size 5 m, 0.3 m/s", held_out=False, path="figure8", speed=0.3,
          path_params={"size": 5.0}),
    cell("lane_change_0.8", "lane change 0.8 m over 4 m, 0.2 m/s", held_out=False, path="lane_change", speed=0.2,
          path_params={"offset": 0.8, "length": 4.0}),
    cell("random_12m", "random paths of 12 m, |kappa| <= 0.8 1/m, 0.2 m/s", held_out=False, path="random",
          speed=0.2, path_params={"length": 12.0, "max_curvature": 0.8, "max_curvature_rate": 0.8}),
    cell("manoeuvre", "the paper's manoeuvre (straight, circle), 0.2 m/s", path="manoeuvre", speed=0.2),
    cell("delay_0.15", "delay 0.15 s, circle R 1 m", path="circle", speed=0.2, randomize=_delay(0.15)),
    cell("delay_0.3", "delay 0.3 s, random paths", path="random", speed=0.2, randomize=_delay(0.3)),
    cell("radii_plus7", "wheel radii +7 % (track nominal), circle R 1 m", path="circle", speed=0.2,
          true_robot={"r1": 1.07 * _R, "r2": 1.07 * _R}),
    cell("track_minus7", "track -7 % (radii nominal), figure-8", path="figure8", speed=0.2,
          true_robot={"l1": 0.93 * _L}),
    cell("wheels_unequal7", "right wheel +7 %, left -7 %, lane change", path="lane_change", speed=0.2,
          true_robot={"r1": 1.07 * _R, "r2": 0.93 * _R}),
    cell("noise_2x", "noise 10 mm, 0.02 rad, 0.4 rad/s, random paths", path="random", speed=0.2,
          randomize={"position_noise": 0.01, "heading_noise": 0.02, "wheel_rate_noise": 0.4}),
)
# fmt: on


def validation_cells(env_id: str, episodes: int = 5, max_steps: int = 0) -> tuple[Scenario, ...]:
    """The validation cells of ``env_id`` on the first ``episodes`` of :data:`VALIDATION_SEEDS`, cut to ``max_steps``
    steps when ``max_steps > 0``. Raises ``ValueError``: ``episodes`` out of range, no cell on ``env_id``."""
    if isinstance(episodes, bool) or not isinstance(episodes, int) or not 1 <= episodes <= len(VALIDATION_SEEDS):
        raise ValueError(f"episodes must be an integer in [1, {len(VALIDATION_SEEDS)}], got {episodes!r}")
    cells = tuple(  # Scenario.cut keeps the first ``episodes`` seeds
        replace(sc, seeds=VALIDATION_SEEDS).cut(episodes, max_steps if max_steps > 0 else sc.max_steps)
        for sc in VALIDATION
        if sc.env_id == env_id
    )
    if not cells:
        raise ValueError(f"env_id must be one of {sorted({sc.env_id for sc in VALIDATION})}, got {env_id!r}")
    return cells
