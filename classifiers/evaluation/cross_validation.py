"""Grouped cross-validation of grip classifiers: folds by object, repeated over seeds.

Every repetition ``r`` uses ``seed = config.seed + r`` both for the ``StratifiedGroupKFold`` split
(all grips of one object fall in the same fold) and for the models' own randomness. Metrics per
fold: accuracy, balanced accuracy, ROC-AUC, F1, Brier score, and two top-1 rates: for each test
object the model's highest-ranked grip is looked up, ``top1_success`` is the share of objects whose
pick holds (``success`` label), ``top1_rate`` the mean ``success_rate`` of the picks. The ranking
score is ``decision_function`` when the model has one (SVM, logistic regression, baselines), else
the positive-class probability.

Intervals: the folds × repeats values are not independent (training sets overlap), so the 95%
interval is the corrected resampled t-interval of Nadeau & Bengio (2003):
``mean ± t(0.975, n-1) * sqrt((1/n + n_test/n_train) * var)``, ``n_test/n_train = 1/(folds-1)``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from joblib import Parallel, delayed
from scipy import stats
from sklearn.base import BaseEstimator, clone
from sklearn.metrics import (
    accuracy_score,
    balanced_accuracy_score,
    brier_score_loss,
    f1_score,
    roc_auc_score,
)
from sklearn.model_selection import GridSearchCV, GroupKFold, StratifiedGroupKFold

from classifiers.learners.models import check_features, make_model
from classifiers.learners.parallel import run_all, worker_count
from classifiers.learners.threads import single_threaded
from grip_env.columns import FEATURES
from grip_env.config import LearningConfig
from grip_env.dataset.split import held_out_objects, split_table
from grip_env.progress import progress_bar
from grip_env.shutdown import raise_if_signalled

METRICS = ("accuracy", "balanced_accuracy", "roc_auc", "f1", "brier", "top1_success", "top1_rate")
GROUP_COLUMN = "object_id"
LABEL_COLUMN = "success"


def check_dataset(table: pd.DataFrame, features: Sequence[str], folds: int) -> None:
    """ValueError unless ``table`` has outcomes, both classes, the features, ≥ ``folds`` objects."""
    if not isinstance(table, pd.DataFrame):
        raise ValueError(f"the dataset must be a DataFrame, got {type(table).__name__}")
    needed = [GROUP_COLUMN, LABEL_COLUMN, "success_rate", *check_features(features)]
    missing = [name for name in needed if name not in table.columns]
    if missing:
        raise ValueError(f"dataset lacks the columns {missing} (outcomes come from simulation)")
    classes = pd.unique(table[LABEL_COLUMN])
    if len(classes) < 2:
        raise ValueError(f"dataset has one class ({LABEL_COLUMN}={classes.tolist()}); need both")
    n_objects = table[GROUP_COLUMN].nunique()
    if n_objects < folds:
        raise ValueError(f"dataset has {n_objects} objects, fewer than the {folds} folds of "
                         f"learning.folds: set it to at most {n_objects} in a --config file, or "
                         "use a dataset of more objects")


def grouped_folds(
    table: pd.DataFrame, folds: int, seed: int
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """(train rows, test rows) of a stratified, object-grouped K-fold split."""
    splitter = StratifiedGroupKFold(n_splits=folds, shuffle=True, random_state=seed)
    groups = table[GROUP_COLUMN].to_numpy()
    labels = table[LABEL_COLUMN].to_numpy().astype(int)
    for train, test in splitter.split(np.zeros(len(table)), labels, groups):
        shared = np.intersect1d(groups[train], groups[test])
        if shared.size:
            raise RuntimeError(f"objects {shared.tolist()} are in both train and test folds")
        yield train, test


def ranking_score(model: BaseEstimator, X: pd.DataFrame) -> np.ndarray:
    """The score a model ranks grips by (higher = pick first)."""
    if hasattr(model, "decision_function"):
        try:
            return np.asarray(model.decision_function(X), dtype=float)
        except AttributeError:
            pass
    return positive_probability(model, X)


def positive_probability(model: BaseEstimator, X: pd.DataFrame) -> np.ndarray:
    """Predicted probability of ``success = True``."""
    proba = model.predict_proba(X)
    classes = list(model.classes_)
    return proba[:, classes.index(True)] if True in classes else np.zeros(len(X))


def fold_metrics(model: BaseEstimator, test: pd.DataFrame) -> dict[str, float]:
    """All metrics of a fitted model on one test fold."""
    label = test[LABEL_COLUMN].to_numpy().astype(bool)
    probability = positive_probability(model, test)
    predicted = np.asarray(model.predict(test)).astype(bool)
    both = np.unique(label).size == 2
    top1_success, top1_rate = top1(test, ranking_score(model, test))
    return {
        "accuracy": accuracy_score(label, predicted),
        "balanced_accuracy": balanced_accuracy_score(label, predicted) if both else np.nan,
        "roc_auc": roc_auc_score(label, probability) if both else np.nan,
        "f1": f1_score(label, predicted, zero_division=0.0),
        "brier": brier_score_loss(label, probability, pos_label=True),
        "top1_success": top1_success,
        "top1_rate": top1_rate,
    }


def top1(test: pd.DataFrame, score: np.ndarray) -> tuple[float, float]:
    """Share of objects whose top-scored grip succeeds, and the picks' mean success rate."""
    frame = pd.DataFrame(
        {"group": test[GROUP_COLUMN].to_numpy(), "score": score,
         "success": test[LABEL_COLUMN].to_numpy().astype(float),
         "rate": test["success_rate"].to_numpy(float)}
    )  # fmt: skip
    picks = frame.loc[frame.groupby("group")["score"].idxmax()]
    return float(picks["success"].mean()), float(picks["rate"].mean())


