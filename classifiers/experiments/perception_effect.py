"""What planning on the rendered contour changes: the same objects planned on the true polygon
and on the contour segmented from the top-down render, paired by object.

The dataset already holds the grips planned on the render (their outcomes simulated on the true
body). This stage plans each object a second time, on its true contour, and simulates that plan's
best grip by Q_C on the true body (the only extra trials). Per object it pairs the two best grips:
each feature, Q_C and the success rate, rendered minus true, with a 95 % bootstrap interval over
objects of the mean difference.

On a dataset of more than :data:`MAX_OBJECTS` objects with grips (the standard dataset's 510) the
stage pairs a seeded sample of that many (``learning.seed``): its interval is over objects, and
planning and simulating every one again would cost the study more than all its learning.
"""

from __future__ import annotations

import json
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from grip_env.columns import FEATURES
from grip_env.config import Config

RESULT_FILE = "perception.json"
BOOTSTRAP = 2000
COMPARED = (*FEATURES, "Q_C", "success_rate", "robustness_mean")
#: The most objects the stage plans again (a seeded sample beyond it).
MAX_OBJECTS = 80


def run_perception_effect(config: Config, data_dir: Path, out: Path) -> dict[str, Any]:
    """Compare best grips planned on the true and on the rendered contour; write the result."""
    from grip_env.dataset import load, load_objects, load_perceived_objects

    out.mkdir(parents=True, exist_ok=True)
    table = load(data_dir)
    manifest = table.attrs["manifest"]
    perceived = load_perceived_objects(data_dir)
    if all(p is None for p in perceived):
        result = {"planned_on": "polygon", "objects": 0}
        (out / RESULT_FILE).write_text(json.dumps(result, indent=2))
        return result
    chosen = sampled_objects(table, config.learning.seed)
    rows, timing = _paired_best(config, table, manifest, load_objects(data_dir), perceived,
                                chosen)
    result = {"planned_on": "render", "objects": len(rows), "timing_s": timing,
              "sampled": len(chosen) < table["object_id"].nunique(),
              "pairs": rows.to_dict("records"),
              "differences": paired_differences(rows, config.learning.seed)}
    (out / RESULT_FILE).write_text(json.dumps(result, indent=2, default=float))
    return result


def sampled_objects(table: pd.DataFrame, seed: int, most: int = MAX_OBJECTS) -> set[str]:
    """The objects with grips the stage pairs: all of them, or a seeded sample of ``most``."""
    ids = sorted(set(table["object_id"].astype(str)))
    if len(ids) <= most:
        return set(ids)
    return set(np.random.default_rng(seed).choice(ids, most, replace=False).tolist())


def _paired_best(
    config: Config, table: pd.DataFrame, manifest: dict[str, Any], objects: list,
    perceived: list, chosen: set[str],
) -> tuple[pd.DataFrame, dict[str, float]]:
    """One row per object with grips on both plans: the two best grips' compared values.

    The objects are planned and simulated in ``dataset.workers`` processes; each row depends on
    its object alone, so the rows are the same whatever the number of workers.
    """
    tasks = []
    for entry, obj, seen in zip(manifest["objects"], objects, perceived, strict=True):
        kept = table[table["object_id"] == entry["object_id"]]
        if seen is None or kept.empty or entry["object_id"] not in chosen:
            continue
        seen_best = kept.sort_values("Q_C", kind="stable").iloc[0]
        tasks.append((config, entry["object_id"], obj, {n: float(seen_best[n]) for n in COMPARED}))
    workers = min(config.dataset.workers, len(tasks))
    if workers > 1:
        with ProcessPoolExecutor(workers) as pool:
            found = list(pool.map(_pair, *zip(*tasks, strict=True)))
    else:
        found = [_pair(*task) for task in tasks]
    rows = [row for row, _ in found if row is not None]
    timing = {"plan_true_s": sum(t[0] for _, t in found),
              "simulate_true_best_s": sum(t[1] for _, t in found)}
    return pd.DataFrame(rows), timing


def _pair(config: Config, object_id: str, obj: Any, seen_best: dict[str, float],
          ) -> tuple[dict[str, Any] | None, tuple[float, float]]:
    """One object's row (None when its true contour gives no grip) and (plan, simulate) s."""
    from grip_env.objects.meshes import execution_height_mm
    from grip_env.planning.pipeline import candidates
    from grip_env.sim import run_trials

    start = time.perf_counter()
    height = execution_height_mm(obj, config.objects)
    true_plan = candidates(obj, config.grasp, config, height_mm=height)
    plan_s = time.perf_counter() - start
    if true_plan.empty:
        return None, (plan_s, 0.0)
    start = time.perf_counter()
    best = true_plan.iloc[:1].assign(object_id=object_id)  # the dataset's draws
    outcome = run_trials(obj, best, config, config.dataset.trials, config.dataset.seed)
    sim_s = time.perf_counter() - start
    true_best = best.iloc[0].to_dict() | {
        "success_rate": outcome["successes"].iloc[0] / outcome["trials"].iloc[0],
        "robustness_mean": outcome["robustness_mean"].iloc[0]}
    row = ({"object_id": object_id} | {f"true_{n}": float(true_best[n]) for n in COMPARED}
           | {f"render_{n}": value for n, value in seen_best.items()})
    return row, (plan_s, sim_s)


def paired_differences(rows: pd.DataFrame, seed: int) -> dict[str, dict[str, Any]]:
    """Per compared quantity: mean on the true and the rendered plans, and the mean paired
    difference (rendered - true) with its 95 % bootstrap interval over objects."""
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, len(rows), (BOOTSTRAP, len(rows))) if len(rows) else None
    found = {}
    for name in COMPARED:
        true, seen = rows[f"true_{name}"].to_numpy(float), rows[f"render_{name}"].to_numpy(float)
        difference = seen - true
        if picks is None:
            found[name] = {"true": None, "render": None, "mean": None, "ci": [None, None]}
            continue
        means = difference[picks].mean(axis=1)
        found[name] = {"true": float(true.mean()), "render": float(seen.mean()),
                       "mean": float(difference.mean()),
                       "ci": [float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))]}
    return found
