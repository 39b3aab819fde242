"""``validate``: check a dataset directory end to end and list every problem found."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from grip_env.columns import (
    FEATURES,
    INDEXES,
    ROBUSTNESS,
    trial_robustness_columns,
    trial_success_columns,
)
from grip_env.dataset.files import sha256_of
from grip_env.dataset.jobs import SUCCESS_THRESHOLD
from grip_env.dataset.manifest import Manifest, read_manifest, shard_records
from grip_env.dataset.shards import ShardRecord, schema_problems
from grip_env.params import GraspParams

FEATURE_RTOL = 1e-7
FEATURE_ATOL = 1e-9


def validate(path: str | Path) -> list[str]:
    """Every problem in a dataset: one line each; an empty list means the dataset is sound.

    Checks the objects table and each shard against the manifest (presence, SHA-256, row count),
    the schema (columns and types), every feature and index recomputed from its row's descriptors,
    outcome consistency (1 <= trials, 0 <= successes <= trials, rates and labels, robustness
    finite and >= 0; every trial's outcome, when recorded, summarising to the row's exactly)
    and that grip ids are unique. String columns may be ``string`` or the
    equivalent ``large_string``.

    Raises:
        ValueError: ``path`` is not a grip-env dataset, or one of another format version
            (:class:`~grip_env.dataset.manifest.FormatVersionError`, which says to regenerate).
    """
    directory = Path(path)
    manifest = read_manifest(directory)
    problems = _objects_file_problems(directory, manifest)
    records = shard_records(manifest)
    params = GraspParams(**manifest["params"])
    grip_ids: list[pd.Series] = []
    files: dict[str, tuple[list[str], pa.Table | None]] = {}
    for entry in manifest["objects"]:
        record = records.get(entry["object_id"])
        if record is None:
            problems.append(f"object {entry['object_id']}: no shard (run unfinished)")
            continue
        if record.file not in files:  # a packed dataset's one file is checked once
            files[record.file] = _file_problems(directory, record)
            problems += files[record.file][0]
        found, grips = _shard_rows(record, files[record.file][1])
        problems += found
        if grips is not None:
            problems += _row_problems(record.file, grips, params, entry["object_id"])
            grip_ids.append(grips["grip_id"])
    if grip_ids:
        ids = pd.concat(grip_ids, ignore_index=True)
        if ids.duplicated().any():
            problems.append(f"grip_id not unique: {ids[ids.duplicated()].iloc[0]!r} repeats")
    return problems


def _objects_file_problems(directory: Path, manifest: Manifest) -> list[str]:
    listed = manifest.get("objects_file", {})
    path = directory / listed.get("file", "objects.parquet")
    if not path.is_file():
        return [f"{path.name}: missing"]
    if sha256_of(path) != listed.get("sha256"):
        return [f"{path.name}: SHA-256 differs from the manifest (file changed or corrupt)"]
    return _perceived_contour_problems(path, manifest)


def _perceived_contour_problems(path: Path, manifest: Manifest) -> list[str]:
    """A run that planned on the render stores each object's perceived contour (>= 3 finite
    points); one that planned on the true objects stores none."""
    config = manifest.get("config", {})
    on_render = (config.get("perception", {}).get("source") == "render"
                 or bool(config.get("uncertainty", {}).get("perceived_contour")))
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as exc:
        return [f"{path.name}: unreadable Parquet ({exc})"]
    if "perceived_contour" not in table.column_names:
        return [f"{path.name}: no perceived_contour column"] if on_render else []
    problems = []
    for object_id, contour in zip(table["object_id"].to_pylist(),
                                  table["perceived_contour"].to_pylist(), strict=True):
        if not on_render and contour is not None:
            problems.append(f"{path.name}: object {object_id} has a perceived contour, but the "
                            "run planned on the true objects")
        elif on_render and not _is_contour(contour):
            problems.append(f"{path.name}: object {object_id}: perceived_contour is not a contour "
                            "of >= 3 finite points")
    return problems


def _is_contour(contour: list | None) -> bool:
    if contour is None or len(contour) < 3:
        return False
    points = np.asarray(contour, dtype=float)
    return points.ndim == 2 and points.shape[1] == 2 and bool(np.isfinite(points).all())


def _file_problems(directory: Path, record: ShardRecord) -> tuple[list[str], pa.Table | None]:
    """Problems of one shard file (presence, checksum, schema), and its table when readable."""
    path = directory / record.file
    if not path.is_file():
        return [f"{record.file}: missing"], None
    problems = []
    if sha256_of(path) != record.sha256:
        problems.append(f"{record.file}: SHA-256 differs from the manifest (changed or corrupt)")
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as exc:
        return [*problems, f"{record.file}: unreadable Parquet ({exc})"], None
    problems_of_schema = schema_problems(record.file, table.schema)
    if problems_of_schema:
        return problems + problems_of_schema, None
    return problems, table


def _shard_rows(
    record: ShardRecord, table: pa.Table | None
) -> tuple[list[str], pd.DataFrame | None]:
    """The object's rows of its (checked) file, and a problem if the manifest's count is off."""
    if table is None:
        return [], None
    if record.packed:
        if record.offset < 0 or record.offset + record.rows > table.num_rows:
            return [f"{record.file}: {table.num_rows} rows, the manifest places rows "
                    f"{record.offset}..{record.offset + record.rows} in it"], None
        return [], table.slice(record.offset, record.rows).to_pandas()
    problems = ([f"{record.file}: {table.num_rows} rows, manifest says {record.rows}"]
                if table.num_rows != record.rows else [])
    return problems, table.to_pandas()


def _row_problems(
    name: str, grips: pd.DataFrame, params: GraspParams, object_id: str
) -> list[str]:
    if grips.empty:
        return []
    problems = []
    if (grips["object_id"] != object_id).any():
        problems.append(f"{name}: rows with an object_id other than {object_id!r}")
    problems += _feature_problems(name, grips, params)
    problems += _outcome_problems(name, grips)
    return problems


def _feature_problems(name: str, grips: pd.DataFrame, params: GraspParams) -> list[str]:
    from grip_env.planning.features import compute_features

    try:
        expected = compute_features(grips, params)
    except ValueError as exc:
        return [f"{name}: features cannot be recomputed: {exc}"]
    problems = []
    for column in FEATURES + INDEXES:
        stored, recomputed = grips[column].to_numpy(), expected[column].to_numpy()
        wrong = ~np.isclose(stored, recomputed, rtol=FEATURE_RTOL, atol=FEATURE_ATOL)
        if wrong.any():
            first = int(np.argmax(wrong))
            problems.append(
                f"{name}: {column} differs from its recomputed value in {int(wrong.sum())} row(s), "
                f"e.g. grip {grips['grip_id'].iloc[first]}: stored {stored[first]!r}, "
                f"recomputed {recomputed[first]!r}"
            )
    return problems


def _outcome_problems(name: str, grips: pd.DataFrame) -> list[str]:
    trials, successes = grips["trials"].to_numpy(), grips["successes"].to_numpy()
    rate = grips["success_rate"].to_numpy()
    checks = {
        "trials < 1": trials < 1,
        "successes outside [0, trials]": (successes < 0) | (successes > trials),
        "success_rate != successes / trials": ~np.isclose(rate, successes / np.maximum(trials, 1)),
        f"success != (success_rate >= {SUCCESS_THRESHOLD})":
            grips["success"].to_numpy() != (rate >= SUCCESS_THRESHOLD),
    }
    for column in ROBUSTNESS:
        values = grips[column].to_numpy(dtype=np.float64)
        checks[f"{column} not a finite value >= 0 g"] = ~(np.isfinite(values) & (values >= 0))
    checks.update(_per_trial_checks(grips))
    ids = grips["grip_id"]
    return [
        f"{name}: {what} in {int(bad.sum())} row(s), e.g. grip {ids.iloc[int(np.argmax(bad))]}"
        for what, bad in checks.items() if bad.any()
    ]


def _per_trial_checks(grips: pd.DataFrame) -> dict[str, np.ndarray]:
    """When every trial's outcome is recorded: do they summarise, bit for bit, to the row's
    ``trials``, ``successes``, ``robustness_mean`` and ``robustness_std``?"""
    from grip_env.dataset.shards import recorded_trials
    from grip_env.sim.execution import trial_summary

    count = recorded_trials(grips.columns)
    if not count:
        return {}
    success = grips[list(trial_success_columns(count))].to_numpy(bool)
    robust = grips[list(trial_robustness_columns(count))].to_numpy(float)
    summary = trial_summary(robust, success)
    return {f"{name} is not the summary of trial_*_0..{count - 1}":
            np.asarray(summary[name]) != grips[name].to_numpy()
            for name in ("trials", "successes", *ROBUSTNESS)}
