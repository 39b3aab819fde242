"""The kernel learners: the "svm" classifier (an RBF ``SVC`` with Platt (sigmoid)
probabilities) and the "svr" regressor (an RBF ``SVR``), each fitted on at most ``max_grips``
grips.

A kernel machine's fit grows with the square of its grips or faster (an exact RBF ``SVC`` took
6 s on 5,300 grips and 19 s on 9,000 here), and the study fits each one dozens of times. So when
a training set is larger than ``max_grips`` (default :data:`MAX_KERNEL_GRIPS`), the machine is
fitted on a seeded sample of that many of its grips (stratified by class for the classifier), and
says so: ``n_fit_grips_`` is the number it learnt from. Smaller sets are fitted whole, as
scikit-learn would.

The probabilities are fitted by internal stratified cross-validation, as
``CalibratedClassifierCV(SVC(), method="sigmoid", ensemble=False)`` fits them (scikit-learn's
replacement for the deprecated ``SVC(probability=True)``), with at most ``cv`` folds: fewer when
the rarer class has fewer training grips, so a small dataset's fold still fits (at least two
grips of each class are needed).
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, RegressorMixin
from sklearn.calibration import CalibratedClassifierCV
from sklearn.svm import SVC, SVR
from sklearn.utils import check_random_state
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

#: The most grips a kernel learner is fitted on (see the module docstring).
MAX_KERNEL_GRIPS = 4000


def kernel_sample(y: np.ndarray, max_grips: int | None, random_state: object,
                  stratify: bool) -> np.ndarray:
    """The rows a kernel learner is fitted on: all of them, or a seeded sample of
    ``max_grips`` (in each class its share of the rows when ``stratify``)."""
    n = len(y)
    if max_grips is None or n <= max_grips:
        return np.arange(n)
    if max_grips < 2:
        raise ValueError(f"max_grips must be at least 2 or None, got {max_grips}")
    rng = check_random_state(random_state)
    if not stratify:
        return np.sort(rng.choice(n, size=max_grips, replace=False))
    classes, counts = np.unique(y, return_counts=True)
    quota = np.maximum(1, np.round(counts / n * max_grips).astype(int))
    picked = [rng.choice(np.flatnonzero(y == c), size=min(q, k), replace=False)
              for c, q, k in zip(classes, quota, counts, strict=True)]
    return np.sort(np.concatenate(picked))


class PlattSVC(ClassifierMixin, BaseEstimator):
    """RBF support-vector classifier with Platt-scaled probabilities (see the module).

    Args:
        C: the SVC's regularisation.
        cv: the most internal folds the probabilities are fitted on.
        max_grips: the most grips it is fitted on (None: all; see the module docstring).
        random_state: the seed of that sample.
    """

    def __init__(self, C: float = 1.0, cv: int = 5, max_grips: int | None = MAX_KERNEL_GRIPS,
                 random_state: int | None = None) -> None:
        self.C = C
        self.cv = cv
        self.max_grips = max_grips
        self.random_state = random_state

    def fit(self, X, y) -> PlattSVC:
        X, y = validate_data(self, X, y)
        check_classification_targets(y)
        rows = kernel_sample(y, self.max_grips, self.random_state, stratify=True)
        X, y = X[rows], y[rows]
        self.n_fit_grips_ = len(rows)
        classes, counts = np.unique(y, return_counts=True)
        if classes.size < 2:
            raise ValueError(f"svm needs two classes to fit, got one class ({classes.tolist()})")
        folds = int(min(self.cv, counts.min()))
        if folds < 2:
            raise ValueError(f"svm fits its probabilities by cross-validation and needs at least "
                             f"2 training grips of each class, got {counts.min()} of "
                             f"{classes[counts.argmin()]!r}")
        svc = SVC(C=self.C)
        self.calibrated_ = CalibratedClassifierCV(svc, method="sigmoid", ensemble=False,
                                                  cv=folds).fit(X, y)
        self.classes_ = self.calibrated_.classes_
        self.folds_ = folds
        return self

    def predict(self, X) -> np.ndarray:
        check_is_fitted(self)
        return self.calibrated_.predict(validate_data(self, X, reset=False))

    def predict_proba(self, X) -> np.ndarray:
        check_is_fitted(self)
        return self.calibrated_.predict_proba(validate_data(self, X, reset=False))

    def decision_function(self, X) -> np.ndarray:
        check_is_fitted(self)
        fitted = self.calibrated_.calibrated_classifiers_[0].estimator  # ensemble=False: one SVC
        return fitted.decision_function(validate_data(self, X, reset=False))


class SampledSVR(RegressorMixin, BaseEstimator):
    """RBF support-vector regressor fitted on at most ``max_grips`` grips (see the module).

    Args:
        C: the SVR's regularisation.
        epsilon: the SVR's insensitive-tube half-width, in the target's units.
        max_grips: the most grips it is fitted on (None: all).
        random_state: the seed of that sample.
    """

    def __init__(self, C: float = 1.0, epsilon: float = 0.1,
                 max_grips: int | None = MAX_KERNEL_GRIPS,
                 random_state: int | None = None) -> None:
        self.C = C
        self.epsilon = epsilon
        self.max_grips = max_grips
        self.random_state = random_state

    def fit(self, X, y) -> SampledSVR:
        X, y = validate_data(self, X, y, y_numeric=True)
        rows = kernel_sample(y, self.max_grips, self.random_state, stratify=False)
        self.svr_ = SVR(C=self.C, epsilon=self.epsilon).fit(X[rows], y[rows])
        self.n_fit_grips_ = len(rows)
        return self

    def predict(self, X) -> np.ndarray:
        check_is_fitted(self)
        return self.svr_.predict(validate_data(self, X, reset=False))
