"""Every estimator of classifiers/learners/ through scikit-learn's estimator checks.

The estimators are taken as the registries build them (``make_model``, ``make_regressor``,
``make_ranker``): a registry pipeline's column selection, and the rest of it (the bare estimator
where that is one step), with a few settings made small so that the checks run fast
(:data:`FAST`). The rank baselines of the ranking task are the regression task's. The registry's
pipelines of scikit-learn's own estimators (a scaler, then the model) are checked too, as slow.

``parametrize_with_checks`` feeds its checks numpy arrays of made-up data. A check that a design
choice rules out is an expected failure, with its reason (:data:`EXPECTED_FAILURES`); they are
strict, so a check that starts to pass fails here and the list stays true. The choices:

- models take the grip table: :class:`ColumnSelector` and :class:`GroupedRanker` read named
  columns of a DataFrame (the ranker also its object column, one query group per object), so a
  check that hands them an array fails at once. What those checks ask is asked on a grip table
  in :func:`test_grip_table_estimators_follow_the_api_on_a_grip_table`.
- a rank baseline scores one column (``-Q_C`` or ``-Q_G``), so it refuses a wider array.
- the chance baselines learn nothing, and score a row by its position (seeded).
- a classifier baseline's ``decision_function`` is its ranking score (``-Q_C``), not a margin
  whose sign is the class: the class comes from the calibrated probability.
- the gradient-boosted trees stop early on a seeded random validation share of the rows, so a
  repeated row is not a weighted one.
- scikit-learn's own estimators keep the registry's settings: 15 neighbours need 15 training
  rows, the MLP's early stopping needs a validation row per class, and ``Pipeline`` fits its
  steps in place (scikit-learn's own test suite expects that failure of ``Pipeline``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
import pytest
from sklearn.base import BaseEstimator, clone
from sklearn.compose import TransformedTargetRegressor
from sklearn.exceptions import NotFittedError
from sklearn.pipeline import Pipeline
from sklearn.utils import get_tags
from sklearn.utils.estimator_checks import parametrize_with_checks

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.learners.models import MODEL_NAMES, REGRESSOR_NAMES, make_model, make_regressor
from classifiers.learners.ranking import make_ranker, relevance

#: Settings that keep the checks fast, by model name (the torch MLP's pass every check so).
FAST: dict[str, dict[str, Any]] = {
    "mlp_torch": {"max_epochs": 10, "learning_rate": 0.03},
    "hgb": {"max_iter": 30},
    "mlp_sklearn": {"max_iter": 50, "hidden_layer_sizes": (16,), "learning_rate_init": 0.03},
}


def _registry_estimators() -> dict[str, BaseEstimator]:
    """``{"task/name": estimator}``: each registry model without its column selection, the
    selection itself, and the lambdarank ranker."""
    found: dict[str, BaseEstimator] = {"column_selector": make_model("logreg")[0]}
    for task, make, names in (("classifier", make_model, MODEL_NAMES),
                              ("regressor", make_regressor, REGRESSOR_NAMES)):
        for name in names:
            rest = make(name, seed=0)[1:]
            fast = FAST.get(name, {})
            if len(rest) == 1:
                found[f"{task}/{name}"] = rest[-1].set_params(**fast)
            else:  # a regressor on a standardised target: its settings are the inner model's
                inner = "regressor__" * isinstance(rest[-1], TransformedTargetRegressor)
                found[f"{task}/{name}"] = rest.set_params(
                    **{f"model__{inner}{key}": value for key, value in fast.items()})
    found["ranker/lambdarank"] = make_ranker("lambdarank", seed=0).set_params(n_estimators=20)
    return found


ESTIMATORS = _registry_estimators()
# rank_qg is rank_qc on another column: the same estimator after the selection
del ESTIMATORS["classifier/rank_qg"], ESTIMATORS["regressor/rank_qg"]

TAKES_THE_GRIP_TABLE = "takes the grip table (a DataFrame with named columns), not an array"
ONE_COLUMN = "a rank baseline scores one column and refuses a wider array"
#: Checks that fit on an array: every one fails for an estimator that takes the grip table.
FITS_AN_ARRAY = (
    "check_complex_data", "check_dict_unchanged", "check_dont_overwrite_parameters",
    "check_dtype_object", "check_estimators_dtypes", "check_estimators_empty_data_messages",
    "check_estimators_fit_returns_self", "check_estimators_nan_inf",
    "check_estimators_overwrite_params", "check_estimators_pickle",
    "check_estimator_sparse_array", "check_estimator_sparse_matrix",
    "check_f_contiguous_array_estimator", "check_fit2d_1feature", "check_fit2d_1sample",
    "check_fit2d_predict1d", "check_fit_check_is_fitted", "check_fit_idempotent",
    "check_fit_score_takes_y", "check_methods_sample_order_invariance",
    "check_methods_subset_invariance", "check_n_features_in", "check_n_features_in_after_fitting",
    "check_pipeline_consistency", "check_positive_only_tag_during_fit",
    "check_readonly_memmap_input",
)
#: Checks that fit on more than one column (a rank baseline's failures).
FITS_COLUMNS = (
    "check_dict_unchanged", "check_dont_overwrite_parameters", "check_dtype_object",
    "check_estimators_dtypes", "check_estimators_fit_returns_self", "check_estimators_nan_inf",
    "check_estimators_overwrite_params", "check_estimators_pickle",
    "check_f_contiguous_array_estimator", "check_fit2d_predict1d", "check_fit_check_is_fitted",
    "check_fit_idempotent", "check_fit_score_takes_y", "check_methods_sample_order_invariance",
    "check_methods_subset_invariance", "check_n_features_in", "check_n_features_in_after_fitting",
    "check_pipeline_consistency", "check_positive_only_tag_during_fit",
    "check_readonly_memmap_input", "check_supervised_y_2d",
)
CHANCE = "the chance baseline learns nothing"
BY_POSITION = "the chance baseline scores a row by its position (seeded), not by its values"
RANK_SCORE = ("decision_function is the ranking score (-Q_C), not a margin whose sign is the "
              "class; predict thresholds the calibrated probability")
PIPELINE_REFITS = "scikit-learn's Pipeline fits the estimators of its steps parameter in place"
PIPELINE_STEPS = {"check_estimators_overwrite_params": PIPELINE_REFITS,
                  "check_dont_overwrite_parameters": PIPELINE_REFITS}
NEIGHBOURS = "15 neighbours need at least 15 training rows"
EARLY_STOPPING = "the MLP's early stopping needs a validation row per class"
EARLY_STOPPING_ROWS = "the MLP's early stopping needs at least two validation rows"
EARLY_STOPPING_SPLIT = ("early stopping holds out a seeded random share of the rows: a repeated "
                        "row is not a weighted one (another split)")

EXPECTED_FAILURES: dict[str, dict[str, str]] = {
    "column_selector": {
        **dict.fromkeys(FITS_AN_ARRAY, TAKES_THE_GRIP_TABLE),
        **dict.fromkeys(("check_estimator_sparse_tag", "check_transformer_data_not_an_array",
                         "check_transformer_general", "check_transformer_preserve_dtypes",
                         "check_transformers_unfitted_stateless"), TAKES_THE_GRIP_TABLE),
    },
    "ranker/lambdarank": dict.fromkeys(FITS_AN_ARRAY, TAKES_THE_GRIP_TABLE),
    "classifier/rank_qc": {
        **dict.fromkeys(FITS_COLUMNS, ONE_COLUMN),
        **dict.fromkeys(("check_classifier_data_not_an_array", "check_classifiers_classes",
                         "check_classifiers_train", "check_decision_proba_consistency"),
                        ONE_COLUMN),
    },
    "classifier/random": {
        "check_classifiers_train": CHANCE,
        "check_classifiers_classes": RANK_SCORE,
        "check_methods_sample_order_invariance": BY_POSITION,
        "check_methods_subset_invariance": BY_POSITION,
    },
    "regressor/rank_qc": {
        **dict.fromkeys(FITS_COLUMNS, ONE_COLUMN),
        **dict.fromkeys(("check_fit2d_1sample", "check_regressor_data_not_an_array",
                         "check_regressors_int",
                         "check_regressors_no_decision_function", "check_regressors_train"),
                        ONE_COLUMN),
    },
    "regressor/random": {
        "check_regressors_train": CHANCE,
        "check_methods_sample_order_invariance": BY_POSITION,
        "check_methods_subset_invariance": BY_POSITION,
    },
    "classifier/svm": PIPELINE_STEPS,
    "classifier/hgb": {"check_sample_weight_equivalence_on_dense_data": EARLY_STOPPING_SPLIT},
    "regressor/hgb": {"check_sample_weight_equivalence_on_dense_data": EARLY_STOPPING_SPLIT},
    "classifier/mlp_sklearn": {
        **PIPELINE_STEPS,
        **dict.fromkeys(("check_estimators_nan_inf", "check_classifiers_one_label",
                         "check_fit2d_1feature"), EARLY_STOPPING),
    },
    "regressor/mlp_sklearn": {
        **PIPELINE_STEPS,
        **dict.fromkeys(("check_estimators_nan_inf", "check_regressors_no_decision_function",
                         "check_fit2d_1feature"), EARLY_STOPPING_ROWS),
    },
    "classifier/knn": {**PIPELINE_STEPS,
                       **dict.fromkeys(("check_classifier_data_not_an_array",
                                        "check_classifiers_one_label"), NEIGHBOURS)},
    "classifier/logreg": PIPELINE_STEPS,
    "regressor/svr": PIPELINE_STEPS,
    "regressor/knn": {**PIPELINE_STEPS, "check_regressor_multioutput": NEIGHBOURS},
    "regressor/ridge": PIPELINE_STEPS,
}
_KEYS = {id(estimator): key for key, estimator in ESTIMATORS.items()}
#: The registry's pipelines of scikit-learn's own estimators (a scaler, then the model): what
#: they check is the composition, and they take longest.
SCIKIT_LEARN_PIPELINES = [estimator for estimator in ESTIMATORS.values()
                          if isinstance(estimator, Pipeline)]


def _expected_failures(estimator: BaseEstimator) -> dict[str, str]:
    return EXPECTED_FAILURES.get(_KEYS[id(estimator)], {})


@parametrize_with_checks([estimator for estimator in ESTIMATORS.values()
                          if not isinstance(estimator, Pipeline)],
                         expected_failed_checks=_expected_failures, xfail_strict=True)
def test_learners_pass_scikit_learn_estimator_checks(estimator, check):
    check(estimator)


@pytest.mark.slow
@parametrize_with_checks(SCIKIT_LEARN_PIPELINES, expected_failed_checks=_expected_failures,
                         xfail_strict=True)
def test_registry_pipelines_pass_scikit_learn_estimator_checks(estimator, check):
    check(estimator)


def test_every_expected_failure_names_an_estimator_here():
    assert set(EXPECTED_FAILURES) <= set(ESTIMATORS)


# ----------------------------------------------------------------------------- on a grip table
@pytest.fixture(scope="module")
def grips() -> pd.DataFrame:
    return synthetic_grips(n_objects=8, grips=(10, 20), seed=5)


def _grip_table_cases(grips: pd.DataFrame) -> dict[str, tuple[BaseEstimator, np.ndarray]]:
    """The estimators that take the grip table, each with a target for it."""
    return {
        "column_selector": (make_model("logreg")[0], grips["success"].to_numpy()),
        "ranker/lambdarank": (ESTIMATORS["ranker/lambdarank"], relevance(grips)),
        "classifier/hgb pipeline": (make_model("hgb").set_params(model__max_iter=10),
                                    grips["success"].to_numpy()),
        "regressor/rank_qg pipeline": (make_regressor("rank_qg"),
                                       grips["robustness_mean"].to_numpy()),
    }


@pytest.mark.parametrize("case", ["column_selector", "ranker/lambdarank",
                                  "classifier/hgb pipeline", "regressor/rank_qg pipeline"])
def test_grip_table_estimators_follow_the_api_on_a_grip_table(grips, case):
    """What the array checks ask of an estimator, asked on a grip table: fit returns the
    estimator, leaves its parameters alone and is repeatable; a clone is unfitted; a fitted
    estimator refuses an array; the output follows the rows."""
    estimator, target = _grip_table_cases(grips)[case]
    estimator = clone(estimator)
    before = repr(estimator.get_params(deep=False))
    assert estimator.fit(grips, target) is estimator
    assert repr(estimator.get_params(deep=False)) == before
    out = _output(estimator, grips)
    np.testing.assert_array_equal(_output(clone(estimator).fit(grips, target), grips), out)
    np.testing.assert_array_equal(_output(estimator, grips.iloc[::-1]), out[::-1])
    if get_tags(estimator).requires_fit:
        with pytest.raises(NotFittedError):
            _output(clone(estimator), grips)
    with pytest.raises(ValueError, match="DataFrame"):
        _output(estimator, grips.to_numpy())


def _output(estimator: BaseEstimator, table: Any) -> np.ndarray:
    method = next(getattr(estimator, name) for name in ("predict", "transform")
                  if hasattr(estimator, name))
    return np.asarray(method(table))


def test_the_svm_fits_its_probabilities_on_as_few_grips_of_a_class_as_it_can():
    from classifiers.learners.svm import PlattSVC

    rng = np.random.default_rng(0)
    X = rng.normal(size=(40, 3))
    y = np.r_[np.ones(3, bool), np.zeros(37, bool)]  # 3 positives: fewer than 5 folds
    model = PlattSVC(random_state=0).fit(X, y)
    assert model.folds_ == 3 and model.predict_proba(X).shape == (40, 2)
    assert PlattSVC(random_state=0).fit(X, ~y).folds_ == 3
    assert PlattSVC(random_state=0).fit(np.r_[X, X], np.r_[y, y]).folds_ == 5
    with pytest.raises(ValueError, match="at least 2 training grips of each class, got 1"):
        PlattSVC().fit(X, np.r_[True, np.zeros(39, bool)])


def test_kernel_learners_fit_a_stated_seeded_sample_of_a_large_training_set():
    from classifiers.learners.svm import PlattSVC, SampledSVR, kernel_sample

    rng = np.random.default_rng(0)
    X = rng.normal(size=(300, 3))
    y = X[:, 0] + 0.3 * rng.normal(size=300) > 0.8  # about a fifth positive
    small = PlattSVC(max_grips=None, random_state=0).fit(X, y)
    assert small.n_fit_grips_ == 300
    sampled = PlattSVC(max_grips=100, random_state=0).fit(X, y)
    assert sampled.n_fit_grips_ == 100
    rows = kernel_sample(y, 100, 0, stratify=True)
    assert abs(y[rows].mean() - y.mean()) < 0.01  # each class its share
    assert np.array_equal(rows, kernel_sample(y, 100, 0, stratify=True))  # seeded
    assert not np.array_equal(rows, kernel_sample(y, 100, 1, stratify=True))
    svr = SampledSVR(max_grips=50, random_state=0).fit(X, X[:, 0])
    assert svr.n_fit_grips_ == 50 and svr.predict(X).shape == (300,)
    assert np.corrcoef(svr.predict(X), X[:, 0])[0, 1] > 0.9
    with pytest.raises(ValueError, match="max_grips must be at least 2"):
        PlattSVC(max_grips=1).fit(X, y)


def test_a_sampled_fit_is_named_with_its_grip_count():
    from classifiers.experiments.training import sampled_fit
    from classifiers.learners.models import make_regressor
    from grip_env.columns import FEATURES

    rng = np.random.default_rng(1)
    table = pd.DataFrame(rng.normal(size=(120, len(FEATURES))), columns=list(FEATURES))
    model = make_regressor("svr", 0).set_params(model__max_grips=50)
    model.fit(table, table["S1"].to_numpy())
    assert sampled_fit("svr", model, 120) == {"svr": 50}
    whole = make_regressor("ridge", 0).fit(table, table["S1"].to_numpy())
    assert sampled_fit("ridge", whole, 120) == {}
