"""Train, evaluate and save the classifiers: what ``grip-env train`` runs.

``train_and_save(table, out_dir, config)`` writes

- ``metrics.json``: grouped, repeated CV of every model
  (:func:`classifiers.evaluation.evaluate_models`) plus the dataset checksum;
- ``roc.png``, ``calibration.png``: curves on a held-out share of objects (``test_fraction``),
  with the models fitted on the other objects;
- ``models/<name>.{json,skops|pt}``: each model refitted on the whole table, with its metadata
  (feature list, parameters, dataset checksum, seed);
- when the table has the graded outcome: ``regression.json`` (grouped CV of
  ``learning.regressors`` on ``robustness_mean``, see :mod:`classifiers.regression`) and
  ``models/regressor_<name>.*``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.model_selection import GroupShuffleSplit

from classifiers.evaluation import GROUP_COLUMN, LABEL_COLUMN, evaluate_models, positive_probability
from classifiers.models import make_model, make_regressor
from classifiers.persistence import dataset_checksum, save_model
from classifiers.plots import plot_calibration, plot_roc
from classifiers.regression import TARGET_COLUMN, evaluate_regressors, has_target
from grip_env.columns import FEATURES
from grip_env.config import Config


def train_and_save(
    table: pd.DataFrame, out_dir: str | Path, config: Config | None = None
) -> dict[str, Any]:
    """Cross-validate, plot, refit on everything and save; returns the metrics dict."""
    config = config or Config()
    learning = config.learning
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    checksum = dataset_checksum(table)
    metrics = evaluate_models(table, learning.models, FEATURES, learning)
    metrics["dataset"] = {"sha256": checksum, "rows": len(table)}
    (out_dir / "metrics.json").write_text(json.dumps(metrics, indent=2))
    _held_out_plots(table, config, out_dir)
    labels = table[LABEL_COLUMN].to_numpy().astype(bool)
    for name in learning.models:
        model = make_model(name, learning.seed, FEATURES).fit(table, labels)
        meta = {"features": list(FEATURES), "dataset_sha256": checksum, "seed": learning.seed}
        save_model(model, out_dir / "models", name, meta)
    if has_target(table):
        train_regressors(table, out_dir, config, checksum)
    return metrics


def train_regressors(
    table: pd.DataFrame, out_dir: Path, config: Config, checksum: str
) -> dict[str, Any]:
    """Cross-validate the regressors into ``regression.json``, refit and save each one."""
    learning = config.learning
    result = evaluate_regressors(table, learning.regressors, FEATURES, learning)
    result["dataset"] = {"sha256": checksum, "rows": len(table)}
    (out_dir / "regression.json").write_text(json.dumps(result, indent=2))
    target = table[TARGET_COLUMN].to_numpy(float)
    for name in learning.regressors:
        model = make_regressor(name, learning.seed, FEATURES).fit(table, target)
        meta = {"features": list(FEATURES), "target": TARGET_COLUMN, "dataset_sha256": checksum,
                "seed": learning.seed}  # fmt: skip
        save_model(model, out_dir / "models", f"regressor_{name}", meta)
    return result


def _held_out_plots(table: pd.DataFrame, config: Config, out_dir: Path) -> None:
    learning = config.learning
    split = GroupShuffleSplit(1, test_size=learning.test_fraction, random_state=learning.seed)
    labels = table[LABEL_COLUMN].to_numpy().astype(bool)
    train, test = next(split.split(table, labels, table[GROUP_COLUMN].to_numpy()))
    if np.unique(labels[test]).size < 2 or np.unique(labels[train]).size < 2:
        return  # curves are undefined with one class on either side
    probabilities = {}
    for name in learning.models:
        model = make_model(name, learning.seed, FEATURES).fit(table.iloc[train], labels[train])
        probabilities[name] = positive_probability(model, table.iloc[test])
    plot_roc(labels[test], probabilities, out_dir / "roc.png")
    plot_calibration(labels[test], probabilities, out_dir / "calibration.png")
