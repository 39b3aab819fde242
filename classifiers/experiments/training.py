"""Train, evaluate and save the classifiers: what ``grip-env train`` runs.

``train_and_save(table, out_dir, config)`` writes

- ``metrics.json``: grouped, repeated CV of every model
  (:func:`classifiers.evaluation.cross_validation.evaluate_models`) plus the dataset checksum;
- ``metrics.json["held_out"]``: every model fitted on the training objects of the study's split
  (:func:`grip_env.dataset.split.held_out_objects`) and scored on its held-out objects, the same
  objects the RL selector and its baselines are scored on;
- ``metrics.json["family_holdout"]``: every model fitted on all object families but one
  (named, procedural, mesh, ...) and scored on the one held out
  (:func:`classifiers.evaluation.cross_validation.family_holdout_metrics`), when the dataset has
  two or more;
- ``roc.png``, ``calibration.png``: curves of the out-of-fold predictions of the CV's first
  repeat, pooled (each grip scored by a model that never saw its object);
- ``models/<name>.{json,skops|pt}``: each model refitted on the whole table, with its metadata
  (feature list, parameters, dataset checksum, seed, and ``trained_on``: the table's object ids
  and the split that chose them, which ``grip-env benchmark`` checks);
- when the table has the graded outcome: ``regression.json`` (grouped CV of
  ``learning.regressors`` on ``robustness_mean``, see :mod:`classifiers.evaluation.regression`) and
  ``models/regressor_<name>.*``;
- ``ranking.json``: grouped CV of ``learning.rankers`` (:mod:`classifiers.evaluation.ranking`), with
  ``models/ranker_<name>.*`` (lambdarank: LightGBM's text model ``.txt`` beside its ``.json``);
- ``scores.parquet``: every learner fitted with each of ``learning.seeds`` seeds on the split's
  training objects, scoring each held-out object's candidates
  (:mod:`classifiers.experiments.candidate_scores`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.pipeline import Pipeline

from classifiers.evaluation.cross_validation import (
    LABEL_COLUMN,
    evaluate_models_out_of_fold,
    family_holdout_metrics,
    held_out_metrics,
    object_families,
)
from classifiers.evaluation.ranking import evaluate_rankers
from classifiers.evaluation.regression import TARGET_COLUMN, evaluate_regressors, has_target
from classifiers.experiments.benchmark.provenance import training_record
from classifiers.experiments.candidate_scores import SCORES_FILE, learner_scores, write_scores
from classifiers.experiments.plots import plot_calibration, plot_roc
from classifiers.learners.models import make_model, make_regressor
from classifiers.learners.parallel import fit_all
from classifiers.learners.persistence import dataset_checksum, save_model
from classifiers.learners.ranking import GroupedRanker, make_ranker, relevance
from classifiers.learners.threads import single_threaded
from grip_env.columns import FEATURES
from grip_env.config import Config


def train_and_save(
    table: pd.DataFrame, out_dir: str | Path, config: Config | None = None,
    split: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Cross-validate, plot, refit on everything and save; returns the metrics dict.

    ``split``: how ``table`` was chosen from its dataset (default ``{"split": "all"}``; its
    ``dataset_sha256``: that dataset's checksum, default ``table``'s), recorded with ``table``'s
    object ids as every saved model's ``trained_on``
    (:func:`~classifiers.experiments.benchmark.provenance.training_record`)."""
    with single_threaded():
        return _train_and_save(table, out_dir, config or Config(), split or {"split": "all"})


def _train_and_save(table: pd.DataFrame, out_dir: str | Path, config: Config,
                    split: dict[str, Any]) -> dict[str, Any]:  # fmt: skip
    learning = config.learning
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    checksum = dataset_checksum(table)
    record = {"dataset_sha256": checksum, **split}  # the split's source dataset, when given
    trained_on = {"trained_on": training_record(table["object_id"], **record)}
    metrics, out_of_fold = evaluate_models_out_of_fold(table, learning.models, FEATURES, learning)
    metrics["held_out"] = held_out_scores(table, config)
    metrics["family_holdout"] = family_holdout_scores(table, config)
    metrics["dataset"] = {"sha256": checksum, "rows": len(table),
                          "objects": int(table["object_id"].nunique()), **split}  # fmt: skip
    labels = table[LABEL_COLUMN].to_numpy().astype(bool)
    sampled = {}
    fitted = fit_all(((make_model(name, learning.seed, FEATURES), table, labels)
                      for name in learning.models), learning.workers)  # fmt: skip
    for name, model in zip(learning.models, fitted, strict=True):
        meta = {"features": list(FEATURES), "dataset_sha256": checksum, "seed": learning.seed,
                **trained_on}  # fmt: skip
        save_model(model, out_dir / "models", name, meta)
        sampled |= sampled_fit(name, model, len(table))
    metrics["sampled"] = sampled  # the kernel learners' stated subsamples (all grips: absent)
    (out_dir / "metrics.json").write_text(json.dumps(metrics, indent=2))
    _out_of_fold_plots(table, out_of_fold, learning.folds, out_dir)
    if has_target(table):
        train_regressors(table, out_dir, config, checksum, trained_on)
    train_rankers(table, out_dir, config, checksum, trained_on)
    write_scores(learner_scores(table, config), out_dir / SCORES_FILE)
    return metrics


