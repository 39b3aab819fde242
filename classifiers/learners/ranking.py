"""The learning-to-rank estimator: LightGBM lambdarank with one query group per object, and
the graded relevance it learns (see :mod:`classifiers.evaluation.cross_validation.ranking` for how
it is scored).

A robot picks one grip per object, so what matters is the order of each object's candidates, not
a probability comparable across objects. :class:`GroupedRanker` fits LightGBM's ``LGBMRanker``
with the ``lambdarank`` objective (it optimises NDCG within each group), a group being all the
training grips of one object; its ``predict`` score is comparable only within an object.
``make_ranker`` also gives the rank baselines ``rank_qc``, ``rank_qg`` and ``random``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from lightgbm import Booster, LGBMRanker
from lightgbm.basic import LightGBMError
from sklearn.base import BaseEstimator
from sklearn.pipeline import Pipeline
from sklearn.utils.validation import check_is_fitted

from classifiers.learners.baselines import ColumnSelector, RandomRegressor, RankingRegressor
from classifiers.learners.models import check_features
from grip_env.columns import FEATURES, IDENTITY, ROBUSTNESS
from grip_env.config import SimConfig

TARGET_COLUMN = ROBUSTNESS[0]  # the graded outcome relevance is read from
GROUP_COLUMN = IDENTITY[0]  # a query group is one object's grips


def relevance(table: pd.DataFrame, sim: SimConfig | None = None) -> np.ndarray:
    """Integer relevance grade of each grip (see the module docstring)."""
    if TARGET_COLUMN not in table.columns:
        return table["successes"].to_numpy().astype(np.int64)
    sim = sim or SimConfig()
    load = table[TARGET_COLUMN].to_numpy(float)
    if not np.isfinite(load).all():
        raise ValueError(f"{TARGET_COLUMN!r} holds NaN or infinite values")
    lowest, ratio = float(sim.ramp_levels_g[0]), float(sim.ramp_ratio)
    levels = np.floor(np.log(np.maximum(load, lowest) / lowest) / np.log(ratio) + 1e-9) + 1
    return np.where(load < lowest, 0, levels).astype(np.int64)


class GroupedRanker(BaseEstimator):
    """LightGBM lambdarank on a grip table; the rows of one ``group_column`` value are a query.

    ``fit(table, grade)`` takes the table (any row order) and integer grades; ``predict(table)``
    returns one score per row (higher = pick first). ``decision_function`` is the same score.
    Bagging (``subsample``) and feature subsampling are seeded by ``random_state``.
    """

    def __init__(self, features: Sequence[str] = FEATURES, group_column: str = GROUP_COLUMN,
                 n_estimators: int = 200, learning_rate: float = 0.05, num_leaves: int = 15,
                 min_child_samples: int = 10, subsample: float = 0.8,
                 colsample_bytree: float = 0.9, reg_lambda: float = 1.0,
                 random_state: int = 0) -> None:  # fmt: skip
        self.features = features
        self.group_column = group_column
        self.n_estimators = n_estimators
        self.learning_rate = learning_rate
        self.num_leaves = num_leaves
        self.min_child_samples = min_child_samples
        self.subsample = subsample
        self.colsample_bytree = colsample_bytree
        self.reg_lambda = reg_lambda
        self.random_state = random_state

    def fit(self, X: pd.DataFrame, y: Any) -> GroupedRanker:
        """Fit on ``X``'s grips grouped by ``group_column``; ``y`` the integer grades."""
        grades = np.asarray(y)
        if grades.shape != (len(X),) or not np.issubdtype(grades.dtype, np.integer):
            raise ValueError(f"grades must be {len(X)} integers, got {grades.dtype} "
                             f"{grades.shape}")  # fmt: skip
        if grades.min(initial=0) < 0:
            raise ValueError(f"grades must be >= 0, got {int(grades.min())}")
        values = self._values(X)
        groups = X[self.group_column].astype(str).to_numpy()
        # a canonical row order (object, then feature values), so that bagging, which depends
        # on the row order, draws the same rows however the table is sorted
        order = np.lexsort((*values.T[::-1], groups))
        _, sizes = np.unique(groups[order], return_counts=True)
        self.ranker_ = LGBMRanker(
            objective="lambdarank", n_estimators=self.n_estimators,
            learning_rate=self.learning_rate, num_leaves=self.num_leaves,
            min_child_samples=self.min_child_samples, subsample=self.subsample, subsample_freq=1,
            colsample_bytree=self.colsample_bytree, reg_lambda=self.reg_lambda,
            random_state=self.random_state, n_jobs=1, deterministic=True, force_row_wise=True,
            label_gain=list(range(int(grades.max()) + 1)), verbose=-1,
        )  # fmt: skip
        self.ranker_.fit(values[order], grades[order], group=sizes)
        self.booster_ = self.ranker_.booster_
        self.n_groups_ = int(sizes.size)
        return self

    def predict(self, X: pd.DataFrame) -> np.ndarray:
        """The ranking score of each row (comparable within one object only)."""
        check_is_fitted(self, "booster_")
        return np.asarray(self.booster_.predict(self._values(X)), dtype=float)

    def decision_function(self, X: pd.DataFrame) -> np.ndarray:
        """Same as :meth:`predict`, the name
        :func:`classifiers.evaluation.cross_validation.ranking_score` reads."""
        return self.predict(X)

    def save(self, directory: str | Path, name: str) -> Path:
        """Write the booster as LightGBM's own text model ``name.txt``; returns its path."""
        check_is_fitted(self, "booster_")
        path = Path(directory) / f"{name}.txt"
        path.parent.mkdir(parents=True, exist_ok=True)
        self.booster_.save_model(str(path))
        return path

    @classmethod
    def load(cls, path: str | Path, params: dict[str, Any]) -> GroupedRanker:
        """A ranker written by :meth:`save`, rebuilt with its ``get_params()``: it predicts as
        the fitted one did (LightGBM parses its text model; nothing is unpickled)."""
        ranker = cls(**params)
        if not Path(path).is_file():
            raise FileNotFoundError(f"no saved ranker {path}")
        try:
            ranker.booster_ = Booster(model_file=str(path))
        except LightGBMError as exc:
            raise ValueError(f"{path} is not a LightGBM model: {exc}") from None
        if ranker.booster_.num_feature() != len(check_features(ranker.features)):
            raise ValueError(f"{path} reads {ranker.booster_.num_feature()} features, its "
                             f"parameters name {len(ranker.features)}")
        return ranker

    def _values(self, X: pd.DataFrame) -> np.ndarray:
        return ColumnSelector(check_features(self.features)).fit_transform(X)


RANKER_NAMES = ("lambdarank", "rank_qc", "rank_qg", "random")


def make_ranker(name: str, seed: int = 0, features: Sequence[str] = FEATURES) -> BaseEstimator:
    """A fresh ranker; the baselines are the regression task's (a monotone map of one column)."""
    features = check_features(features)
    if name == "lambdarank":
        return GroupedRanker(features, random_state=seed)
    baselines = {"rank_qc": (("Q_C",), RankingRegressor(sign=-1.0)),
                 "rank_qg": (("Q_G",), RankingRegressor(sign=-1.0)),
                 "random": (("Q_C",), RandomRegressor(random_state=seed))}  # fmt: skip
    if name not in baselines:
        raise ValueError(f"unknown ranker name {name!r}; known: {list(RANKER_NAMES)}")
    columns, estimator = baselines[name]
    return Pipeline([("select", ColumnSelector(columns)), ("model", estimator)])
