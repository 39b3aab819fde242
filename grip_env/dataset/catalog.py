"""The objects of a dataset: which objects a run covers, and their table ``objects.parquet``."""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from grip_env.columns import FAMILY
from grip_env.config import Config, check_contour_budget
from grip_env.dataset.files import write_atomically
from grip_env.mesh_sets import configured_meshes, named_set
from grip_env.objects import PlanarObject, procedural_objects
from grip_env.objects.family import object_family
from grip_env.objects.meshes import MESH_COLUMNS, MeshPose
from grip_env.objects.simulated import DEFAULT_TOLERANCE_MM

OBJECTS_FILE = "objects.parquet"


@dataclass(frozen=True, eq=False)
class DatasetObject:
    """One object of a dataset: its position in the run, unique id and polygon."""

    index: int
    object_id: str
    obj: PlanarObject


ObjectsSpec = str | int | Sequence[PlanarObject] | None
_UNSAFE = re.compile(r"[^A-Za-z0-9_.+-]+")


def resolve_objects(config: Config, objects: ObjectsSpec, seed: int) -> list[DatasetObject]:
    """The objects a run covers, with unique ids that are safe file names.

    Args:
        config: supplies ``objects.set``, ``procedural_count`` and ``procedural_size_mm``
            when ``objects`` is None, and the contour budget (``perception``).
        objects: a named object set (or shape name), a number of procedural objects (an int or
            a string of digits), a list of ``PlanarObject``, or None for the config's set plus
            its procedural objects.
        seed: the run seed; procedural objects are drawn from it.

    Raises:
        ValueError: unknown object set, negative count, no object at all, or an object too
            large or detailed to process (naming its source file when it has one).
    """
    shapes = _shapes(config, objects, seed)
    if not shapes:
        raise ValueError("the run has no objects: choose an object set or a count >= 1")
    for shape in shapes:
        _check_budget(shape, config)
    return [DatasetObject(i, object_id, obj) for i, (object_id, obj) in
            enumerate(zip(_unique_ids([s.name for s in shapes]), shapes, strict=True))]


def own_objects(objects: ObjectsSpec) -> bool:
    """Whether ``objects`` is the caller's own list (whose contours identify the run)."""
    return not isinstance(objects, (str, int, type(None)))


def _shapes(config: Config, objects: ObjectsSpec, seed: int) -> list[PlanarObject]:
    size = config.objects.procedural_size_mm
    if isinstance(objects, str) and objects.strip().lstrip("-").isdigit():
        objects = int(objects)
    if isinstance(objects, bool):
        raise ValueError(f"objects must be a set name or a count, got {objects!r}")
    if isinstance(objects, int):
        if objects < 1:
            raise ValueError(f"number of objects must be >= 1, got {objects}")
        return procedural_objects(objects, seed, size)
    if isinstance(objects, str):
        return named_set(objects, seed, config.objects).objects
    if objects is not None:
        shapes = list(objects)
        wrong = [type(s).__name__ for s in shapes if not isinstance(s, PlanarObject)]
        if wrong:
            raise ValueError(f"objects must be PlanarObject instances, got a {wrong[0]}")
        return shapes
    named = config.objects.set
    shapes = [] if named == "procedural" else named_set(named, seed, config.objects).objects
    shapes += procedural_objects(config.objects.procedural_count, seed, size)
    return shapes + configured_meshes(config.objects, seed).objects


def skipped_objects(config: Config, objects: ObjectsSpec, seed: int) -> list[dict[str, str]]:
    """The meshes a run's sets skipped, with the reason (recorded in the manifest)."""
    skipped = []
    if isinstance(objects, str) and not objects.strip().lstrip("-").isdigit():
        skipped = named_set(objects, seed, config.objects).skipped
    elif objects is None:
        named = config.objects.set
        if named != "procedural":
            skipped = named_set(named, seed, config.objects).skipped
        skipped = skipped + configured_meshes(config.objects, seed).skipped
    return [{"mesh": mesh, "reason": reason} for mesh, reason in skipped]


def _check_budget(obj: PlanarObject, config: Config) -> None:
    """Refuse an object too large or detailed to process, or one the simulator cannot build
    within ``objects.sim_tolerance_mm`` (its shape is then cached for the objects table)."""
    low, high = obj.contour.min(axis=0), obj.contour.max(axis=0)
    try:
        check_contour_budget(obj.name, len(obj.contour), float(obj.polygon.length),
                             float((high - low).max()), config.perception)
        obj.simulated_shape(config.objects.sim_tolerance_mm)
    except ValueError as exc:
        if obj.source in ("polygon", "mask"):
            raise
        raise ValueError(f"object file {obj.source}: {exc}") from None


