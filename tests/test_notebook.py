"""Execute ``experiments/notebooks/evaluate_policy.ipynb`` with nbclient (kernel ``python3``).

``python3`` is ipykernel's native kernel: jupyter_client finds it without an installed kernel spec, so
the test needs no setup beyond the ``notebook`` extra (nbclient, nbformat, ipykernel).
"""

from __future__ import annotations

from pathlib import Path

import nbformat
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK = ROOT / "experiments" / "notebooks" / "evaluate_policy.ipynb"


def test_notebook_runs_and_shows_tables_and_plots() -> None:
    nb = nbformat.read(NOTEBOOK, as_version=4)  # type: ignore[no-untyped-call]
    client = NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOK.parent)}}
    )
    client.execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    errors = [o for o in outputs if o.get("output_type") == "error"]
    assert not errors, errors
    markdown = "".join(o["data"].get("text/markdown", "") for o in outputs if "data" in o)
    assert "| analytic | perturbed |" in markdown and "| analytic_ff | nominal |" in markdown
    images = [o for o in outputs if "data" in o and "image/png" in o["data"]]
    assert len(images) == 6  # trajectories, wheels; benchmark per scenario, profiles; curves vs steps, wall time
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert "analytic: H RMS" in text
    # the quick benchmark and the learning curves (synthetic runs on a fresh clone)
    assert "# AmigoBot benchmark, suite 1.0 (quick subset)" in markdown and "| v0_paper_circle |" in markdown
    assert "# Learning curves" in markdown and "seeds reaching 5 mm" in markdown
