"""How strong the worm gear's stop must be to hold every trial (run by hand):

    python -m tests.benchmarks.stop_hold --grips 150 --seed 0

Trial 0 (its recorded draw) of a seeded sample of the standard dataset's grips, in PyBullet, with
the stop at each ``hand.HOLD_FACTOR`` (times the joint's motor torque) against the unbounded one
(``inf``, a self-locking worm): how many outcomes (held, success and robustness) are the
unbounded stop's, bit for bit, and how many succeed. A factor whose outcomes are all the
unbounded stop's is one no trial loads its stop to.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import math
import platform
import time
from datetime import UTC, datetime

import pandas as pd

import grip_env.sim.hand as hand
from grip_env.portable_process import in_place
from grip_env.sim import run_trial_outcomes
from tests.benchmarks.engines import sampled_work

FACTORS = (math.inf, 50.0, 20.0, 5.0)
OUTCOME = ["held", "success", "robustness"]


def outcomes(work: list, factor: float) -> pd.DataFrame:
    """Trial 0 of every sampled grip with the stop at ``factor`` (patched in this process)."""
    kept = hand.HOLD_FACTOR
    hand.HOLD_FACTOR = factor
    try:
        with in_place():
            rows = [run_trial_outcomes(obj, table, config, trials=1, seed=config.dataset.seed)
                    for obj, table, config in work]
    finally:
        hand.HOLD_FACTOR = kept
    return pd.concat(rows, ignore_index=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grips", type=int, default=150)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    work = sampled_work(args.grips, args.seed)
    found, seconds = {}, {}
    for factor in FACTORS:
        started = time.process_time()
        found[factor] = outcomes(work, factor)
        seconds[factor] = time.process_time() - started
    unbounded = found[math.inf][OUTCOME]
    print("| stop (x motor) | trials | outcomes as the unbounded stop's | success | CPU s |")
    print("| --- | --- | --- | --- | --- |")
    for factor, table in found.items():
        same = int((table[OUTCOME] == unbounded).all(axis=1).sum())
        print(f"| {factor:g} | {len(table)} | {same} | {int(table['success'].sum())} | "
              f"{seconds[factor]:.0f} |")
    print(f"\n{datetime.now(UTC):%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()}")


if __name__ == "__main__":
    main()
