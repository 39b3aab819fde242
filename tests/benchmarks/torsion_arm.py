"""How much the pads' torsional arm moves the labels (run by hand), in each engine.

    python -m tests.benchmarks.torsion_arm --grips 100 --arms 3.0 1.7
    python -m tests.benchmarks.torsion_arm --grips 100 --setting ramp_ratio --arms 1.1892 1.4142

Draws the seeded sample of the standard dataset's grips that ``tests.benchmarks.engines --grips``
draws, runs trial 0 (its recorded draw) of each at every ``sim.pad_torsion_mm`` in each engine,
and prints, against the first arm, how many trials keep their success, the mean robustness's
change with a 95 % paired bootstrap interval over grips, and the Spearman of robustness.
``--setting`` sweeps another ``sim`` setting the same way (``--arms`` are then its values).
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import time

import numpy as np
import pandas as pd
from scipy.stats import spearmanr

from tests.benchmarks.engines import ENGINES, sampled_work


def outcomes(work: list[tuple], engine: str, value: float,
             setting: str = "pad_torsion_mm") -> pd.DataFrame:
    """Trial 0 of every grip of ``work`` in ``engine`` with ``sim.<setting>`` at ``value`` (by
    default the pads' torsional arm, mm)."""
    from grip_env.sim import run_trial_outcomes

    rows = [run_trial_outcomes(obj, table, config.override(
        sim={"engine": engine, setting: value}), trials=1, seed=config.dataset.seed)
        for obj, table, config in work]
    return pd.concat(rows, ignore_index=True)


def paired_interval(difference: np.ndarray, seed: int = 0, resamples: int = 2000,
                    ) -> tuple[float, float]:
    """95 % bootstrap interval of the mean of paired differences."""
    rng = np.random.default_rng(seed)
    means = difference[rng.integers(0, len(difference), (resamples, len(difference)))].mean(1)
    return float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grips", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--arms", type=float, nargs="+", default=[3.0, 1.7])
    parser.add_argument("--engines", nargs="+", default=list(ENGINES), choices=ENGINES)
    parser.add_argument("--setting", default="pad_torsion_mm", help="the sim setting swept")
    args = parser.parse_args()
    work = sampled_work(args.grips, args.seed)
    print(f"| engine | {args.setting} | held | success | mean robustness (g) | minus the first "
          "value's | success alike | Spearman | CPU s | steps |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    tables: dict[tuple[str, float], pd.DataFrame] = {}
    for engine in args.engines:
        first = None
        for arm in args.arms:
            started = time.process_time()
            table = tables[engine, arm] = outcomes(work, engine, arm, args.setting)
            seconds = time.process_time() - started
            first = table if first is None else first
            change = table["robustness"].to_numpy() - first["robustness"].to_numpy()
            low, high = paired_interval(change)
            alike = int((table["success"] == first["success"]).sum())
            rho = spearmanr(table["robustness"], first["robustness"]).statistic
            print(f"| {engine} | {arm:g} | {int(table['held'].sum())} | "
                  f"{int(table['success'].sum())} | {table['robustness'].mean():.1f} | "
                  f"{change.mean():+.1f} [{low:+.1f}, {high:+.1f}] | {alike} of {len(table)} | "
                  f"{rho:.2f} | {seconds:.1f} | {int(table['steps'].sum())} |")
    if len(args.engines) == 2:
        _between_engines(tables, args.engines, args.arms)


def _between_engines(tables: dict[tuple[str, float], pd.DataFrame], engines: list[str],
                     arms: list[float]) -> None:
    print("\n| value | success alike between engines | Spearman of robustness |")
    print("| --- | --- | --- |")
    for arm in arms:
        a, b = (tables[engine, arm] for engine in engines)
        alike = int((a["success"] == b["success"]).sum())
        rho = spearmanr(a["robustness"], b["robustness"]).statistic
        print(f"| {arm:g} | {alike} of {len(a)} | {rho:.2f} |")


if __name__ == "__main__":
    main()
