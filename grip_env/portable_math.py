"""The same float64 results on every x86-64 machine: vector math held at x86-64-v3 (AVX2, FMA).

numpy picks its kernels for ``sin``, ``cos``, ``exp``, ``log``, ``arctan2``, ``power`` and the
like at import, and OpenBLAS its matrix kernels at load, by the CPU. Their AVX-512 kernels round
some results a unit in the last place otherwise than the AVX2 ones, and planning and a grip's
closing amplify that into other candidates and other outcomes (measured on an AVX-512 Xeon against
the AVX2 EPYCs that recorded the golden trials and the standard dataset: BENCHMARKS.md, "AVX-512:
the same labels on every machine"). Held at x86-64-v3, which every x86-64 server since 2015 has,
both give the recorded bits.

Importing :mod:`grip_env` sets ``NPY_DISABLE_CPU_FEATURES`` and, on a CPU with AVX-512,
``OPENBLAS_CORETYPE=Haswell`` (each unless set already) before numpy loads; child processes
inherit them. When numpy was imported first (``import gymnasium, grip_env``), its AVX-512 kernels
are live in this process: planning, perception and trials then run in a worker process held at
x86-64-v3 (:mod:`grip_env.portable_process`), and the commands that record labels (generate,
calibrate, validate, the study's replication) make them in held workers, so candidates, outcomes
and datasets are the same on every machine whatever the order of imports.
"""

from __future__ import annotations

import os
from pathlib import Path

#: numpy's dispatch targets above x86-64-v3 (the names of numpy 2.4, then of 1.26 to 2.3).
BEYOND_V3 = ("X86_V4", "AVX512_ICL", "AVX512_SPR", "AVX512F", "AVX512CD", "AVX512_KNL",
             "AVX512_KNM", "AVX512_SKX", "AVX512_CLX", "AVX512_CNL")
#: OpenBLAS's kernels for AVX-512 CPUs, and the AVX2 one they are held at.
OPENBLAS_BEYOND_V3 = ("SkylakeX", "Cooperlake", "SapphireRapids")
OPENBLAS_V3 = "Haswell"
NUMPY_ENVIRONMENT = "NPY_DISABLE_CPU_FEATURES"
OPENBLAS_ENVIRONMENT = "OPENBLAS_CORETYPE"


def hold_at_v3() -> None:
    """Ask numpy and OpenBLAS (when loaded after this, here or in a child process) for no AVX-512
    kernels; a value the user set is kept."""
    os.environ.setdefault(NUMPY_ENVIRONMENT, " ".join(BEYOND_V3))
    if _cpu_has_avx512():  # OpenBLAS's Haswell kernel would fault on a CPU without AVX2
        os.environ.setdefault(OPENBLAS_ENVIRONMENT, OPENBLAS_V3)


def _cpu_has_avx512() -> bool:
    try:
        flags = Path("/proc/cpuinfo").read_text().split()
    except OSError:  # not Linux: numpy's part still holds
        return False
    return "avx512f" in flags


def live_beyond_v3() -> list[str]:
    """The kernels above x86-64-v3 active in this process: numpy's dispatch targets and the
    OpenBLAS libraries' kernels (``"numpy X86_V4"``, ``"OpenBLAS SkylakeX"``)."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    from threadpoolctl import threadpool_info

    live = [f"numpy {t}" for t in __cpu_dispatch__ if t in BEYOND_V3 and __cpu_features__.get(t)]
    kernels = {info.get("architecture") for info in threadpool_info()
               if info.get("internal_api") == "openblas"}
    return live + [f"OpenBLAS {k}" for k in sorted(kernels & set(OPENBLAS_BEYOND_V3))]


def math_is_portable() -> bool:
    """Whether this process computes with x86-64-v3 kernels only (the recorded labels' bits)."""
    return not live_beyond_v3()

