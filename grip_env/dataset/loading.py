"""``load``: a dataset directory back into one grip table."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from grip_env.columns import DATASET_COLUMNS, trial_columns
from grip_env.dataset.manifest import FORMAT, MANIFEST_FILE, Manifest, read_manifest, shard_records
from grip_env.dataset.shards import GRIP_SCHEMA, ShardReader, recorded_trials
from grip_env.label_model import label_model_of, label_model_warning


def load(path: str | Path, verify: bool = True, allow_partial: bool = False) -> pd.DataFrame:
    """All grips of a dataset, in run order (object by object, best Q_C first within an object).

    Args:
        path: dataset directory written by :func:`grip_env.dataset.generate`.
        verify: check every shard's SHA-256 and row count against the manifest.
        allow_partial: load an unfinished dataset instead of raising.

    Returns:
        A DataFrame with :data:`~grip_env.columns.DATASET_COLUMNS`, then every trial's outcome
        by trial index (:func:`~grip_env.columns.trial_columns`) when every object's shard
        records them (datasets made before they were recorded do not), and a fresh RangeIndex;
        ``attrs["params"]`` holds the GraspParams as a dict and ``attrs["manifest"]`` the manifest
        (both :class:`SharedAttribute`).

    Raises:
        ValueError: not a dataset, missing or corrupt shard, unfinished run, or another format
            version (:class:`~grip_env.dataset.manifest.FormatVersionError`: regenerate it).
    """
    directory = Path(path)
    manifest = read_manifest(directory)
    records = shard_records(manifest)
    order = [entry["object_id"] for entry in manifest["objects"]]
    missing = [object_id for object_id in order if object_id not in records]
    if missing and not allow_partial:
        raise ValueError(
            f"dataset {directory} is unfinished: {len(missing)} of {len(order)} objects missing "
            f"(first: {missing[0]}); rerun the same generate command to complete it"
        )
    reader = ShardReader(directory)
    parts = [reader.record(records[object_id], verify) for object_id in order
             if object_id in records]
    grips = pd.concat(parts, ignore_index=True) if parts else _empty_grips()
    grips = grips.loc[:, list(DATASET_COLUMNS) + _shared_trial_columns(parts)]
    grips.attrs["params"] = SharedAttribute(manifest["params"])
    grips.attrs["manifest"] = SharedAttribute(manifest)
    return grips


class SharedAttribute(dict):
    """A loaded table's manifest or params, shared (not copied) by every frame derived from the
    table.

    pandas deep-copies ``attrs`` into the result of nearly every operation; a standard-dataset
    manifest (598 objects and their shards) made each column selection of one object's
    candidates cost milliseconds, most of the learning stages' time, and copying the params
    (a nested dict) still cost 7 s of a selector run's 118 s. Treat both as read-only.
    """

    def __deepcopy__(self, memo: dict[int, object]) -> SharedAttribute:
        return self


def dataset_manifest(path: str | Path) -> Manifest:
    """The checked manifest of a dataset directory."""
    return read_manifest(Path(path))


def dataset_label_model(path: str | Path) -> str | None:
    """The label model the dataset in ``path`` records (``"unrecorded"`` for an older one);
    None when ``path`` holds no readable manifest (a bare table, or not a dataset)."""
    manifest = _manifest_json(Path(path))
    return None if manifest is None else label_model_of(manifest)


def label_model_notice(path: str | Path) -> str | None:
    """One line when the dataset in ``path`` was labelled by another label model than this
    code's (:func:`~grip_env.label_model.label_model_warning`), else None."""
    manifest = _manifest_json(Path(path))
    return None if manifest is None else label_model_warning(manifest, f"dataset {path}")


def _manifest_json(directory: Path) -> Manifest | None:
    """A grip-env manifest as stored, unchecked (its readers report a bad one); None when
    ``directory`` holds none."""
    try:
        manifest = json.loads((directory / MANIFEST_FILE).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return manifest if isinstance(manifest, dict) and manifest.get("format") == FORMAT else None


def _shared_trial_columns(parts: list[pd.DataFrame]) -> list[str]:
    """The per-trial columns every part has (none when a part lacks them: a dataset resumed
    across the change that added them keeps the columns every object has)."""
    counts = {recorded_trials(part.columns) for part in parts}
    return list(trial_columns(counts.pop())) if len(counts) == 1 else []


def _empty_grips() -> pd.DataFrame:
    return GRIP_SCHEMA.empty_table().to_pandas()
