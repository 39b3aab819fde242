"""Where the engines part, disturbance by disturbance, on every trial (run by hand).

    python -m tests.benchmarks.direction_limits --objects 40 --workers 2 \\
        --parts runs/crosscheck/standard40-hertz.crosscheck --out runs/directions40.json

Every recorded grip of the cross-check's seeded objects (the sample ``grip-env validate
--crosscheck`` draws) runs trials 0..T-1 (the dataset's draws) in both engines with a ramp that
climbs every disturbance to its own limit (:func:`grip_env.sim.disturbance.direction_limits`,
where the labels' ramp stops each at the weakest level found so far). Printed:

- the within-object Spearman between the engines of the grips' mean label (the weakest limit),
  of their weakest push (the four forces), of their weakest twist, and of each disturbance, with
  95 % intervals over objects;
- each engine's mean push and twist limits, and the share of held trials a twist limits;
- with ``--parts`` (the cross-check's kept outcomes), how many labels equal the cross-check's bit
  for bit: a label the order of the directions cannot change.

``--out`` keeps each object's limits as it finishes, so the same command resumes.
(``crosscheck_directions`` does the same on a sample of the trials the engines judge apart.)
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from grip_env.dataset.crosscheck import _spearman
from tests.benchmarks.crosscheck_contact_loads import kept_runs

ENGINES = ("pybullet", "mujoco")
FORCES, TWISTS = slice(0, 4), slice(4, 6)  # PLANAR_DISTURBANCES: four pushes, two twists
BOOTSTRAP = 2000


def limits_of(job: tuple) -> tuple[str, str, dict]:
    """One object's trials in one engine: each trial's six direction limits (0 when not held)."""
    from grip_env.sim.disturbance import direction_limits
    from grip_env.sim.execution import grip_keys, object_key
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import trial_noises

    object_id, obj, grips, config, trials, engine = job
    config = config.override(sim={"engine": engine})
    seed = config.dataset.seed
    noises = trial_noises(config, seed, object_key(obj, grips), grip_keys(grips), range(trials))
    seen: list[list[float]] = []

    def ramp(probe, mass_kg, gyration_m, sim):
        limits = direction_limits(probe, mass_kg, gyration_m, sim)
        seen.append(limits.tolist())
        return float(limits.min())

    rows = []
    with TrialScene(obj, config, ramp=ramp) as scene:
        for label, plan, draws in zip(grips.index, grip_plans(grips), noises, strict=True):
            for k, noise in enumerate(draws):
                seen.clear()
                result = scene.run(plan, noise)
                rows.append({"grip": int(label), "trial": k, "robustness": result.robustness_g,
                             "limits": seen[0] if seen else [0.0] * 6})
    return object_id, engine, {"rows": rows}


def jobs(objects: int, seed: int, done: dict) -> list[tuple]:
    from grip_env.dataset.resimulation import _retest_sample
    from grip_env.datasets import standard_path

    work = []
    for check in _retest_sample(standard_path(), objects, seed):
        grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        for engine in ENGINES:
            if engine not in done.get(check.task.object_id, {}):
                work.append((check.task.object_id, check.task.obj, grips, check.task.config,
                             check.task.config.dataset.trials, engine))
    return work


def frame(rows: list[dict]) -> pd.DataFrame:
    table = pd.DataFrame(rows)
    limits = np.array(table.pop("limits").tolist(), dtype=float)
    table["push"], table["twist"] = limits[:, FORCES].min(1), limits[:, TWISTS].min(1)
    for k in range(limits.shape[1]):
        table[f"d{k}"] = limits[:, k]
    return table


def with_interval(values: np.ndarray, rng: np.random.Generator) -> str:
    values = values[np.isfinite(values)]
    picks = rng.integers(0, len(values), (BOOTSTRAP, len(values)))
    low, high = np.percentile(values[picks].mean(axis=1), [2.5, 97.5])
    return f"{values.mean():.2f} [{low:.2f}, {high:.2f}] ({len(values)} objects)"


def summary(done: dict, parts: Path | None, objects: int, seed: int) -> None:
    columns = ["robustness", "push", "twist"] + [f"d{k}" for k in range(6)]
    names = {"robustness": "the label (weakest)", "push": "weakest push", "twist": "weakest twist",
             "d0": "push +x", "d1": "push -x", "d2": "push +y", "d3": "push -y",
             "d4": "twist +z", "d5": "twist -z"}
    scores = {c: [] for c in columns}
    tables = {e: [] for e in ENGINES}
    for runs in done.values():
        if set(ENGINES) - set(runs):
            continue
        t = {e: frame(runs[e]["rows"]) for e in ENGINES}
        for c in columns:
            means = [t[e].groupby("grip")[c].mean().to_numpy() for e in ENGINES]
            scores[c].append(_spearman(*means))
        for e in ENGINES:
            tables[e].append(t[e])
    rng = np.random.default_rng(0)
    print("within-object Spearman between engines of the grips' means:")
    for c in columns:
        print(f"  {names[c]}: {with_interval(np.array(scores[c]), rng)}")
    for e in ENGINES:
        all_trials = pd.concat(tables[e])
        held = all_trials[all_trials["robustness"] > 0]
        print(f"{e}: {len(all_trials)} trials, mean push limit {all_trials['push'].mean():.1f} g,"
              f" twist limit {all_trials['twist'].mean():.1f} g; a twist limits "
              f"{(held['twist'] < held['push']).mean():.1%} of {len(held)} held trials")
    if parts is not None:
        compare_with_parts(done, parts, objects, seed)


def compare_with_parts(done: dict, parts: Path, objects: int, seed: int) -> None:
    """Labels equal to the cross-check's kept outcomes, bit for bit, per engine."""
    kept = {check.task.object_id: runs.draws for check, runs in kept_runs(parts, objects, seed)}
    for e in ENGINES:
        same = total = 0
        for object_id, runs in done.items():
            if e in runs and object_id in kept:
                ours = np.array([r["robustness"] for r in runs[e]["rows"]])
                theirs = kept[object_id][e]["robustness"].to_numpy()
                same, total = same + int((ours == theirs).sum()), total + len(ours)
        print(f"{e}: the weakest limit is the cross-check's label in {same} of {total} trials")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--parts", type=Path, help="the cross-check's kept outcomes (a folder)")
    parser.add_argument("--out", type=Path, required=True, help="JSON of every limit (resumes)")
    args = parser.parse_args()
    done = json.loads(args.out.read_text()) if args.out.exists() else {}
    work = jobs(args.objects, args.seed, done)
    with ProcessPoolExecutor(args.workers) as pool:
        for object_id, engine, runs in pool.map(limits_of, work):
            done.setdefault(object_id, {})[engine] = runs
            args.out.write_text(json.dumps(done))
            print(f"{object_id} {engine}: {len(runs['rows'])} trials", flush=True)
    summary(done, args.parts, args.objects, args.seed)


if __name__ == "__main__":
    main()
