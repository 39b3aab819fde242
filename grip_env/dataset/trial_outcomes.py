"""``record_trials``: every trial's outcome, by trial index, of a dataset made before datasets
kept them, by re-simulating its grips; one small shard file an object, resumably.

Trial k of every grip of an object meets one draw, keyed by (seed, object, k), so simulating a
recorded grip again (:func:`~grip_env.sim.run_trial_outcomes` over the dataset's trials) gives
the trials it was labelled with, in order. Each object's grips are planned again (and must equal
the recorded ones, bit for bit) and simulated; the trials' summaries
(:func:`~grip_env.sim.execution.trial_summary`) must equal the recorded ``trials``,
``successes``, ``robustness_mean`` and ``robustness_std`` bit for bit, else the run stops with
:class:`TrialMismatchError` and writes nothing for that object.

Objects run in :func:`resimulation_order`: the held-out objects of the dataset's split
(``learning.test_fraction``, ``learning.seed``: on the standard dataset, split v4's 128) first,
then the training objects. A finished object is its own Parquet file ``<object_id>.parquet``
(``object_id``, ``grip_id`` and :func:`~grip_env.columns.trial_columns`), listed with its
checksum and cost in ``index.json``; an interrupted run loses the object in flight only, and
the same command continues.

    python -m grip_env.dataset.trial_outcomes SOURCE --out DIR [--until HH:MM] [--objects N]
    python -m grip_env.dataset.trial_outcomes SOURCE --out DIR --attach   # once all are done

The standard dataset's are in :data:`STANDARD_TRIALS` (``SOURCE`` = ``standard``);
:func:`attach_trials` (``--attach``) writes them into the dataset's own files when complete.
"""

from __future__ import annotations

import argparse
import json
import re
import time
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from grip_env.columns import (
    ROBUSTNESS,
    TRIAL_SUCCESS_PREFIX,
    trial_columns,
    trial_robustness_columns,
    trial_success_columns,
)
from grip_env.config import Config
from grip_env.dataset.files import sha256_of, write_atomically, write_text_atomically
from grip_env.dataset.jobs import ObjectTask, kept_grips
from grip_env.dataset.loading import load
from grip_env.dataset.manifest import read_manifest
from grip_env.dataset.resimulation import _as_planned, recorded_objects, same_candidates
from grip_env.dataset.shards import recorded_trials
from grip_env.dataset.split import held_out_objects
from grip_env.shutdown import deferred_signals

#: The standard dataset's per-trial outcomes (re-simulated; see the module docstring).
STANDARD_TRIALS = Path(__file__).resolve().parents[1] / "data" / "standard_trials"
INDEX_FILE = "index.json"
#: The summaries a re-simulated grip must reproduce exactly.
SUMMARY_COLUMNS = ("trials", "successes", *ROBUSTNESS)


class TrialMismatchError(RuntimeError):
    """A re-simulated grip's trials do not give its recorded summaries (or the grips planned
    again are not the recorded ones): the dataset is not this code's, and no trial is kept."""


@dataclass(frozen=True)
class TrialRecordProgress:
    """How far :func:`record_trials` is: objects and grips done (of all), and this call's share."""

    objects_done: int
    objects: int
    grips_done: int
    grips: int
    held_out_done: int
    held_out: int
    new_objects: int
    new_grips: int
    seconds: float

    def summary(self) -> str:
        rate = self.new_grips / self.seconds * 3600 if self.seconds > 0 else float("nan")
        return (f"{self.objects_done} of {self.objects} objects ({self.grips_done} of "
                f"{self.grips} grips; held-out {self.held_out_done} of {self.held_out}); this "
                f"run {self.new_objects} objects, {self.new_grips} grips in "
                f"{self.seconds:.0f} s ({rate:.0f} grips an hour)")


def resimulation_order(table: pd.DataFrame, config: Config) -> tuple[list[str], list[str]]:
    """(held-out object ids, training object ids) of the dataset's split, each sorted: the
    order :func:`record_trials` runs them in."""
    train, test = held_out_objects(table["object_id"].astype(str), config.learning)
    return list(test), list(train)


