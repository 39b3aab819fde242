"""The "svm" classifier: an RBF ``SVC`` with Platt (sigmoid) probabilities.

The probabilities are fitted by internal stratified cross-validation, as
``CalibratedClassifierCV(SVC(), method="sigmoid", ensemble=False)`` fits them (scikit-learn's
replacement for the deprecated ``SVC(probability=True)``), with at most ``cv`` folds: fewer when
the rarer class has fewer training grips, so a small dataset's fold still fits (at least two
grips of each class are needed).
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.calibration import CalibratedClassifierCV
from sklearn.svm import SVC
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data


class PlattSVC(ClassifierMixin, BaseEstimator):
    """RBF support-vector classifier with Platt-scaled probabilities (see the module).

    Args:
        C: the SVC's regularisation.
        cv: the most internal folds the probabilities are fitted on.
        random_state: the SVC's seed.
    """

    def __init__(self, C: float = 1.0, cv: int = 5, random_state: int | None = None) -> None:
        self.C = C
        self.cv = cv
        self.random_state = random_state

    def fit(self, X, y) -> PlattSVC:
        X, y = validate_data(self, X, y)
        check_classification_targets(y)
        classes, counts = np.unique(y, return_counts=True)
        if classes.size < 2:
            raise ValueError(f"svm needs two classes to fit, got one class ({classes.tolist()})")
        folds = int(min(self.cv, counts.min()))
        if folds < 2:
            raise ValueError(f"svm fits its probabilities by cross-validation and needs at least "
                             f"2 training grips of each class, got {counts.min()} of "
                             f"{classes[counts.argmin()]!r}")
        svc = SVC(C=self.C, random_state=self.random_state)
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
