"""``manifest.json``: what a dataset is (config, seed, objects), where it came from, what is done.

The manifest is rewritten atomically, and a shard enters it only once the shard file is complete,
so the manifest never lists anything that is not on disk.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import subprocess
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path
from typing import Any

import grip_env
from grip_env.config import DEFAULT_ENGINE, Config
from grip_env.dataset.catalog import OBJECTS_FILE, DatasetObject
from grip_env.dataset.files import write_text_atomically
from grip_env.dataset.sampling import sampling_record
from grip_env.dataset.shards import GRIPS_DIR, SHARD_FILE, ShardRecord
from grip_env.label_model import engine_of, label_model_for
from grip_env.objects.family import object_family

FORMAT = "grip-env-dataset"
#: 2: outcome columns robustness_mean and robustness_std; kept grips chosen by dataset.sampling.
FORMAT_VERSION = 2
MANIFEST_FILE = "manifest.json"
#: Config fields that change how a dataset is computed, not what it holds.
EXECUTION_FIELDS = ("workers", "backend")
#: Config sections only the learning stages read: a dataset is the same run whatever they say.
LEARNING_SECTIONS = ("learning", "selector")
#: Settings added after datasets were made without them, with the value that reproduces those
#: datasets: a run identity leaves them out at that value, so such a dataset stays this code's run.
LATER_SETTINGS: dict[str, dict[str, Any]] = {"synthesis": {"frictional_closure": False},
                                              "sim": {"engine": DEFAULT_ENGINE},
                                              "uncertainty": {"stratified_palm": False}}
_VERSIONED_PACKAGES = ("numpy", "pandas", "pyarrow", "pybullet", "mujoco", "scipy", "shapely",
                       "pydantic")

Manifest = dict[str, Any]


class FormatVersionError(ValueError):
    """A dataset written in another format version than this grip-env reads."""

    def __init__(self, directory: Path, version: object) -> None:
        self.version = version
        if not isinstance(version, int) or isinstance(version, bool):
            super().__init__(
                f"dataset {directory} has format_version {_described(version)}, not an integer "
                f"(this grip-env reads format version {FORMAT_VERSION}): regenerate it "
                "(grip-env generate --overwrite into it)"
            )
            return
        if version < FORMAT_VERSION:
            advice = "it is too old: regenerate it (grip-env generate --overwrite into it)"
        else:
            advice = "it is newer: upgrade grip-env to read it"
        super().__init__(
            f"dataset {directory} has format version {version!r}, this grip-env reads version "
            f"{FORMAT_VERSION}; {advice}"
        )


class CorruptManifestError(ValueError):
    """A manifest that cannot be read as JSON (a truncated copy, a disk that filled up)."""

    def __init__(self, path: Path, reason: object) -> None:
        super().__init__(
            f"{path} is corrupt ({reason}): the dataset cannot be read without it; restore "
            f"{MANIFEST_FILE} from a copy of the dataset, or rerun the generate command that made "
            "it with --overwrite to regenerate it"
        )


def _described(value: object) -> str:
    """``value`` with its type, for a message: "the string '2'", "None"."""
    kinds = {str: "the string", float: "the float", bool: "the boolean"}
    kind = kinds.get(type(value))
    return f"{kind} {value!r}" if kind else f"{value!r} ({type(value).__name__})"


def run_identity(
    config: Config, entries: list[DatasetObject], own_objects: bool = False
) -> dict[str, Any]:
    """Everything that determines a dataset's rows: config (minus execution fields, the learning
    sections and :data:`LATER_SETTINGS` at their reproducing value), objects and the label model
    (a new one never resumes an old run). ``sim.engine`` is one of those later settings, so a
    PyBullet run keeps the identity it had before engines could be chosen.

    Named and procedural objects are fixed by their ids and the config; a caller's own objects
    (``own_objects``) also by the SHA-256 of their contours, so an edited file is a new run.
    """
    settings = config.model_dump(mode="json")
    for name in EXECUTION_FIELDS:
        settings["dataset"].pop(name, None)
    for section, later in LATER_SETTINGS.items():
        for name, value in later.items():
            if settings[section].get(name) == value:
                del settings[section][name]
    identity = {"config": settings, "object_ids": [entry.object_id for entry in entries],
                "label_model": label_model_for(config.sim.engine)}
    if own_objects:
        identity["object_contours_sha256"] = contours_sha256(entries)
    return without_learning(identity)


def contours_sha256(entries: list[DatasetObject]) -> str:
    """SHA-256 of the objects' contours (float64 bytes, in run order)."""
    digest = hashlib.sha256()
    for entry in entries:
        digest.update(len(entry.obj.contour).to_bytes(8, "little"))
        digest.update(entry.obj.contour.astype("<f8").tobytes())
    return digest.hexdigest()


