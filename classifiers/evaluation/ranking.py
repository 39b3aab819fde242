"""Learning to rank the grips of one object: LightGBM lambdarank, one query group per object.

A robot picks one grip per object, so what matters is the order of each object's candidates, not
a probability comparable across objects. :class:`GroupedRanker` fits LightGBM's ``LGBMRanker``
with the ``lambdarank`` objective (it optimises NDCG within each group), a group being all the
training grips of one object; its ``predict`` score is comparable only within an object.

Graded relevance (:func:`relevance`): the number of the load ramp's levels (``sim.ramp_levels_g``
from the lowest, ratio ``sim.ramp_ratio``, a quarter octave by default) that the grip's mean
robustness reaches, 0 below the first level: 0..25 on the default ramp. Robustness, not success,
because it is graded far more finely: on the default dataset 438 of 1332 grips tie at success
rate 1.0 (five values in all from four trials), while robustness spreads them over 25 grades and
agrees with the success rate within objects (mean Spearman 0.80). Without ``robustness_mean`` the
grade is the number of successful trials. The gain of grade g is g (linear), so a miss by one
level costs the same anywhere on the ramp.

Metrics per fold (:func:`ranking_fold_metrics`): ``spearman_object``, the mean over test objects
of the within-object Spearman correlation of score and robustness (``spearman_object_rate``:
with the success rate); ``roc_auc_object``, the mean within-object ROC-AUC of score against
``success`` over objects holding both classes (a pooled ROC-AUC is not reported: scores of two
objects are not on one scale); ``top1_success``, ``top1_rate`` and ``top1_robustness`` of each
object's top-scored grip. ``make_ranker`` also gives the rank baselines ``rank_qc``, ``rank_qg``
and ``random``, scored the same way.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator
from sklearn.metrics import roc_auc_score

from classifiers.evaluation.cross_validation import (
    GROUP_COLUMN,
    LABEL_COLUMN,
    Models,
    Task,
    against_baselines,
    cross_validate,
    paired_metrics,
    summarise_metrics,
)
from classifiers.evaluation.regression import TARGET_COLUMN, spearman
from classifiers.learners.ranking import make_ranker, relevance
from grip_env.columns import FEATURES
from grip_env.config import LearningConfig, SimConfig

RANKING_METRICS = ("spearman_object", "spearman_object_rate", "roc_auc_object", "top1_success",
                   "top1_rate", "top1_robustness")  # fmt: skip
BASELINES = ("rank_qc", "rank_qg")
_BOUNDS = {"top1_robustness": (0.0, np.inf), "spearman_object": (-1.0, 1.0),
           "spearman_object_rate": (-1.0, 1.0)}  # fmt: skip


def ranking_fold_metrics(model: BaseEstimator, test: pd.DataFrame) -> dict[str, float]:
    """The ranking metrics of a fitted ranker on one test fold (see the module docstring)."""
    frame = pd.DataFrame({
        "group": test[GROUP_COLUMN].to_numpy(), "score": np.asarray(model.predict(test), float),
        "success": test[LABEL_COLUMN].to_numpy().astype(bool),
        "rate": test["success_rate"].to_numpy(float),
        "load": test[TARGET_COLUMN].to_numpy(float) if TARGET_COLUMN in test else np.nan,
    })  # fmt: skip
    within, within_rate, auc = [], [], []
    for _, group in frame.groupby("group"):
        within.append(spearman(group["score"], group["load"]))
        within_rate.append(spearman(group["score"], group["rate"]))
        if group["success"].nunique() == 2:
            auc.append(roc_auc_score(group["success"], group["score"]))
    picks = frame.loc[frame.groupby("group")["score"].idxmax()]
    return {
        "spearman_object": _nanmean(within),
        "spearman_object_rate": _nanmean(within_rate),
        "roc_auc_object": _nanmean(auc),
        "top1_success": float(picks["success"].mean()),
        "top1_rate": float(picks["rate"].mean()),
        "top1_robustness": float(picks["load"].mean()),
    }


def _nanmean(values: Sequence[float]) -> float:
    values = np.asarray(values, float)
    return float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")


def ranking_task(sim: SimConfig | None = None) -> Task:
    """Ranking an object's grips by their relevance (:func:`relevance` under ``sim``)."""
    return Task(RANKING_METRICS, lambda table: relevance(table, sim), make_ranker,
                ranking_fold_metrics, _BOUNDS)


def cross_validate_rankers(table: pd.DataFrame, models: Models,
                           features: Sequence[str] = FEATURES,
                           config: LearningConfig | None = None,
                           sim: SimConfig | None = None) -> pd.DataFrame:
    """Per-fold ranking metrics on the classifiers' grouped folds: a row per (model, repeat,
    fold). Folds are whole objects, so every query group is entirely in train or in test."""
    return cross_validate(table, ranking_task(sim), models, features, config)


def summarise_ranking(per_fold: pd.DataFrame, folds: int) -> dict[str, dict[str, Any]]:
    """Mean and corrected 95% interval of each ranking metric, per model."""
    return summarise_metrics(per_fold, RANKING_METRICS, folds, _BOUNDS)


def paired_ranking_difference(
    frame: pd.DataFrame, reference: pd.DataFrame, folds: int
) -> dict[str, dict[str, Any]]:
    """Mean and interval of (frame − reference) per ranking metric, matched on (repeat, fold)."""
    return paired_metrics(frame, reference, RANKING_METRICS, folds)


def evaluate_rankers(
    table: pd.DataFrame,
    models: Sequence[str] | Mapping[str, BaseEstimator],
    features: Sequence[str] = FEATURES,
    config: LearningConfig | None = None,
    sim: SimConfig | None = None,
) -> dict[str, Any]:
    """The ``ranking.json`` content: summaries and paired differences to the rank baselines."""
    config = config or LearningConfig()
    per_fold = cross_validate_rankers(table, models, features, config, sim)
    return {
        "relevance": "robustness_mean in ramp levels reached (0..), linear gain"
        if TARGET_COLUMN in table.columns else "successful trials (0..trials), linear gain",
        "models": summarise_ranking(per_fold, config.folds),
        "paired_difference": against_baselines(per_fold, ranking_task(sim), config.folds,
                                               BASELINES),
        "cv": {"folds": config.folds, "repeats": config.repeats,
               "seeds": [config.seed + r for r in range(config.repeats)], "groups": GROUP_COLUMN,
               "query_groups": "one object's grips", "features": list(features),
               "n_grips": len(table), "n_objects": int(table[GROUP_COLUMN].nunique())},
    }  # fmt: skip
