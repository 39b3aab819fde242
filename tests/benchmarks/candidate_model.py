"""A candidate label model for both engines on the cross-check's objects (run by hand; issue 45).

    python -m tests.benchmarks.candidate_model run --engine pybullet --objects 20 \
        --sim ramp_ratio=1.4142135623730951 pad_torsion_mm=2.0 --out DIR
    python -m tests.benchmarks.candidate_model run --engine mujoco ...   # the same, beside it
    python -m tests.benchmarks.candidate_model summary --out DIR --parts KEPT.crosscheck

``run`` simulates every recorded grip of ``--objects`` objects of the cross-check's sample after
its first ``--skip`` (those ``KEPT`` holds, in the sample's order) in one engine with ``sim``
settings overridden (``--set SECTION.NAME=VALUE`` for another section's, e.g.
``uncertainty.stratified=true``), trials 0..T-1 and T..2T-1 as the cross-check does, and writes
each object's outcomes and CPU seconds to
``DIR``. ``summary`` prints, for the candidate and for the committed models' kept outcomes on the
same objects: each engine's within-object retest, the within-object Spearman and per-trial success
agreement between the engines; then, per engine, how far the candidate keeps the committed label
(trials judged alike, Spearman of the grips' means), its CPU ms a trial and the trials and
core-seconds of a trustworthy label (``crosscheck.trials_for``).

A candidate run with ``--set dataset.trials=T`` is compared at T trials a grip: its trials 0..T-1
against T..2T-1, the committed models' kept trials 0..T-1 against 5..5+T-1, both retests measured,
not extrapolated. Under stratified draws (``uncertainty.stratified``/``stratified_palm``) a label
is a whole block, so it needs at least T trials; ``summary`` then also prints, per engine, the
change of each object's mean robustness and success rate from the committed's ten trials: the
draws' distribution is unchanged by stratifying, so the label's expectation must be.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

from grip_env.dataset.crosscheck import _means, _spearman, trials_for
from grip_env.sim import run_trial_outcomes
from tests.benchmarks.crosscheck_contact_loads import kept_runs
from tests.benchmarks.torsion_arm import paired_interval

ENGINES = ("pybullet", "mujoco")
#: The cross-check sample's size: ``KEPT`` holds its objects' outcomes (the shipped one's, 80).
SAMPLE = 80


def run(parts: Path, objects: int, engine: str, sim: dict[str, float], out: Path,
        other: dict[str, dict[str, Any]] | None = None, skip: int = 0) -> None:
    """Simulate ``objects`` kept objects, after the first ``skip``, in ``engine`` under ``sim``
    (and the other sections' settings ``other``), into ``out``."""
    other = other or {}
    out.mkdir(parents=True, exist_ok=True)
    for count, (check, _) in enumerate(kept_runs(parts, SAMPLE, 0)):
        if count < skip:
            continue
        if count >= skip + objects:
            break
        config = check.task.config.override(sim={"engine": engine, **sim}, **other)
        grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        trials, seed = config.dataset.trials, config.dataset.seed
        started = time.process_time()
        both = pd.concat([run_trial_outcomes(check.task.obj, grips, config, trials, seed,
                                             trial_offset=offset) for offset in (0, trials)])
        seconds = time.process_time() - started
        both.to_parquet(out / f"{check.task.object_id}.{engine}.parquet")
        (out / f"{check.task.object_id}.{engine}.json").write_text(json.dumps(
            {"seconds": seconds, "trials": len(both), "sim": sim, "other": other}))
        print(f"{check.task.object_id} {engine}: {1e3 * seconds / len(both):.0f} ms a trial",
              flush=True)


def _figures(draws: dict[str, pd.DataFrame], retest: dict[str, pd.DataFrame]) -> dict[str, float]:
    a, b = (draws[e] for e in ENGINES)
    return {"retest pybullet": _spearman(_means(draws["pybullet"]), _means(retest["pybullet"])),
            "retest mujoco": _spearman(_means(draws["mujoco"]), _means(retest["mujoco"])),
            "within-object between engines": _spearman(_means(a), _means(b)),
            "success alike": float(np.mean(a["success"].to_numpy() == b["success"].to_numpy()))}


def summary(parts: Path, out: Path) -> None:
    """The candidate's figures beside the committed models' on the objects ``out`` holds; how
    far it keeps the committed label in each engine; each engine's cost of a trustworthy label."""
    rows: dict[str, list[dict[str, float]]] = {"committed": [], "candidate": []}
    cost = {e: [0.0, 0] for e in ENGINES}
    same: dict[str, list[pd.DataFrame]] = {e: [] for e in ENGINES}
    shifts: dict[str, list[tuple[float, float]]] = {e: [] for e in ENGINES}
    trials, stratified = 0, False
    for check, kept in kept_runs(parts, SAMPLE, 0):
        files = {e: out / f"{check.task.object_id}.{e}.parquet" for e in ENGINES}
        if not all(f.is_file() for f in files.values()):
            continue
        records = {e: json.loads(f.with_suffix(".json").read_text()) for e, f in files.items()}
        other = records["mujoco"].get("other", {})
        trials = other.get("dataset", {}).get("trials", check.task.config.dataset.trials)
        stratified = any(other.get("uncertainty", {}).get(name, False)
                         for name in ("stratified", "stratified_palm"))
        kept_first = {e: t[t["trial"] < trials] for e, t in kept.draws.items()}
        kept_retest = {e: t[t["trial"] < t["trial"].min() + trials] for e, t in kept.retest.items()}
        rows["committed"].append(_figures(kept_first, kept_retest))
        tables = {e: pd.read_parquet(f) for e, f in files.items()}
        draws = {e: t[t["trial"] < trials] for e, t in tables.items()}
        rows["candidate"].append(_figures(draws, {e: t[t["trial"] >= trials]
                                                  for e, t in tables.items()}))
        for e in ENGINES:
            same[e].append(_paired(draws[e], kept.draws[e], check.task.object_id))
            shifts[e].append(_shift(tables[e], pd.concat([kept.draws[e], kept.retest[e]])))
            cost[e][0] += records[e]["seconds"]
            cost[e][1] += records[e]["trials"]
    names = list(rows["candidate"][0])
    means = {model: {n: float(np.nanmean([r[n] for r in found])) for n in names}
             for model, found in rows.items()}
    print(f"{len(rows['candidate'])} objects (mean over objects), {trials} trials a grip "
          f"against the next {trials}\n")
    print("| model | " + " | ".join(names) + " |")
    print("| --- " * (len(names) + 1) + "|")
    for model, figures in means.items():
        print(f"| {model} | " + " | ".join(f"{figures[n]:.3f}" for n in names) + " |")
    print("| candidate − committed, 95 % over objects | " + " | ".join(
        _paired_change(rows, n) for n in names) + " |")
    print("\n| engine | trials alike with the committed | Spearman of grip means with the "
          "committed (pooled) | CPU ms a trial | trials for a retest of 0.8 (committed's) | "
          "core-s a label |")
    print("| --- | --- | --- | --- | --- | --- |")
    for e, (seconds, count) in cost.items():
        paired = pd.concat(same[e], ignore_index=True)
        alike = float((paired["success"] == paired["success_committed"]).mean())
        grips = paired.groupby(["object_id", "grip"])[["robustness", "robustness_committed"]]
        rho = _spearman(*grips.mean().to_numpy().T)
        before = trials_for(means["committed"][f"retest {e}"], trials)
        needed = trials_for(means["candidate"][f"retest {e}"], trials)
        needed = max(needed, trials) if stratified else needed
        ms = 1e3 * seconds / count
        print(f"| {e} | {alike:.1%} | {rho:.3f} | {ms:.0f} | {needed:.1f} ({before:.1f}) | "
              f"{needed * ms / 1e3:.2f} |")
    print("\n| engine | mean robustness a grip, candidate − committed (g, 95 % over objects) | "
          "success rate, candidate − committed |")
    print("| --- | --- | --- |")
    for e in ENGINES:
        change = np.array(shifts[e])
        print(f"| {e} | " + " | ".join(_interval(change[:, i], f) for i, f in
                                       ((0, "{:+.2f}"), (1, "{:+.3f}"))) + " |")


def _shift(candidate: pd.DataFrame, committed: pd.DataFrame) -> tuple[float, float]:
    """The change of an object's mean robustness (g) and success rate from the committed
    model's trials to the candidate's."""
    return (float(candidate["robustness"].mean() - committed["robustness"].mean()),
            float(candidate["success"].mean() - committed["success"].mean()))


def _interval(change: np.ndarray, form: str) -> str:
    """``change``'s mean with its 95 % paired bootstrap interval over objects."""
    low, high = paired_interval(change)
    return f"{form.format(change.mean())} [{form.format(low)}, {form.format(high)}]"


def _paired_change(rows: dict[str, list[dict[str, float]]], name: str) -> str:
    """The mean change of ``name`` from the committed model to the candidate over the objects
    where both are defined, with its 95 % paired bootstrap interval."""
    change = np.array([c[name] - k[name] for c, k in zip(rows["candidate"], rows["committed"],
                                                          strict=True)])
    return _interval(change[np.isfinite(change)], "{:+.3f}")


def _paired(candidate: pd.DataFrame, committed: pd.DataFrame, object_id: str) -> pd.DataFrame:
    """The candidate's trials beside the committed model's same trials (grip, trial)."""
    kept = committed[["grip", "trial", "robustness", "success"]]
    return candidate[["grip", "trial", "robustness", "success"]].merge(
        kept, on=["grip", "trial"], suffixes=("", "_committed"), validate="one_to_one"
    ).assign(object_id=object_id)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mode", choices=("run", "summary"))
    parser.add_argument("--parts", type=Path, default=Path(
        "/work/runs/crosscheck/standard40-lean.crosscheck"))
    parser.add_argument("--objects", type=int, default=20)
    parser.add_argument("--skip", type=int, default=0,
                        help="start after this many of the sample's objects")
    parser.add_argument("--engine", choices=ENGINES, default="mujoco")
    parser.add_argument("--sim", nargs="*", default=[], metavar="NAME=VALUE")
    parser.add_argument("--set", nargs="*", default=[], metavar="SECTION.NAME=VALUE",
                        help="another section's setting, its value read as YAML")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    if args.mode == "run":
        sim = {name: float(value) for name, value in (item.split("=") for item in args.sim)}
        other: dict[str, dict[str, Any]] = {}
        for item in args.set:
            key, value = item.split("=", 1)
            section, name = key.split(".", 1)
            other.setdefault(section, {})[name] = yaml.safe_load(value)
        run(args.parts, args.objects, args.engine, sim, args.out, other, args.skip)
    else:
        summary(args.parts, args.out)


if __name__ == "__main__":
    main()
