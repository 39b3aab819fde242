"""A convolutional evaluator of grips (PyTorch, CPU) with the scikit-learn estimator API.

The network reads one flat row per grip: the grip's image (``image_shape`` = channels, height,
width, flattened in C order) and, after it, ``n_measures`` numbers (the twelve measures for
``cnn_measures``, none for ``cnn``). The image goes through a small convolutional trunk (3×3
convolutions of stride 2, ReLU), is pooled to a fixed ``pooled × pooled`` grid and flattened; the
measures are concatenated after it, and a fully connected head gives the output, as GQ-CNN joins
its depth-image stream and its gripper-depth input. Every input column is standardised inside the
network (mean and scale are buffers of the ``state_dict``, as in
:mod:`classifiers.learners.torch_mlp`, whose training loop, early stopping, seeding and
single-threaded fitting this reuses).

With ``image_shape=None`` the row is read as a one-channel, one-pixel-high image of its columns
(and the measures after them): what scikit-learn's estimator checks feed it. The grip table is
turned into the flat row by :class:`classifiers.learners.image_inputs.ImageInputs`, the first step
of the registry's ``cnn`` and ``cnn_measures`` pipelines (:mod:`classifiers.learners.models`).
"""

from __future__ import annotations

import copy
from numbers import Integral
from typing import Any, ClassVar

import numpy as np
import torch
from sklearn.utils.validation import check_is_fitted, validate_data
from torch import nn

from classifiers.learners.torch_mlp import (
    TorchMLPClassifier,
    TorchMLPRegressor,
    _Network,
    _Range,
    _single_thread,
    _TorchMLP,
)

#: The trunk's default widths (output channels of each stride-2 convolution), head and grid.
CONV_CHANNELS = (8, 16, 32)
HEAD_SIZES = (64,)
POOLED = 4


class ImageNetwork(nn.Module):
    """Convolutions on the image part of a flat row, its measures joined before the head."""

    def __init__(self, image_shape: tuple[int, int, int], n_measures: int,
                 channels: tuple[int, ...], hidden: tuple[int, ...], n_outputs: int,
                 dropout: float, pooled: int) -> None:  # fmt: skip
        super().__init__()
        n_inputs = int(np.prod(image_shape)) + n_measures
        self.image_shape = tuple(int(size) for size in image_shape)
        self.register_buffer("mean", torch.zeros(n_inputs))
        self.register_buffer("scale", torch.ones(n_inputs))
        layers: list[nn.Module] = []
        width = self.image_shape[0]
        for size in channels:
            layers += [nn.Conv2d(width, size, 3, stride=2, padding=1), nn.ReLU()]
            width = size
        self.trunk = nn.Sequential(*layers, nn.AdaptiveAvgPool2d(pooled), nn.Flatten())
        self.head = _Network(width * pooled * pooled + n_measures, hidden, n_outputs, dropout)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = (x - self.mean) / self.scale
        pixels = int(np.prod(self.image_shape))
        image = x[:, :pixels].reshape(-1, *self.image_shape)
        return self.head(torch.cat([self.trunk(image), x[:, pixels:]], dim=1))


def _shape_ok(shape: Any) -> bool:
    """None, or three whole sizes, each at least 1."""
    if shape is None:
        return True
    return (isinstance(shape, (tuple, list)) and len(shape) == 3
            and all(isinstance(s, Integral) and not isinstance(s, bool) and s >= 1
                    for s in shape))  # fmt: skip


