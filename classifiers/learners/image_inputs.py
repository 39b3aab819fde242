"""The first step of an image model: the grip table → one flat row per grip (image, measures).

:class:`ImageInputs` renders each grip's image with its ``images`` transformer (a
:class:`~classifiers.learners.grip_images.GripImages`, or anything that maps a grip table to a float
array of shape ``(n, C, H, W)``), flattens it, and appends the table's ``measures`` columns: the
row :class:`~classifiers.learners.cnn.CNNClassifier` reads. It plays the part the
:class:`~classifiers.learners.baselines.ColumnSelector` plays for the feature learners: a model
takes the grip table and picks its own inputs.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, TransformerMixin, clone
from sklearn.utils.validation import check_is_fitted

from classifiers.learners.baselines import ColumnSelector


def default_images() -> BaseEstimator:
    """The grip images of the registry's image models, at their default settings."""
    from classifiers.learners.grip_images import GripImages

    return GripImages()


def image_shape(images: BaseEstimator) -> tuple[int, int, int]:
    """(channels, height, width) of the images a ``GripImages`` draws, from its settings."""
    size = int(images.size_px)
    return len(tuple(images.channels)), size, size


class ImageInputs(TransformerMixin, BaseEstimator):
    """Grip table → ``(n, C·H·W + len(measures))`` float32: each grip's image, flattened, then
    its ``measures`` columns.

    Parameters
    ----------
    images : transformer of the grip table to images ``(n, C, H, W)``; None: the default
        :class:`~classifiers.learners.grip_images.GripImages`.
    measures : table columns appended after the image (none: the image alone).

    Attributes
    ----------
    images_ : the fitted image transformer.
    image_shape_ : (C, H, W) of the images seen in ``fit``; ``transform`` refuses another.
    n_features_out_ : int, columns of the output.
    """

    def __init__(self, images: BaseEstimator | None = None, measures: Sequence[str] = ()):
        self.images = images
        self.measures = measures

    def fit(self, X: pd.DataFrame, y: Any = None) -> ImageInputs:
        """Fit the image transformer on ``X`` and record the image shape."""
        _check_table(X)
        images = default_images() if self.images is None else clone(self.images)
        self.images_ = images.fit(X, y)
        self.image_shape_ = tuple(int(s) for s in self._images(X).shape[1:])
        self.n_features_out_ = int(np.prod(self.image_shape_)) + len(tuple(self.measures))
        return self

    def transform(self, X: pd.DataFrame) -> np.ndarray:
        """Each grip's flat image and measures, float32."""
        check_is_fitted(self, "images_")
        _check_table(X)
        images = self._images(X)
        if tuple(images.shape[1:]) != self.image_shape_:
            raise ValueError(f"the model was fitted on images of shape {self.image_shape_} "
                             f"(channels, height, width), this table gives "
                             f"{tuple(images.shape[1:])}")  # fmt: skip
        flat = images.reshape(len(images), -1).astype(np.float32, copy=False)
        if not tuple(self.measures):
            return flat
        measures = ColumnSelector(tuple(self.measures)).transform(X).astype(np.float32)
        return np.hstack([flat, measures])

    def settings(self) -> dict[str, Any]:
        """JSON-able settings that rebuild the fitted step (:meth:`from_settings`): the image
        transformer's class and parameters, the measures, the image shape."""
        check_is_fitted(self, "images_")
        kind = type(self.images_)
        params = self.images_.get_params(deep=False)
        plain = {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}
        return {"images": f"{kind.__module__}.{kind.__qualname__}", "params": plain,
                "measures": list(self.measures), "image_shape": list(self.image_shape_)}

    @classmethod
    def from_settings(cls, settings: dict[str, Any]) -> ImageInputs:
        """The fitted step :meth:`settings` describes; only the default image transformer's
        class is rebuilt (a saved file names no other code to run)."""
        kind = type(default_images())
        if settings.get("images") != f"{kind.__module__}.{kind.__qualname__}":
            raise ValueError(f"a saved image model names the image transformer "
                             f"{settings.get('images')!r}; only "
                             f"{kind.__module__}.{kind.__qualname__} is loaded")  # fmt: skip
        params = {k: tuple(v) if isinstance(v, list) else v
                  for k, v in dict(settings["params"]).items()}  # fmt: skip
        step = cls(kind(**params), tuple(settings["measures"]))
        step.images_ = kind(**params)
        step.image_shape_ = tuple(int(s) for s in settings["image_shape"])
        step.n_features_out_ = int(np.prod(step.image_shape_)) + len(step.measures)
        return step

    def _images(self, X: pd.DataFrame) -> np.ndarray:
        images = np.asarray(self.images_.transform(X))
        if images.ndim != 4 or len(images) != len(X):
            raise ValueError(f"the image transformer must give ({len(X)}, C, H, W), gave "
                             f"{images.shape}")  # fmt: skip
        if not np.all(np.isfinite(images)):
            raise ValueError("the grip images hold NaN or infinite values")
        return images


def _check_table(X: Any) -> None:
    if not isinstance(X, pd.DataFrame):
        raise ValueError(f"models take the grip table as a DataFrame, got {type(X).__name__}")
