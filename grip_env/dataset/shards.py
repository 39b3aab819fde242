"""Parquet shards: one file of grips per object, with a fixed Arrow schema and run metadata.

A finished dataset may be packed (:mod:`grip_env.dataset.packing`): every object's grips then
stand in one file, ``grips/grips.parquet``, and each object's record says where its rows start.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from grip_env.columns import (
    DATASET_COLUMNS,
    IDENTITY,
    OUTCOMES,
    TRIAL_ROBUSTNESS_PREFIX,
    TRIAL_SUCCESS_PREFIX,
    trial_columns,
    trial_success_columns,
)
from grip_env.dataset.files import sha256_of, write_atomically

GRIPS_DIR = "grips"
METADATA_KEY = b"grip_env"

_TYPES: dict[str, pa.DataType] = {
    "object_id": pa.string(),
    "grasp_id": pa.int64(),
    "grip_id": pa.string(),
    "two_finger": pa.bool_(),
    "trials": pa.int64(),
    "successes": pa.int64(),
    "success_rate": pa.float64(),
    "success": pa.bool_(),
}
#: Arrow schema of every grip shard: DATASET_COLUMNS in order; descriptors and features float64.
GRIP_SCHEMA = pa.schema([(name, _TYPES.get(name, pa.float64())) for name in DATASET_COLUMNS])


def dataset_schema(trials: int = 0) -> pa.Schema:
    """:data:`GRIP_SCHEMA`, then the per-trial columns of ``trials`` trials a grip
    (:func:`~grip_env.columns.trial_columns`: success bool, robustness float64); none for 0."""
    extra = [(name, pa.bool_() if name.startswith(TRIAL_SUCCESS_PREFIX) else pa.float64())
             for name in trial_columns(trials)]
    return pa.schema([*GRIP_SCHEMA, *(pa.field(n, t) for n, t in extra)])


def recorded_trials(columns: Iterable[str]) -> int:
    """How many trials a grip the per-trial columns among ``columns`` record (0: none).

    Raises:
        ValueError: they are not exactly :func:`~grip_env.columns.trial_columns` of a count.
    """
    names = [str(c) for c in columns
             if str(c).startswith((TRIAL_SUCCESS_PREFIX, TRIAL_ROBUSTNESS_PREFIX))]
    trials = sum(name.startswith(TRIAL_SUCCESS_PREFIX) for name in names)
    if sorted(names) != sorted(trial_columns(trials)):
        raise ValueError(f"per-trial columns {names} are not trial_success_0..T-1 and "
                         "trial_robustness_0..T-1 of one T")
    return trials


def recorded_trial_successes(columns: Iterable[str]) -> int:
    """How many trials' successes (``trial_success_0..T-1``) ``columns`` hold (0: none): what
    replaying or scoring trials by index needs (the robustness columns may be absent).

    Raises:
        ValueError: they are not ``trial_success_0..T-1`` of one T.
    """
    names = sorted(str(c) for c in columns if str(c).startswith(TRIAL_SUCCESS_PREFIX))
    if names != sorted(trial_success_columns(len(names))):
        raise ValueError(f"per-trial columns {names} are not trial_success_0..T-1 of one T")
    return len(names)


NON_FLOAT_COLUMNS = tuple(name for name in IDENTITY + OUTCOMES if name != "success_rate")
#: The one file of a packed dataset, relative to the dataset.
PACKED_FILE = f"{GRIPS_DIR}/grips.parquet"
#: A shard's file name inside the dataset: ``grips/part-<index>-<safe object id>.parquet``, or
#: the packed file.
SHARD_FILE = re.compile(rf"{GRIPS_DIR}/(part-\d{{6}}-[A-Za-z0-9_.-]+|grips)\.parquet")


def _equivalent_types() -> dict[pa.DataType, pa.DataType]:
    """Arrow types that hold the same values as the schema's (pandas 3 writes large_string)."""
    found = {pa.large_string(): pa.string()}
    if hasattr(pa, "string_view"):
        found[pa.string_view()] = pa.string()
    return found


_EQUIVALENT_TYPES = _equivalent_types()


def same_type(found: pa.DataType, expected: pa.DataType) -> bool:
    """Whether a column of type ``found`` holds what the schema's ``expected`` type holds."""
    return _EQUIVALENT_TYPES.get(found, found) == expected


def schema_problems(name: str, schema: pa.Schema) -> list[str]:
    """One line per dataset column missing from ``schema`` or of another type."""
    problems = []
    try:
        expected = dataset_schema(recorded_trials(schema.names))
    except ValueError as exc:
        return [f"{name}: {exc}"]
    for field in expected:
        if field.name not in schema.names:
            problems.append(f"{name}: column {field.name} missing")
        elif not same_type(schema.field(field.name).type, field.type):
            problems.append(
                f"{name}: column {field.name} has type {schema.field(field.name).type}, "
                f"expected {field.type}"
            )
    return problems


