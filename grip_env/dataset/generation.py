"""``generate``: build a dataset directory, resumably, with any backend.

Each finished object is written as its own shard (temp file + atomic rename) and only then
entered in the manifest, so an interrupted run loses at most the objects in flight; running the
same call again computes only what is missing. One run at a time may write a directory (an
``flock``); a second is refused with :class:`~grip_env.dataset.lock.DatasetLockedError`.
"""

from __future__ import annotations

import shutil
import time
from datetime import UTC, datetime
from pathlib import Path

from grip_env.config import Config
from grip_env.dataset.backends import check_backend, run_jobs
from grip_env.dataset.catalog import (
    OBJECTS_FILE,
    DatasetObject,
    ObjectsSpec,
    own_objects,
    resolve_objects,
    skipped_objects,
    write_objects,
)
from grip_env.dataset.files import check_writable, sha256_of
from grip_env.dataset.jobs import (
    ObjectJob,
    ObjectTask,
    object_seeds,
    planning_contour,
    plans_on_render,
    simulate_object,
)
from grip_env.dataset.lock import dataset_lock
from grip_env.dataset.manifest import (
    FORMAT_VERSION,
    MANIFEST_FILE,
    CorruptManifestError,
    FormatVersionError,
    Manifest,
    current_commit,
    identity_differences,
    new_manifest,
    read_manifest,
    run_identity,
    session_record,
    shard_records,
    write_manifest,
)
from grip_env.dataset.shards import GRIPS_DIR, shard_path, write_shard
from grip_env.label_model import engine_of
from grip_env.objects import PlanarObject
from grip_env.progress import progress_bar
from grip_env.shutdown import deferred_signals

_MANIFEST_FLUSH_SECONDS = 1.0


class DatasetMismatchError(ValueError):
    """The output directory holds a dataset made with another config, seed or object list."""


def generate(
    config: Config,
    out_dir: str | Path,
    objects: ObjectsSpec = None,
    trials: int | None = None,
    seed: int | None = None,
    workers: int | None = None,
    backend: str | None = None,
    address: str | None = None,
    progress: bool = True,
    overwrite: bool = False,
    job: ObjectJob = simulate_object,
) -> Path:
    """Generate (or finish) a grip dataset in ``out_dir``.

    Args:
        config: the run configuration; ``trials``, ``seed``, ``workers`` and ``backend`` default
            to its ``dataset`` section.
        out_dir: dataset directory (created if needed).
        objects: a named object set, a number of procedural objects, a list of ``PlanarObject``
            (ids from their names, made safe file names), or None for ``config.objects``.
        trials: simulated trials per grip (>= 1).
        seed: run seed; object ``i`` gets a seed derived from (seed, i).
        workers: parallel workers (>= 1); the dataset does not depend on it.
        backend: ``"process"`` (local process pool) or ``"ray"``.
        address: Ray cluster address (``backend="ray"`` only; local instance when None).
        progress: show a progress bar on stderr.
        overwrite: replace a dataset made with another config, seed or object list.
        job: the per-object function (default: plan, simulate, label).

    Returns:
        The dataset directory.

    Raises:
        DatasetMismatchError: ``out_dir`` holds another run's dataset and ``overwrite`` is False.
        DatasetLockedError: another run is writing ``out_dir``.
        WorkerLost: an object lost its worker process on every attempt.
        OSError: a write failed (disk full); finished shards stay and a rerun continues.
        ValueError: bad argument, unknown object set, unwritable directory.
    """
    config = _effective_config(config, trials, seed)
    workers = config.dataset.workers if workers is None else workers
    backend = config.dataset.backend if backend is None else backend
    check_backend(backend, workers)
    if address is not None and backend != "ray":
        raise ValueError(f"address {address!r} is for backend 'ray' only, not {backend!r}")
    directory = Path(out_dir)
    entries = resolve_objects(config, objects, config.dataset.seed)
    check_writable(directory)
    with dataset_lock(directory):
        manifest, perceived = _open_run(directory, config, entries, overwrite,
                                        own_objects(objects))
        skipped = skipped_objects(config, objects, config.dataset.seed)
        if skipped and manifest.get("skipped_objects") != skipped:
            manifest["skipped_objects"] = skipped  # meshes a set refused, with the reason
            write_manifest(directory, manifest)
        seeds = [record["seed"] for record in manifest["objects"]]
        pending = [
            ObjectTask(e.index, e.object_id, e.obj, config, seeds[e.index],
                       None if perceived is None else perceived[e.index])
            for e in entries if not _is_done(directory, manifest, e)
        ]
        if backend == "process":  # no more processes than objects left (one: none at all)
            workers = max(1, min(workers, len(pending)))
        _run(directory, manifest, job, pending, len(entries), workers, backend, address, progress)
    return directory


def _effective_config(config: Config, trials: int | None, seed: int | None) -> Config:
    overrides = {"trials": trials, "seed": seed}
    for name, value in overrides.items():
        if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
            raise ValueError(f"{name} must be an integer, got {value!r}")
    if trials is not None and trials < 1:
        raise ValueError(f"trials must be >= 1, got {trials}")
    if seed is not None and seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    changes = {name: value for name, value in overrides.items() if value is not None}
    return config.override(dataset=changes) if changes else config