def held_out_metrics(
    table: pd.DataFrame, learning: LearningConfig, models: Mapping[str, BaseEstimator]
) -> dict[str, Any]:
    """Each model (cloned) fitted on the split's training objects and scored on its held-out
    objects (:func:`grip_env.dataset.split.held_out_objects`, those the RL selector is scored on).

    Returns ``{"split": {"train", "test", "test_fraction", "seed"}, "models": {name: metrics}}``;
    a metric is None where it is undefined, and ``models`` is empty when the training objects
    hold one class or no object is held out.
    """
    train_ids, test_ids = held_out_objects(table[GROUP_COLUMN].astype(str), learning)
    train, test = split_table(table, learning)
    split = {"train": list(train_ids), "test": list(test_ids),
             "test_fraction": learning.test_fraction, "seed": learning.seed}  # fmt: skip
    labels = train[LABEL_COLUMN].to_numpy().astype(bool)
    if test.empty or np.unique(labels).size < 2:
        return {"split": split, "models": {}}
    return {"split": split, "models": fitted_metrics(models, train, labels, test, learning.workers)}


def fitted_metrics(models: Mapping[str, BaseEstimator], train: pd.DataFrame, labels: np.ndarray,
                   test: pd.DataFrame, workers: int = 1) -> dict[str, dict[str, float | None]]:
    """Each model (cloned) fitted on ``train`` and scored on ``test`` (None where a metric is
    undefined), in up to ``workers`` processes."""
    jobs = [(clone(model), train, labels, test) for model in models.values()]
    found = run_all(_fit_and_score, jobs, len(train), workers)
    return dict(zip(models, found, strict=True))


def _fit_and_score(model: BaseEstimator, train: pd.DataFrame, labels: np.ndarray,
                   test: pd.DataFrame) -> dict[str, float | None]:
    metrics = fold_metrics(model.fit(train, labels), test)
    return {k: (float(v) if np.isfinite(v) else None) for k, v in metrics.items()}


def object_families(table: pd.DataFrame) -> dict[str, str]:
    """Object id -> family (``grip_env.objects.family``) from a loaded dataset's manifest;
    empty for a table without one (or a dataset written before families were recorded)."""
    manifest = table.attrs.get("manifest") or {}
    return {str(entry["object_id"]): str(entry["family"])
            for entry in manifest.get("objects", []) if entry.get("family")}


def family_holdout_metrics(
    table: pd.DataFrame, families: Mapping[str, str], models: Mapping[str, BaseEstimator],
    workers: int = 1,
) -> dict[str, Any]:
    """Each model (cloned) fitted on every family but one and scored on that family's objects,
    for each family: does what is learnt on drawn shapes hold on real silhouettes, and back?

    Returns ``{"families": {family: {"objects", "grips", "models": {name: metrics}}}}``, empty
    with fewer than two families; a family whose training grips hold one class gets no models.
    Objects of no known family are always trained on.
    """
    family = table[GROUP_COLUMN].astype(str).map(dict(families))
    present = sorted(family.dropna().unique())
    result: dict[str, Any] = {"families": {}}
    if len(present) < 2:
        return result
    jobs = []
    for name in present:
        held = (family == name).to_numpy()
        train, test = table[~held], table[held]
        labels = train[LABEL_COLUMN].to_numpy().astype(bool)
        learnable = np.unique(labels).size == 2
        jobs += [(name, model_name, (clone(model), train, labels, test))
                 for model_name, model in models.items() if learnable]  # fmt: skip
        result["families"][name] = {"objects": int(test[GROUP_COLUMN].nunique()),
                                    "grips": len(test), "models": {}}
    found = run_all(_fit_and_score, [job for *_, job in jobs], len(table), workers)
    for (name, model_name, _), metrics in zip(jobs, found, strict=True):
        result["families"][name]["models"][model_name] = metrics
    return result


