"""Grouped cross-validation of regressors of the graded outcome ``robustness_mean``.

The folds are the classifiers' (:func:`classifiers.evaluation.cross_validation.grouped_folds`:
object-grouped,
stratified on ``success``, seed ``config.seed + repeat``), so every regressor, and every feature
set of the ablation, is scored on exactly the same held-out objects. Metrics per fold:

- ``spearman``: rank correlation of prediction and robustness over the fold's grips (pooled);
- ``spearman_object``: the mean over test objects of the within-object rank correlation (objects
  with fewer than 3 grips or one robustness value are skipped): what a selector needs;
- ``top1_robustness``: the mean robustness of each test object's top-predicted grip;
- ``r2`` and ``mae`` (g).

Intervals are the classifiers' corrected resampled t-intervals (Nadeau & Bengio). Each learned
model is compared with the rank baselines ``rank_qc`` and ``rank_qg`` by its paired per-fold
difference.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import spearmanr
from sklearn.base import BaseEstimator
from sklearn.metrics import mean_absolute_error, r2_score

from classifiers.evaluation.cross_validation import (
    GROUP_COLUMN,
    Models,
    Task,
    against_baselines,
    cross_validate,
    paired_metrics,
    summarise_metrics,
)
from classifiers.learners.models import make_regressor
from grip_env.columns import FEATURES
from grip_env.config import LearningConfig

TARGET_COLUMN = "robustness_mean"
REGRESSION_METRICS = ("spearman", "spearman_object", "top1_robustness", "r2", "mae")
BASELINES = ("rank_qc", "rank_qg")
_BOUNDS = {
    "spearman": (-1.0, 1.0), "spearman_object": (-1.0, 1.0), "top1_robustness": (0.0, np.inf),
    "r2": (-np.inf, 1.0), "mae": (0.0, np.inf),
}  # fmt: skip


_DIFFERENCE_BOUNDS = {"spearman": (-2.0, 2.0), "spearman_object": (-2.0, 2.0)}


def has_target(table: pd.DataFrame) -> bool:
    """Whether the table carries the graded outcome (datasets before it do not)."""
    return TARGET_COLUMN in table.columns and bool(np.isfinite(table[TARGET_COLUMN]).all())


def check_target(table: pd.DataFrame) -> None:
    """ValueError unless the table has a finite ``robustness_mean`` column."""
    if TARGET_COLUMN not in table.columns:
        raise ValueError(f"dataset lacks {TARGET_COLUMN!r}: regenerate it with the graded outcome")
    if not np.isfinite(table[TARGET_COLUMN].to_numpy(float)).all():
        raise ValueError(f"{TARGET_COLUMN!r} holds NaN or infinite values")


def spearman(a: np.ndarray, b: np.ndarray) -> float:
    """Spearman rank correlation; NaN when either side is constant or has < 3 values."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.size < 3 or np.unique(a).size < 2 or np.unique(b).size < 2:
        return float("nan")
    return float(spearmanr(a, b).statistic)


def regression_fold_metrics(model: BaseEstimator, test: pd.DataFrame) -> dict[str, float]:
    """All regression metrics of a fitted model on one test fold."""
    truth = test[TARGET_COLUMN].to_numpy(float)
    predicted = np.asarray(model.predict(test), dtype=float)
    frame = pd.DataFrame({"group": test[GROUP_COLUMN].to_numpy(), "p": predicted, "y": truth})
    within = [spearman(g["p"], g["y"]) for _, g in frame.groupby("group")]
    picks = frame.loc[frame.groupby("group")["p"].idxmax()]
    return {
        "spearman": spearman(predicted, truth),
        "spearman_object": float(np.nanmean(within)) if np.isfinite(within).any() else np.nan,
        "top1_robustness": float(picks["y"].mean()),
        "r2": float(r2_score(truth, predicted)) if np.unique(truth).size > 1 else np.nan,
        "mae": float(mean_absolute_error(truth, predicted)),
    }


def _target(table: pd.DataFrame) -> np.ndarray:
    check_target(table)
    return table[TARGET_COLUMN].to_numpy(float)


#: The graded outcome: the regressors' task.
REGRESSION = Task(REGRESSION_METRICS, _target, make_regressor, regression_fold_metrics, _BOUNDS,
                  _DIFFERENCE_BOUNDS)


def cross_validate_regressors(table: pd.DataFrame, models: Models,
                              features: Sequence[str] = FEATURES,
                              config: LearningConfig | None = None) -> pd.DataFrame:
    """Per-fold metrics: one row per (model, repeat, fold) with ``REGRESSION_METRICS``."""
    return cross_validate(table, REGRESSION, models, features, config)


def summarise_regression(per_fold: pd.DataFrame, folds: int) -> dict[str, dict[str, Any]]:
    """Mean and corrected 95% interval of each metric, per model."""
    return summarise_metrics(per_fold, REGRESSION_METRICS, folds, _BOUNDS)


def paired_regression_difference(
    frame: pd.DataFrame, reference: pd.DataFrame, folds: int
) -> dict[str, dict[str, Any]]:
    """Mean and interval of (frame − reference) per metric, matched on (repeat, fold)."""
    return paired_metrics(frame, reference, REGRESSION_METRICS, folds, _DIFFERENCE_BOUNDS)


def evaluate_regressors(
    table: pd.DataFrame,
    models: Sequence[str] | Mapping[str, BaseEstimator],
    features: Sequence[str] = FEATURES,
    config: LearningConfig | None = None,
) -> dict[str, Any]:
    """The ``regression.json`` content: summaries, paired differences to the rank baselines."""
    config = config or LearningConfig()
    per_fold = cross_validate_regressors(table, models, features, config)
    return {
        "target": TARGET_COLUMN,
        "models": summarise_regression(per_fold, config.folds),
        "paired_difference": against_baselines(per_fold, REGRESSION, config.folds, BASELINES),
        "cv": {
            "folds": config.folds, "repeats": config.repeats,
            "seeds": [config.seed + r for r in range(config.repeats)],
            "groups": GROUP_COLUMN, "splitter": "StratifiedGroupKFold(shuffle=True) on success",
            "interval": "95% corrected resampled t (Nadeau-Bengio) over folds x repeats",
            "features": list(features), "n_grips": len(table),
            "n_objects": int(table[GROUP_COLUMN].nunique()),
        },
    }  # fmt: skip
