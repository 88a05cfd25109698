"""The machine a speed figure was measured on: CPU model and the SIMD level numpy dispatches to.

Speed ratios move with the CPU (numpy picks its SIMD ``exp``/``sin``/``cos`` at run time), so every benchmark
prints these beside its figures. Standard library and numpy only.
"""

from __future__ import annotations

import platform

import numpy as np

__all__ = ["cpu_model", "machine_line", "simd_level"]

#: numpy's CPU feature names, from the widest level down (x86-64 micro-architecture levels, then ARM)
_LEVELS = (
    ("AVX512_SPR", "AVX-512 (Sapphire Rapids)"),
    ("AVX512_ICL", "AVX-512 (Ice Lake)"),
    ("AVX512_SKX", "AVX-512 (Skylake-X)"),
    ("AVX512F", "AVX-512"),
    ("AVX2", "AVX2"),
    ("AVX", "AVX"),
    ("SSE42", "SSE4.2"),
    ("SVE", "SVE"),
    ("ASIMD", "NEON (ASIMD)"),
)


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``'s ``model name``; else :func:`platform.processor`)."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def simd_level() -> str:
    """The widest SIMD level that numpy found on this CPU and may dispatch to, e.g. ``"AVX2"``.

    Read from numpy's own run-time detection (``__cpu_features__``), which also honours
    ``NPY_DISABLE_CPU_FEATURES``; ``"unknown"`` if this numpy does not expose it.
    """
    import importlib

    features: dict[str, bool] | None = None
    for name in ("numpy._core._multiarray_umath", "numpy.core._multiarray_umath"):  # numpy 2, numpy 1
        try:
            features = getattr(importlib.import_module(name), "__cpu_features__", None)
        except ImportError:
            continue
        if features is not None:
            break
    if features is None:
        return "unknown"
    for key, name in _LEVELS:
        if features.get(key):
            return name
    return "none"


def machine_line() -> str:
    """One line for a benchmark's header: CPU, SIMD level, CPUs visible, Python and numpy versions."""
    import os

    return (
        f"CPU: {cpu_model()}, SIMD {simd_level()}, {os.cpu_count()} CPUs visible; "
        f"{platform.python_implementation()} {platform.python_version()}, numpy {np.__version__}"
    )
