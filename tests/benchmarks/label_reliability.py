"""Within-object test-retest of the labels by trials per grip and draw scheme (BENCHMARKS.md,
"Labels that rank the grips of one object"). Run by hand; it takes minutes.

    python -m tests.benchmarks.label_reliability --objects 12 --trials 3 --cache runs/reliability
    python -m tests.benchmarks.label_reliability --objects 12 --trials 5 --schemes common

Objects: the default set in order, then procedural ones, each with at least 4 kept grips (the
dataset's own ``keep_grips``: up to ``dataset.max_grips_per_object``, stratified over Q_C). Each
grip runs 2 x T trials (``--trials`` T) under every draw scheme of ``SCHEMES``: seed set A is
trials 0..t-1, set B trials T..T+t-1, for t = 1..T (independent draws are independent of T; a
stratified scheme stratifies blocks of ``dataset.trials`` = T). Per object: Spearman of the A
and B grip means; the figure is their mean over objects with a bootstrap interval over objects,
and the pooled Spearman over all grips. The cost: core-seconds per grip per trial.

    python -m tests.benchmarks.label_reliability --data standard --objects 40 --trials 5 \
        --cache runs/reliability

With ``--data``, the objects are those ``grip-env validate DATA --retest N`` draws (all their
recorded grips) and the scheme is the dataset's own: its recorded ``R`` trials stand as trials
0..R-1 (their mean), trials R..2T-1 are simulated with the dataset's config and seed, and the
figure is given for t = R..T.
"""

from __future__ import annotations

import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from grip_env.config import Config
from grip_env.dataset.resimulation import retest_sample
from grip_env.dataset.sampling import keep_grips
from grip_env.datasets import standard_path
from grip_env.objects import PlanarObject, load_object_set, procedural_objects
from grip_env.planning.pipeline import candidates
from grip_env.sim import run_trial_outcomes

#: (name, uncertainty overrides).
SCHEMES = {
    "per_grip": {"draws": "per_grip", "stratified": False},
    "common": {"draws": "common", "stratified": False},
    "common_stratified": {"draws": "common", "stratified": True},
}
MIN_GRIPS = 4


def chosen_objects(count: int, config: Config) -> list[tuple[PlanarObject, pd.DataFrame]]:
    """The first ``count`` objects with at least ``MIN_GRIPS`` kept grips, and those grips."""
    out = []
    for index, obj in enumerate([*load_object_set("default"), *procedural_objects(40, 0)]):
        kept = keep_grips(candidates(obj, config=config), config.dataset, seed=index)
        if len(kept) >= MIN_GRIPS:
            out.append((obj, kept))
        if len(out) == count:
            break
    return out


def _run(job: tuple) -> pd.DataFrame:
    obj, grips, config, trials, scheme = job
    started = time.process_time()
    out = run_trial_outcomes(obj, grips, config, trials=2 * trials, seed=0)
    seconds = time.process_time() - started
    return out.assign(object=obj.name, scheme=scheme, core_s=seconds / len(out))


def outcomes(count: int, trials: int, workers: int, cache: str | None,
             schemes: tuple[str, ...] = tuple(SCHEMES)) -> pd.DataFrame:
    """Every trial of every scheme (cached in ``cache``/reliability_T[_schemes].parquet)."""
    tag = "" if set(schemes) == set(SCHEMES) else "_" + "_".join(schemes)
    path = Path(cache) / f"reliability_{trials}{tag}.parquet" if cache else None
    if path is not None and path.exists():
        return pd.read_parquet(path)
    base = Config().override(dataset={"trials": trials})
    objects = chosen_objects(count, base)
    jobs = [(obj, grips, base.override(uncertainty=overrides), trials, name)
            for name, overrides in SCHEMES.items() if name in schemes for obj, grips in objects]
    with ProcessPoolExecutor(workers) as pool:
        table = pd.concat(pool.map(_run, jobs), ignore_index=True)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        table.to_parquet(path)
    return table


