"""Multilayer perceptrons in PyTorch with the scikit-learn estimator API: classifier, regressor.

CPU only and single-threaded while fitting and predicting (for networks this small, intra-op
threads cost far more than they save: 0.6 s vs 19 s for one fit measured on two busy cores),
seeded, inputs standardised inside the network (mean and scale are buffers of the
``state_dict``), Adam, early stopping on a validation split. The classifier minimises
cross-entropy over the classes (stratified split); the regressor minimises the squared error of
the standardised target (random split; target mean and scale are fitted metadata).
``state_dict()`` / ``from_state_dict()`` give a pickle-free save format.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any, ClassVar

import numpy as np
import torch
from sklearn.base import BaseEstimator, ClassifierMixin, RegressorMixin
from sklearn.model_selection import train_test_split
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data
from torch import nn


class _Network(nn.Module):
    def __init__(self, n_inputs: int, hidden: tuple[int, ...], n_outputs: int, dropout: float):
        super().__init__()
        self.register_buffer("mean", torch.zeros(n_inputs))
        self.register_buffer("scale", torch.ones(n_inputs))
        layers: list[nn.Module] = []
        width = n_inputs
        for size in hidden:
            layers += [nn.Linear(width, size), nn.ReLU(), nn.Dropout(dropout)]
            width = size
        layers.append(nn.Linear(width, n_outputs))
        self.layers = nn.Sequential(*layers)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.layers((x - self.mean) / self.scale)


@dataclass(frozen=True)
class _Range:
    """What a numeric parameter may be: an int or a float (``kind``) from ``low`` to ``high``
    (None: unbounded), each end included or not, and perhaps None."""

    kind: type[Integral] | type[Real]
    low: float | None = None
    high: float | None = None
    low_included: bool = True
    high_included: bool = False
    or_none: bool = False

    def admits(self, value: Any) -> bool:
        if value is None:
            return self.or_none
        if isinstance(value, bool) or not isinstance(value, self.kind):
            return False
        above = self.low is None or value > self.low or (self.low_included and value == self.low)
        below = (self.high is None or value < self.high
                 or (self.high_included and value == self.high))
        return bool(above and below)

    def __str__(self) -> str:
        kind = "an int" if self.kind is Integral else "a float"
        low = f"{'[' if self.low_included else '('}{'-inf' if self.low is None else self.low}"
        high = f"{'inf' if self.high is None else self.high}{']' if self.high_included else ')'}"
        return f"{kind} in the range {low}, {high}{' or None' if self.or_none else ''}"


def _hidden_sizes_ok(sizes: Any) -> bool:
    """A sequence (list, tuple, array) of whole widths, each at least 1."""
    if isinstance(sizes, str) or not isinstance(sizes, (Sequence, np.ndarray)):
        return False
    return all(isinstance(size, Real) and not isinstance(size, bool) and size == int(size) >= 1
               for size in sizes)


class _TorchMLP(BaseEstimator):
    """What the classifier and the regressor share: parameters, network, training loop.

    Parameters
    ----------
    hidden_layer_sizes : widths of the hidden ReLU layers (each >= 1; the one positional
        parameter, every other one is keyword-only).
    learning_rate : Adam step size.
    weight_decay : Adam L2 penalty.
    dropout : dropout after each hidden layer.
    batch_size : minibatch size.
    max_epochs : upper bound on training epochs.
    validation_fraction : share of the training rows held out for early stopping; 0 disables
        early stopping, and so does a split too small to be useful.
    patience : epochs without validation-loss improvement before stopping.
    random_state : seed of weights, shuffling and the validation split.

    Every parameter is checked against :attr:`_parameter_ranges` when ``fit`` starts (a
    ``ValueError`` naming the parameter, its range and the value, in scikit-learn's words).
    """

    _parameter_ranges: ClassVar[dict[str, _Range]] = {
        "learning_rate": _Range(Real, 0.0, low_included=False),
        "weight_decay": _Range(Real, 0.0),
        "dropout": _Range(Real, 0.0, 1.0),
        "batch_size": _Range(Integral, 1),
        "max_epochs": _Range(Integral, 1),
        "validation_fraction": _Range(Real, 0.0, 1.0),
        "patience": _Range(Integral, 1),
        "random_state": _Range(Integral, 0, or_none=True),
    }

    def __init__(
        self,
        hidden_layer_sizes: tuple[int, ...] = (64, 64),
        *,
        learning_rate: float = 1e-3,
        weight_decay: float = 1e-4,
        dropout: float = 0.0,
        batch_size: int = 128,
        max_epochs: int = 200,
        validation_fraction: float = 0.15,
        patience: int = 15,
        random_state: int | None = None,
    ):
        self.hidden_layer_sizes = hidden_layer_sizes
        self.learning_rate = learning_rate
        self.weight_decay = weight_decay
        self.dropout = dropout
        self.batch_size = batch_size
        self.max_epochs = max_epochs
        self.validation_fraction = validation_fraction
        self.patience = patience
        self.random_state = random_state

    def state_dict(self) -> dict[str, torch.Tensor]:
        """The fitted network's tensors (weights and input standardisation)."""
        check_is_fitted(self, "network_")
        return self.network_.state_dict()

    def _check_parameters(self) -> None:
        """Refuse a parameter outside its range, as scikit-learn's own estimators do in ``fit``."""
        name = type(self).__name__
        if not _hidden_sizes_ok(self.hidden_layer_sizes):
            raise ValueError(f"The 'hidden_layer_sizes' parameter of {name} must be a sequence of "
                             f"whole widths >= 1. Got {self.hidden_layer_sizes!r} instead.")
        for key, allowed in self._parameter_ranges.items():
            value = getattr(self, key)
            if not allowed.admits(value):
                raise ValueError(f"The {key!r} parameter of {name} must be {allowed}. "
                                 f"Got {value!r} instead.")

    def _fit_network(self, X: np.ndarray, targets: torch.Tensor, n_outputs: int,
                     stratify: np.ndarray | None, loss_fn: nn.Module) -> None:
        seed = _seed(self.random_state)
        with _single_thread():
            torch.manual_seed(seed)
            self.network_ = self._build(X.shape[1], n_outputs)
            self.network_.mean.copy_(torch.from_numpy(X.mean(axis=0)))
            spread = X.std(axis=0)
            self.network_.scale.copy_(torch.from_numpy(np.where(spread > 1e-12, spread, 1.0)))
            train_idx, valid_idx = self._split(len(X), stratify, seed)
            self.n_epochs_, self.best_validation_loss_ = self._train(
                torch.tensor(X), targets, train_idx, valid_idx, seed, loss_fn
            )

    def _outputs(self, X: Any) -> torch.Tensor:
        check_is_fitted(self, "network_")
        X = validate_data(self, X, dtype=np.float32, reset=False)
        self.network_.eval()
        with _single_thread(), torch.no_grad():
            return self.network_(torch.tensor(X))

    def _build(self, n_inputs: int, n_outputs: int) -> _Network:
        if any(int(size) < 1 for size in self.hidden_layer_sizes):
            raise ValueError(f"hidden_layer_sizes must be positive, got {self.hidden_layer_sizes}")
        hidden = tuple(int(size) for size in self.hidden_layer_sizes)
        return _Network(n_inputs, hidden, n_outputs, self.dropout)

    def _split(self, n_rows: int, stratify: np.ndarray | None,
               seed: int) -> tuple[np.ndarray, np.ndarray]:
        rows = np.arange(n_rows)
        n_valid = round(self.validation_fraction * n_rows)
        if stratify is None:
            if n_valid < 2 or n_rows - n_valid < 2:
                return rows, rows[:0]
            return train_test_split(rows, test_size=n_valid, random_state=seed)
        n_classes = int(stratify.max()) + 1
        smallest = np.bincount(stratify).min()
        if n_valid < n_classes or n_rows - n_valid < n_classes or smallest < 2:
            return rows, rows[:0]
        return train_test_split(rows, test_size=n_valid, stratify=stratify, random_state=seed)

    def _train(
        self, inputs: torch.Tensor, targets: torch.Tensor, train_idx: np.ndarray,
        valid_idx: np.ndarray, seed: int, loss_fn: nn.Module,
    ) -> tuple[int, float]:  # fmt: skip
        optimiser = torch.optim.Adam(
            self.network_.parameters(), lr=self.learning_rate, weight_decay=self.weight_decay
        )
        generator = torch.Generator().manual_seed(seed)
        best_loss, best_state, stale, epochs = np.inf, None, 0, 0
        for epoch in range(1, self.max_epochs + 1):
            epochs = epoch
            self.network_.train()
            order = torch.from_numpy(train_idx)[torch.randperm(train_idx.size, generator=generator)]
            for batch in order.split(max(1, int(self.batch_size))):
                optimiser.zero_grad()
                loss_fn(self.network_(inputs[batch]), targets[batch]).backward()
                optimiser.step()
            if valid_idx.size == 0:
                continue
            self.network_.eval()
            with torch.no_grad():
                valid = torch.from_numpy(valid_idx)
                loss = float(loss_fn(self.network_(inputs[valid]), targets[valid]))
            if loss < best_loss - 1e-6:
                best_loss, stale = loss, 0
                best_state = {k: v.clone() for k, v in self.network_.state_dict().items()}
            else:
                stale += 1
                if stale >= self.patience:
                    break
        if best_state is not None:
            self.network_.load_state_dict(best_state)
        return epochs, float(best_loss)

    @classmethod
    def _rebuilt(cls, params: dict[str, Any], metadata: dict[str, Any], n_outputs: int,
                 state: dict[str, torch.Tensor]) -> Any:
        params = {**params, "hidden_layer_sizes": tuple(params["hidden_layer_sizes"])}
        model = cls(**params)
        model.n_features_in_ = int(metadata["n_features_in"])
        model.n_epochs_ = int(metadata["n_epochs"])
        model.best_validation_loss_ = float("nan")
        model.network_ = model._build(model.n_features_in_, n_outputs)
        model.network_.load_state_dict(state)
        return model


class TorchMLPClassifier(ClassifierMixin, _TorchMLP):
    """MLP classifier (PyTorch, CPU): cross-entropy, stratified early-stopping split.

    Parameters
    ----------
    Those of the shared base (see ``_TorchMLP``): ``hidden_layer_sizes``, then keyword-only
    ``learning_rate``, ``weight_decay``, ``dropout``, ``batch_size``, ``max_epochs``,
    ``validation_fraction`` (stratified; too small to hold every class disables it),
    ``patience``, ``random_state``.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,), the labels seen in ``fit``, in column order of
        ``predict_proba``.
    n_features_in_ : int, number of features seen in ``fit``.
    network_ : torch.nn.Module, the fitted network (input standardisation included).
    n_epochs_ : int, epochs run (early stopping may end before ``max_epochs``).
    best_validation_loss_ : float, lowest validation loss (inf without a validation split;
        NaN for a model rebuilt by :meth:`from_state_dict`).
    """

    def fit(self, X: Any, y: Any) -> TorchMLPClassifier:
        """Train on ``X`` (n_samples, n_features) and labels ``y``."""
        self._check_parameters()
        X, y = validate_data(self, X, y, dtype=np.float32)
        check_classification_targets(y)
        self.classes_, codes = np.unique(y, return_inverse=True)
        targets = torch.from_numpy(codes.astype(np.int64))
        self._fit_network(X, targets, len(self.classes_), codes, nn.CrossEntropyLoss())
        return self

    def predict_proba(self, X: Any) -> np.ndarray:
        """Class probabilities, columns in the order of ``classes_``."""
        logits = self._outputs(X)
        return torch.softmax(logits, dim=1).numpy().astype(np.float64)

    def predict(self, X: Any) -> np.ndarray:
        """Most probable class of each row."""
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]

    def fitted_metadata(self) -> dict[str, Any]:
        """JSON-able facts needed, with ``state_dict``, to rebuild the fitted estimator."""
        check_is_fitted(self, "network_")
        return {
            "classes": self.classes_.tolist(),
            "n_features_in": int(self.n_features_in_),
            "n_epochs": int(self.n_epochs_),
        }

    @classmethod
    def from_state_dict(
        cls, params: dict[str, Any], metadata: dict[str, Any], state: dict[str, torch.Tensor]
    ) -> TorchMLPClassifier:
        """Rebuild a fitted estimator from ``get_params()``, ``fitted_metadata()`` and tensors."""
        classes = np.asarray(metadata["classes"])
        model = cls._rebuilt(params, metadata, len(classes), state)
        model.classes_ = classes
        return model