Bounds = Mapping[str, tuple[float, float]]
Models = Sequence[str] | Mapping[str, BaseEstimator]


@dataclass(frozen=True)
class Task:
    """What a grouped cross-validation learns and how it scores one fold: classification,
    regression of the graded outcome and ranking are values of this, run by one engine
    (:func:`cross_validate`)."""

    metrics: tuple[str, ...]
    target: Callable[[pd.DataFrame], np.ndarray]  # the fitted target, from the table
    make: Callable[[str, int, Sequence[str]], BaseEstimator]  # registry name, seed, features
    score: Callable[[BaseEstimator, pd.DataFrame], Mapping[str, float]]  # one test fold
    bounds: Bounds | None = None  # what each metric can take (summaries are clipped to it)
    difference_bounds: Bounds | None = None  # the same for paired differences


def cross_validate(table: pd.DataFrame, task: Task, models: Models,
                   features: Sequence[str] = FEATURES,
                   config: LearningConfig | None = None) -> pd.DataFrame:
    """Per-fold metrics of ``task``: one row per (model, repeat, fold).

    ``models`` is a list of registry names (built with ``task.make(name, seed, features)`` for
    each repeat's seed) or a mapping of name → estimator (cloned for each fold).
    """
    return _cross_validate(table, task, models, features, config or LearningConfig())[0]


def _cross_validate(table: pd.DataFrame, task: Task, models: Models, features: Sequence[str],
                    config: LearningConfig, predict: Predict | None = None) -> CVResult:
    check_dataset(table, features, config.folds)
    table = table.reset_index(drop=True)
    return grouped_cv(table, task.target(table),
                      lambda seed: fresh_models(task, models, seed, features), task.score, config,
                      predict)


def fresh_models(task: Task, models: Models, seed: int,
                 features: Sequence[str]) -> dict[str, BaseEstimator]:
    """Unfitted estimators for one repeat: clones of given ones, or the registry's."""
    if isinstance(models, Mapping):
        return {name: clone(model) for name, model in models.items()}
    return {name: task.make(name, seed, features) for name in models}


def summarise_task(per_fold: pd.DataFrame, task: Task, folds: int) -> dict[str, Any]:
    """Mean and corrected 95% interval of each of the task's metrics, per model."""
    return summarise_metrics(per_fold, task.metrics, folds, task.bounds)


def against_baselines(per_fold: pd.DataFrame, task: Task, folds: int,
                      baselines: Sequence[str] = ("rank_qc", "rank_qg")) -> dict[str, Any]:
    """Every model's paired per-fold difference to each rank baseline run beside it."""
    by_model = {name: group.drop(columns="model") for name, group in per_fold.groupby("model")}
    return {
        name: {f"vs_{base}": paired_metrics(frame, by_model[base], task.metrics, folds,
                                            task.difference_bounds)
               for base in baselines if base in by_model and base != name}
        for name, frame in by_model.items()
    }  # fmt: skip


def _labels(table: pd.DataFrame) -> np.ndarray:
    return table[LABEL_COLUMN].to_numpy().astype(bool)


#: Grip success: the classifiers' task.
CLASSIFICATION = Task(METRICS, _labels, make_model, fold_metrics)


def cross_validate_models(table: pd.DataFrame, models: Models,
                          features: Sequence[str] = FEATURES,
                          config: LearningConfig | None = None) -> pd.DataFrame:
    """Per-fold classification metrics: one row per (model, repeat, fold) with ``METRICS``."""
    return cross_validate(table, CLASSIFICATION, models, features, config)


Predict = Callable[[BaseEstimator, pd.DataFrame], np.ndarray]
#: Per-fold rows, and each model's out-of-fold ``predict`` of the first repeat (one value per
#: table row, NaN on a fold left out; empty without ``predict``).
CVResult = tuple[pd.DataFrame, dict[str, np.ndarray]]


