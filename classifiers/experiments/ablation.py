"""The feature-ablation study: do the hand (C) features add to the grasp (S, G) features?

One model (default ``learning.ablation_model``, "hgb") is cross-validated on each feature set
with exactly the folds and seeds of :mod:`classifiers.evaluation.cross_validation`, so the per-fold
metric
differences to the reference set (all twelve features) are paired; their mean and corrected 95%
t-interval are reported. The permutation importance of each of the twelve features (drop of
ROC-AUC when the feature is shuffled in the held-out fold,
``sklearn.inspection.permutation_importance``) is summarised the same way. ``held_out`` scores
the model of each feature set, fitted on the training objects of the study's split, on its
held-out objects (the RL selector's test objects; one split, so no interval; not the
leave-one-feature-out sets). ``eps`` is the Ferrari–Canny ε of
:mod:`grip_env.planning.epsilon`, added when missing.

When the table has the graded outcome, the regression task runs alongside on the same folds:
one regressor (default ``"svr"``) of ``robustness_mean`` per feature set, scored by Spearman
(pooled and within object, :mod:`classifiers.evaluation.regression`), with the same paired
differences.

``"learners"`` repeats the hand question for the other learners (:data:`OTHER_LEARNERS`: the
classifiers "hgb" and "svm" other than the study's model, the gradient-boosted regressor "hgb"
and the lambdarank ranker of :mod:`classifiers.evaluation.ranking`): the twelve features against
``without_hand`` only, on the same folds, paired (the other sets would triple the cost).

``grip-env ablate`` runs every set of :func:`feature_sets`; the study runs the named sets
(:func:`named_feature_sets`), whose ``without_hand`` is its question, and leaves the twelve
leave-one-feature-out sets, whose per-feature answer the permutation importance also gives, to
``ablate``: on the standard dataset they would be two thirds of the stage's fits.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator
from sklearn.inspection import permutation_importance

from classifiers.evaluation.cross_validation import (
    LABEL_COLUMN,
    METRICS,
    check_dataset,
    cross_validate_models,
    cv_description,
    grouped_folds,
    held_out_metrics,
    interval,
    paired_metrics,
    summarise,
)
from classifiers.evaluation.ranking import (
    RANKING_METRICS,
    cross_validate_rankers,
    paired_ranking_difference,
    summarise_ranking,
)
from classifiers.evaluation.regression import (
    REGRESSION_METRICS,
    cross_validate_regressors,
    has_target,
    paired_regression_difference,
    summarise_regression,
)
from classifiers.experiments.plots import plot_ablation
from classifiers.learners.models import make_model
from classifiers.learners.parallel import run_all
from classifiers.learners.threads import single_threaded
from grip_env.columns import FEATURES, GRASP_FEATURES, HAND_FEATURES, SHARED_FEATURES
from grip_env.config import Config, LearningConfig
from grip_env.planning.epsilon import EPSILON_COLUMN, add_epsilon
from grip_env.progress import progress_bar

REFERENCE = "all_twelve"
#: Shuffles of each feature in each held-out fold of the permutation importance: the interval is
#: over the CV's folds (10 by default), each fold's figure a mean of this many shuffles; the
#: shuffles' predictions were about a quarter of the ablation stage at scikit-learn's default of 5.
IMPORTANCE_REPEATS = 2
SHARED, GRASP, HAND = SHARED_FEATURES, GRASP_FEATURES, HAND_FEATURES


_LEAVE_ONE_OUT = frozenset(f"without_{feature}" for feature in FEATURES)
#: The learners the ablation also runs on the named feature sets: task → model names (a
#: classifier that is the study's own model is not run twice).
OTHER_LEARNERS: dict[str, tuple[str, ...]] = {
    "classifier": ("hgb", "svm"), "regressor": ("hgb",), "ranker": ("lambdarank",),
}


def named_feature_sets() -> dict[str, tuple[str, ...]]:
    """The named feature sets, the reference first: the study's ablation."""
    return {
        REFERENCE: FEATURES,
        "without_hand": SHARED + GRASP,
        "hand_only": HAND,
        "shared_and_hand": SHARED + HAND,
        "eps_only": (EPSILON_COLUMN,),
        "twelve_and_eps": (*FEATURES, EPSILON_COLUMN),
    }


