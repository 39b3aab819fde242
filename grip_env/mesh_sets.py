"""Object sets of real silhouettes: meshes of ``pybullet_data`` dropped on the table in PyBullet,
at rest, seen from above.

Each mesh is scaled so that the longest side of its bounding box (as the file stands it) is a
size drawn in ``objects.mesh_size_mm`` (seeded by the run seed and the mesh's file, so a mesh's
object does not depend on which others are in the set), released 1.5 mm above the table in the
file's own orientation, and simulated until it is at rest. Its resting pose (kept in the objects
table) gives the silhouette (:mod:`grip_env.objects.meshes`), a ``PlanarObject`` centred on its
centroid that carries the mesh and its pose, so a trial can run on the extrusion of the silhouette
(``objects.execute_on: extrusion``) or on the mesh body itself (``mesh``).

A mesh that does not come to rest, or whose silhouette has several parts or a hole, is refused
by :func:`mesh_object` (``ValueError`` naming it); a set skips it, logs why and lists it in
:attr:`MeshSet.skipped`, and goes on with the next mesh.
"""

from __future__ import annotations

import logging
import zlib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from grip_env.config import ObjectsConfig
from grip_env.objects import PlanarObject, load_object_set
from grip_env.objects.meshes import (
    MESH_SET_NAMES,
    MeshPose,
    mass_properties,
    mesh_label,
    posed_pieces,
    pybullet_data_path,
    read_obj_pieces,
    silhouette,
)
from grip_env.objects.shapes import SetLoader, register_object_set

LOG = logging.getLogger(__name__)

#: Household models of ``pybullet_data``: name -> its collision mesh (a VHACD file when shipped).
HOUSEHOLD_MESHES: dict[str, str] = {
    "duck": "duck_vhacd.obj",
    "teddy": "teddy2_VHACD_CHs.obj",
    "mug": "objects/mug_col.obj",
    "lego": "lego/lego_vhacd.obj",
    "jenga": "jenga/jenga.obj",
    "domino": "domino/domino.obj",
    "cube": "cube.obj",
    "bunny": "bunny.obj",
    "soccerball": "soccerball.obj",
}
#: Mesh object sets: ``household``, ``random_urdfs`` (about 1,000 meshes), and ``mesh`` (both).

RELEASE_GAP_MM = 1.5
SETTLE_WINDOW_S = 0.1
MAX_SETTLE_S = 4.0
REST_DRIFT_MM = 0.05  # per window, at rest
REST_TURN_DEG = 0.05
DROP_MASS_KG = 0.1
DROP_FRICTION = 0.5


@dataclass
class MeshSet:
    """The objects of a mesh set and the meshes it skipped, as (mesh file, reason)."""

    objects: list[PlanarObject] = field(default_factory=list)
    skipped: list[tuple[str, str]] = field(default_factory=list)


def random_urdf_meshes() -> list[Path]:
    """The meshes of ``pybullet_data/random_urdfs`` (``NNN/NNN.obj``), sorted."""
    root = pybullet_data_path() / "random_urdfs"
    return sorted(p for p in root.glob("*/*.obj") if p.stem == p.parent.name)


def household_meshes() -> list[Path]:
    """The household models' meshes, in ``HOUSEHOLD_MESHES`` order."""
    return [pybullet_data_path() / file for file in HOUSEHOLD_MESHES.values()]


def mesh_name(path: Path) -> str:
    """An object name for a mesh: the household name, ``urdf_NNN``, or the file's stem."""
    label = mesh_label(path)
    for name, file in HOUSEHOLD_MESHES.items():
        if label == f"pybullet_data/{file}":
            return name
    if label.startswith("pybullet_data/random_urdfs/"):
        return f"urdf_{path.stem}"
    return path.stem


