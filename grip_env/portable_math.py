"""The same float64 results on every x86-64 machine: numpy's vector math held at x86-64-v3.

numpy picks its kernels for ``sin``, ``cos``, ``exp``, ``log``, ``arctan2``, ``power`` and the
like at import, by the CPU. Its AVX-512 kernels round some results one unit in the last place
otherwise than its AVX2 ones, and planning and a grip's closing amplify that into other candidates
and other outcomes (measured on an AVX-512 Xeon against the AVX2 EPYCs that recorded the golden
trials and the standard dataset: BENCHMARKS.md, "The same labels on every machine"). Holding
numpy at x86-64-v3 (AVX2 and FMA, which every x86-64 server since 2015 has) gives the recorded
bits on both.

Importing :mod:`grip_env` sets ``NPY_DISABLE_CPU_FEATURES`` (unless it is set already) before it
imports numpy, and child processes inherit it. When numpy was imported first, its AVX-512 kernels
may be live: :func:`check_portable_math` then refuses to make labels, rather than make other ones.
"""

from __future__ import annotations

import os

#: numpy's dispatch targets above x86-64-v3 (the names of numpy 2.4, then of 1.26 to 2.3).
BEYOND_V3 = ("X86_V4", "AVX512_ICL", "AVX512_SPR", "AVX512F", "AVX512CD", "AVX512_KNL",
             "AVX512_KNM", "AVX512_SKX", "AVX512_CLX", "AVX512_CNL")
ENVIRONMENT = "NPY_DISABLE_CPU_FEATURES"


def hold_numpy_at_v3() -> None:
    """Ask numpy (when imported after this, here or in a child process) for no AVX-512 kernels;
    a value the user set is kept."""
    os.environ.setdefault(ENVIRONMENT, " ".join(BEYOND_V3))


def live_beyond_v3() -> list[str]:
    """numpy's dispatch targets above x86-64-v3 that are active in this process."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    return [t for t in __cpu_dispatch__ if t in BEYOND_V3 and __cpu_features__.get(t)]


def check_portable_math() -> None:
    """Raise ``RuntimeError`` when numpy's AVX-512 kernels are active in this process: labels
    made here would differ from every other machine's."""
    live = live_beyond_v3()
    if live:
        raise RuntimeError(
            f"numpy's {', '.join(live)} kernels are active here (numpy was imported before "
            "grip_env, or NPY_DISABLE_CPU_FEATURES was set otherwise): they round sin, exp and "
            "arctan2 differently from other machines, so the labels would differ. Import "
            f"grip_env before numpy, or set {ENVIRONMENT}=\"{' '.join(BEYOND_V3)}\"")
