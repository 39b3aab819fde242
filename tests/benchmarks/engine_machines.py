"""Do the golden trials give the same bits on another CPU, in each engine? (run by hand)

    python -m tests.benchmarks.engine_machines

Runs ``tests/golden.py``'s trials (6 objects, 18 grips, 3 trials) in each engine in fresh
processes whose kernels stand in for other machines, and counts the trials where any pinned field
(robustness, success, steps, drift...) moved, and where robustness or success did:

* ``numpy<v3``: numpy without its AVX2/FMA kernels and OpenBLAS on its SSE kernel (what
  ``tests/test_machine_repro.py`` calls an older CPU);
* ``libm-fma-off``: glibc's libm without its FMA variants of sin, cos, exp, pow, atan
  (``GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA``: glibc picks them only on a CPU with FMA and
  AVX2, x86-64-v3; a CPU before 2013 does not have them);
* ``older-cpu``: both, as a pre-x86-64-v3 CPU would run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
MACHINES = {
    "numpy<v3": {"NPY_DISABLE_CPU_FEATURES": "X86_V3", "OPENBLAS_CORETYPE": "Nehalem"},
    "libm-fma-off": {"GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA"},
    "older-cpu": {"NPY_DISABLE_CPU_FEATURES": "X86_V3", "OPENBLAS_CORETYPE": "Nehalem",
                  "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA"},
}
_SCRIPT = ("import json, sys, golden, pandas as pd; engine = sys.argv[1]; "
           "print(json.dumps(golden.run(pd.DataFrame(golden.recording(engine)['grips']), "
           "engine)))")


def outcomes(engine: str, environment: dict[str, str]) -> list[dict]:
    """The golden trials' pinned outcomes in ``engine``, in a fresh process."""
    done = subprocess.run([sys.executable, "-c", _SCRIPT, engine], capture_output=True,
                          text=True, env={**os.environ, **environment}, cwd=TESTS, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", nargs="+", default=["pybullet", "mujoco"])
    args = parser.parse_args()
    for engine in args.engines:
        reference = outcomes(engine, {})
        for machine, environment in MACHINES.items():
            other = outcomes(engine, environment)
            moved = sum(a != b for a, b in zip(reference, other, strict=True))
            label = sum((a["robustness"], a["success"]) != (b["robustness"], b["success"])
                        for a, b in zip(reference, other, strict=True))
            flips = sum(a["success"] != b["success"] for a, b in zip(reference, other,
                                                                     strict=True))
            print(f"{engine:8} {machine:13} trials moved {moved:2d} of {len(reference)}, "
                  f"robustness or success {label}, success flipped {flips}", flush=True)


if __name__ == "__main__":
    main()