def mesh_object(
    path: str | Path, size_mm: float, name: str | None = None, margin_mm: float | None = None,
) -> PlanarObject:
    """The resting silhouette of one mesh whose longest bounding-box side is ``size_mm``.

    Raises:
        ValueError: an unreadable mesh, a bad size, a mesh that does not come to rest, or a
            silhouette in several parts or with a hole (naming the mesh).
    """
    from grip_env.sim.world import COLLISION_MARGIN_MM

    path = Path(path)
    name = name or mesh_name(path)
    if not (np.isfinite(size_mm) and size_mm > 0):
        raise ValueError(f"mesh {name!r}: size must be a positive number of mm, got {size_mm!r}")
    margin = COLLISION_MARGIN_MM if margin_mm is None else margin_mm
    pieces = read_obj_pieces(path)
    extent = float(np.ptp(np.vstack(pieces), axis=0).max())
    if extent <= 0:
        raise ValueError(f"mesh {name!r} has no extent")
    scale = size_mm / extent
    pose = rest_pose(path, pieces, scale, name)
    posed = posed_pieces(pieces, pose)
    outline = silhouette(posed, margin, name)
    obj = PlanarObject(outline, name=name, source=mesh_label(path), mesh=pose)
    return obj.centred()


def rest_pose(
    path: Path, pieces: list[NDArray[np.float64]], scale: float, name: str
) -> MeshPose:
    """Drop the mesh (scaled by ``scale`` mm per unit) on the table and return its pose at rest.

    Raises:
        ValueError: still moving after ``MAX_SETTLE_S``, or rolled off the table.
    """
    from grip_env.sim.world import COLLISION_MARGIN_MM, World

    try:
        com, inertia, axes = mass_properties([piece * scale for piece in pieces])
    except ValueError as exc:
        raise ValueError(f"mesh {name!r}: {exc}") from None
    lowest = min(float((piece * scale - com)[:, 2].min()) for piece in pieces)
    start = np.array([0.0, 0.0, -lowest + RELEASE_GAP_MM])
    steps = max(1, round(SETTLE_WINDOW_S * 240))
    with World(timestep=1.0 / 240.0) as world:
        world.add_table()
        body = world.add_mesh(path, scale, com, start, (0.0, 0.0, 0.0, 1.0), DROP_MASS_KG,
                              DROP_FRICTION, inertia, axes)
        previous = world.pose_mm(body.uid)
        for window in range(round(MAX_SETTLE_S / SETTLE_WINDOW_S)):
            world.step(steps)
            current = world.pose_mm(body.uid)
            drift = float(np.linalg.norm(current[0] - previous[0]))
            turn = _turn_deg(previous[1], current[1])
            if np.linalg.norm(current[0][:2]) > 400.0 or current[0][2] < -50.0:
                raise ValueError(f"mesh {name!r} does not rest stably: it rolls off the table")
            if window >= 2 and drift < REST_DRIFT_MM and turn < REST_TURN_DEG:
                break
            previous = current
        else:
            raise ValueError(
                f"mesh {name!r} does not rest stably: still moving after {MAX_SETTLE_S:g} s "
                f"({drift / SETTLE_WINDOW_S:.1f} mm/s, {turn / SETTLE_WINDOW_S:.1f} deg/s)")
    position = current[0]  # the centre of mass; the reported frame is the inertia's axes
    orientation = (Rotation.from_quat(current[1]) * Rotation.from_quat(axes).inv()).as_quat()
    posed = posed_pieces(pieces, MeshPose("", scale, tuple(com), tuple(position),
                                          tuple(orientation), 0.0))
    height = float(max(piece[:, 2].max() for piece in posed)) + COLLISION_MARGIN_MM
    return MeshPose(mesh_label(path), float(scale), tuple(map(float, com)),
                    tuple(map(float, position)), tuple(map(float, orientation)), height)


def _turn_deg(q0: NDArray[np.float64], q1: NDArray[np.float64]) -> float:
    return float(np.degrees((Rotation.from_quat(q0).inv() * Rotation.from_quat(q1)).magnitude()))


