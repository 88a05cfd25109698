"""The machine a speed figure was measured on: CPU model and the SIMD level numpy dispatches to.

Speed ratios move with the CPU (numpy picks its SIMD ``exp``/``sin``/``cos`` at run time), so every benchmark
prints these beside its figures. Standard library and numpy only.
"""

from __future__ import annotations

import importlib
import os
import platform
from importlib.metadata import PackageNotFoundError, version

import numpy as np

#: numpy's CPU feature names, from the widest level down (x86-64 micro-architecture levels, numpy >= 2.4 naming them
#: ``X86_V4`` ... too, then ARM)
_LEVELS = (
    ("AVX512_SPR", "AVX-512 (Sapphire Rapids)"),
    ("AVX512_ICL", "AVX-512 (Ice Lake)"),
    ("AVX512_SKX", "AVX-512 (Skylake-X)"),
    ("X86_V4", "AVX-512"),
    ("AVX512F", "AVX-512"),
    ("X86_V3", "AVX2"),
    ("AVX2", "AVX2"),
    ("AVX", "AVX"),
    ("X86_V2", "SSE4.2"),
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

    Read from numpy's own run-time detection (``__cpu_features__``) among the levels numpy dispatches to or was built
    for (``__cpu_dispatch__``, ``__cpu_baseline__``), which also honours ``NPY_DISABLE_CPU_FEATURES`` (numpy's AVX2
    code on an AVX-512 machine says ``"AVX2"``); ``"unknown"`` if this numpy does not expose it.
    """
    module = None
    for name in ("numpy._core._multiarray_umath", "numpy.core._multiarray_umath"):  # numpy 2, numpy 1
        try:
            module = importlib.import_module(name)
        except ImportError:
            continue
        break
    features: dict[str, bool] | None = getattr(module, "__cpu_features__", None)
    if features is None:
        return "unknown"
    dispatch = getattr(module, "__cpu_dispatch__", None)
    levels = None if dispatch is None else {*dispatch, *getattr(module, "__cpu_baseline__", ())}
    for key, name in _LEVELS:
        if features.get(key) and (levels is None or key in levels):
            return name
    return "none"


def machine_line() -> str:
    """One line for a benchmark's header: CPU, SIMD level, CPUs visible, Python and numpy versions."""
    return (
        f"CPU: {cpu_model()}, SIMD {simd_level()}, {os.cpu_count()} CPUs visible; "
        f"{platform.python_implementation()} {platform.python_version()}, numpy {np.__version__}"
    )


def bits_key() -> str:
    """What the last bits of a float result depend on: CPU model, numpy's SIMD level, the kernels torch dispatches to
    (``ATEN_CPU_CAPABILITY``), MKL's code path (``MKL_ENABLE_INSTRUCTIONS``, ``MKL_CBWR``), numpy's and torch's
    versions (a claim recorded with the same key is compared exactly; tests/test_agents_v1_pretrained.py)."""
    try:
        torch = version("torch")
    except PackageNotFoundError:
        torch = "none"
    else:
        import torch as _torch

        torch += f" ({_torch.backends.cpu.get_cpu_capability()})"
    mkl = ",".join(f"{k}={os.environ[k]}" for k in ("MKL_ENABLE_INSTRUCTIONS", "MKL_CBWR") if os.environ.get(k))
    key = f"{cpu_model()}; SIMD {simd_level()}; numpy {np.__version__}; torch {torch}"
    return f"{key}; MKL {mkl}" if mkl else key
