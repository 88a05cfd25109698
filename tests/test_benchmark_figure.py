"""docs/benchmark/benchmark_scenarios.png's layout: the whole title inside the figure, the legend off the bars."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("quick", [False, True])
def test_title_and_legend_stay_clear(quick: bool) -> None:
    from amigo_gym.tools.training.benchmark import scenarios_figure

    doc = json.loads((ROOT / "docs/benchmark/benchmark.json").read_text())
    if quick:  # compare's quick subset: 3 scenarios, a narrow figure (where the title was cut)
        keep = {"v0_paper_circle", "v0_speed_0.4", "circle_r1_ccw"}
        doc = {**doc, "quick": True, "scenarios": [s for s in doc["scenarios"] if s["name"] in keep]}
    fig = scenarios_figure(doc, reps=50)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    whole = fig.bbox
    ax = fig.axes[0]
    title = ax.title.get_window_extent(renderer)
    legend = fig.legends[0].get_window_extent(renderer)
    axes = ax.get_window_extent(renderer)
    for box in (title, legend):  # nothing cut at the figure's edges
        assert whole.x0 <= box.x0 and box.x1 <= whole.x1 and whole.y0 <= box.y0 and box.y1 <= whole.y1, box
    assert legend.x0 >= axes.x1  # the legend is beside the bars, not over them
    assert "\n" in ax.get_title()  # two short lines
    import matplotlib.pyplot as plt

    plt.close(fig)