def grouped_cv(
    table: pd.DataFrame, target: np.ndarray, fresh: Callable[[int], Mapping[str, BaseEstimator]],
    score: Callable[[BaseEstimator, pd.DataFrame], Mapping[str, float]], config: LearningConfig,
    predict: Predict | None = None,
) -> CVResult:
    """The repeated grouped folds: ``fresh(seed)`` estimators fitted on each training fold,
    ``score(model, test)`` on its test fold; one row per (model, repeat, fold). With
    ``predict``, the first repeat's fitted models also give ``predict(model, test)``, pooled
    into one out-of-fold prediction per row (what a ROC curve of the CV plots, at no extra fit).

    The folds are fitted in ``config.workers`` processes (:mod:`classifiers.learners.parallel`);
    every fit is seeded by its repeat alone, so the rows are the same whatever the number of
    workers.
    A fold whose training grips all have one class (a boolean ``target``; possible on a few
    objects) has nothing to learn from and gives no row, for every model alike, so paired
    differences stay matched on the folds both sides have.
    """
    jobs = [(repeat, fold, train, test)
            for repeat in range(config.repeats)
            for fold, (train, test) in enumerate(grouped_folds(table, config.folds,
                                                               config.seed + repeat))]
    run_fold = delayed(_fold_records)
    records: list[dict[str, Any]] = []
    pooled: dict[str, np.ndarray] = {}
    with progress_bar(len(jobs), "cross-validation") as bar:
        workers = worker_count(len(table), config.workers, len(jobs))
        found = Parallel(n_jobs=workers, return_as="generator")(
            run_fold(table, target, fresh, score, config.seed + repeat, repeat, fold, train, test,
                     predict if repeat == 0 else None)
            for repeat, fold, train, test in jobs)
        for (rows, predictions), (_, _, _, test) in zip(found, jobs, strict=True):
            raise_if_signalled()  # a stop signal the fold's library code lost stops here
            records += rows
            for name, values in predictions.items():
                pooled.setdefault(name, np.full(len(table), np.nan))[test] = values
            bar.advance()
    return pd.DataFrame.from_records(records), pooled


def _fold_records(
    table: pd.DataFrame, target: np.ndarray, fresh: Callable[[int], Mapping[str, BaseEstimator]],
    score: Callable[[BaseEstimator, pd.DataFrame], Mapping[str, float]], seed: int, repeat: int,
    fold: int, train: np.ndarray, test: np.ndarray, predict: Predict | None,
) -> tuple[list[dict[str, Any]], dict[str, np.ndarray]]:
    """One fold of :func:`grouped_cv`: every model fitted and scored (and its ``predict`` on
    the test fold, when given), on one thread."""
    if target.dtype == bool and np.unique(target[train]).size < 2:
        return [], {}
    records, predictions = [], {}
    with single_threaded():
        for name, model in fresh(seed).items():
            fit_fold(name, model, table.iloc[train], target[train])
            records.append({"model": name, "repeat": repeat, "fold": fold,
                            **score(model, table.iloc[test])})
            if predict is not None:
                predictions[name] = predict(model, table.iloc[test])
    return records, predictions


def fit_fold(name: str, model: BaseEstimator, train: pd.DataFrame, target: np.ndarray) -> None:
    """Fit ``model`` on a training fold; a model that cannot learn from so few grips (an early
    stopping split or internal folds larger than a class) is a ``ValueError`` naming it."""
    try:
        model.fit(train, target)
    except ValueError as exc:
        objects = train[GROUP_COLUMN].nunique()
        raise ValueError(
            f"model {name!r} cannot be fitted on a training fold of {len(train)} grips on "
            f"{objects} objects ({exc}); use a dataset of more grips, or leave {name!r} out of "
            "the learning settings (learning.models, .regressors or .rankers)") from exc


def evaluate_models(
    table: pd.DataFrame,
    models: Sequence[str] | Mapping[str, BaseEstimator],
    features: Sequence[str] = FEATURES,
    config: LearningConfig | None = None,
) -> dict[str, Any]:
    """Grouped, repeated CV summary in the ``metrics.json`` shape.

    ``{"models": {name: {metric: {"mean": m, "ci": [lo, hi]}}}, "cv": {...}}``
    """
    return evaluate_models_out_of_fold(table, models, features, config)[0]