def feature_sets() -> dict[str, tuple[str, ...]]:
    """Every feature set of ``grip-env ablate``: the named ones, then each of the twelve left
    out in turn."""
    sets = named_feature_sets()
    for feature in FEATURES:
        sets[f"without_{feature}"] = tuple(f for f in FEATURES if f != feature)
    return sets


def ablation_study(
    table: pd.DataFrame,
    config: Config | None = None,
    model: str | None = None,
    sets: dict[str, Sequence[str]] | None = None,
    importance_repeats: int = IMPORTANCE_REPEATS,
    regressor: str = "svr",
) -> dict[str, Any]:
    """Run the study of ``model`` (default ``learning.ablation_model``); returns the
    ``ablation.json`` content (``"regression"``: the graded task, present when the table has
    ``robustness_mean``)."""
    config = config or Config()
    with single_threaded():
        return _ablation_study(table, config, model or config.learning.ablation_model, sets,
                               importance_repeats, regressor)


def _ablation_study(table: pd.DataFrame, config: Config, model: str,
                    sets: dict[str, Sequence[str]] | None, importance_repeats: int,
                    regressor: str) -> dict[str, Any]:
    learning = config.learning
    sets = dict(sets or feature_sets())
    if REFERENCE not in sets:
        raise ValueError(f"feature sets must include the reference {REFERENCE!r}")
    check_dataset(table, FEATURES, learning.folds)
    if EPSILON_COLUMN not in table.columns:
        table = add_epsilon(table, config.grasp)
    per_fold = _per_set(sets, "ablation", lambda features: cross_validate_models(
        table, [model], features, learning))
    reference = per_fold[REFERENCE]
    results = {
        name: {
            "features": list(sets[name]),
            "models": summarise(frame, learning.folds),
            "paired_difference": {model: paired_difference(frame, reference, learning.folds)},
        }
        for name, frame in per_fold.items()
    }
    output = {
        "model": model,
        "reference": REFERENCE,
        "feature_sets": results,
        "permutation_importance": importance(table, model, learning, importance_repeats),
        "held_out": held_out_metrics(table, learning, _held_out_models(model, sets, learning)),
        "cv": cv_description(table, FEATURES, learning),
    }
    if has_target(table):
        output["regression"] = regression_ablation(table, learning, regressor, sets)
    hand_question = {name: sets[name] for name in (REFERENCE, "without_hand") if name in sets}
    others = {task: tuple(n for n in names if not (task == "classifier" and n == model))
              for task, names in OTHER_LEARNERS.items()}  # fmt: skip
    output["learners"] = learner_ablation(table, config, hand_question, others)
    return output


def learner_ablation(
    table: pd.DataFrame, config: Config, sets: dict[str, Sequence[str]],
    learners: dict[str, tuple[str, ...]] = OTHER_LEARNERS,
) -> dict[str, Any]:
    """``{"<task>_<name>": {"metrics", "feature_sets": {set: {"models", "paired_difference"}}}}``
    for each learner of ``learners`` (regressors only with the graded outcome)."""
    learning = config.learning
    tasks: dict[str, tuple[Callable[..., pd.DataFrame], Callable[..., Any],
                           Callable[..., Any], tuple[str, ...]]] = {
        "classifier": (cross_validate_models, summarise, paired_difference, METRICS),
        "regressor": (cross_validate_regressors, summarise_regression,
                      paired_regression_difference, REGRESSION_METRICS),
        "ranker": (lambda t, m, f, c: cross_validate_rankers(t, m, f, c, config.sim),
                   summarise_ranking, paired_ranking_difference, RANKING_METRICS),
    }  # fmt: skip
    output = {}
    for task, names in learners.items():
        if task == "regressor" and not has_target(table):
            continue
        validate, summary, paired, metrics = tasks[task]
        for name in names:
            per_fold = _per_set(sets, f"ablation ({task} {name})",
                                lambda features, v=validate, n=name: v(table, [n], features,
                                                                       learning))  # fmt: skip
            reference = per_fold[REFERENCE]
            output[f"{task}_{name}"] = {"metrics": list(metrics), "feature_sets": {
                set_name: {"features": list(sets[set_name]),
                           "models": summary(frame, learning.folds),
                           "paired_difference": {name: paired(frame, reference, learning.folds)}}
                for set_name, frame in per_fold.items()}}  # fmt: skip
    return output


