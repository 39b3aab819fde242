"""The model registry: ``make_model(name, seed, features)`` → a scikit-learn ``Pipeline``.

Each pipeline starts with a :class:`~classifiers.learners.baselines.ColumnSelector` (models take
the grip
table and pick their columns) and ends with a step named ``"model"``, so hyper-parameters are set
as ``pipeline.set_params(model__C=...)``. The baselines ignore ``features``: ``rank_qc`` reads
``Q_C``, ``rank_qg`` reads ``Q_G`` and ``random`` reads nothing but the row count.

"svm" is an RBF ``SVC`` with Platt (sigmoid) probabilities fitted by internal CV of at most 5
folds, fewer when a class has fewer training grips (:class:`~classifiers.learners.svm.PlattSVC`,
wrapping ``CalibratedClassifierCV(SVC(), ensemble=False)``, the replacement scikit-learn 1.9 gives
for the deprecated ``SVC(probability=True)``). It and "svr" are fitted on a seeded sample of at
most 4,000 grips (:data:`~classifiers.learners.svm.MAX_KERNEL_GRIPS`): a kernel machine's cost
grows with the square of its grips, so on the standard dataset they are stated subsamples.

"hgb" is scikit-learn's ``HistGradientBoostingClassifier`` (gradient-boosted trees, the usual
strongest learner on small tabular data) on the raw features (trees need no scaling), with
early stopping on a seeded 15 % validation split of the training grips: the seed changes which
grips stop the boosting, so "hgb" is a stochastic learner whose seeds give different models. It
runs on one thread (:class:`~classifiers.learners.threads.OneThreadHGBClassifier`, 13x faster here).

"cnn" and "cnn_measures" (:data:`IMAGE_MODELS`, in both registries but not in
:data:`MODEL_NAMES`, whose learners read the measures alone) are the image models: each grip's
image (:class:`~classifiers.learners.image_inputs.ImageInputs` and its ``GripImages``; the table
must carry the grips' contours) through a small convolutional network
(:mod:`classifiers.learners.cnn`), with, for "cnn_measures", the features joined after its
convolutional trunk.

``make_regressor(name, seed, features)`` is the same for the regression task (predicting a grip's
``robustness_mean``): "svr" (RBF ``SVR`` on standardised features,
:class:`~classifiers.learners.svm.SampledSVR`), "mlp_torch"
(:class:`~classifiers.learners.torch_mlp.TorchMLPRegressor`), "mlp_sklearn" (scikit-learn's
``MLPRegressor``, the classifier's architecture, on the standardised target: on grams, with a
spread of 34 g, Adam took 225-273 epochs and 11-13 s to stop on the standard dataset's training
grips, on the standardised target 83-135 epochs and 5-7 s for the same Spearman), "knn",
"ridge", "hgb" (``HistGradientBoostingRegressor``, squared error, early stopping as the
classifier's), and the rank baselines "rank_qc", "rank_qg" and "random"
(:class:`~classifiers.learners.baselines.RankingRegressor`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from sklearn.base import BaseEstimator
from sklearn.compose import TransformedTargetRegressor
from sklearn.linear_model import LogisticRegression, Ridge
from sklearn.neighbors import KNeighborsClassifier, KNeighborsRegressor
from sklearn.neural_network import MLPClassifier, MLPRegressor
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler

from classifiers.learners.baselines import (
    ColumnSelector,
    RandomClassifier,
    RandomRegressor,
    RankingClassifier,
    RankingRegressor,
)
from classifiers.learners.cnn import CNNClassifier, CNNRegressor
from classifiers.learners.image_inputs import ImageInputs, default_images, image_shape
from classifiers.learners.svm import PlattSVC, SampledSVR
from classifiers.learners.threads import OneThreadHGBClassifier, OneThreadHGBRegressor
from classifiers.learners.torch_mlp import TorchMLPClassifier, TorchMLPRegressor
from grip_env.columns import FEATURES

EXTRA_FEATURES = ("eps",)
BASELINES = ("rank_qc", "rank_qg", "random")


#: Shared settings of the gradient-boosted trees (classifier and regressor): small leaves and
#: early stopping suit a few thousand grips; nothing here was tuned on the study's data.
HGB_SETTINGS: dict[str, object] = {
    "learning_rate": 0.05, "max_iter": 300, "max_leaf_nodes": 15, "min_samples_leaf": 20,
    "l2_regularization": 1.0, "early_stopping": True, "validation_fraction": 0.15,
    "n_iter_no_change": 20,
}  # fmt: skip


def _scaled(estimator: BaseEstimator) -> list[tuple[str, BaseEstimator]]:
    return [("scale", StandardScaler()), ("model", estimator)]


#: The steps after the column selection, for a seed.
Steps = Callable[[int], list[tuple[str, BaseEstimator]]]
#: A registry entry: the columns the model reads (None: the features it is given), its steps.
Entry = tuple[tuple[str, ...] | None, Steps]


def _rank_baselines(ranking: type[BaseEstimator], chance: type[BaseEstimator]) -> dict[str, Entry]:
    """One task's :data:`BASELINES`: ``ranking`` (a ``RankingClassifier`` or
    ``RankingRegressor``) scores -Q_C or -Q_G, ``chance`` a seeded random score."""
    return {
        "rank_qc": (("Q_C",), lambda seed: [("model", ranking(sign=-1.0))]),
        "rank_qg": (("Q_G",), lambda seed: [("model", ranking(sign=-1.0))]),
        "random": (("Q_C",), lambda seed: [("model", chance(random_state=seed))]),
    }


_CLASSIFIERS: dict[str, Entry] = {
    "svm": (None, lambda seed: _scaled(
        PlattSVC(random_state=seed)
    )),
    "mlp_torch": (None, lambda seed: [("model", TorchMLPClassifier(random_state=seed))]),
    "mlp_sklearn": (None, lambda seed: _scaled(
        MLPClassifier((64, 64), early_stopping=True, max_iter=500, random_state=seed)
    )),
    "knn": (None, lambda seed: _scaled(KNeighborsClassifier(n_neighbors=15, weights="distance"))),
    "logreg": (None, lambda seed: _scaled(LogisticRegression(max_iter=1000))),
    "hgb": (None, lambda seed: [("model", OneThreadHGBClassifier(**HGB_SETTINGS,
                                                                 random_state=seed))]),
    **_rank_baselines(RankingClassifier, RandomClassifier),
}
MODEL_NAMES = tuple(_CLASSIFIERS)

_REGRESSORS: dict[str, Entry] = {
    "svr": (None, lambda seed: _scaled(SampledSVR(C=1.0, epsilon=0.1, random_state=seed))),
    "mlp_torch": (None, lambda seed: [("model", TorchMLPRegressor(random_state=seed))]),
    "mlp_sklearn": (None, lambda seed: _scaled(TransformedTargetRegressor(
        MLPRegressor(hidden_layer_sizes=(64, 64), early_stopping=True, max_iter=500,
                     random_state=seed), transformer=StandardScaler(),
    ))),
    "knn": (None, lambda seed: _scaled(KNeighborsRegressor(n_neighbors=15, weights="distance"))),
    "ridge": (None, lambda seed: _scaled(Ridge(alpha=1.0))),
    "hgb": (None, lambda seed: [("model", OneThreadHGBRegressor(**HGB_SETTINGS,
                                                                random_state=seed))]),
    **_rank_baselines(RankingRegressor, RandomRegressor),
}
REGRESSOR_NAMES = tuple(_REGRESSORS)


#: The image models (:mod:`classifiers.learners.cnn`): name → whether the twelve measures (or the
#: features given) are joined to the image. Registered for both tasks, not in MODEL_NAMES.
IMAGE_MODELS = {"cnn": False, "cnn_measures": True}
IMAGE_MODEL_NAMES = tuple(IMAGE_MODELS)


def _image_pipeline(name: str, seed: int, features: tuple[str, ...], regressor: bool) -> Pipeline:
    """The grip images (and the measures, for ``cnn_measures``), then the convolutional net."""
    measures = features if IMAGE_MODELS[name] else ()
    images = default_images()
    network = (CNNRegressor if regressor else CNNClassifier)(
        image_shape(images), n_measures=len(measures), random_state=seed)
    return Pipeline([("select", ImageInputs(images, measures)), ("model", network)])


def _pipeline(registry: dict[str, Entry], kind: str, name: str, seed: int,
              features: Sequence[str]) -> Pipeline:
    """``registry[name]``'s pipeline: its column selection, then its steps for ``seed``."""
    features = check_features(features)
    if name in IMAGE_MODELS:
        return _image_pipeline(name, seed, features, registry is _REGRESSORS)
    if name not in registry:
        raise ValueError(f"unknown {kind} name {name!r}; known: "
                         f"{[*registry, *IMAGE_MODEL_NAMES]}")
    columns, steps = registry[name]
    return Pipeline([("select", ColumnSelector(columns or features)), *steps(seed)])


