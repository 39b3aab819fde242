"""``pack``: a finished dataset's shards into one Parquet file, for shipping.

A shard per object suits a long, resumable run; shipped, its 600 small files cost more in
Parquet footers than in grips. Packing concatenates them, in the manifest's object order, into
``grips/grips.parquet`` (zstd), points every object's record at its rows there and removes the
shard files. The grips are the same values: :func:`~grip_env.dataset.load` gives the same table.

Crash-safe: the packed file is written atomically, then the manifest, then the old shards go;
an interrupted pack leaves a dataset that loads, and packing again finishes it.

    python -m grip_env.dataset.packing DIR
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from grip_env.dataset.files import write_atomically
from grip_env.dataset.manifest import read_manifest, shard_records, write_manifest
from grip_env.dataset.shards import (
    GRIPS_DIR,
    PACKED_FILE,
    ShardReader,
    ShardRecord,
    dataset_schema,
    recorded_trials,
)

#: Rows per Parquet row group of the packed file (a few objects' grips).
ROW_GROUP_ROWS = 4096


def pack(path: str | Path) -> Path:
    """Pack the finished dataset in ``path`` (see the module docstring); returns the packed file.

    Raises:
        ValueError: not a dataset, or an unfinished one (finish it first: rerun its generate).
    """
    directory = Path(path)
    manifest = read_manifest(directory)
    records = shard_records(manifest)
    order = [entry["object_id"] for entry in manifest["objects"]]
    if not manifest.get("complete") or any(object_id not in records for object_id in order):
        raise ValueError(f"dataset {directory} is unfinished ({len(records)} of {len(order)} "
                         "objects): rerun its generate command to finish it before packing")
    packed = directory / PACKED_FILE
    if not all(record.packed for record in records.values()):
        reader = ShardReader(directory)
        parts = [reader.record(records[object_id]) for object_id in order]
        counts = {recorded_trials(part.columns) for part in parts}
        schema = dataset_schema(counts.pop() if len(counts) == 1 else 0)  # what every shard has
        table = pa.concat_tables(
            [pa.Table.from_pandas(part.loc[:, schema.names], schema=schema, preserve_index=False)
             for part in parts])  # fmt: skip
        checksum = write_atomically(packed, lambda temp: pq.write_table(
            table, temp, compression="zstd", row_group_size=ROW_GROUP_ROWS))
        offset = 0
        for object_id, part in zip(order, parts, strict=True):
            manifest["shards"][object_id] = ShardRecord(
                PACKED_FILE, len(part), checksum, offset).as_dict()
            offset += len(part)
        write_manifest(directory, manifest)
    for shard in (directory / GRIPS_DIR).glob("part-*.parquet"):
        shard.unlink()
    return packed


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m grip_env.dataset.packing",
                                     description=pack.__doc__.splitlines()[0])  # type: ignore[union-attr]
    parser.add_argument("dataset", type=Path, help="a finished dataset folder")
    args = parser.parse_args(argv)
    try:
        packed = pack(args.dataset)
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    print(f"packed {args.dataset} into {packed} ({packed.stat().st_size / 1e6:.1f} MB)")


if __name__ == "__main__":
    main()
