"""Does the Python API give the recorded labels whatever is imported first? (BENCHMARKS.md,
"Import order"). Run by hand, on a CPU with AVX-512:

    python -m tests.benchmarks.import_order --objects 5 --grips 5

In a fresh process that imports numpy and gymnasium before grip_env (and in one that imports
grip_env first), a seeded sample of the standard dataset's objects is perceived and planned again
with ``grip_env.pipeline.candidates`` and ``grips`` recorded grips of each simulated again with
``grip_env.sim.run_trials`` (the script of tests/test_portable_math.py), compared bit for bit with
the recorded rows.
"""

from __future__ import annotations

import argparse

from tests.test_portable_math import REPLAY, _run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=5, help="standard objects to plan again")
    parser.add_argument("--grips", type=int, default=5, help="recorded grips an object")
    args = parser.parse_args()
    for first in ("import numpy, gymnasium", "import grip_env"):
        found = _run(REPLAY.format(first=first, objects=args.objects, grips=args.grips,
                                   replay=True))
        print(f"{first}: kernels {', '.join(found['live']) or 'x86-64-v3'}; candidates "
              f"identical on {found['candidates_identical']} of {len(found['objects'])} objects, "
              f"outcomes on {found['outcomes_identical']} of {found['grips']} grips")


if __name__ == "__main__":
    main()
