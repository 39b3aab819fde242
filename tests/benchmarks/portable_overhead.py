"""What running planning and trials in the held worker costs (BENCHMARKS.md, "Import order"):
``candidates()`` and one live ``GripSelect-v0`` step, in a process whose numpy came first (they
run in :mod:`grip_env.portable_process`'s worker) against one that imported grip_env first (they
run in place). Run by hand, on a CPU with AVX-512 (elsewhere both run in place):

    python -m tests.benchmarks.portable_overhead --repeats 5
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

#: Times, in one fresh process, the first ``candidates`` call (which starts the worker when the
#: kernels are not portable), then the median of ``repeats`` calls on each of the default set's
#: objects, and of ``repeats`` live steps (one trial each) on one of them.
TIMING = """
import json, statistics, time
{first}
import gymnasium
import grip_env
from grip_env.objects import load_object_set
from grip_env.pipeline import candidates
from grip_env.portable_math import math_is_portable

objects = load_object_set("default")
start = time.perf_counter()
candidates(objects[0])
first_call = time.perf_counter() - start
plan = []
for obj in objects:
    for _ in range({repeats}):
        start = time.perf_counter()
        candidates(obj)
        plan.append(time.perf_counter() - start)
env = gymnasium.make("GripSelect-v0", objects=[objects[0]])
steps = []
for seed in range({repeats}):
    observation, _ = env.reset(seed=seed)
    start = time.perf_counter()
    env.step(int(observation["mask"].argmax()))
    steps.append(time.perf_counter() - start)
env.close()
print(json.dumps({{"portable": math_is_portable(), "first_call_s": first_call,
                  "candidates_s": statistics.median(plan), "step_s": statistics.median(steps),
                  "objects": len(objects)}}))
"""


def _time(first: str, repeats: int) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE")}
    done = subprocess.run([sys.executable, "-c", TIMING.format(first=first, repeats=repeats)],
                          env=env, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(f"{'first import':16} {'kernels':9} {'1st candidates()':>17} {'candidates()':>13} "
          f"{'live step':>10}")
    for first in ("import grip_env", "import numpy"):
        found = _time(first, args.repeats)
        kernels = "x86-64-v3" if found["portable"] else "AVX-512"
        print(f"{first:16} {kernels:9} {found['first_call_s']:16.3f}s "
              f"{found['candidates_s']:12.4f}s {found['step_s']:9.3f}s")
    print(f"(medians over {args.repeats} calls on each of the {found['objects']} default "
          f"objects, and over {args.repeats} steps)")


if __name__ == "__main__":
    main()
