"""The leaderboard: per-method aggregates of the selection metrics, as JSON, Markdown and figures.

Every method is compared with the best-Q_C pick (``best_qc``, the paper's index): the difference
of the mean normalised score, paired over the same resampled objects, and the probability of
improvement. A method *beats* best-Q_C when the 95 % interval of that difference lies above zero,
is *worse* when it lies below, and is *not distinguishable* otherwise.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

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
JSON_FILE, MARKDOWN_FILE = "leaderboard.json", "leaderboard.md"
PROFILE_FILE, ATTEMPTS_FILE = "performance_profile.png", "attempts.png"
PLAIN = ("success", "robustness", "regret", "robustness_regret", "ndcg5",
         *(f"success_at_{k}" for k in range(1, MAX_ATTEMPTS + 1)), "attempts")  # fmt: skip
VERDICTS = ("beats best_qc", "worse than best_qc", "not distinguishable from best_qc")
TAUS = np.linspace(-1.0, 1.0, 201)
#: Below this many ranked objects the leaderboard says its intervals are indicative only.
FEW_OBJECTS = 10


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
    boot = paired_bootstraps(matrices, reps, seed, task_bootstrap=True)
    runs_only = paired_bootstraps(matrices, reps, seed, task_bootstrap=False)
    ref, ref_boot = matrices[reference], boot[reference]
    plain = metrics.groupby("method")[list(PLAIN)].mean()
    every = sorted(set(metrics["object_id"]))
    success = metric_matrices(metrics, "success", every)
    success_boot = paired_bootstraps(success, reps, seed + 1, task_bootstrap=True)
    rows = {}
    for name, matrix in matrices.items():
        difference = estimate(mean(matrix) - mean(ref), mean(boot[name]) - mean(ref_boot))
        rows[name] = {
            "runs": int(matrix.shape[0]),
            **{k: _round(plain.loc[name, k]) for k in PLAIN},
            "success_ci": estimate(mean(success[name]), mean(success_boot[name]))["ci"],
            "iqm": estimate(iqm(matrix), iqm(boot[name])),
            "mean": estimate(mean(matrix), mean(boot[name])),
            "iqm_runs_only_ci": estimate(iqm(matrix), iqm(runs_only[name]))["ci"],
            "mean_runs_only_ci": estimate(mean(matrix), mean(runs_only[name]))["ci"],
            "difference_vs_reference": difference,
            "probability_of_improvement": estimate(probability_of_improvement(matrix, ref),
                                                   probability_of_improvement(boot[name],
                                                                              ref_boot)),
            "verdict": _verdict(difference["ci"], name == reference),
            "profile": _round(performance_profile(matrix, TAUS)),
        }  # fmt: skip
    order = sorted(rows, key=lambda n: (-rows[n]["iqm"]["estimate"], -rows[n]["mean"]["estimate"]))
    degenerate = sorted(set(metrics["object_id"]) - set(objects))
    return {
        "split": dict(split), "reference": reference, "objects": objects,
        "degenerate_objects": degenerate, "taus": _round(TAUS),
        "interval": (f"95% percentile stratified bootstrap ({reps} resamples, seed {seed}): "
                     "objects resampled, runs resampled within each object (rliable's "
                     "StratifiedBootstrap, task_bootstrap=True); the JSON's `iqm_runs_only_ci` and "
                     "`mean_runs_only_ci` resample runs only (rliable's default)"),
        "methods": {name: rows[name] for name in order},
    }  # fmt: skip


def beaten(board: Mapping[str, Any]) -> dict[str, list[str]]:
    """Method names per verdict (the reference itself left out)."""
    found: dict[str, list[str]] = {v: [] for v in VERDICTS}
    for name, row in board["methods"].items():
        if row["verdict"] in found:
            found[row["verdict"]].append(name)
    return found


def verdict_sentence(board: Mapping[str, Any]) -> str:
    """One plain sentence: who beats best-Q_C with an interval excluding zero, and who does not."""
    groups = beaten(board)
    ref = board["reference"]

    def names(key: str) -> str:
        return ", ".join(f"`{n}`" for n in groups[key]) or "none"

    return (f"Beat the best-Q_C pick (95% interval of the difference in mean normalised score "
            f"above zero): {names(VERDICTS[0])}. Worse than `{ref}` (interval below zero): "
            f"{names(VERDICTS[1])}. Not distinguishable from `{ref}` (interval contains zero): "
            f"{names(VERDICTS[2])}.")


def leaderboard_frames(board: Mapping[str, Any]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(main table, attempts table) as shown in leaderboard.md and the report."""
    main, attempts = [], []
    for name, row in board["methods"].items():
        main.append({
            "method": name, "runs": row["runs"],
            "top-1 success": _ci({"estimate": row["success"], "ci": row["success_ci"]}),
            "top-1 robustness (g)": _f(row["robustness"], 1), "regret": _f(row["regret"]),
            "NDCG@5": _f(row["ndcg5"]), "normalised IQM": _ci(row["iqm"]),
            "normalised mean": _ci(row["mean"]),
            "mean - best_qc": _ci(row["difference_vs_reference"]),
            "P(improve over best_qc)": _ci(row["probability_of_improvement"]),
            "verdict": row["verdict"],
        })  # fmt: skip
        attempts.append({"method": name, **{f"{k} attempt{'s' * (k > 1)}":
                         _f(row[f"success_at_{k}"]) for k in range(1, MAX_ATTEMPTS + 1)},
                         "expected attempts (budget 5)": _f(row["attempts"])})  # fmt: skip
    return pd.DataFrame(main), pd.DataFrame(attempts)


