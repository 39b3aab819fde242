"""How long grip images take on the standard dataset, cold and cached (BENCHMARKS.md, "Grip
images"). Run by hand:

    python -m tests.benchmarks.grip_images --repeats 3

It loads the dataset with its contours, then, ``--repeats`` times, clears the image cache and
draws every grip (cold), draws them again (cached, checked equal bit for bit) and draws a fold
without every fifth object (cached), printing CPU and wall seconds of each step.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from classifiers.learners.grip_images import GripImages, clear_image_cache, load_with_contours
from grip_env import datasets


def timed(step: Callable[[], Any]) -> tuple[Any, float, float]:
    """``step()``'s result, its CPU seconds and its wall seconds."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = step()
    return result, time.process_time() - cpu, time.perf_counter() - wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()}")
    grips, cpu, wall = timed(lambda: load_with_contours(datasets.standard_path()))
    print(f"load_with_contours: {len(grips)} grips, CPU {cpu:.2f} s, wall {wall:.2f} s")
    images = GripImages()
    ids = grips["object_id"].unique()
    fold = grips[~grips["object_id"].isin(ids[::5])]
    for _ in range(args.repeats):
        clear_image_cache()
        cold, cpu, wall = timed(lambda: images.fit_transform(grips))
        print(f"cold: {cold.shape} {cold.dtype}, CPU {cpu:.2f} s, wall {wall:.2f} s")
        cached, cpu, wall = timed(lambda: images.transform(grips))
        print(f"cached: same bits {np.array_equal(cold, cached)}, CPU {cpu:.2f} s, "
              f"wall {wall:.2f} s")
        _, cpu, wall = timed(lambda: images.transform(fold))
        print(f"cached fold of {len(fold)} grips: CPU {cpu:.2f} s, wall {wall:.2f} s")
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
