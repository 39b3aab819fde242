"""What running planning and trials in the held worker costs (BENCHMARKS.md, "Import order"):
``candidates()`` and one live ``GripSelect-v0`` step. Run by hand, on a CPU with AVX-512:

    python -m tests.benchmarks.portable_overhead --repeats 5

In a fresh process whose numpy came first, each call is timed twice, back to back: as it runs
(in :mod:`grip_env.portable_process`'s worker) and in place
(:func:`~grip_env.portable_process.in_place`, the same work on this process's kernels).
The overhead is the median of the paired differences, so that the load of a shared machine
cancels as far as it can. The first call, which starts the worker, is timed on its own.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

TIMING = """
import json, statistics, time
import numpy, gymnasium
import grip_env
from grip_env.objects import load_object_set
from grip_env.pipeline import candidates
from grip_env.portable_math import math_is_portable
from grip_env.portable_process import in_place

def timed(call):
    start = time.perf_counter()
    call()
    return time.perf_counter() - start

def paired(call):
    there = timed(call)
    with in_place():
        here = timed(call)
    return there, here

objects = load_object_set("default")
first_call = timed(lambda: candidates(objects[0]))
plans = [paired(lambda: candidates(obj)) for obj in objects for _ in range({repeats})]
env = gymnasium.make("GripSelect-v0", objects=[objects[0]])
steps = []
for seed in range({repeats}):
    for where in ("worker", "here"):
        observation, _ = env.reset(seed=seed)
        step = lambda: env.step(int(observation["mask"].argmax()))
        if where == "worker":
            there = timed(step)
        else:
            with in_place():
                steps.append((there, timed(step)))
env.close()
median = lambda pairs, i: statistics.median(p[i] for p in pairs)
print(json.dumps({{
    "portable": math_is_portable(), "first_call_s": first_call, "objects": len(objects),
    "candidates_here_s": median(plans, 1),
    "candidates_overhead_s": statistics.median(a - b for a, b in plans),
    "step_here_s": median(steps, 1), "step_overhead_s": statistics.median(a - b for a, b in steps),
}}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items()
           if k not in ("NPY_DISABLE_CPU_FEATURES", "OPENBLAS_CORETYPE")}
    done = subprocess.run([sys.executable, "-c", TIMING.format(repeats=args.repeats)], env=env,
                          check=True, capture_output=True, text=True)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    if found["portable"]:
        print("this CPU's numpy has no kernels beyond x86-64-v3: nothing runs in a worker")
        return
    print(f"first candidates() call, which starts the worker: {found['first_call_s']:.2f} s")
    print(f"candidates(), median over {args.repeats} calls on each of the {found['objects']} "
          f"default objects: {found['candidates_here_s'] * 1e3:.1f} ms in place, "
          f"{found['candidates_overhead_s'] * 1e3:+.1f} ms in the worker")
    print(f"one live GripSelect-v0 step, median over {args.repeats} steps: "
          f"{found['step_here_s'] * 1e3:.0f} ms in place, "
          f"{found['step_overhead_s'] * 1e3:+.1f} ms in the worker")


if __name__ == "__main__":
    main()