def without_learning(identity: dict[str, Any]) -> dict[str, Any]:
    """A run identity without :data:`LEARNING_SECTIONS` (older manifests recorded them)."""
    settings = {k: v for k, v in identity.get("config", {}).items() if k not in LEARNING_SECTIONS}
    return {**identity, "config": settings}


def fingerprint(identity: dict[str, Any]) -> str:
    """SHA-256 of the canonical JSON of a run identity."""
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()


def new_manifest(
    config: Config, entries: list[DatasetObject], object_seeds: list[int], objects_sha256: str,
    own_objects: bool = False,
) -> Manifest:
    """The manifest of a run that has no shard yet (``own_objects``: see :func:`run_identity`)."""
    identity = run_identity(config, entries, own_objects)
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "package_version": grip_env.__version__,
        "git_commit": _git_commit(),
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "versions": _versions(),
        "label_model": label_model_for(config.sim.engine),
        "engine": engine_record(config.sim.engine),
        "seed": config.dataset.seed,
        "trials": config.dataset.trials,
        "sampling": sampling_record(config.dataset),
        "params": config.grasp.model_dump(mode="json"),
        "feature_cap": config.grasp.feature_cap,
        "config": config.model_dump(mode="json"),
        "identity": identity,
        "fingerprint": fingerprint(identity),
        "objects": [
            {"index": e.index, "object_id": e.object_id, "name": e.obj.name,
             "source": e.obj.source, "family": object_family(e.obj), "seed": seed}
            for e, seed in zip(entries, object_seeds, strict=True)
        ],
        "objects_file": {"file": "objects.parquet", "sha256": objects_sha256},
        "shards": {},
        "rows": 0,
        "complete": False,
    }


def read_manifest(directory: Path) -> Manifest:
    """Read and check the manifest of a dataset directory.

    Raises:
        ValueError: no manifest, or not a grip-env dataset.
        CorruptManifestError: a manifest that is not JSON (a ``ValueError``).
        FormatVersionError: a dataset of another format version (a ``ValueError``).
    """
    path = Path(directory) / MANIFEST_FILE
    if not path.is_file():
        raise ValueError(f"{directory} is not a grip-env dataset: {MANIFEST_FILE} is missing")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CorruptManifestError(path, exc) from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise ValueError(f"{path} is not a grip-env dataset manifest")
    version = manifest.get("format_version")
    if version != FORMAT_VERSION:
        raise FormatVersionError(directory, version)
    _check_files(path, manifest)
    if isinstance(manifest.get("identity"), dict):
        manifest["identity"] = without_learning(manifest["identity"])
    return manifest


def _check_files(path: Path, manifest: Manifest) -> None:
    """Every file the manifest names is a shard in ``grips/`` or ``objects.parquet``: a crafted
    manifest cannot point a reader outside the dataset directory."""
    shards = manifest.get("shards")
    if not isinstance(shards, dict) or not isinstance(manifest.get("objects"), list):
        raise ValueError(f"{path} is corrupt: no shards or objects list")
    for object_id, record in shards.items():
        file = record.get("file") if isinstance(record, dict) else None
        if not isinstance(file, str) or not SHARD_FILE.fullmatch(file):
            raise ValueError(
                f"{path} is corrupt: object {object_id!r} names shard file {file!r}, "
                f"not a {GRIPS_DIR}/part-*.parquet file of the dataset"
            )
    listed = manifest.get("objects_file")
    objects_file = listed.get("file") if isinstance(listed, dict) else listed
    if objects_file != OBJECTS_FILE:
        raise ValueError(f"{path} is corrupt: objects file {objects_file!r} is not {OBJECTS_FILE}")


