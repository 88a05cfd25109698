"""Figures of the tools: matplotlib on its file backend (Agg, no display needed), PNGs written atomically."""

from __future__ import annotations

import os
from typing import Any

from amigo_gym.io import atomic_save


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend (imported here, when a figure is drawn)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: int = 110) -> None:
    """Write ``fig`` as a PNG to ``path`` atomically (its folders created), then close it."""
    atomic_save(lambda tmp: fig.savefig(tmp, format="png", dpi=dpi), path, parents=True)
    pyplot().close(fig)
