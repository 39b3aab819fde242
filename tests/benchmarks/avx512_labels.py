"""Do numpy's AVX-512 kernels move the labels? (BENCHMARKS.md, "The same labels on every machine").
Run by hand, on a CPU with AVX-512; an explicit ``NPY_DISABLE_CPU_FEATURES`` is kept by
:mod:`grip_env.portable_math`, here and in its workers.

    python -m tests.benchmarks.avx512_labels --grips 48                             # held at v3
    NPY_DISABLE_CPU_FEATURES="" python -m tests.benchmarks.avx512_labels --grips 48  # AVX-512 live

It counts the golden trials that differ from their recording, and re-plans and re-simulates a
seeded sample of the standard dataset's grips (``grip-env validate --resimulate``).
"""

from __future__ import annotations

import argparse

from grip_env import datasets
from grip_env.dataset.resimulation import resimulate
from grip_env.portable_math import live_beyond_v3
from tests.golden import differences, recording


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grips", type=int, default=48, help="standard grips to re-simulate")
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args()
    live = live_beyond_v3()
    stored = recording()
    moved = {line.split(" trial ")[0] + " " + line.split(" trial ")[1].split(":")[0]
             for line in differences(stored)}
    found = resimulate(datasets.standard_path(), args.grips, seed=0, workers=args.workers)
    print(f"numpy kernels above x86-64-v3 live: {live or 'none'}")
    print(f"golden trials that differ from the recording: {len(moved)} of "
          f"{len(stored['outcomes'])}")
    print(f"standard dataset: {found.summary()}")


if __name__ == "__main__":
    main()