def check_features(features: Sequence[str]) -> tuple[str, ...]:
    """The feature list as a tuple; unknown names, duplicates or an empty list → ValueError."""
    features = tuple(features)
    allowed = FEATURES + EXTRA_FEATURES
    unknown = [name for name in features if name not in allowed]
    if unknown:
        raise ValueError(f"unknown feature names {unknown}; known: {list(allowed)}")
    if not features or len(set(features)) != len(features):
        raise ValueError(f"feature list must be non-empty without duplicates, got {list(features)}")
    return features


def make_model(name: str, seed: int = 0, features: Sequence[str] = FEATURES) -> Pipeline:
    """A fresh, unfitted model pipeline; unknown ``name`` → ValueError listing the known ones."""
    return _pipeline(_CLASSIFIERS, "model", name, seed, features)


def make_models(
    names: Sequence[str], seed: int = 0, features: Sequence[str] = FEATURES
) -> dict[str, Pipeline]:
    """``{name: make_model(name, seed, features)}`` for each name."""
    if not names:
        raise ValueError("no model names given")
    return {name: make_model(name, seed, features) for name in names}


def make_regressor(name: str, seed: int = 0, features: Sequence[str] = FEATURES) -> Pipeline:
    """A fresh, unfitted regression pipeline; unknown ``name`` → ValueError listing the known."""
    return _pipeline(_REGRESSORS, "regressor", name, seed, features)