def object_trials(task: ObjectTask, rows: pd.DataFrame) -> pd.DataFrame:
    """One object's recorded grips simulated again: ``object_id``, ``grip_id`` and every trial's
    success and robustness by trial index.

    Raises:
        TrialMismatchError: the grips planned again, or the trials' summaries, differ from the
            recorded ones.
    """
    from grip_env.sim import run_trial_outcomes

    config = task.config
    trials = int(rows["trials"].iloc[0])
    kept = kept_grips(task)
    if not same_candidates(kept, rows):
        raise TrialMismatchError(f"{task.object_id}: the grips planned again differ from the "
                                 "recorded ones")
    grips = _as_planned(rows.reset_index(drop=True), kept, task.object_id)
    outcome = run_trial_outcomes(task.obj, grips, config, trials, config.dataset.seed)
    robust = outcome["robustness"].to_numpy(float).reshape(len(rows), trials)
    success = outcome["success"].to_numpy(bool).reshape(len(rows), trials)
    check_summaries(task.object_id, rows, robust, success)
    frame = pd.DataFrame({"object_id": task.object_id, "grip_id": rows["grip_id"].to_numpy()})
    frame[list(trial_success_columns(trials))] = success
    frame[list(trial_robustness_columns(trials))] = robust
    return frame


def check_summaries(object_id: str, rows: pd.DataFrame, robust: np.ndarray,
                    success: np.ndarray) -> None:
    """TrialMismatchError unless the per-trial arrays (grips × trials) summarise, bit for bit,
    to the recorded rows' ``trials``, ``successes``, ``robustness_mean`` and ``robustness_std``."""
    from grip_env.sim.execution import trial_summary

    summary = trial_summary(robust, success)
    for name in SUMMARY_COLUMNS:
        differ = np.asarray(summary[name]) != rows[name].to_numpy()
        if differ.any():
            grip = rows["grip_id"].to_numpy()[differ][0]
            raise TrialMismatchError(
                f"{object_id}: the trials simulated again give another {name} than recorded on "
                f"{int(differ.sum())} grips (first {grip}): not the recorded label model's trials")


def record_trials(source: str | Path, out_dir: str | Path, until: datetime | None = None,
                  limit: int | None = None, progress: bool = True) -> TrialRecordProgress:
    """Re-simulate the objects of ``source`` not yet in ``out_dir`` (held-out first), writing
    one shard each, until every object is done, ``limit`` objects were done or the clock
    passes ``until`` (checked before each object). Returns how far it got.

    Raises:
        ValueError: ``out_dir`` holds another dataset's trials, or a bad ``limit``.
        TrialMismatchError: as :func:`object_trials`.
    """
    if limit is not None and (isinstance(limit, bool) or limit < 1):
        raise ValueError(f"--objects takes a positive number of objects, got {limit!r}")
    source, out = Path(source), Path(out_dir)
    manifest = read_manifest(source)
    table = load(source)
    config = Config.model_validate(manifest["config"])
    index = _open_index(out, manifest)
    held_out, training = resimulation_order(table, config)
    sizes = table.groupby("object_id").size()
    pending = [oid for oid in held_out + training if oid not in index["objects"]]
    start, new_grips, done = time.perf_counter(), 0, 0
    for object_id in pending:
        if (limit is not None and done >= limit) or (until is not None
                                                      and datetime.now(UTC) >= until):
            break
        began, began_cpu = time.perf_counter(), time.process_time()
        ((task, rows),) = recorded_objects(source, table, [object_id])
        frame = object_trials(task, rows)
        with deferred_signals():  # the shard and its index entry, never one without the other
            _write_object(out, index, object_id, frame, time.perf_counter() - began,
                          time.process_time() - began_cpu)
        done, new_grips = done + 1, new_grips + len(frame)
        if progress:
            print(f"{object_id}: {len(frame)} grips in {time.perf_counter() - began:.0f} s "
                  f"({len(index['objects'])} of {len(sizes)} objects)", flush=True)
    return _progress(index, sizes, held_out, done, new_grips, time.perf_counter() - start)


def _open_index(out: Path, manifest: dict) -> dict:
    """``out``'s index (made empty for a new folder), checked to be ``manifest``'s dataset."""
    out.mkdir(parents=True, exist_ok=True)
    identity = {"fingerprint": manifest["fingerprint"], "label_model": manifest["label_model"],
                "trials": int(manifest["trials"])}
    path = out / INDEX_FILE
    if not path.exists():
        index = {**identity, "columns": list(trial_columns(identity["trials"])), "objects": {}}
        write_text_atomically(path, json.dumps(index, indent=1) + "\n")
        return index
    index = json.loads(path.read_text(encoding="utf-8"))
    differ = [k for k, v in identity.items() if index.get(k) != v]
    if differ:
        raise ValueError(f"{out} holds the trials of another dataset ({', '.join(differ)} "
                         "differ); choose another folder")
    return index


