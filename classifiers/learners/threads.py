"""One thread for the native pools (OpenMP, BLAS) while small models are fitted.

scikit-learn's HistGradientBoosting and LightGBM start one OpenMP thread per core for every fit;
on a few thousand grips the threads cost more than they save, and on a shared or busy machine
they oversubscribe it: one HistGradientBoosting fit on the default dataset took 3.0 s with the
default pool and 0.23 s with one thread (2 busy cores). Torch has its own setting
(:mod:`classifiers.learners.torch_mlp` already trains single-threaded).

The "hgb" models are :class:`OneThreadHGBClassifier` and :class:`OneThreadHGBRegressor`: the
scikit-learn estimators, unchanged, with ``fit`` and every prediction run single-threaded, so a
model loaded by a user's own code is as fast as inside the study.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import Any, Self

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier, HistGradientBoostingRegressor
from threadpoolctl import threadpool_limits


def single_threaded() -> AbstractContextManager[object]:
    """A context in which OpenMP and BLAS pools use one thread."""
    return threadpool_limits(limits=1)


class _OneThread:
    """``fit`` and ``predict`` of the HistGradientBoosting estimator this is mixed into (listed
    before it), run single-threaded with the same arguments."""

    def fit(self, X: Any, y: Any, sample_weight: Any = None, *, X_val: Any = None,
            y_val: Any = None, sample_weight_val: Any = None) -> Self:
        """As the parent's ``fit`` (an explicit validation set included), single-threaded."""
        with single_threaded():
            return super().fit(X, y, sample_weight=sample_weight, X_val=X_val,
                               y_val=y_val, sample_weight_val=sample_weight_val)

    def predict(self, X: Any) -> np.ndarray:
        """As the parent's ``predict``, single-threaded."""
        with single_threaded():
            return super().predict(X)


class OneThreadHGBClassifier(_OneThread, HistGradientBoostingClassifier):
    """``HistGradientBoostingClassifier`` fitted and queried on one thread."""

    def predict_proba(self, X: Any) -> np.ndarray:
        """As the parent's ``predict_proba``, single-threaded."""
        with single_threaded():
            return super().predict_proba(X)

    def decision_function(self, X: Any) -> np.ndarray:
        """As the parent's ``decision_function``, single-threaded."""
        with single_threaded():
            return super().decision_function(X)


class OneThreadHGBRegressor(_OneThread, HistGradientBoostingRegressor):
    """``HistGradientBoostingRegressor`` fitted and queried on one thread."""
