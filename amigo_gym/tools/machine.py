"""The machine a speed figure was measured on: CPU model and the SIMD level numpy dispatches to."""

from __future__ import annotations

import contextlib
import os
import platform
from importlib.metadata import PackageNotFoundError, version

import numpy as np

from amigo_gym.sim.fast_v1_batch import NUMPY_UMATH

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
    with contextlib.suppress(OSError), open("/proc/cpuinfo") as f:
        for line in f:
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine() or "unknown"


def simd_level() -> str:
    """The widest SIMD level that numpy detected on this CPU and may dispatch to (honouring
    ``NPY_DISABLE_CPU_FEATURES``), e.g. ``"AVX2"``; ``"unknown"`` if this numpy does not expose it."""
    features: dict[str, bool] | None = getattr(NUMPY_UMATH, "__cpu_features__", None)
    if features is None:
        return "unknown"
    dispatch = getattr(NUMPY_UMATH, "__cpu_dispatch__", None)
    levels = None if dispatch is None else {*dispatch, *getattr(NUMPY_UMATH, "__cpu_baseline__", ())}
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
    """What the last bits of a float result depend on: CPU model, numpy's SIMD level, torch's CPU capability, MKL's
    code path (``MKL_ENABLE_INSTRUCTIONS``, ``MKL_CBWR``), numpy's and torch's versions."""
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