def leaderboard_markdown(board: Mapping[str, Any]) -> str:
    """The leaderboard as Markdown (the same table as the study report's)."""
    main, attempts = leaderboard_frames(board)
    split = board["split"]
    lines = [
        f"# Grip-selection leaderboard ({split.get('name', 'split')})", "",
        split_line(board), "", _table(main), "",
        f"Normalised score: (method - random) / (oracle - random) of the top-1 pick's expected "
        f"success, per object; {board['interval']}. {verdict_sentence(board)}", "",
        "## Success within k attempts (GripAccept-v0 / GripSelect-v0 with max_attempts = k)", "",
        _table(attempts), "",
        "Chance that one of the method's top-k picks holds, from the recorded success rates, "
        "assuming independent trials (the replay backend's draws).", "",
    ]  # fmt: skip
    return "\n".join(lines)


def write_leaderboard(board: Mapping[str, Any], out: str | Path) -> list[Path]:
    """Write leaderboard.json, leaderboard.md and the two figures into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / JSON_FILE).write_text(json.dumps(board, indent=2))
    (out / MARKDOWN_FILE).write_text(leaderboard_markdown(board))
    from classifiers.experiments.benchmark.plots import plot_attempts, plot_profiles

    plot_profiles(board, out / PROFILE_FILE)
    plot_attempts(board, out / ATTEMPTS_FILE)
    return [out / name for name in (JSON_FILE, MARKDOWN_FILE, PROFILE_FILE, ATTEMPTS_FILE)]


def split_line(board: Mapping[str, Any]) -> str:
    """One sentence: which split, how many objects, seeds and the dataset's checksum."""
    split = board["split"]
    seeds = split.get("seeds")
    return (f"Split `{split.get('name')}` (version {split.get('version')}): "
            f"{len(board['objects']) + len(board['degenerate_objects'])} held-out objects "
            f"({len(board['degenerate_objects'])} where every candidate has the same success "
            f"rate are left out of the normalised score), up to {split.get('max_candidates')} "
            f"candidates each (lowest Q_C first); training seeds {seeds}; dataset sha256 "
            f"`{str(split.get('dataset_sha256', ''))[:12]}`." + _not_standard(split)
            + _few_objects(board))  # fmt: skip


def _not_standard(split: Mapping[str, Any]) -> str:
    """Why the split is not the latest standard one, and, when it is no standard split at all,
    that its scores do not compare with the standard leaderboards."""
    if split.get("note"):
        return f" Split chosen: {split['note']}."
    if split.get("standard", True):
        return ""
    return " Not the standard split: do not compare these scores with its leaderboards."


def _few_objects(board: Mapping[str, Any]) -> str:
    """A caution when the bootstrap has too few objects to resample."""
    n = len(board["objects"])
    if n >= FEW_OBJECTS:
        return ""
    return (f" Only {n} objects enter the normalised score: a bootstrap over so few objects "
            f"understates the uncertainty; read its intervals and verdicts as indicative only.")


def _verdict(ci: Sequence[float], is_reference: bool) -> str:
    if is_reference:
        return "reference"
    low, high = ci
    return VERDICTS[0] if low > 0 else VERDICTS[1] if high < 0 else VERDICTS[2]


def _table(frame: pd.DataFrame) -> str:
    head = "| " + " | ".join(frame.columns) + " |"
    rule = "| " + " | ".join("---" for _ in frame.columns) + " |"
    body = ["| " + " | ".join(str(v) for v in row) + " |" for row in frame.itertuples(index=False)]
    return "\n".join([head, rule, *body])


def _ci(value: Mapping[str, Any]) -> str:
    low, high = value["ci"]
    return f"{_f(value['estimate'])} [{_f(low)}, {_f(high)}]"


def _f(value: float | None, digits: int = 3) -> str:
    if value is None or not np.isfinite(value):
        return "n/a"
    return f"{round(float(value), digits) + 0.0:.{digits}f}"  # + 0.0: no "-0.000"


def _round(value: Any) -> Any:
    array = np.asarray(value, dtype=float)
    if array.ndim == 0:
        return None if not np.isfinite(array) else round(float(array), 6)
    return [None if not np.isfinite(v) else round(float(v), 6) for v in array]