def evaluate_models_out_of_fold(
    table: pd.DataFrame,
    models: Sequence[str] | Mapping[str, BaseEstimator],
    features: Sequence[str] = FEATURES,
    config: LearningConfig | None = None,
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """:func:`evaluate_models`, and each model's positive-class probability of every grip from
    the first repeat's fold that held it out (NaN on a fold left out), in the table's row
    order."""
    config = config or LearningConfig()
    per_fold, probabilities = _cross_validate(table, CLASSIFICATION, models, features, config,
                                              positive_probability)
    summary = {"models": summarise(per_fold, config.folds),
               "cv": cv_description(table, features, config)}
    return summary, probabilities


def summarise(per_fold: pd.DataFrame, folds: int) -> dict[str, dict[str, dict[str, Any]]]:
    """Mean and corrected 95% t-interval of each classification metric, per model."""
    return summarise_metrics(per_fold, METRICS, folds)


def summarise_metrics(per_fold: pd.DataFrame, metrics: Sequence[str], folds: int,
                      bounds: Bounds | None = None,
                      default: tuple[float, float] = (0.0, 1.0)) -> dict[str, dict[str, Any]]:
    """Mean and corrected 95% interval of each metric, per model; a metric's interval is
    clipped to ``bounds[metric]`` (else ``default``)."""
    bounds = bounds or {}
    return {
        str(name): {m: interval(group[m].to_numpy(float), folds, bounds.get(m, default))
                    for m in metrics}
        for name, group in per_fold.groupby("model", sort=False)
    }  # fmt: skip


def paired_metrics(frame: pd.DataFrame, reference: pd.DataFrame, metrics: Sequence[str],
                   folds: int, bounds: Bounds | None = None,
                   default: tuple[float, float] = (-np.inf, np.inf)) -> dict[str, Any]:
    """Mean and corrected 95% interval of (frame − reference) per metric, matched on
    (repeat, fold); clipped to ``bounds[metric]`` (else ``default``)."""
    bounds = bounds or {}
    merged = frame.merge(reference, on=["repeat", "fold"], suffixes=("", "_ref"),
                         validate="one_to_one")  # fmt: skip
    return {m: interval((merged[m] - merged[f"{m}_ref"]).to_numpy(float), folds,
                        bounds.get(m, default))
            for m in metrics}  # fmt: skip


def interval(
    values: np.ndarray, folds: int, bounds: tuple[float, float] = (-np.inf, np.inf)
) -> dict[str, Any]:
    """``{"mean", "ci", "n"}`` by the Nadeau–Bengio corrected resampled t-test; NaNs dropped.

    The interval is clipped to ``bounds``, the range the metric can take (all of ours lie in
    [0, 1]; paired differences in [-1, 1]).
    """
    values = values[np.isfinite(values)]
    n = values.size
    if n == 0:
        return {"mean": None, "ci": [None, None], "n": 0}
    mean = float(values.mean())
    if n == 1:
        return {"mean": mean, "ci": [mean, mean], "n": 1}
    half = half_width(values, folds)
    low, high = max(mean - half, bounds[0]), min(mean + half, bounds[1])
    return {"mean": mean, "ci": [float(low), float(high)], "n": int(n)}


def half_width(values: np.ndarray, folds: int) -> float:
    """Half-width of the Nadeau–Bengio corrected 95% interval of :func:`interval`, unclipped
    (NaNs dropped; NaN with fewer than two values)."""
    values = values[np.isfinite(values)]
    n = values.size
    if n < 2:
        return float("nan")
    spread = np.sqrt((1.0 / n + 1.0 / (folds - 1)) * values.var(ddof=1))
    return float(stats.t.ppf(0.975, n - 1) * spread)


def cv_description(
    table: pd.DataFrame, features: Sequence[str], config: LearningConfig
) -> dict[str, Any]:
    """The ``"cv"`` block of ``metrics.json``."""
    return {
        "folds": config.folds,
        "repeats": config.repeats,
        "seeds": [config.seed + r for r in range(config.repeats)],
        "groups": GROUP_COLUMN,
        "splitter": "StratifiedGroupKFold(shuffle=True)",
        "interval": "95% corrected resampled t (Nadeau-Bengio) over folds x repeats",
        "features": list(features),
        "n_grips": len(table),
        "n_objects": int(table[GROUP_COLUMN].nunique()),
        "positive_rate": float(table[LABEL_COLUMN].astype(bool).mean()),
    }


def grouped_search(
    model: BaseEstimator,
    grid: Mapping[str, Sequence[Any]],
    table: pd.DataFrame,
    folds: int = LearningConfig().folds,
    scoring: str = "roc_auc",
) -> GridSearchCV:
    """A fitted ``GridSearchCV`` whose inner folds are grouped by object (``GroupKFold``)."""
    if table[GROUP_COLUMN].nunique() < folds:
        raise ValueError(f"fewer objects than the {folds} search folds")
    search = GridSearchCV(model, dict(grid), scoring=scoring, cv=GroupKFold(n_splits=folds))
    labels = table[LABEL_COLUMN].to_numpy().astype(bool)
    return search.fit(table, labels, groups=table[GROUP_COLUMN].to_numpy())