class _ConvNet(_TorchMLP):
    """What the convolutional classifier and regressor add to the torch MLP's base.

    Parameters
    ----------
    image_shape : (channels, height, width) of the image part of a row, or None (the row's
        columns before the measures as a 1 × 1 × n image).
    n_measures : columns after the image, joined after the convolutional trunk.
    conv_channels : output channels of each 3×3, stride-2 convolution (each >= 1).
    hidden_layer_sizes : widths of the head's hidden ReLU layers.
    pooled : side of the grid the trunk's output is average-pooled to.
    learning_rate, weight_decay, dropout, batch_size, max_epochs, validation_fraction,
    patience, random_state : as :class:`~classifiers.learners.torch_mlp.TorchMLPClassifier`.
    """

    _parameter_ranges: ClassVar[dict[str, _Range]] = {
        **_TorchMLP._parameter_ranges,
        "n_measures": _Range(Integral, 0),
        "pooled": _Range(Integral, 1),
    }

    def __init__(
        self,
        image_shape: tuple[int, int, int] | None = None,
        *,
        n_measures: int = 0,
        conv_channels: tuple[int, ...] = CONV_CHANNELS,
        hidden_layer_sizes: tuple[int, ...] = HEAD_SIZES,
        pooled: int = POOLED,
        learning_rate: float = 1e-3,
        weight_decay: float = 1e-4,
        dropout: float = 0.0,
        batch_size: int = 256,
        max_epochs: int = 30,
        validation_fraction: float = 0.15,
        patience: int = 5,
        random_state: int | None = None,
    ):
        super().__init__(hidden_layer_sizes, learning_rate=learning_rate,
                         weight_decay=weight_decay, dropout=dropout, batch_size=batch_size,
                         max_epochs=max_epochs, validation_fraction=validation_fraction,
                         patience=patience, random_state=random_state)  # fmt: skip
        self.image_shape = image_shape
        self.n_measures = n_measures
        self.conv_channels = conv_channels
        self.pooled = pooled

    def _check_parameters(self) -> None:
        super()._check_parameters()
        name = type(self).__name__
        if not _shape_ok(self.image_shape):
            raise ValueError(f"The 'image_shape' parameter of {name} must be None or three "
                             f"whole sizes >= 1 (channels, height, width). Got "
                             f"{self.image_shape!r} instead.")  # fmt: skip
        from classifiers.learners.torch_mlp import _hidden_sizes_ok

        if not _hidden_sizes_ok(self.conv_channels) or not len(self.conv_channels):
            raise ValueError(f"The 'conv_channels' parameter of {name} must be a non-empty "
                             f"sequence of whole widths >= 1. Got {self.conv_channels!r} "
                             f"instead.")  # fmt: skip

    def input_shape(self, n_inputs: int) -> tuple[int, int, int]:
        """The image shape a row of ``n_inputs`` columns holds; ValueError when they differ."""
        pixels = n_inputs - int(self.n_measures)
        shape = (1, 1, pixels) if self.image_shape is None else tuple(self.image_shape)
        if pixels < 1 or int(np.prod(shape)) != pixels:
            raise ValueError(f"{type(self).__name__} reads images of shape {shape} and "
                             f"{self.n_measures} measures ({int(np.prod(shape))} + "
                             f"{self.n_measures} columns), got rows of n_features={n_inputs}")
        return shape  # type: ignore[return-value]

    def _build(self, n_inputs: int, n_outputs: int) -> ImageNetwork:  # type: ignore[override]
        return ImageNetwork(self.input_shape(n_inputs), int(self.n_measures),
                            tuple(int(c) for c in self.conv_channels),
                            tuple(int(h) for h in self.hidden_layer_sizes), n_outputs,
                            float(self.dropout), int(self.pooled))  # fmt: skip

    def _outputs(self, X: Any) -> torch.Tensor:
        """The network's outputs, computed in float64: a float32 convolution's result depends
        on how many rows it is given at once (its blocking), float64's agrees to 1e-12, so a
        grip's score does not depend on the other grips of the call."""
        check_is_fitted(self, "network_")
        X = validate_data(self, X, dtype=np.float64, reset=False)
        network = copy.deepcopy(self.network_).double().eval()
        with _single_thread(), torch.no_grad():
            return network(torch.from_numpy(X))

    @classmethod
    def _rebuilt(cls, params: dict[str, Any], metadata: dict[str, Any], n_outputs: int,
                 state: dict[str, torch.Tensor]) -> Any:
        shape = params.get("image_shape")
        params = {**params, "conv_channels": tuple(params["conv_channels"]),
                  "image_shape": None if shape is None else tuple(shape)}  # fmt: skip
        return super()._rebuilt(params, metadata, n_outputs, state)


class CNNClassifier(_ConvNet, TorchMLPClassifier):
    """Convolutional classifier of grips (PyTorch, CPU): cross-entropy, stratified early
    stopping; parameters as :class:`_ConvNet`, ``image_shape`` the one positional one.

    Attributes
    ----------
    ``classes_`` : ndarray of shape (n_classes,), the labels seen in ``fit``.
    ``n_features_in_`` : int, columns seen in ``fit`` (the image's pixels and the measures).
    ``network_`` : torch.nn.Module, the fitted :class:`ImageNetwork`.
    ``n_epochs_`` : int, epochs run (early stopping may end before ``max_epochs``).
    ``best_validation_loss_`` : float, lowest validation loss.
    """

    def decision_function(self, X: Any) -> np.ndarray:
        """The log-odds of the last class (the positive one of two): a ranking score."""
        logits = self._outputs(X)
        if logits.shape[1] == 2:
            return (logits[:, 1] - logits[:, 0]).numpy().astype(np.float64)
        return logits.numpy().astype(np.float64)


class CNNRegressor(_ConvNet, TorchMLPRegressor):
    """Convolutional regressor of grips (PyTorch, CPU): squared error of the standardised
    target; parameters as :class:`_ConvNet`.

    Attributes
    ----------
    ``n_features_in_`` : int, columns seen in ``fit``.
    ``network_`` : torch.nn.Module, the fitted :class:`ImageNetwork`.
    ``n_epochs_`` : int, epochs run.
    ``best_validation_loss_`` : float, lowest validation loss.
    ``target_mean_``, ``target_scale_`` : float, the target's standardisation.
    """