def held_out_scores(table: pd.DataFrame, config: Config) -> dict[str, Any]:
    """Each of ``learning.models`` fitted on the split's training objects, scored on the rest
    (:func:`classifiers.evaluation.cross_validation.held_out_metrics`)."""
    learning = config.learning
    models = {name: make_model(name, learning.seed, FEATURES) for name in learning.models}
    return held_out_metrics(table, learning, models)


def family_holdout_scores(table: pd.DataFrame, config: Config) -> dict[str, Any]:
    """Each of ``learning.models`` fitted on all families but one, scored on that one
    (:func:`classifiers.evaluation.cross_validation.family_holdout_metrics`)."""
    learning = config.learning
    models = {name: make_model(name, learning.seed, FEATURES) for name in learning.models}
    return family_holdout_metrics(table, object_families(table), models, learning.workers)


def train_regressors(
    table: pd.DataFrame, out_dir: Path, config: Config, checksum: str,
    metadata: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Cross-validate the regressors into ``regression.json``, refit and save each one."""
    learning = config.learning
    result = evaluate_regressors(table, learning.regressors, FEATURES, learning)
    result["dataset"] = {"sha256": checksum, "rows": len(table)}
    target = table[TARGET_COLUMN].to_numpy(float)
    result["sampled"] = {}
    fitted = fit_all(((make_regressor(name, learning.seed, FEATURES), table, target)
                      for name in learning.regressors), learning.workers)  # fmt: skip
    for name, model in zip(learning.regressors, fitted, strict=True):
        meta = {"features": list(FEATURES), "target": TARGET_COLUMN, "dataset_sha256": checksum,
                "seed": learning.seed, **(metadata or {})}  # fmt: skip
        save_model(model, out_dir / "models", f"regressor_{name}", meta)
        result["sampled"] |= sampled_fit(name, model, len(table))
    (out_dir / "regression.json").write_text(json.dumps(result, indent=2))
    return result


def sampled_fit(name: str, model: Pipeline, rows: int) -> dict[str, int]:
    """``{name: grips}`` when the fitted ``model`` learnt from a sample of its ``rows`` grips
    (:mod:`classifiers.learners.svm`), else nothing."""
    fitted_on = getattr(model[-1], "n_fit_grips_", rows)
    return {name: int(fitted_on)} if fitted_on < rows else {}


def train_rankers(
    table: pd.DataFrame, out_dir: Path, config: Config, checksum: str,
    metadata: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Cross-validate the rankers into ``ranking.json``, refit and save each one."""
    learning = config.learning
    result = evaluate_rankers(table, learning.rankers, FEATURES, learning, config.sim)
    result["dataset"] = {"sha256": checksum, "rows": len(table)}
    (out_dir / "ranking.json").write_text(json.dumps(result, indent=2))
    grades = relevance(table, config.sim)
    fitted = fit_all(((make_ranker(name, learning.seed, FEATURES), table, grades)
                      for name in learning.rankers), learning.workers)  # fmt: skip
    for name, model in zip(learning.rankers, fitted, strict=True):
        meta = {"features": list(FEATURES), "target": result["relevance"],
                "dataset_sha256": checksum, "seed": learning.seed, **(metadata or {})}  # fmt: skip
        if isinstance(model, GroupedRanker):
            path = model.save(out_dir / "models", f"ranker_{name}")
            meta |= {"name": f"ranker_{name}", "format": "lightgbm_text", "model": path.name,
                     "params": model.get_params()}  # fmt: skip
            (out_dir / "models" / f"ranker_{name}.json").write_text(json.dumps(meta, indent=2))
        else:
            save_model(model, out_dir / "models", f"ranker_{name}", meta)
    return result


def _out_of_fold_plots(table: pd.DataFrame, probabilities: dict[str, np.ndarray], folds: int,
                       out_dir: Path) -> None:
    """ROC and reliability from the CV's pooled out-of-fold predictions (its first repeat)."""
    labels = table[LABEL_COLUMN].to_numpy().astype(bool)
    if np.unique(labels).size < 2 or not probabilities:
        return  # curves are undefined with one class
    scored = np.all([np.isfinite(p) for p in probabilities.values()], axis=0)
    pooled = {name: p[scored] for name, p in probabilities.items()}
    title = f"{folds}-fold grouped CV, out-of-fold predictions pooled"
    plot_roc(labels[scored], pooled, out_dir / "roc.png", title)
    plot_calibration(labels[scored], pooled, out_dir / "calibration.png", title=title)
