"""The leaderboard: per-method aggregates of the selection metrics, as JSON and figures.

Every method is compared with the best-Q_C pick (``best_qc``, the paper's index): the difference
of the mean normalised score, paired over the same resampled objects, and the probability of
improvement; and, in plain units, the difference of the top-1 pick's success
(``success_difference_vs_reference``), paired the same way over every held-out object (an object
whose candidates all succeed alike adds zero to it). A method *beats* best-Q_C when the 95 %
interval of the normalised difference lies above zero, is *worse* when it lies below, and is
*not distinguishable* otherwise.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from classifiers.evaluation.verdicts import relation
from classifiers.experiments.benchmark.aggregate import (
    estimate,
    iqm,
    mean,
    paired_bootstraps,
    performance_profile,
    probability_of_improvement,
)
from classifiers.experiments.benchmark.selection import MAX_ATTEMPTS

REFERENCE = "best_qc"
JSON_FILE = "leaderboard.json"
PROFILE_FILE, ATTEMPTS_FILE = "performance_profile.png", "attempts.png"
PLAIN = ("success", "robustness", "regret", "robustness_regret", "ndcg5",
         *(f"success_at_{k}" for k in range(1, MAX_ATTEMPTS + 1)), "attempts")  # fmt: skip
TAUS = np.linspace(-1.0, 1.0, 201)


class NoRankableObject(ValueError):
    """No held-out object has candidates of different success rates: nothing can be ranked."""


def score_matrices(metrics: pd.DataFrame) -> tuple[dict[str, np.ndarray], list[str]]:
    """Each method's ``(runs, objects)`` normalised scores over the non-degenerate objects."""
    valid = metrics.groupby("object_id")["normalised"].apply(lambda s: s.notna().all())
    objects = sorted(valid.index[valid.to_numpy(bool)])
    if not objects:
        raise NoRankableObject("no held-out object has candidates of different success rates "
                               "(oracle = random on each): nothing to rank")
    return metric_matrices(metrics, "normalised", objects), objects


def metric_matrices(metrics: pd.DataFrame, column: str, objects: Sequence[str]) -> dict[
        str, np.ndarray]:  # fmt: skip
    """Each method's ``(runs, objects)`` values of ``column`` on ``objects``."""
    kept = metrics[metrics["object_id"].isin(objects)]
    return {
        str(name): group.pivot(index="seed", columns="object_id", values=column)
        .loc[:, list(objects)].to_numpy(float)
        for name, group in kept.groupby("method", sort=True)
    }  # fmt: skip


def build_leaderboard(
    metrics: pd.DataFrame, split: Mapping[str, Any], reps: int = 2000, seed: int = 0,
    reference: str = REFERENCE,
) -> dict[str, Any]:
    """The leaderboard dict (``methods`` sorted by IQM of the normalised score)."""
    matrices, objects = score_matrices(metrics)
    if reference not in matrices:
        raise ValueError(f"the leaderboard needs the reference method {reference!r}")
    boot = paired_bootstraps(matrices, reps, seed, task_bootstrap=True, objects=objects)
    runs_only = paired_bootstraps(matrices, reps, seed, task_bootstrap=False, objects=objects)
    ref, ref_boot = matrices[reference], boot[reference]
    plain = metrics.groupby("method")[list(PLAIN)].mean()
    every = sorted(set(metrics["object_id"]))
    success = metric_matrices(metrics, "success", every)
    success_boot = paired_bootstraps(success, reps, seed + 1, task_bootstrap=True,
                                    objects=every)
    rows = {}
    for name, matrix in matrices.items():
        difference = estimate(mean(matrix) - mean(ref), mean(boot[name]) - mean(ref_boot))
        rows[name] = {
            "runs": int(matrix.shape[0]),
            **{k: _round(plain.loc[name, k]) for k in PLAIN},
            "success_ci": estimate(mean(success[name]), mean(success_boot[name]))["ci"],
            "success_difference_vs_reference": estimate(
                mean(success[name]) - mean(success[reference]),
                mean(success_boot[name]) - mean(success_boot[reference])),
            "iqm": estimate(iqm(matrix), iqm(boot[name])),
            "mean": estimate(mean(matrix), mean(boot[name])),
            "iqm_runs_only_ci": estimate(iqm(matrix), iqm(runs_only[name]))["ci"],
            "mean_runs_only_ci": estimate(mean(matrix), mean(runs_only[name]))["ci"],
            "difference_vs_reference": difference,
            "probability_of_improvement": estimate(probability_of_improvement(matrix, ref),
                                                   probability_of_improvement(boot[name],
                                                                              ref_boot)),
            "verdict": _verdict(difference["ci"], name, reference),
            "profile": _round(performance_profile(matrix, TAUS)),
        }  # fmt: skip
    order = sorted(rows, key=lambda n: (-rows[n]["iqm"]["estimate"], -rows[n]["mean"]["estimate"]))
    degenerate = sorted(set(metrics["object_id"]) - set(objects))
    return {
        "split": dict(split), "reference": reference, "objects": objects,
        "degenerate_objects": degenerate, "taus": _round(TAUS),
        "interval": (f"95% percentile stratified bootstrap ({reps} resamples, seed {seed}): "
                     "objects resampled, runs resampled within each object (rliable's "
                     "StratifiedBootstrap, task_bootstrap=True), the resampled objects the same "
                     "for every method and each method's runs from a stream of its own, so a "
                     "method's interval does not depend on the board's other methods; the JSON's "
                     "`iqm_runs_only_ci` and `mean_runs_only_ci` resample runs only (rliable's "
                     "default)"),
        "methods": {name: rows[name] for name in order},
    }  # fmt: skip


def write_leaderboard(board: Mapping[str, Any], out: str | Path) -> list[Path]:
    """Write leaderboard.json and the two figures into ``out`` (the Markdown table is the
    report's: :func:`classifiers.report.leaderboard.write_leaderboard_markdown`)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / JSON_FILE).write_text(json.dumps(board, indent=2))
    from classifiers.experiments.benchmark.plots import plot_attempts, plot_profiles

    plot_profiles(board, out / PROFILE_FILE)
    plot_attempts(board, out / ATTEMPTS_FILE)
    return [out / name for name in (JSON_FILE, PROFILE_FILE, ATTEMPTS_FILE)]


def _verdict(ci: Sequence[float], name: str, reference: str) -> str:
    """``beats``, ``worse than`` or ``not distinguishable from`` the reference, by the interval
    of the difference (the reference itself: ``reference``)."""
    if name == reference:
        return "reference"
    return f"{relation(ci).removeprefix('is ')} {reference}"


def _round(value: Any) -> Any:
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return None if not np.isfinite(array) else round(float(array), 6)
    return [None if not np.isfinite(v) else round(float(v), 6) for v in array]
