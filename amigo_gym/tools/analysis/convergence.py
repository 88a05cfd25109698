"""Convergence of the analytic policy from perturbed starts, for several feedback gains.

``amigo-gym convergence`` rolls out :class:`amigo_gym.policies.analytic.AnalyticPolicy` with each gain ``k`` from the
evaluation protocol's perturbed starts and fits, over all episodes, the slope of ``log|e(t)|`` over a time window: H's
error halves every ``ln 2 / -slope`` (the continuous-time law: ``ln 2 / k``). Prints a Markdown table; ``--plot FILE``
draws ``|e(t)|`` for every gain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from amigo_gym.model.params import check_real
from amigo_gym.policies.analytic import AnalyticPolicy
from amigo_gym.task.v1 import TrackingParams
from amigo_gym.tools.options import run_command
from amigo_gym.tools.plots import pyplot, save_figure
from amigo_gym.tools.training.evaluate import trajectories
from amigo_gym.tools.training.task_metrics import Scenario


@dataclass(frozen=True)
class GainFit:
    """The fitted decay for one gain.

    Attributes:
        gain: feedback gain k [1/s].
        slope: least-squares slope of ``log|e|`` over the window [1/s].
        halving_s: ``ln 2 / -slope`` [s] (``inf`` if the error does not decay).
        continuous_halving_s: ``ln 2 / k`` [s], the continuous-time law's.
        curves: per episode, ``(t [s], |e| [m])``.
    """

    gain: float
    slope: float
    halving_s: float
    continuous_halving_s: float
    curves: list[tuple[list[float], list[float]]]


@dataclass(frozen=True)
class Settings:
    """Options of ``amigo-gym convergence``.

    Attributes:
        gains: feedback gains ``k`` to compare [1/s], comma-separated on the command line.
        seeds: how many perturbed starts, as ``--seeds`` of evaluate and compare [episodes].
        first_seed: reset seed of the first start (seeds ``first_seed``..``first_seed + seeds - 1``) [-].
        t_from: start of the fit window [s].
        t_to: end of the fit window [s].
        steps: steps per episode, dt = 0.1 s [steps].
        plot: PNG for the ``|e(t)|`` plot [file], '' for none.
    """

    gains: str = "1,2,3,5"
    seeds: int = 10
    first_seed: int = 100
    t_from: float = 1.0
    t_to: float = 4.0
    steps: int = 80
    plot: str = ""

    def gain_list(self) -> list[float]:
        """The gains as floats, each validated in (0, 10] 1/s."""
        try:
            gains = [float(g) for g in self.gains.split(",") if g.strip()]
        except ValueError:
            raise ValueError(f"--gains must be comma-separated numbers, got {self.gains!r}") from None
        if not gains:
            raise ValueError("--gains must name at least one gain")
        return [check_real("Settings", "gains", g, 0.0, 10.0, low_open=True) for g in gains]


def halving_times(settings: Settings) -> list[GainFit]:
    """Fit the error's decay for every gain; ``ValueError`` on a bad window, or if an episode leaves the path."""
    check_real("Settings", "t_from", settings.t_from, 0.0)
    check_real("Settings", "t_to", settings.t_to, settings.t_from, low_open=True)
    if settings.seeds < 1 or settings.steps < 1:
        raise ValueError(f"--seeds and --steps must be >= 1, got {settings.seeds} and {settings.steps}")
    seeds = tuple(range(settings.first_seed, settings.first_seed + settings.seeds))
    steps = min(settings.steps, gym.spec("AmigoBot-v0").max_episode_steps or settings.steps)
    sc = Scenario("convergence", "AmigoBot-v0", {}, seeds, steps)
    out: list[GainFit] = []
    for k in settings.gain_list():
        trs = trajectories(AnalyticPolicy(TrackingParams.v0(), gain=k), sc, gain=k)
        if left := [seed for seed, tr in zip(seeds, trs, strict=True) if tr.terminated]:
            raise ValueError(f"gain {k}: the episode with seed {left[0]} left the path")
        curves = [(tr.time.tolist(), np.abs(tr.e).tolist()) for tr in trs]
        t, e = (np.concatenate(c) for c in zip(*curves, strict=True))
        win = (t >= settings.t_from) & (t <= settings.t_to) & (e > 0)
        slope = float(np.polyfit(t[win], np.log(e[win]), 1)[0])
        halving = math.log(2.0) / -slope if slope < 0 else math.inf
        out.append(GainFit(k, slope, halving, math.log(2.0) / k, curves))
    return out


def _plot(rows: list[GainFit], path: str, seeds: range) -> None:
    fig, ax = pyplot().subplots(figsize=(7.0, 3.8), layout="constrained")
    for i, row in enumerate(rows):
        color = f"C{i}"
        for j, (t, e) in enumerate(row.curves):
            label = f"k = {row.gain:g} 1/s (halves every {row.halving_s:.2f} s)" if j == 0 else None
            ax.semilogy(t, np.maximum(e, 1e-12), color=color, lw=0.8, alpha=0.7, label=label)
    ax.set(xlabel="t [s]", ylabel="|cross-track error of H| [m]", ylim=(1e-12, 0.05))
    ax.set_title(f"Analytic policy from perturbed starts (seeds {seeds[0]}-{seeds[-1]}), dt = 0.1 s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path)


def _report(settings: Settings) -> None:
    rows = halving_times(settings)
    print(f"fit of log|e| over t in [{settings.t_from:g}, {settings.t_to:g}] s, {settings.seeds} seeds")
    print("| gain k [1/s] | " + " | ".join(f"{r.gain:g}" for r in rows) + " |")
    print("|---|" + "---|" * len(rows))
    print("| error halves every [s] | " + " | ".join(f"{r.halving_s:.2f}" for r in rows) + " |")
    print("| continuous-time ln2/k [s] | " + " | ".join(f"{r.continuous_halving_s:.2f}" for r in rows) + " |")
    if settings.plot:
        _plot(rows, settings.plot, range(settings.first_seed, settings.first_seed + settings.seeds))
        print(f"plot: {settings.plot}")


def main(argv: Sequence[str] | None = None) -> int:
    """``amigo-gym convergence [--gains 1,2,3,5] [--plot FILE]``: the halving-time table."""
    return run_command(Settings, _report, argv, "amigo-gym convergence", __doc__.splitlines()[0])