def _open_run(
    directory: Path, config: Config, entries: list[DatasetObject], overwrite: bool, own: bool
) -> tuple[Manifest, list[PlanarObject] | None]:
    """The manifest to continue: the existing one if it is the same run, else a fresh one; and
    a fresh run's perceived objects (None when continuing, or planning on the true ones)."""
    if (directory / MANIFEST_FILE).exists():
        old, differences = _compare_with_existing(directory, config, entries, own)
        if old is not None and not differences:
            return old, None
        if not overwrite:
            raise DatasetMismatchError(
                f"{directory} holds a dataset made with other settings ({'; '.join(differences)}"
                "); use --overwrite to replace it, or choose another directory"
            )
        _remove_dataset(directory)
    elif overwrite:
        _remove_dataset(directory)
    seeds = object_seeds(config.dataset.seed, len(entries))
    start = time.perf_counter()
    perceived = _perceived(config, entries, seeds)
    perception_s = time.perf_counter() - start
    objects_sha = write_objects(directory, entries, config.objects.sim_tolerance_mm, perceived)
    manifest = new_manifest(config, entries, seeds, objects_sha, own)
    if perceived is not None:
        manifest["perception_seconds"] = round(perception_s, 3)  # render + segment, all objects
    write_manifest(directory, manifest)
    return manifest, perceived


def _perceived(
    config: Config, entries: list[DatasetObject], seeds: list[int]
) -> list[PlanarObject] | None:
    """The contours the grips are planned on, when they are the render's (one PyBullet
    connection for all); None when grips are planned on the true objects."""
    if not plans_on_render(config):
        return None
    from grip_env.sim.world import World

    with World() as world:
        return [planning_contour(ObjectTask(e.index, e.object_id, e.obj, config, seeds[e.index]),
                                 world) for e in entries]


def _compare_with_existing(
    directory: Path, config: Config, entries: list[DatasetObject], own: bool
) -> tuple[Manifest | None, list[str]]:
    """The dataset already in ``directory`` and how its run differs from this one."""
    try:
        old = read_manifest(directory)
    except FormatVersionError as exc:
        return None, [f"format_version: {exc.version!r} -> {FORMAT_VERSION}"]
    except CorruptManifestError:
        return None, [f"its {MANIFEST_FILE} is unreadable"]
    return old, identity_differences(old["identity"], run_identity(config, entries, own))


def _remove_dataset(directory: Path) -> None:
    """Delete the files of a dataset (and nothing else in the directory)."""
    (directory / MANIFEST_FILE).unlink(missing_ok=True)
    (directory / OBJECTS_FILE).unlink(missing_ok=True)
    shutil.rmtree(directory / GRIPS_DIR, ignore_errors=True)


def _is_done(directory: Path, manifest: Manifest, entry: DatasetObject) -> bool:
    """Whether the object's shard is in the manifest and intact on disk."""
    record = shard_records(manifest).get(entry.object_id)
    if record is None:
        return False
    path = directory / record.file
    if path.is_file() and sha256_of(path) == record.sha256:
        return True
    del manifest["shards"][entry.object_id]
    return False


def _run(
    directory: Path, manifest: Manifest, job: ObjectJob, pending: list[ObjectTask], total: int,
    workers: int, backend: str, address: str | None, progress: bool,
) -> None:
    started, rows, last_flush = time.perf_counter(), 0, 0.0
    began, done, commit = datetime.now(UTC), 0, current_commit()
    feature_cap = manifest["feature_cap"]
    with progress_bar(total, "generate", done=total - len(pending), enabled=progress) as bar:
        try:
            for task, grips in run_jobs(job, pending, workers, backend, address):
                path = shard_path(directory, task.index, task.object_id)
                metadata = {"object_id": task.object_id, "object_index": task.index,
                            "feature_cap": feature_cap, "params": manifest["params"],
                            "sampling": manifest["sampling"]}
                with deferred_signals():  # a shard is written and listed whole, or not at all
                    record = write_shard(path, grips, metadata)
                    manifest["shards"][task.object_id] = record.as_dict()
                    if time.perf_counter() - last_flush >= _MANIFEST_FLUSH_SECONDS:
                        write_manifest(directory, manifest)
                        last_flush = time.perf_counter()
                rows += record.rows
                done += 1
                bar.advance(1, info=f"{rows} grips, {rows / _elapsed(started):.1f} grips/s")
        finally:
            manifest["complete"] = len(manifest["shards"]) == total
            if done:
                manifest.setdefault("sessions", []).append(session_record(
                    began, _elapsed(started), workers, backend, done, rows, commit,
                    engine_of(manifest)))
            try:
                write_manifest(directory, manifest)
            except OSError:  # disk full: a shard the manifest on disk does not list goes
                _drop_unlisted_shards(directory)
                raise


def _drop_unlisted_shards(directory: Path) -> None:
    """Remove the shard files the manifest on disk does not list (a rerun recomputes them), so
    that every shard is written and listed whole, or not at all."""
    try:
        listed = {Path(r.file).name for r in shard_records(read_manifest(directory)).values()}
    except (OSError, ValueError):
        return
    for path in (directory / GRIPS_DIR).glob("*.parquet"):
        if path.name not in listed:
            path.unlink(missing_ok=True)


def _elapsed(started: float) -> float:
    return max(time.perf_counter() - started, 1e-9)