def dataset_outcomes(path: str, count: int, trials: int, workers: int,
                     cache: str | None = None) -> pd.DataFrame:
    """The ``--data`` rows: each recorded grip's mean as trials 0..R-1, then trials R..2T-1
    (cached in ``cache``/reliability_data_<objects>_<T>.parquet)."""
    stored = Path(cache) / f"reliability_data_{count}_{trials}.parquet" if cache else None
    if stored is not None and stored.exists():
        return pd.read_parquet(stored)
    sample = retest_sample(standard_path() if path == "standard" else path, count)
    recorded = sample[0][0].config.dataset.trials
    if trials < recorded:
        raise ValueError(f"--trials must be at least the dataset's {recorded}, got {trials}")
    with ProcessPoolExecutor(workers) as pool:
        found = list(pool.map(_extend, [(task, rows, 2 * trials) for task, rows in sample]))
    table = pd.concat(found, ignore_index=True)
    if stored is not None:
        stored.parent.mkdir(parents=True, exist_ok=True)
        table.to_parquet(stored)
    return table


def _extend(job: tuple) -> pd.DataFrame:
    task, rows, total = job
    config = task.config
    recorded = config.dataset.trials
    grips = rows.assign(object_id=task.object_id).reset_index(drop=True)
    started = time.process_time()
    new = run_trial_outcomes(task.obj, grips, config, total - recorded, config.dataset.seed,
                             trial_offset=recorded)
    seconds = time.process_time() - started
    old = pd.DataFrame({"grip": np.repeat(grips.index.to_numpy(), recorded),
                        "trial": np.tile(np.arange(recorded), len(grips)),
                        "robustness": np.repeat(grips["robustness_mean"].to_numpy(), recorded)})
    return pd.concat([old, new[["grip", "trial", "robustness"]]], ignore_index=True).assign(
        object=task.object_id, scheme="dataset", core_s=seconds / len(new), recorded=recorded)


def retest(table: pd.DataFrame, trials: int, t: int, resamples: int = 2000) -> dict:
    """Within-object and pooled Spearman of set A (trials 0..t-1) against B (T..T+t-1)."""
    a = table[table["trial"] < t].groupby(["object", "grip"])["robustness"].mean()
    b = table[(table["trial"] >= trials) & (table["trial"] < trials + t)]
    b = b.groupby(["object", "grip"])["robustness"].mean()
    both = pd.DataFrame({"A": a, "B": b}).dropna()
    within = []
    for _, g in both.groupby(level="object"):
        if g["A"].nunique() > 1 and g["B"].nunique() > 1:
            within.append(stats.spearmanr(g["A"], g["B"]).statistic)
    within = np.array(within)
    rng = np.random.default_rng(0)
    boot = [within[rng.integers(0, within.size, within.size)].mean() for _ in range(resamples)]
    return {"trials": t, "within": round(float(within.mean()), 3),
            "within_ci": np.round(np.percentile(boot, [2.5, 97.5]), 3).tolist(),
            "objects": int(within.size), "grips": len(both),
            "pooled": round(float(stats.spearmanr(both["A"], both["B"]).statistic), 3),
            "robustness_g": round(float(table["robustness"].mean()), 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=12)
    parser.add_argument("--trials", type=int, default=3, help="T: trials per seed set")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--cache", default=None)
    parser.add_argument("--schemes", nargs="*", choices=tuple(SCHEMES), default=list(SCHEMES))
    parser.add_argument("--data", default=None, help="a dataset folder or 'standard'")
    args = parser.parse_args()
    started = time.perf_counter()
    if args.data:
        table = dataset_outcomes(args.data, args.objects, args.trials, args.workers, args.cache)
        first = int(table["recorded"].iloc[0])
    else:
        table = outcomes(args.objects, args.trials, args.workers, args.cache, tuple(args.schemes))
        first = 1
    result = {name: {"retest": [retest(part, args.trials, t)
                                for t in range(first, args.trials + 1)],
                     "core_s_per_trial": round(float(part["core_s"].mean()), 3)}
              for name, part in table.groupby("scheme", sort=False)}
    print(json.dumps({"objects": args.objects, "trials": args.trials, "result": result,
                      "seconds": round(time.perf_counter() - started, 1)}, indent=1))


if __name__ == "__main__":
    main()
