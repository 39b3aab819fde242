"""One engine's setting changed, the other engine's cross-check trials kept (run by hand).

    python -m tests.benchmarks.crosscheck_setting --parts R.crosscheck --family mesh \\
        --engine pybullet --setting pad_torsion_mm --values 1.7 0.0 --workers 2

A diagnostic of where the engines part, not a label model: the objects of a cross-check whose
parts are in ``--parts`` (``grip-env validate DIR --crosscheck N --report R.json`` keeps them in
``R.crosscheck/``) run their recorded grips and draws (trials 0..T-1) again in ``--engine`` with
``sim.<setting>`` at each value, and each object's within-object Spearman of the grips' mean
robustness against the other engine's kept trials is compared with the kept run's (the setting
as recorded), with a 95 % paired bootstrap interval over objects; also each engine's mean
robustness and the trials alike.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from tests.benchmarks.crosscheck_contact_loads import kept_runs
from tests.benchmarks.engines import ENGINES

SAMPLE = 80


def _kept(parts: Path, family: str | None) -> list:
    """(check, kept runs) of the sample's objects with parts, of ``family`` if given."""
    from grip_env.objects.family import object_family

    return [(check, runs) for check, runs in kept_runs(parts, SAMPLE, 0)
            if family is None or object_family(check.task.obj) == family]


def run_object(item: tuple[Path, str, str, str, list[float]]) -> list[dict]:
    """One object's figures: the kept run's and each value's."""
    from grip_env.dataset.crosscheck import _means, _spearman
    from grip_env.sim import run_trial_outcomes

    parts, object_id, engine, setting, values = item
    check, kept = next((c, r) for c, r in kept_runs(parts, SAMPLE, 0)
                       if c.task.object_id == object_id)
    other = next(e for e in ENGINES if e != engine)
    theirs = kept.draws[other]
    config = check.task.config
    grips = check.recorded.assign(object_id=object_id).reset_index(drop=True)
    runs: list[tuple[str, pd.DataFrame, float]] = [("kept", kept.draws[engine], 0.0)]
    for value in values:
        started = time.process_time()
        table = run_trial_outcomes(check.task.obj, grips, config.override(
            sim={"engine": engine, setting: value}), config.dataset.trials, config.dataset.seed)
        runs.append((f"{value:g}", table, time.process_time() - started))
    return [{"object_id": object_id, "run": name, "within": _spearman(_means(own), _means(theirs)),
             "own": own.robustness.mean(), "other": theirs.robustness.mean(), "trials": len(own),
             "alike": int((own.success.to_numpy(bool) == theirs.success.to_numpy(bool)).sum()),
             "cpu_s": seconds} for name, own, seconds in runs]


def report(table: pd.DataFrame, engine: str, setting: str, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    kept = table[table.run == "kept"].set_index("object_id")
    print(f"| {engine} {setting} | objects | within-object Spearman | minus the kept run's, 95 % "
          f"| mean robustness {engine} / other (g) | trials alike |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, rows in table.groupby("run", sort=False):
        rows = rows.set_index("object_id")
        difference = (rows.within - kept.within.loc[rows.index]).dropna().to_numpy()
        boot = difference[rng.integers(0, len(difference), (2000, len(difference)))].mean(1)
        low, high = np.quantile(boot, [0.025, 0.975])
        own = (rows.own * rows.trials).sum() / rows.trials.sum()
        other = (rows.other * rows.trials).sum() / rows.trials.sum()
        print(f"| {name} | {len(rows)} | {rows.within.mean():.3f} | {difference.mean():+.3f} "
              f"[{low:+.3f}, {high:+.3f}] | {own:.1f} / {other:.1f} | "
              f"{rows.alike.sum() / rows.trials.sum():.1%} |")
    print(f"CPU s {table.cpu_s.sum():.0f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--family", help="only this family's objects (mesh, procedural, named)")
    parser.add_argument("--engine", default="pybullet", choices=ENGINES)
    parser.add_argument("--setting", default="pad_torsion_mm")
    parser.add_argument("--values", type=float, nargs="+", required=True)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", help="a CSV of each object's figures")
    args = parser.parse_args()
    names = [check.task.object_id for check, _ in _kept(args.parts, args.family)]
    items = [(args.parts, n, args.engine, args.setting, args.values) for n in names]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = [row for found in pool.map(run_object, items) for row in found]
    table = pd.DataFrame(rows)
    if args.out:
        table.to_csv(args.out, index=False)
    report(table, args.engine, args.setting)


if __name__ == "__main__":
    main()