def shard_file(out: Path, object_id: str) -> Path:
    """``out/<object_id>.parquet``, the id made a safe file name."""
    return out / f"{re.sub(r'[^A-Za-z0-9_.-]+', '_', object_id)}.parquet"


def _write_object(out: Path, index: dict, object_id: str, frame: pd.DataFrame,
                  seconds: float, cpu_seconds: float) -> None:
    """The object's shard, then its index entry: wall ``seconds`` and this process's CPU
    ``cpu_seconds`` (the trials run in it: grip_env is imported first, so its kernels are
    portable), both including the re-planning."""
    path = shard_file(out, object_id)
    table = pa.Table.from_pandas(frame, preserve_index=False)
    checksum = write_atomically(path, lambda temp: pq.write_table(table, temp))
    index["objects"][object_id] = {"file": path.name, "rows": len(frame), "sha256": checksum,
                                   "seconds": round(seconds, 2),
                                   "cpu_seconds": round(cpu_seconds, 2)}
    write_text_atomically(out / INDEX_FILE, json.dumps(index, indent=1) + "\n")


def _progress(index: dict, sizes: pd.Series, held_out: list[str], new_objects: int,
              new_grips: int, seconds: float) -> TrialRecordProgress:
    done = index["objects"]
    return TrialRecordProgress(
        len(done), len(sizes), int(sum(r["rows"] for r in done.values())), int(sizes.sum()),
        sum(oid in done for oid in held_out), len(held_out), new_objects, new_grips, seconds)


def read_trial_shards(folder: str | Path = STANDARD_TRIALS) -> pd.DataFrame:
    """Every finished object's per-trial outcomes in ``folder`` (checksums checked), one row a
    grip: ``object_id``, ``grip_id`` and the trial columns. Empty (those columns) when none.

    Raises:
        ValueError: no index in ``folder``, or a shard differs from its index entry.
    """
    folder = Path(folder)
    path = folder / INDEX_FILE
    if not path.exists():
        raise ValueError(f"{folder} holds no per-trial outcomes ({INDEX_FILE} missing)")
    index = json.loads(path.read_text(encoding="utf-8"))
    frames = []
    for object_id, record in index["objects"].items():
        shard = folder / record["file"]
        if not shard.exists() or sha256_of(shard) != record["sha256"]:
            raise ValueError(f"{shard}: missing or not the file its index lists for {object_id}")
        frames.append(pq.read_table(shard).to_pandas())
    if not frames:
        return pd.DataFrame(columns=["object_id", "grip_id", *index["columns"]])
    return pd.concat(frames, ignore_index=True)