class TorchMLPRegressor(RegressorMixin, _TorchMLP):
    """MLP regressor (PyTorch, CPU): squared error of the standardised target, random
    early-stopping split; same parameters as :class:`TorchMLPClassifier`.

    Attributes
    ----------
    n_features_in_ : int, number of features seen in ``fit``.
    network_ : torch.nn.Module, the fitted network (input standardisation included).
    n_epochs_ : int, epochs run (early stopping may end before ``max_epochs``).
    best_validation_loss_ : float, lowest validation loss (inf without a validation split).
    target_mean_, target_scale_ : float, the target's standardisation.
    """

    def fit(self, X: Any, y: Any) -> TorchMLPRegressor:
        """Train on ``X`` (n_samples, n_features) and real targets ``y``."""
        self._check_parameters()
        X, y = validate_data(self, X, y, dtype=np.float32, y_numeric=True)
        y = np.asarray(y, dtype=np.float64)
        self.target_mean_ = float(y.mean())
        spread = float(y.std())
        self.target_scale_ = spread if spread > 1e-12 else 1.0
        standard = ((y - self.target_mean_) / self.target_scale_).astype(np.float32)
        targets = torch.from_numpy(standard).reshape(-1, 1)
        self._fit_network(X, targets, 1, None, nn.MSELoss())
        return self

    def predict(self, X: Any) -> np.ndarray:
        """Predicted target of each row, shape (n_samples,)."""
        outputs = self._outputs(X).numpy().astype(np.float64)[:, 0]
        return outputs * self.target_scale_ + self.target_mean_

    def fitted_metadata(self) -> dict[str, Any]:
        """JSON-able facts needed, with ``state_dict``, to rebuild the fitted estimator."""
        check_is_fitted(self, "network_")
        return {
            "n_features_in": int(self.n_features_in_),
            "n_epochs": int(self.n_epochs_),
            "target_mean": self.target_mean_,
            "target_scale": self.target_scale_,
        }

    @classmethod
    def from_state_dict(
        cls, params: dict[str, Any], metadata: dict[str, Any], state: dict[str, torch.Tensor]
    ) -> TorchMLPRegressor:
        """Rebuild a fitted estimator from ``get_params()``, ``fitted_metadata()`` and tensors."""
        model = cls._rebuilt(params, metadata, 1, state)
        model.target_mean_ = float(metadata["target_mean"])
        model.target_scale_ = float(metadata["target_scale"])
        return model


@contextmanager
def _single_thread() -> Iterator[None]:
    previous = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(previous)


def _seed(random_state: int | None) -> int:
    if random_state is None:
        return int(np.random.default_rng().integers(2**31 - 1))
    if isinstance(random_state, (int, np.integer)):
        return int(random_state)
    raise ValueError(f"random_state must be an int or None, got {random_state!r}")
