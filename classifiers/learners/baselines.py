"""Column selection and the models that need no learning beyond a monotone calibration.

Every model in this package is a scikit-learn ``Pipeline`` whose first step is a
:class:`ColumnSelector`: models take the grip table (a ``pandas.DataFrame``) and pick their own
columns, so features, ranking indexes and identity columns cannot be mixed up by a caller.

The analytic baselines score each grip from one column (``rank_qc``: ``-Q_C``, ``rank_qg``:
``-Q_G``; lower index = better grip) or at random (``random``). Their ``decision_function`` is that
score; ``predict_proba`` maps the score through an isotonic (monotone non-decreasing) regression
fitted on the training labels, so the probabilities are calibrated but the ranking is the column's.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, ClassifierMixin, RegressorMixin, TransformerMixin
from sklearn.isotonic import IsotonicRegression
from sklearn.utils import Tags
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data


class ColumnSelector(TransformerMixin, BaseEstimator):
    """Select ``columns`` of a DataFrame as a float array; unknown or non-finite → ValueError."""

    def __init__(self, columns: Sequence[str] = ()):
        self.columns = columns

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        tags.requires_fit = False  # stateless: it selects by name, whatever it was fitted on
        return tags

    def fit(self, X: pd.DataFrame, y: Any = None) -> ColumnSelector:
        """Check that ``X`` holds the columns."""
        self._select(X)
        self.n_features_out_ = len(self.columns)
        return self

    def transform(self, X: pd.DataFrame) -> np.ndarray:
        """The selected columns, shape (rows, len(columns))."""
        return self._select(X)

    def get_feature_names_out(self, input_features: Any = None) -> np.ndarray:
        """The selected column names."""
        return np.asarray(self.columns, dtype=object)

    def _select(self, X: pd.DataFrame) -> np.ndarray:
        if not isinstance(X, pd.DataFrame):
            raise ValueError(f"models take the grip table as a DataFrame, got {type(X).__name__}")
        columns = list(self.columns)
        if not columns:
            raise ValueError("ColumnSelector needs at least one column")
        missing = [name for name in columns if name not in X.columns]
        if missing:
            raise ValueError(f"columns {missing} are not in the table")
        values = X[columns].to_numpy(dtype=np.float64)
        if not np.all(np.isfinite(values)):
            bad = [name for name in columns if not np.all(np.isfinite(X[name].to_numpy(float)))]
            raise ValueError(f"columns {bad} hold NaN or infinite values")
        return values


class RankingClassifier(ClassifierMixin, BaseEstimator):
    """Binary classifier scoring each row as ``sign * x`` (one column), isotonically calibrated."""

    def __init__(self, sign: float = -1.0):
        self.sign = sign

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        tags.classifier_tags.multi_class = False  # success or failure: two classes only
        return tags

    def fit(self, X: Any, y: Any) -> RankingClassifier:
        """Fit the monotone map from score to success probability."""
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        self.classes_ = np.unique(y)
        if self.classes_.size < 2:
            raise ValueError(f"a ranking baseline needs both outcomes; got 1 class "
                             f"{self.classes_.tolist()}")
        if self.classes_.size > 2:
            raise ValueError(f"Only binary classification is supported: a ranking baseline "
                             f"scores success or failure; got classes {self.classes_.tolist()}")
        positive = (y == self.classes_[1]).astype(float)
        self.calibration_ = IsotonicRegression(y_min=0.0, y_max=1.0, out_of_bounds="clip")
        self.calibration_.fit(self._score(X), positive)
        return self

    def decision_function(self, X: Any) -> np.ndarray:
        """The ranking score (higher = more likely to hold)."""
        check_is_fitted(self, "calibration_")
        return self._score(validate_data(self, X, dtype=np.float64, reset=False))

    def predict_proba(self, X: Any) -> np.ndarray:
        """Calibrated probabilities, columns in the order of ``classes_``."""
        check_is_fitted(self, "calibration_")
        positive = self.calibration_.predict(self.decision_function(X))
        return np.column_stack([1.0 - positive, positive])

    def predict(self, X: Any) -> np.ndarray:
        """The more probable class."""
        positive = self.predict_proba(X)[:, 1]
        return self.classes_[(positive >= 0.5).astype(int)]

    def _score(self, X: np.ndarray) -> np.ndarray:
        if X.shape[1] != 1:
            raise ValueError(f"a ranking baseline scores one column, got {X.shape[1]}")
        return float(self.sign) * X[:, 0]


class RandomClassifier(RankingClassifier):
    """The chance baseline: a seeded uniform random score per row, isotonically calibrated.

    The score depends only on ``random_state`` and the row's position, so repeated calls agree.
    """

    def __init__(self, random_state: int = 0):
        self.random_state = random_state

    def _score(self, X: np.ndarray) -> np.ndarray:
        return np.random.default_rng(self.random_state).random(X.shape[0])


class RankingRegressor(RegressorMixin, BaseEstimator):
    """Regressor whose ranking is one column's, ``sign * x``; only the units are fitted.

    ``predict`` is ``a + b * sign * x`` with the least-squares slope ``b`` clipped to be
    positive, so the predictions order the rows exactly as the column does (the rank baselines
    of the regression task) while living on the target's scale.
    """

    def __init__(self, sign: float = -1.0):
        self.sign = sign

    def fit(self, X: Any, y: Any) -> RankingRegressor:
        """Fit the affine map from score to target."""
        X, y = validate_data(self, X, y, dtype=np.float64, y_numeric=True)
        score = self._score(X)
        spread = score.var()
        slope = float(np.cov(score, y, bias=True)[0, 1] / spread) if spread > 0 else 0.0
        self.slope_ = max(slope, 1e-9)
        self.intercept_ = float(np.mean(y) - self.slope_ * score.mean())
        return self

    def predict(self, X: Any) -> np.ndarray:
        """Predicted targets, monotone increasing in the score."""
        check_is_fitted(self, "slope_")
        score = self._score(validate_data(self, X, dtype=np.float64, reset=False))
        return self.intercept_ + self.slope_ * score

    def _score(self, X: np.ndarray) -> np.ndarray:
        if X.shape[1] != 1:
            raise ValueError(f"a ranking baseline scores one column, got {X.shape[1]}")
        return float(self.sign) * X[:, 0]


class RandomRegressor(RankingRegressor):
    """The chance baseline of the regression task: a seeded uniform score per row."""

    def __init__(self, random_state: int = 0):
        self.random_state = random_state

    def _score(self, X: np.ndarray) -> np.ndarray:
        return np.random.default_rng(self.random_state).random(X.shape[0])
