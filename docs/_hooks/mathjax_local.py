"""mkdocs hook: copy MathJax 3 (``tex-svg-full.js``, one self-contained file) into the built site.

The math renderer comes from the ``django-static-mathjax`` wheel (the ``docs`` extra; it ships MathJax's
release files and needs no Django to be read), so ``mkdocs build`` works offline and the site loads no
script from a CDN. The SVG output needs no web fonts.
"""

from __future__ import annotations

import shutil
from importlib.util import find_spec
from pathlib import Path
from typing import Any

MATHJAX_FILE = "tex-svg-full.js"


def mathjax_source() -> Path:
    """Path of ``tex-svg-full.js`` inside the installed ``mathjax`` package (django-static-mathjax)."""
    spec = find_spec("mathjax")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError(
            "the docs site needs MathJax from the 'docs' extra: "
            'pip install -e ".[docs]" (missing: django-static-mathjax)'
        )
    src = Path(next(iter(spec.submodule_search_locations))) / "static" / "mathjax" / "es5" / MATHJAX_FILE
    if not src.is_file():
        raise RuntimeError(f"django-static-mathjax installed without {MATHJAX_FILE} (looked at {src})")
    return src


def on_post_build(config: Any, **kwargs: Any) -> None:
    """Copy MathJax to ``<site_dir>/assets/mathjax/`` (referenced by ``extra_javascript`` in mkdocs.yml)."""
    dest = Path(config["site_dir"]) / "assets" / "mathjax"
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(mathjax_source(), dest / MATHJAX_FILE)
