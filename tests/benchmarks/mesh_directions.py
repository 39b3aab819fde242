"""Each disturbance direction's level on every grip of named cross-check objects, both engines
(run by hand; issue 45).

    python -m tests.benchmarks.mesh_directions urdf_901 urdf_930 --trials 3

Runs every recorded grip of each named object of the cross-check's sample (``--objects``,
``--seed`` as the cross-check's) for trials 0..T-1 in both engines, with every direction of the
ramp raised to the ceiling (``crosscheck_directions.every_direction``), and prints per grip the
mean level (g) each direction held and the robustness (the lowest): which direction limits the
grips, and whether it tells the grips apart.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import time

import numpy as np

import grip_env.sim.trial as trial_module
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.sim import run_trial_outcomes
from tests.benchmarks.crosscheck_directions import every_direction

ENGINES = ("pybullet", "mujoco")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("object_ids", nargs="+")
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    found: list[dict[str, float]] = []
    trial_module.robustness = every_direction(found)
    started = time.process_time()
    for check in _retest_sample(standard_path(), args.objects, args.seed):
        if check.task.object_id not in args.object_ids:
            continue
        grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        config = check.task.config
        for engine in ENGINES:
            in_engine = config.override(sim={"engine": engine})
            per_grip: dict[int, list[dict[str, float]]] = {}
            robust: dict[int, list[float]] = {}
            for grip in range(len(grips)):
                for trial in range(args.trials):
                    found.clear()
                    row = run_trial_outcomes(check.task.obj, grips.iloc[[grip]], in_engine, 1,
                                             config.dataset.seed, trial_offset=trial)
                    per_grip.setdefault(grip, []).append(found[0] if found else {})
                    robust.setdefault(grip, []).append(float(row["robustness"].iloc[0]))
            print(f"\n{check.task.object_id} in {engine}: mean level (g) each direction held "
                  f"over trials 0..{args.trials - 1} (trials not held after the lift count 0)")
            names = sorted({k for ls in per_grip.values() for d in ls for k in d})
            print("| grip | " + " | ".join(names) + " | robustness |")
            print("| --- " * (len(names) + 2) + "|")
            for grip, ls in per_grip.items():
                cells = [np.mean([d.get(n, 0.0) for d in ls]) for n in names]
                print(f"| {grip} | " + " | ".join(f"{c:.1f}" for c in cells)
                      + f" | {np.mean(robust[grip]):.1f} |", flush=True)
    print(f"\nCPU {time.process_time() - started:.1f} s (this process)")


if __name__ == "__main__":
    main()
