"""Saving and loading fitted models without arbitrary pickles.

Each model ``name`` is saved as ``name.json`` (metadata: format, features, parameters, dataset
checksum, anything the caller adds) plus either

- ``name.skops`` for scikit-learn pipelines (``skops.io``; on load, only the types of
  :data:`TRUSTED_TYPES` (this package's estimators) and scikit-learn's own internals
  (``sklearn.*``: calibrators, KD-trees, optimisers) are accepted beyond skops' defaults), or
- ``name.pt`` for the torch MLP and the convolutional image models: the network's ``state_dict``
  (loaded with ``weights_only=True``), rebuilt with its JSON parameters (an image model's first
  step, :class:`~classifiers.learners.image_inputs.ImageInputs`, from its JSON ``inputs``: the
  image transformer's parameters, the measures and the image shape), or
- ``name.txt`` for the lambdarank ranker (``format: lightgbm_text``, written by
  :meth:`~classifiers.learners.ranking.GroupedRanker.save`): LightGBM's own text model, rebuilt
  with its JSON parameters.

:data:`MODEL_FORMATS` are the formats :func:`load_model` reads; :func:`saved_models` lists the
models of a folder by them (a folder also holds other JSON files, e.g. ``grip-env train``'s
metrics beside its ``models/``).
"""

from __future__ import annotations

import hashlib
import importlib
import json
import sys
from pathlib import Path
from typing import Any

import pandas as pd
import torch
from sklearn.pipeline import Pipeline

from classifiers.learners.baselines import ColumnSelector
from classifiers.learners.cnn import CNNClassifier, CNNRegressor
from classifiers.learners.image_inputs import ImageInputs
from classifiers.learners.torch_mlp import TorchMLPClassifier, TorchMLPRegressor

TRUSTED_TYPES = frozenset(
    {
        "classifiers.learners.baselines.ColumnSelector",
        "classifiers.learners.baselines.RankingClassifier",
        "classifiers.learners.baselines.RandomClassifier",
        "classifiers.learners.baselines.RankingRegressor",
        "classifiers.learners.baselines.RandomRegressor",
        "classifiers.learners.threads.OneThreadHGBClassifier",
        "classifiers.learners.threads.OneThreadHGBRegressor",
        "classifiers.learners.svm.PlattSVC",
        "classifiers.learners.svm.SampledSVR",
    }
)
_TORCH_MODELS = {cls.__name__: cls for cls in (TorchMLPClassifier, TorchMLPRegressor,
                                                CNNClassifier, CNNRegressor)}
#: Where the trusted types lived before classifiers/ was laid out by kind: a model saved then
#: names them so, and still loads.
LEGACY_MODULES = {"classifiers.baselines": "classifiers.learners.baselines",
                  "classifiers.threads": "classifiers.learners.threads"}

TRUSTED_PREFIXES = ("sklearn.",)
#: The ``format`` of a model's JSON metadata, and the file beside it that holds the model.
MODEL_FORMATS = {"skops": ".skops", "torch_state_dict": ".pt", "lightgbm_text": ".txt"}


def dataset_checksum(table: pd.DataFrame) -> str:
    """SHA-256 of the table's values and column names (row order matters)."""
    digest = hashlib.sha256()
    digest.update(json.dumps(list(map(str, table.columns))).encode())
    digest.update(pd.util.hash_pandas_object(table, index=False).to_numpy().tobytes())
    return digest.hexdigest()