def _held_out_models(
    model: str, sets: dict[str, Sequence[str]], learning: LearningConfig
) -> dict[str, Any]:
    """``model`` on each named feature set (the leave-one-feature-out sets are left out)."""
    return {name: make_model(model, learning.seed, features)
            for name, features in sets.items() if name not in _LEAVE_ONE_OUT}  # fmt: skip


def _per_set(sets: dict[str, Sequence[str]], description: str,
             run: Callable[[Sequence[str]], pd.DataFrame]) -> dict[str, pd.DataFrame]:
    """``run(features)`` for every feature set, with one progress bar over the sets."""
    per_fold = {}
    with progress_bar(len(sets), description) as bar:
        for name, features in sets.items():
            per_fold[name] = run(features)
            bar.advance(info=name)
    return per_fold


def regression_ablation(
    table: pd.DataFrame, learning: LearningConfig, regressor: str,
    sets: dict[str, Sequence[str]],
) -> dict[str, Any]:
    """The regression task on every feature set, paired against the reference set."""
    per_fold = _per_set(sets, "ablation (regression)", lambda features: cross_validate_regressors(
        table, [regressor], features, learning))
    reference = per_fold[REFERENCE]
    return {
        "model": regressor,
        "reference": REFERENCE,
        "metrics": list(REGRESSION_METRICS),
        "feature_sets": {
            name: {
                "features": list(sets[name]),
                "models": summarise_regression(frame, learning.folds),
                "paired_difference": {
                    regressor: paired_regression_difference(frame, reference, learning.folds)
                },
            }
            for name, frame in per_fold.items()
        },
    }


def paired_difference(
    frame: pd.DataFrame, reference: pd.DataFrame, folds: int
) -> dict[str, dict[str, Any]]:
    """Mean and interval of (set − reference) per metric, matched on (repeat, fold)."""
    return paired_metrics(frame, reference, METRICS, folds, default=(-1.0, 1.0))


def importance(
    table: pd.DataFrame, model: str, learning: LearningConfig,
    n_repeats: int = IMPORTANCE_REPEATS,
) -> dict[str, dict[str, Any]]:
    """Permutation importance (ROC-AUC drop) of the twelve features on held-out folds."""
    table = table.reset_index(drop=True)
    labels = table[LABEL_COLUMN].to_numpy().astype(bool)
    jobs = [(make_model(model, seed, FEATURES), table.iloc[train], labels[train],
             table.iloc[test], labels[test], n_repeats, seed)
            for seed in range(learning.seed, learning.seed + learning.repeats)
            for train, test in grouped_folds(table, learning.folds, seed)
            if np.unique(labels[test]).size == 2]  # fmt: skip
    rows = run_all(_fold_importance, jobs, len(table), learning.workers)
    values = np.array(rows).reshape(-1, len(FEATURES))
    return {f: interval(values[:, k], learning.folds) for k, f in enumerate(FEATURES)}


def _fold_importance(model: BaseEstimator, train: pd.DataFrame, labels: np.ndarray,
                     test: pd.DataFrame, test_labels: np.ndarray, n_repeats: int,
                     seed: int) -> np.ndarray:
    """Mean ROC-AUC drop of each of the twelve features, shuffled in one held-out fold."""
    fitted = model.fit(train, labels)
    result = permutation_importance(fitted, test[list(FEATURES)], test_labels,
                                    scoring="roc_auc", n_repeats=n_repeats, random_state=seed)
    return result.importances_mean


def run_ablation(
    table: pd.DataFrame, out_dir: str | Path, config: Config | None = None,
    model: str | None = None, regressor: str = "svr",
    sets: dict[str, Sequence[str]] | None = None,
) -> dict[str, Any]:
    """Run the study on ``sets`` (default :func:`feature_sets`); write ``ablation.json``,
    ``ablation.png`` (ROC-AUC bars) and, with the graded outcome, ``ablation_regression.png``
    (Spearman bars) to ``out_dir``."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    result = ablation_study(table, config, model, sets, regressor=regressor)
    (out_dir / "ablation.json").write_text(json.dumps(result, indent=2))
    plot_ablation(result, "roc_auc", out_dir / "ablation.png")
    if "regression" in result:
        plot_ablation(result["regression"], "spearman", out_dir / "ablation_regression.png")
    return result