def _unique_ids(names: list[str]) -> list[str]:
    """Object names as safe file names (letters, digits, ``_.+-``; no leading dot), with
    ``-<n>`` appended to repeated ones (skipping any ``-<n>`` another name already is)."""
    safe = [_UNSAFE.sub("_", name).lstrip(".") or "object" for name in names]
    repeated = {name for name, count in Counter(safe).items() if count > 1}
    taken = set(safe) - repeated
    seen: Counter[str] = Counter()
    ids = []
    for name in safe:
        if name in repeated:
            seen[name] += 1
            while f"{name}-{seen[name]}" in taken:
                seen[name] += 1
            name = f"{name}-{seen[name]}"
        taken.add(name)
        ids.append(name)
    return ids


def objects_table(
    entries: list[DatasetObject], tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    perceived: Sequence[PlanarObject] | None = None,
) -> pa.Table:
    """One row per object: id, name, source, contour (list of [x, y] mm) and descriptors, then
    its simulated shape within ``tolerance_mm``: ``sim_*`` columns (vertex and piece counts,
    tolerance, deviation bound, area, whether approximate) and ``sim_contour``; its ``family``
    (``grip_env.objects.family``) and, for a mesh object, the mesh and its resting pose
    (``mesh_*`` columns, empty otherwise); ``perceived_contour``: the contour the grips were
    planned on when that is the render's (``perceived``, in entry order), else empty."""
    if perceived is not None and len(perceived) != len(entries):
        raise ValueError(f"{len(perceived)} perceived objects for {len(entries)} entries")
    seen = [None] * len(entries) if perceived is None else [p.contour.tolist() for p in perceived]
    rows = [{
        "object_index": entry.index,
        "object_id": entry.object_id,
        "name": entry.obj.name,
        "source": entry.obj.source,
        "vertices": len(entry.obj.contour),
        "contour": entry.obj.contour.tolist(),
        **entry.obj.descriptors(),
        **entry.obj.simulated_shape(tolerance_mm).record(),
        "sim_contour": entry.obj.simulated_shape(tolerance_mm).contour.tolist(),
        FAMILY: object_family(entry.obj),
        **_mesh_record(entry.obj),
        "perceived_contour": contour,
    } for entry, contour in zip(entries, seen, strict=True)]
    return pa.Table.from_pylist(rows, schema=_with_contour_type(pa.Table.from_pylist(rows).schema))


def _with_contour_type(schema: pa.Schema) -> pa.Schema:
    """``perceived_contour`` typed as a contour (list of [x, y]) even when every row is empty."""
    index = schema.get_field_index("perceived_contour")
    return schema.set(index, pa.field("perceived_contour", pa.list_(pa.list_(pa.float64()))))


def _mesh_record(obj: PlanarObject) -> dict[str, object]:
    if obj.mesh is None:
        return dict.fromkeys(MESH_COLUMNS)
    return obj.mesh.record()


def write_objects(
    directory: Path, entries: list[DatasetObject], tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    perceived: Sequence[PlanarObject] | None = None,
) -> str:
    """Write ``objects.parquet`` atomically; returns its SHA-256."""
    table = objects_table(entries, tolerance_mm, perceived)
    return write_atomically(directory / OBJECTS_FILE, lambda temp: pq.write_table(table, temp))


def read_objects(directory: Path) -> pd.DataFrame:
    """The objects table of a dataset directory."""
    path = Path(directory) / OBJECTS_FILE
    if not path.is_file():
        raise ValueError(f"{path} is missing")
    try:
        return pq.read_table(path).to_pandas()
    except (OSError, pa.ArrowException) as exc:
        raise ValueError(f"{path} is corrupt: {exc}") from None


def load_perceived_objects(directory: str | Path) -> list[PlanarObject | None]:
    """The contours the dataset's grips were planned on when they were the render's
    (``perceived_contour``), in run order; None for objects planned on their true contour (and
    for every object of a dataset written before the column existed)."""
    table = read_objects(Path(directory)).sort_values("object_index")
    if "perceived_contour" not in table.columns:
        return [None] * len(table)
    return [
        None if contour is None else PlanarObject(np.array([list(p) for p in contour]),
                                                  name=object_id, source="render")
        for object_id, contour in zip(table["object_id"], table["perceived_contour"], strict=True)
    ]


def load_objects(directory: str | Path) -> list[PlanarObject]:
    """The dataset's objects as ``PlanarObject`` (name = object_id), in run order."""
    table = read_objects(Path(directory)).sort_values("object_index")
    return [
        PlanarObject(np.array([list(p) for p in row["contour"]]), name=row["object_id"],
                     source=row["source"], mesh=MeshPose.from_record(row))
        for row in table.to_dict("records")
    ]
