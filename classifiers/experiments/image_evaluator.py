"""What the twelve measures miss: the image models beside them, on the same folds and objects.

The study's image stage (``images/``) asks Dex-Net 2.0's question of this toolkit: does a
convolutional network on the grip's image (``cnn``), or on the image and the twelve measures
(``cnn_measures``), learn more than the learner of the measures (``learning.ablation_model``,
"hgb")? :func:`image_study`

- cross-validates the image models and that learner with exactly the grouped folds and seeds of
  :mod:`classifiers.evaluation.cross_validation`, so each image model's per-fold ROC-AUC minus the
  learner's is paired (:func:`classifiers.experiments.ablation.paired_difference`, the ablation's
  own; the Nadeau–Bengio corrected interval), and records each fit's time;
- fits each image model with every training seed on the study split's training objects and scores
  every held-out object's candidates (``images/scores.parquet``, the columns of
  :mod:`classifiers.experiments.candidate_scores`), which the benchmark stage reads beside the
  other learners' scores: top-1 success on split v4 and its paired differences come from the
  leaderboard (:mod:`classifiers.experiments.answers`);
- correlates the first seed's ``cnn`` score of every held-out grip with each measure (Spearman):
  which measure, if any, the network's judgement resembles;
- computes the occlusion maps of that network on a handful of held-out grips
  (``images/occlusion.npz``; the report draws them).

The grips' images need the contours they were planned on: the stage reads them from the
dataset's objects table (:func:`classifiers.learners.grip_images.attach_contours`).
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats
from sklearn.base import BaseEstimator
from sklearn.pipeline import Pipeline

from classifiers.evaluation.cross_validation import (
    CLASSIFICATION,
    GROUP_COLUMN,
    LABEL_COLUMN,
    cross_validate,
    cv_description,
    fold_metrics,
    object_families,
    ranking_score,
    summarise,
)
from classifiers.experiments.ablation import paired_difference
from classifiers.experiments.benchmark.provenance import training_record
from classifiers.experiments.candidate_scores import (
    _score_table,
    held_out_candidates,
    training_seeds,
    write_scores,
)
from classifiers.learners.models import make_model
from classifiers.learners.parallel import run_all
from grip_env.columns import FEATURES
from grip_env.config import Config
from grip_env.dataset.split import split_table

RESULT_FILE = "images.json"
SCORES_FILE = "scores.parquet"
OCCLUSION_FILE = "occlusion.npz"
#: Held-out grips whose occlusion maps are drawn: the network's most and least confident picks.
OCCLUDED_GRIPS = 6
#: The seconds each fit took, a column of the per-fold rows beside the metrics.
FIT_SECONDS, FIT_CPU_SECONDS = "fit_seconds", "fit_cpu_seconds"


def with_contours(table: pd.DataFrame, data_dir: Path) -> pd.DataFrame:
    """``table`` with each grip's planned-on contour within the image models' reach."""
    from classifiers.learners.grip_images import attach_contours
    from grip_env.dataset import read_objects

    return attach_contours(table, read_objects(Path(data_dir)))


def _timed_metrics(model: BaseEstimator, test: pd.DataFrame) -> dict[str, float]:
    return {**fold_metrics(model, test), FIT_SECONDS: model.fit_seconds_,
            FIT_CPU_SECONDS: model.fit_cpu_seconds_}


def timed(model: BaseEstimator) -> BaseEstimator:
    """``model`` with its fit timed: ``model.fit_seconds_`` (wall) and ``fit_cpu_seconds_`` (this
    process's CPU: on a busy machine, what the fit itself cost) after each fit."""
    fit = model.fit

    def timed_fit(X: Any, y: Any, **kwargs: Any) -> BaseEstimator:
        start, cpu = time.perf_counter(), time.process_time()
        fit(X, y, **kwargs)
        model.fit_seconds_ = time.perf_counter() - start
        model.fit_cpu_seconds_ = time.process_time() - cpu
        return model

    model.fit = timed_fit  # type: ignore[method-assign]
    return model


def image_cv(grips: pd.DataFrame, config: Config) -> tuple[pd.DataFrame, list[str]]:
    """Per-fold rows of the image models and the measures' learner (with each fit's seconds),
    and the model names, the reference (``learning.ablation_model``) last."""
    learning = config.learning
    names = [*learning.image_models, learning.ablation_model]
    task = replace(CLASSIFICATION, metrics=(*CLASSIFICATION.metrics, FIT_SECONDS,
                                            FIT_CPU_SECONDS),
                   make=lambda name, seed, features: timed(make_model(name, seed, features)),
                   score=_timed_metrics)  # fmt: skip
    return cross_validate(grips, task, names, FEATURES, learning), names


def summarise_cv(per_fold: pd.DataFrame, names: list[str], folds: int) -> dict[str, Any]:
    """Each model's CV metrics, each image model's paired difference to the reference, and the
    fit times per fold."""
    by_model = {name: frame.drop(columns="model") for name, frame in per_fold.groupby("model")}
    reference = names[-1]
    seconds = {name: {"mean": float(frame[FIT_SECONDS].mean()),
                      "max": float(frame[FIT_SECONDS].max()),
                      "cpu_mean": float(frame[FIT_CPU_SECONDS].mean()),
                      "cpu_max": float(frame[FIT_CPU_SECONDS].max()), "folds": len(frame)}
               for name, frame in by_model.items()}  # fmt: skip
    return {
        "reference": reference,
        "models": summarise(per_fold.drop(columns=[FIT_SECONDS, FIT_CPU_SECONDS]), folds),
        "paired_difference": {name: paired_difference(by_model[name], by_model[reference], folds)
                              for name in names[:-1]},
        "fit_seconds": seconds,
    }


def held_out_image_scores(grips: pd.DataFrame,
                          config: Config) -> tuple[pd.DataFrame, Any, dict[str, float]]:
    """Every image model fitted with each training seed on the split's training objects,
    scoring each held-out object's candidates (:mod:`classifiers.experiments.candidate_scores`'
    table, methods ``classifier_<name>``); each image model fitted with ``learning.seed``, by
    name; and each run's CPU seconds (fit and scores)."""
    learning = config.learning
    train, _ = split_table(grips, learning)
    candidates = held_out_candidates(grips, config)
    stacked = pd.concat(candidates.values(), ignore_index=True)
    labels = train[LABEL_COLUMN].to_numpy().astype(bool)
    runs = [(seed, f"classifier_{name}") for seed in training_seeds(learning.seed, learning.seeds)
            for name in learning.image_models]  # fmt: skip
    jobs = [(make_model(method.removeprefix("classifier_"), seed), train, labels, stacked)
            for seed, method in runs]  # fmt: skip
    fitted = run_all(_fit_and_score, jobs, len(train), learning.workers)
    scores = _score_table(candidates, stacked, runs, [score for _, score, _ in fitted])
    cpu = {f"{method} seed {seed}": seconds
           for (seed, method), (_, _, seconds) in zip(runs, fitted, strict=True)}  # fmt: skip
    first = {method.removeprefix("classifier_"): model
             for (seed, method), (model, _, _) in zip(runs, fitted, strict=True)
             if seed == learning.seed}  # fmt: skip
    return scores, first, cpu


def _fit_and_score(model: BaseEstimator, train: pd.DataFrame, labels: np.ndarray,
                   rows: pd.DataFrame) -> tuple[BaseEstimator, np.ndarray, float]:  # fmt: skip
    """The fitted model, its scores of ``rows`` and the CPU seconds both took."""
    cpu = time.process_time()
    model.fit(train, labels)
    score = ranking_score(model, rows)
    return model, score, time.process_time() - cpu


def save_models(models: dict[str, Pipeline], grips: pd.DataFrame, folder: Path,
                config: Config) -> None:
    """Each image model fitted on the split's training objects, saved as ``folder/<name>``
    (torch weights and JSON; ``trained_on`` names its objects, so ``grip-env benchmark`` takes
    it)."""
    from classifiers.learners.grip_images import CONTOUR_COLUMN
    from classifiers.learners.persistence import dataset_checksum, save_model

    learning = config.learning
    checksum = dataset_checksum(grips.drop(columns=CONTOUR_COLUMN))
    train, _ = split_table(grips, learning)
    trained_on = training_record(train[GROUP_COLUMN], checksum, split="train",
                                 test_fraction=learning.test_fraction, seed=learning.seed)
    for name, model in models.items():
        save_model(model, folder, name, {"features": list(model[0].measures), "seed": learning.seed,
                                         "dataset_sha256": checksum, "trained_on": trained_on})


def measure_resemblance(model: BaseEstimator, held_out: pd.DataFrame) -> dict[str, Any]:
    """Spearman correlation of the model's score with each of the twelve measures on the
    held-out grips, and the measure of the largest absolute correlation."""
    score = ranking_score(model, held_out)
    rho = {m: float(stats.spearmanr(score, held_out[m].to_numpy(float)).statistic)
           for m in FEATURES}  # fmt: skip
    finite = {m: r for m, r in rho.items() if np.isfinite(r)}
    closest = max(finite, key=lambda m: abs(finite[m])) if finite else None
    return {"spearman": rho, "closest": closest, "grips": len(held_out)}


def occluded_grips(model: BaseEstimator, held_out: pd.DataFrame,
                   count: int = OCCLUDED_GRIPS) -> pd.DataFrame:  # fmt: skip
    """The held-out grips whose maps are drawn: the ``count // 2`` the model scores highest and
    the rest it scores lowest (ties by row order)."""
    order = np.argsort(-ranking_score(model, held_out), kind="stable")
    top = count // 2
    return held_out.iloc[np.r_[order[:top], order[len(order) - (count - top):]]]


def image_study(grips: pd.DataFrame, out_dir: Path, config: Config,
                families: dict[str, str] | None = None) -> dict[str, Any]:  # fmt: skip
    """Run the stage on a grip table that carries its contours (``families``: object id →
    family, recorded for the held-out objects, whose picks the answers compare by family);
    writes ``out_dir``'s ``images.json``, ``scores.parquet`` and ``occlusion.npz``; returns the
    JSON content."""
    learning = config.learning
    out_dir.mkdir(parents=True, exist_ok=True)
    per_fold, names = image_cv(grips, config)
    result = {"models": list(learning.image_models),
              "cv": {**summarise_cv(per_fold, names, learning.folds),
                     **cv_description(grips, FEATURES, learning)}}  # fmt: skip
    start = time.perf_counter()
    scores, models, cpu = held_out_image_scores(grips, config)
    result["held_out_seconds"] = time.perf_counter() - start
    result["held_out_cpu_seconds"] = cpu
    write_scores(scores, out_dir / SCORES_FILE)
    save_models(models, grips, out_dir / "models", config)
    model = models[learning.image_models[0]]
    _, held_out = split_table(grips, learning)
    result["families"] = {oid: (families or {})[oid]
                          for oid in held_out[GROUP_COLUMN].astype(str).unique()
                          if oid in (families or {})}  # fmt: skip
    result["resemblance"] = {"model": learning.image_models[0], "seed": learning.seed,
                             **measure_resemblance(model, held_out)}  # fmt: skip
    if not model[0].measures:  # the maps hide pixels: of a network that reads the image alone
        result["occlusion"] = occlusion_record(model, occluded_grips(model, held_out),
                                               out_dir / OCCLUSION_FILE)  # fmt: skip
    (out_dir / RESULT_FILE).write_text(json.dumps(result, indent=2))
    return result


def occlusion_record(model: Pipeline, grips: pd.DataFrame, path: Path) -> dict[str, Any]:
    """The occlusion maps (:func:`classifiers.learners.occlusion.occlusion_maps`) of an image-only
    ``model`` on ``grips``, written to ``path`` (``.npz``: ``images``, ``maps``, ``titles``,
    ``channels``; the report draws them); returns which grips and their scores."""
    from classifiers.learners.occlusion import occlusion_maps

    inputs, network = model[0], model[-1]
    images = np.asarray(inputs.images_.transform(grips), dtype=np.float32)
    maps = occlusion_maps(lambda batch: network.predict_proba(batch.reshape(len(batch), -1))[:, 1],
                          images)  # fmt: skip
    probability = network.predict_proba(images.reshape(len(images), -1))[:, 1]
    titles = [f"{row.object_id}\n{'held' if row.success else 'slipped'}, P={p:.2f}"
              for row, p in zip(grips.itertuples(), probability, strict=True)]  # fmt: skip
    np.savez_compressed(path, images=images, maps=maps, titles=np.array(titles),
                        channels=np.array(list(inputs.images_.channels)))  # fmt: skip
    return {"file": path.name, "grip_ids": grips["grip_id"].astype(str).tolist(),
            "p_success": probability.round(4).tolist()}


def run_image_study(table: pd.DataFrame, data_dir: Path, out_dir: Path,
                    config: Config) -> dict[str, Any]:  # fmt: skip
    """The study's image stage on the dataset in ``data_dir`` (its contours) and its table."""
    return image_study(with_contours(table, data_dir), Path(out_dir), config,
                       object_families(table))