@dataclass(frozen=True)
class ShardRecord:
    """A completed shard as the manifest lists it: its file, rows and the file's SHA-256; in a
    packed dataset the object's rows are ``rows`` rows of the packed file from ``offset``."""

    file: str
    rows: int
    sha256: str
    offset: int = 0

    @property
    def packed(self) -> bool:
        return self.file == PACKED_FILE

    def as_dict(self) -> dict[str, Any]:
        record = {"file": self.file, "rows": self.rows, "sha256": self.sha256}
        return record | {"offset": self.offset} if self.packed else record


def shard_path(directory: Path, index: int, object_id: str) -> Path:
    """``DIR/grips/part-<index>-<object_id>.parquet``; the object id is made a safe file name
    (letters, digits, ``_.-`` only), so no object name can lead out of ``DIR/grips``."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", object_id)
    return directory / GRIPS_DIR / f"part-{index:06d}-{safe}.parquet"


def grips_to_arrow(grips: pd.DataFrame, metadata: dict[str, Any]) -> pa.Table:
    """The grip table in the shard schema (with its per-trial columns, when it has them);
    ``metadata`` is stored as JSON in the file.

    Raises:
        ValueError: a dataset column is missing or cannot be cast to its type, or the per-trial
            columns are not those of one trial count.
    """
    missing = [name for name in DATASET_COLUMNS if name not in grips.columns]
    if missing:
        raise ValueError(f"grip table is missing dataset column(s): {', '.join(missing)}")
    schema = dataset_schema(recorded_trials(grips.columns))
    try:
        table = pa.Table.from_pandas(
            grips.loc[:, schema.names], schema=schema, preserve_index=False
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        raise ValueError(f"grip table does not fit the dataset schema: {exc}") from None
    return table.replace_schema_metadata({METADATA_KEY: json.dumps(metadata).encode()})


def write_shard(path: Path, grips: pd.DataFrame, metadata: dict[str, Any]) -> ShardRecord:
    """Write one shard atomically; returns its manifest record (file relative to the dataset)."""
    table = grips_to_arrow(grips, metadata)
    path.parent.mkdir(parents=True, exist_ok=True)
    checksum = write_atomically(path, lambda temp: pq.write_table(table, temp))
    return ShardRecord(f"{GRIPS_DIR}/{path.name}", table.num_rows, checksum)


def read_shard(path: Path, expected: ShardRecord | None = None) -> pd.DataFrame:
    """Read a shard's dataset columns (Parquet only: nothing in the file is run as code),
    checking it against its manifest record when given and its schema always.

    Raises:
        ValueError: the file is missing, unreadable, of another schema, or differs from
            ``expected``.
    """
    return ShardReader(path.parent.parent).read(path, expected)


class ShardReader:
    """Reads the shards of one dataset, each file once: a packed dataset's file holds every
    object, so its checksum, schema and rows are checked once, then sliced per object."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self._tables: dict[Path, pa.Table] = {}

    def record(self, record: ShardRecord, verify: bool = True) -> pd.DataFrame:
        """The rows of the object ``record`` lists (checked against it when ``verify``)."""
        path = self.directory / record.file
        if not verify:
            return self._slice(self._table(path, None), record, path)
        return self.read(path, record)

    def read(self, path: Path, expected: ShardRecord | None = None) -> pd.DataFrame:
        """The rows of ``path`` (of the object ``expected`` lists, when it is packed)."""
        table = self._table(path, expected)
        if expected is not None and not expected.packed and table.num_rows != expected.rows:
            raise ValueError(f"shard {path} has {table.num_rows} rows, manifest says "
                             f"{expected.rows}")
        return self._slice(table, expected, path)

    def _slice(self, table: pa.Table, record: ShardRecord | None, path: Path) -> pd.DataFrame:
        if record is not None and record.packed:
            if record.offset < 0 or record.offset + record.rows > table.num_rows:
                raise ValueError(f"shard {path} has {table.num_rows} rows, the manifest places "
                                 f"rows {record.offset}..{record.offset + record.rows} in it")
            table = table.slice(record.offset, record.rows)
        return table.select(dataset_schema(recorded_trials(table.schema.names)).names).to_pandas()

    def _table(self, path: Path, expected: ShardRecord | None) -> pa.Table:
        if path not in self._tables:
            self._tables[path] = _read_checked(path, expected)
        return self._tables[path]


def _read_checked(path: Path, expected: ShardRecord | None) -> pa.Table:
    """A shard file's table, its checksum (against ``expected``) and schema checked."""
    if not path.is_file():
        raise ValueError(f"shard {path} is missing")
    if expected is not None and sha256_of(path) != expected.sha256:
        raise ValueError(f"shard {path} is corrupt: its SHA-256 differs from the manifest")
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as exc:
        raise ValueError(f"shard {path} is corrupt: {exc}") from None
    problems = schema_problems(str(path), table.schema)
    if problems:
        raise ValueError(f"shard {problems[0]}" + (f" (and {len(problems) - 1} more)"
                                                  if len(problems) > 1 else ""))
    return table


def shard_metadata(path: Path) -> dict[str, Any]:
    """The JSON metadata stored in a shard's schema (empty when absent)."""
    raw = (pq.read_schema(path).metadata or {}).get(METADATA_KEY)
    return json.loads(raw) if raw else {}
