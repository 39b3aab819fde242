"""MuJoCo's own within-object retest on the cross-check's finished objects (run by hand; issue 45).

    python -m tests.benchmarks.mujoco_retest --out runs/crosscheck-40 --objects 6

For each of the first ``--objects`` objects that ``tests.benchmarks.crosscheck_resumable`` has
finished, runs every grip's trials ``T..2T-1`` (``trial_offset=T``: draws disjoint from the
cross-check's ``0..T-1``) in MuJoCo and prints the Spearman of the grips' mean robustness between
the two sets, per object and their mean: the ceiling for the engines' within-object agreement, as
PyBullet's retest (0.83) is for PyBullet.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.sim import run_trial_outcomes
from tests.benchmarks.crosscheck_resumable import _files


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=6)
    parser.add_argument("--sample", type=int, default=40, help="the cross-check's sample size")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    checks = _retest_sample(standard_path(), args.sample, args.seed)
    scores = []
    for k, check in enumerate(checks[: args.objects]):
        first = pd.read_parquet(_files(args.out, k)[1])
        config = check.task.config.override(sim={"engine": "mujoco"})
        grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        trials, seed = config.dataset.trials, config.dataset.seed
        second = run_trial_outcomes(check.task.obj, grips, config, trials, seed,
                                    trial_offset=trials)
        a = first.groupby("grip")["robustness"].mean()
        b = second.groupby("grip")["robustness"].mean()
        rho = (float(stats.spearmanr(a, b).statistic)
               if np.ptp(a) > 0 and np.ptp(b) > 0 else float("nan"))
        scores.append(rho)
        print(f"object {k} ({check.task.object_id}): {len(a)} grips, retest Spearman {rho:.3f}",
              flush=True)
    print(f"MuJoCo within-object retest on {len(scores)} objects: mean "
          f"{np.nanmean(scores):.3f} ({datetime.now(UTC):%Y-%m-%d %H:%M} UTC)")


if __name__ == "__main__":
    main()