def write_manifest(directory: Path, manifest: Manifest) -> None:
    """Atomically (re)write the manifest, with its row total updated."""
    manifest["rows"] = sum(record["rows"] for record in manifest["shards"].values())
    write_text_atomically(Path(directory) / MANIFEST_FILE, json.dumps(manifest, indent=1) + "\n")


def shard_records(manifest: Manifest) -> dict[str, ShardRecord]:
    """Completed shards by object id."""
    return {object_id: ShardRecord(**record) for object_id, record in manifest["shards"].items()}


def objects_without_grips(manifest: Manifest) -> list[str]:
    """The ids of the finished objects that got no grip (a shard of 0 rows), in run order."""
    shards = manifest["shards"]
    return [entry["object_id"] for entry in manifest["objects"]
            if entry["object_id"] in shards and shards[entry["object_id"]]["rows"] == 0]


def identity_differences(old: dict[str, Any], new: dict[str, Any], prefix: str = "") -> list[str]:
    """Human-readable ``key: old -> new`` lines where two run identities differ."""
    if isinstance(old, dict) and isinstance(new, dict):
        lines = []
        for key in sorted(set(old) | set(new)):
            lines += identity_differences(old.get(key), new.get(key), f"{prefix}{key}.")
        return lines
    if old == new:
        return []
    if isinstance(old, list) and isinstance(new, list) and len(old) + len(new) > 6:
        return [f"{prefix.rstrip('.')}: {len(old)} entries -> {len(new)} entries (differ)"]
    return [f"{prefix.rstrip('.')}: {old!r} -> {new!r}"]


def earlier_runs(manifest: Manifest) -> list[dict[str, Any]]:
    """The runs at fewer trials a grip that ``trial_extension`` grew this dataset from, oldest
    first: each its ``git_commit``, ``trials`` and ``sessions`` (its cost)."""
    return list(manifest.get("trials_added_to", []))


def session_record(started: datetime, seconds: float, workers: int, backend: str, objects: int,
                   rows: int, git_commit: str | None, engine: str = DEFAULT_ENGINE,
                   ) -> dict[str, Any]:
    """One ``generate`` run's share of a dataset (``manifest["sessions"]``): a resumed dataset
    lists every run, so its cost (core-hours, grips per core-second) adds up across them. It
    names the label model ``engine`` made (``label_model_for``) and that engine's version."""
    return {"started": started.isoformat(timespec="seconds"), "seconds": round(seconds, 1),
            "workers": workers, "backend": backend, "objects": objects, "rows": rows,
            "git_commit": git_commit, "label_model": label_model_for(engine),
            "engine": engine_record(engine), "machine": _machine()}


def _machine() -> str:
    """The CPU model and the number of logical CPUs, e.g. ``AMD EPYC 7B13 x 2``."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model} x {os.cpu_count()}"


def engine_record(name: str) -> dict[str, str | None]:
    """The physics engine that made the labels and its installed version (the distribution's,
    which is ``mujoco.__version__`` for MuJoCo; None when it is not installed)."""
    try:
        version: str | None = metadata.version(name)
    except metadata.PackageNotFoundError:
        version = None
    return {"name": name, "version": version}


def recorded_engine(manifest: dict[str, Any]) -> dict[str, str | None]:
    """The engine a manifest says made its labels, with that engine's version: its ``engine``
    record, else (a dataset made before engines were recorded) the engine it names
    (``engine_of``) and the version of that package its ``versions`` recorded when it was made."""
    recorded = manifest.get("engine")
    if isinstance(recorded, dict) and isinstance(recorded.get("name"), str):
        return {"name": recorded["name"], "version": recorded.get("version")}
    name = engine_of(manifest)
    versions = manifest.get("versions")
    version = versions.get(name) if isinstance(versions, dict) else None
    return {"name": name, "version": version if isinstance(version, str) else None}


def _versions() -> dict[str, str]:
    found = {"python": platform.python_version()}
    for name in _VERSIONED_PACKAGES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return found


def current_commit() -> str | None:
    """The checkout's commit (read when a run starts: a run that commits its own shards as it
    goes moves HEAD without changing the code)."""
    return _git_commit()


def _git_commit() -> str | None:
    try:
        result = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=Path(__file__).parent, capture_output=True,
            text=True, timeout=5, check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return result.stdout.strip() or None if result.returncode == 0 else None