def save_model(
    model: Pipeline, directory: str | Path, name: str, metadata: dict[str, Any] | None = None
) -> Path:
    """Write a fitted pipeline under ``directory``; returns the JSON metadata path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    selector, estimator = model[0], model[-1]
    if isinstance(selector, ImageInputs):
        return _save_image_model(model, directory, name, metadata)
    if not isinstance(selector, ColumnSelector):
        raise ValueError(f"model {name!r} must start with a ColumnSelector step")
    import skops.io as sio  # here, not at import: skops' import walks all of scikit-learn

    info = {"name": name, "columns": list(selector.columns), **(metadata or {})}
    if type(estimator).__name__ in _TORCH_MODELS and len(model) == 2:
        torch.save(estimator.state_dict(), directory / f"{name}.pt")
        info |= {"format": "torch_state_dict", "estimator": type(estimator).__name__,
                 "params": _jsonable(estimator.get_params()),
                 "fitted": estimator.fitted_metadata()}  # fmt: skip
    else:
        sio.dump(model, directory / f"{name}.skops")
        info |= {"format": "skops", "params": _jsonable(estimator.get_params(deep=False))}
    path = directory / f"{name}.json"
    path.write_text(json.dumps(info, indent=2, sort_keys=True))
    return path


def _save_image_model(model: Pipeline, directory: Path, name: str,
                      metadata: dict[str, Any] | None) -> Path:
    """An image model: its network's ``state_dict`` and, in the JSON, its first step's
    settings (:meth:`ImageInputs.settings`)."""
    inputs, estimator = model[0], model[-1]
    if len(model) != 2 or type(estimator).__name__ not in _TORCH_MODELS:
        raise ValueError(f"model {name!r}: an image model is ImageInputs then a torch network")
    torch.save(estimator.state_dict(), directory / f"{name}.pt")
    info = {"name": name, "columns": list(inputs.measures), **(metadata or {}),
            "format": "torch_state_dict", "estimator": type(estimator).__name__,
            "params": _jsonable(estimator.get_params()), "fitted": estimator.fitted_metadata(),
            "inputs": inputs.settings()}  # fmt: skip
    path = directory / f"{name}.json"
    path.write_text(json.dumps(info, indent=2, sort_keys=True))
    return path


def model_format(meta_path: str | Path) -> str | None:
    """The saved format named by a model's JSON metadata; ``None`` for any other file (not JSON,
    not an object, no known ``format``)."""
    try:
        info = json.loads(Path(meta_path).read_text())
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    found = info.get("format") if isinstance(info, dict) else None
    return found if found in MODEL_FORMATS else None


def saved_models(directory: str | Path) -> list[str]:
    """The names of the models saved in ``directory`` (each ``NAME.json`` whose format
    :func:`load_model` reads), sorted."""
    return sorted(path.stem for path in Path(directory).glob("*.json")
                  if path.is_file() and model_format(path) is not None)


def load_model(directory: str | Path, name: str) -> tuple[Any, dict[str, Any]]:
    """Read back a model written by :func:`save_model` (or a ranker's
    :meth:`~classifiers.learners.ranking.GroupedRanker.save`), with its metadata; the metadata's
    ``columns`` are the table columns the model reads."""
    directory = Path(directory)
    meta_path = directory / f"{name}.json"
    if not meta_path.is_file():
        raise FileNotFoundError(f"no saved model metadata {meta_path}")
    info = json.loads(meta_path.read_text())
    if not isinstance(info, dict):
        raise ValueError(f"{meta_path}: not a model's metadata (a JSON object)")
    if info.get("format") == "lightgbm_text":
        from classifiers.learners.ranking import GroupedRanker  # LightGBM: only when needed

        ranker = GroupedRanker.load(directory / f"{name}.txt", info.get("params", {}))
        return ranker, {**info, "columns": list(ranker.features)}
    if info.get("format") == "torch_state_dict":
        state = torch.load(directory / f"{name}.pt", weights_only=True)
        kind = info.get("estimator", "TorchMLPClassifier")
        if kind not in _TORCH_MODELS:
            raise ValueError(f"{meta_path}: unknown torch estimator {kind!r}")
        estimator = _TORCH_MODELS[kind].from_state_dict(info["params"], info["fitted"], state)
        if "inputs" in info:
            selector = ImageInputs.from_settings(info["inputs"])
        else:
            selector = ColumnSelector(tuple(info["columns"]))
            selector.n_features_out_ = len(selector.columns)
        return Pipeline([("select", selector), ("model", estimator)]), info
    if info.get("format") == "skops":
        import skops.io as sio

        path = directory / f"{name}.skops"
        untrusted = sio.get_untrusted_types(file=path)
        unexpected = sorted(
            kind for kind in untrusted
            if _current_name(kind) not in TRUSTED_TYPES and not kind.startswith(TRUSTED_PREFIXES)
        )  # fmt: skip
        if unexpected:
            raise ValueError(f"{path} holds types outside the trusted list: {unexpected}")
        _alias_legacy_modules()
        return sio.load(path, trusted=untrusted), info
    raise ValueError(f"{meta_path}: unknown model format {info.get('format')!r}")


def _current_name(kind: str) -> str:
    """A type's name under today's layout (an older file may name its old module)."""
    module, _, name = kind.rpartition(".")
    return f"{LEGACY_MODULES.get(module, module)}.{name}"


def _alias_legacy_modules() -> None:
    """Let an older file's module names import today's modules."""
    for old, new in LEGACY_MODULES.items():
        sys.modules.setdefault(old, importlib.import_module(new))


def _jsonable(params: dict[str, Any]) -> dict[str, Any]:
    """Parameters as JSON values (estimators and other objects by their repr)."""

    def convert(value: Any) -> Any:
        if value is None or isinstance(value, (bool, int, float, str)):
            return value
        if isinstance(value, (list, tuple)):
            return [convert(item) for item in value]
        return repr(value)

    return {key: convert(value) for key, value in params.items()}