def per_trial_outcomes(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(success bool, robustness g), each grips × trials by trial index, from a grip table
    with the per-trial columns.

    Raises:
        ValueError: the table lacks them (a dataset made before they were recorded), naming
            the way to add them.
    """
    trials = recorded_trials(table.columns)
    if trials == 0:
        raise ValueError(
            "this grip table records no per-trial outcomes (trial_success_k, trial_robustness_k:"
            " datasets made before they were kept lack them); re-simulate them with "
            "`python -m grip_env.dataset.trial_outcomes DIR --out TRIALS` and add them with "
            "grip_env.dataset.trial_outcomes.with_trial_outcomes, or generate the dataset again")
    return (table[list(trial_success_columns(trials))].to_numpy(bool),
            table[list(trial_robustness_columns(trials))].to_numpy(float))


def with_trial_outcomes(table: pd.DataFrame, folder: str | Path = STANDARD_TRIALS,
                        ) -> pd.DataFrame:
    """The grips of ``table`` whose per-trial outcomes ``folder`` holds (the objects re-simulated
    so far), with those columns added; ``attrs`` kept. A table that records every trial already
    (as every dataset ``generate`` writes now) is returned as it is.

    Raises:
        ValueError: as :func:`read_trial_shards`, or the folder's trials are not the table's
            (their summaries differ).
    """
    if any(str(c).startswith(TRIAL_SUCCESS_PREFIX) for c in table.columns):
        return table
    trials = read_trial_shards(folder)
    rows = table.loc[table["grip_id"].isin(trials["grip_id"])]
    merged = rows.merge(trials.drop(columns="object_id"), on="grip_id", how="left",
                        validate="one_to_one")
    success, robust = per_trial_outcomes(merged)
    for object_id, group in merged.groupby("object_id", sort=False):
        at = group.index.to_numpy()
        check_summaries(str(object_id), group, robust[at], success[at])
    merged.attrs = table.attrs
    return merged


def attach_trials(dataset: str | Path, folder: str | Path) -> Path:
    """Write the per-trial outcomes of ``folder`` into the dataset's own files, once every
    object is done: the dataset is packed (:func:`~grip_env.dataset.packing.pack`), its packed
    file rewritten with the trial columns (every summary checked again, bit for bit) and the
    manifest's shard checksums updated; the grips and their order do not change. Returns the
    packed file.

    Raises:
        ValueError: ``folder`` lacks some of the dataset's grips (finish the re-simulation), or
            holds another dataset's trials.
    """
    from grip_env.dataset.manifest import write_manifest
    from grip_env.dataset.packing import ROW_GROUP_ROWS, pack
    from grip_env.dataset.shards import PACKED_FILE, ShardRecord, dataset_schema

    directory, folder = Path(dataset), Path(folder)
    if not (folder / INDEX_FILE).exists():
        raise ValueError(f"{folder} holds no per-trial outcomes ({INDEX_FILE} missing)")
    _open_index(folder, read_manifest(directory))  # the same dataset's trials, or raise
    packed = pack(directory)
    table = load(directory)
    found = with_trial_outcomes(table, folder)
    if len(found) != len(table):
        missing = table.loc[~table["grip_id"].isin(found["grip_id"]), "object_id"].nunique()
        raise ValueError(f"{folder} lacks the trials of {missing} of the dataset's objects: "
                         "finish the re-simulation first")
    schema = dataset_schema(recorded_trials(found.columns))
    rows = pa.Table.from_pandas(found.loc[:, schema.names], schema=schema, preserve_index=False)
    checksum = write_atomically(packed, lambda temp: pq.write_table(
        rows, temp, compression="zstd", row_group_size=ROW_GROUP_ROWS))
    manifest = read_manifest(directory)
    for object_id, record in manifest["shards"].items():
        manifest["shards"][object_id] = ShardRecord(
            PACKED_FILE, int(record["rows"]), checksum, int(record.get("offset", 0))).as_dict()
    manifest["trials_recorded_by"] = "re-simulation (grip_env.dataset.trial_outcomes)"
    write_manifest(directory, manifest)
    return packed


def _until(text: str) -> datetime:
    """``HH:MM`` (UTC): the next such time from now."""
    try:
        hour, minute = (int(part) for part in text.split(":"))
        now = datetime.now(UTC)
        moment = now.replace(hour=hour, minute=minute, second=0, microsecond=0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--until takes HH:MM (UTC), got {text!r}") from None
    return moment if moment > now else moment + timedelta(days=1)


def main(argv: list[str] | None = None) -> None:
    from grip_env.datasets import resolve_data

    parser = argparse.ArgumentParser(prog="python -m grip_env.dataset.trial_outcomes",
                                     description=__doc__.splitlines()[0])  # type: ignore[union-attr]
    parser.add_argument("source", help="the dataset (a folder, or 'standard')")
    parser.add_argument("--out", type=Path, default=None,
                        help="the shards' folder (default for 'standard': grip_env/data/"
                             "standard_trials)")
    parser.add_argument("--until", type=_until, default=None,
                        help="start no object after this time, HH:MM UTC")
    parser.add_argument("--objects", type=int, default=None, help="stop after this many objects")
    parser.add_argument("--attach", action="store_true",
                        help="once every object is done: write the trials into SOURCE's files")
    args = parser.parse_args(argv)
    out = args.out if args.out is not None else (
        STANDARD_TRIALS if args.source == "standard" else None)
    if out is None:
        parser.exit(2, "error: --out is needed for a dataset other than 'standard'\n")
    from grip_env.shutdown import stop_on_signals

    try:  # a signal stops it between writes: the finished objects stay, the same command resumes
        if args.attach:
            print(f"wrote {attach_trials(resolve_data(args.source), out)}")
            return
        with stop_on_signals("run the same command again to continue"):
            found = record_trials(resolve_data(args.source), out, args.until, args.objects)
    except ValueError as exc:
        parser.exit(2, f"error: {exc}\n")
    print(found.summary())


if __name__ == "__main__":
    main()