def mesh_size(label: str, seed: int, size_range_mm: tuple[float, float]) -> float:
    """The size drawn for mesh ``label``: uniform in the range, from (seed, the label) only."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), zlib.crc32(label.encode())]))
    return float(rng.uniform(*size_range_mm))


def mesh_set(
    name: str, count: int | None = None, seed: int = 0,
    size_range_mm: tuple[float, float] | None = None,
) -> MeshSet:
    """The objects of mesh set ``name`` (``MESH_SET_NAMES``), at most ``count`` of them.

    ``household``: the household models in order; ``random_urdfs``: those meshes permuted by
    ``seed``; ``mesh``: the household models, then the permuted ``random_urdfs``. Meshes that are
    refused are skipped (logged, listed in ``skipped``) and the next one is taken.

    Raises:
        ValueError: unknown set name or a negative count.
    """
    if name not in MESH_SET_NAMES:
        raise ValueError(f"unknown mesh set {name!r}; known: {', '.join(MESH_SET_NAMES)}")
    if count is not None and count < 0:
        raise ValueError(f"mesh count must be >= 0, got {count}")
    sizes = size_range_mm or ObjectsConfig().mesh_size_mm
    files: list[Path] = household_meshes() if name in ("household", "mesh") else []
    if name in ("random_urdfs", "mesh"):
        urdfs = random_urdf_meshes()
        files += [urdfs[i] for i in np.random.default_rng(seed).permutation(len(urdfs))]
    result = MeshSet()
    for path in files:
        if count is not None and len(result.objects) >= count:
            break
        built = _cached_mesh_object(str(path), mesh_size(mesh_label(path), seed, tuple(sizes)))
        if isinstance(built, str):
            LOG.warning("skipped %s: %s", mesh_label(path), built)
            result.skipped.append((mesh_label(path), built))
        else:
            result.objects.append(built)
    return result


@lru_cache(maxsize=4096)
def _cached_mesh_object(path: str, size_mm: float) -> PlanarObject | str:
    """The mesh object, or the reason it is refused (cached: a drop costs tens of ms)."""
    try:
        return mesh_object(path, size_mm)
    except ValueError as exc:
        return str(exc)


def named_set(name: str, seed: int = 0, config: ObjectsConfig | None = None) -> MeshSet:
    """A named object set (see :func:`grip_env.objects.load_object_set`) with the meshes it
    skipped."""
    if name in MESH_SET_NAMES:
        return mesh_set(name, None, seed, (config or ObjectsConfig()).mesh_size_mm)
    return MeshSet(load_object_set(name))


def _load_mesh_set(name: str) -> SetLoader:
    """:func:`load_object_set`'s loader of mesh set ``name``."""
    def load(seed: int, config: ObjectsConfig | None) -> list[PlanarObject]:
        return named_set(name, seed, config).objects

    return load


for _name in MESH_SET_NAMES:
    register_object_set(_name, _load_mesh_set(_name))


def configured_meshes(config: ObjectsConfig, seed: int) -> MeshSet:
    """The ``objects.mesh_count`` mesh objects a run adds to its set (``mesh`` set order)."""
    if config.mesh_count == 0:
        return MeshSet()
    return mesh_set("mesh", config.mesh_count, seed, config.mesh_size_mm)


def mesh_from_spec(
    spec: str, seed: int = 0, config: ObjectsConfig | None = None
) -> PlanarObject | None:
    """The mesh object ``spec`` names (a household model, ``urdf_NNN``, or an ``.obj`` file),
    sized as in a set; None when ``spec`` names no mesh.

    Raises:
        ValueError: the mesh is refused (see :func:`mesh_object`), or no such ``urdf_NNN``.
    """
    if spec in HOUSEHOLD_MESHES:
        path = pybullet_data_path() / HOUSEHOLD_MESHES[spec]
    elif spec.startswith("urdf_") and spec[5:].isdigit():
        path = pybullet_data_path() / "random_urdfs" / spec[5:] / f"{spec[5:]}.obj"
        if not path.is_file():
            raise ValueError(f"no mesh {spec!r}: random_urdfs has urdf_000 to urdf_999")
    elif spec.lower().endswith(".obj") and Path(spec).is_file():
        path = Path(spec)
    else:
        return None
    sizes = (config or ObjectsConfig()).mesh_size_mm
    return mesh_object(path, mesh_size(mesh_label(path), seed, tuple(sizes)))
