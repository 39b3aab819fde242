"""Mesh objects: a mesh file resting on the table, and its top-down silhouette as a planar object.

The geometry only: reading a Wavefront OBJ file into the convex pieces PyBullet builds from it
(one convex hull per ``o``/``g`` object of the file, as for a VHACD decomposition), and projecting
the pieces, in a resting pose, onto the table. The resting pose itself comes from the simulator
(:mod:`grip_env.mesh_sets`). The silhouette is the union of the pieces' projected convex hulls,
grown by the engine's collision margin (Bullet collides a convex hull grown by it), so it is the
outline of the simulated body seen from above. A silhouette in several parts, or with a hole,
is not one planar object: it is refused with a ``ValueError`` naming the mesh.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import shapely
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, QhullError
from scipy.spatial.transform import Rotation
from shapely.geometry import MultiPoint, Polygon

from grip_env.columns import MESH_POSE
from grip_env.config import ObjectsConfig

#: The object sets of pybullet_data meshes (loaded by :func:`grip_env.objects.load_object_set`;
#: built by :mod:`grip_env.mesh_sets`, which drops each mesh in the simulator until it rests).
MESH_SET_NAMES = ("household", "random_urdfs", "mesh")
#: Parts and holes of a silhouette smaller than this (mm²) are numerical slivers between pieces.
SLIVER_MM2 = 1.0
#: The silhouette is simplified within this distance (mm): far below the perception's pixel.
SIMPLIFY_MM = 0.05
#: Posed vertices are rounded to this grid (mm) before the outline is built: the rotation's last
#: bits depend on the CPU's vector kernels (numpy's dispatch), and an outline must not.
VERTEX_GRID_DECIMALS = 6
#: Largest mesh file read.
MAX_MESH_FILE_BYTES = 32_000_000


@dataclass(frozen=True)
class MeshPose:
    """A mesh resting on the table, in the planar object's frame (mm).

    Attributes:
        file: the mesh file (``pybullet_data/...`` for a file of the installed package).
        scale: millimetres per mesh unit.
        com_mm: the body's centre of mass in the mesh frame (mm).
        position_mm: where that centre of mass rests (x, y in the object's plane frame, z above
            the table).
        orientation: the resting orientation, a quaternion (x, y, z, w).
        height_mm: the resting body's height above the table (mm).
    """

    file: str
    scale: float
    com_mm: tuple[float, float, float]
    position_mm: tuple[float, float, float]
    orientation: tuple[float, float, float, float]
    height_mm: float

    def shifted(self, offset_mm: NDArray[np.float64]) -> MeshPose:
        """The same pose moved by ``offset_mm`` (x, y) in the plane."""
        x, y, z = self.position_mm
        return MeshPose(self.file, self.scale, self.com_mm,
                        (x + float(offset_mm[0]), y + float(offset_mm[1]), z),
                        self.orientation, self.height_mm)

    def path(self) -> Path:
        """The mesh file on this machine."""
        if self.file.startswith("pybullet_data/"):
            return pybullet_data_path() / self.file.removeprefix("pybullet_data/")
        return Path(self.file)

    def record(self) -> dict[str, object]:
        """The mesh columns of the objects table."""
        return {"mesh_file": self.file, "mesh_scale": self.scale, "mesh_com_mm": list(self.com_mm),
                "mesh_position_mm": list(self.position_mm),
                "mesh_orientation": list(self.orientation), "mesh_height_mm": self.height_mm}

    @classmethod
    def from_record(cls, row: dict) -> MeshPose | None:
        """The pose of an objects-table row, None when the object has no mesh."""
        file = row.get("mesh_file")
        if not isinstance(file, str) or not file:
            return None
        return cls(file, float(row["mesh_scale"]), tuple(map(float, row["mesh_com_mm"])),
                   tuple(map(float, row["mesh_position_mm"])),
                   tuple(map(float, row["mesh_orientation"])), float(row["mesh_height_mm"]))


#: The objects table's mesh columns, empty (None) for an object without a mesh.
MESH_COLUMNS = MESH_POSE


def executes_on_mesh(obj: object, objects: ObjectsConfig) -> bool:
    """Whether ``obj``'s trials run on its mesh (``objects.execute_on: mesh`` and it has one)."""
    return objects.execute_on == "mesh" and getattr(obj, "mesh", None) is not None


def execution_height_mm(obj: object, objects: ObjectsConfig) -> float:
    """Height of the body ``obj``'s trials run on: its mesh at rest, or the extrusion's."""
    if executes_on_mesh(obj, objects):
        return float(obj.mesh.height_mm)  # type: ignore[attr-defined]
    return float(objects.thickness_mm)


def pybullet_data_path() -> Path:
    """The installed ``pybullet_data`` folder."""
    import pybullet_data

    return Path(pybullet_data.getDataPath())


def mesh_label(path: Path) -> str:
    """``pybullet_data/<relative path>`` for a file of the installed package, else the path."""
    try:
        return "pybullet_data/" + path.resolve().relative_to(pybullet_data_path().resolve()
                                                             ).as_posix()
    except ValueError:
        return path.as_posix()


def read_obj_pieces(path: Path) -> list[NDArray[np.float64]]:
    """The vertices (k, 3) of each object (``o`` or ``g``) of a Wavefront OBJ file that has
    faces: the pieces PyBullet builds one convex hull each from.

    Raises:
        ValueError: unreadable, too large, or no face at all (naming the file).
    """
    try:
        if path.stat().st_size > MAX_MESH_FILE_BYTES:
            raise ValueError(f"mesh {path} is larger than {MAX_MESH_FILE_BYTES} bytes")
        text = path.read_text(errors="replace")
    except OSError as exc:
        raise ValueError(f"cannot read mesh {path}: {exc}") from None
    vertices: list[list[float]] = []
    groups: list[set[int]] = [set()]
    for line in text.splitlines():
        fields = line.split()
        if not fields:
            continue
        if fields[0] == "v" and len(fields) >= 4:
            vertices.append([float(x) for x in fields[1:4]])
        elif fields[0] in ("o", "g") and groups[-1]:
            groups.append(set())
        elif fields[0] == "f":
            for corner in fields[1:]:
                index = int(corner.split("/")[0])
                groups[-1].add(index - 1 if index > 0 else len(vertices) + index)
    points = np.asarray(vertices, dtype=float)
    pieces = [points[sorted(group)] for group in groups if len(group) >= 3]
    if not pieces or not np.isfinite(points).all():
        raise ValueError(f"mesh {path} has no faces (or non-finite vertices)")
    return pieces


MassProperties = tuple[NDArray[np.float64], tuple[float, float, float],
                       tuple[float, float, float, float]]


def mass_properties(pieces_mm: list[NDArray[np.float64]]) -> MassProperties:
    """Centre of mass (mm), principal inertia per kg (m²) and principal axes (quaternion x, y, z,
    w) of the union of the pieces' convex hulls at uniform density, from their tetrahedra
    (pieces that overlap count twice there; a decomposition's barely do).

    Raises:
        ValueError: no piece has volume.
    """
    tetra_sets = []
    for piece in pieces_mm:
        try:
            hull = ConvexHull(piece)
        except QhullError:
            continue  # a flat piece has no volume
        apex = piece[hull.vertices].mean(axis=0)
        tetra_sets.append(np.concatenate(
            [np.broadcast_to(apex, (len(hull.simplices), 1, 3)), piece[hull.simplices]], axis=1))
    if not tetra_sets:
        raise ValueError("the mesh has no volume")
    tetra = np.concatenate(tetra_sets)  # (T, 4, 3)
    edges = tetra[:, 1:] - tetra[:, :1]
    volume = np.abs(np.linalg.det(edges)) / 6.0
    com = (volume[:, None] * tetra.mean(axis=1)).sum(axis=0) / volume.sum()
    rel = (tetra - com) * 1e-3  # m
    total = rel.sum(axis=1)
    second = (np.einsum("tvi,tvj->tij", rel, rel) + np.einsum("ti,tj->tij", total, total)) / 20.0
    moments = (volume[:, None, None] * second).sum(axis=0) / volume.sum()  # per unit volume
    tensor = np.trace(moments) * np.eye(3) - moments
    principal, vectors = np.linalg.eigh(tensor)
    if np.linalg.det(vectors) < 0:
        vectors[:, 2] = -vectors[:, 2]
    axes = Rotation.from_matrix(vectors).as_quat()
    return (com, tuple(float(i) for i in principal),  # type: ignore[return-value]
            tuple(float(q) for q in axes))


@lru_cache(maxsize=256)
def pose_mass_properties(pose: MeshPose) -> MassProperties:
    """:func:`mass_properties` of a posed mesh's file at its scale (cached per pose)."""
    return mass_properties([piece * pose.scale for piece in read_obj_pieces(pose.path())])


def posed_pieces(pieces: list[NDArray[np.float64]], pose: MeshPose) -> list[NDArray[np.float64]]:
    """The pieces' vertices in the table frame (mm) for ``pose``."""
    rotation = Rotation.from_quat(pose.orientation)
    com, position = np.asarray(pose.com_mm), np.asarray(pose.position_mm)
    return [rotation.apply(piece * pose.scale - com) + position for piece in pieces]


def silhouette(
    pieces_mm: list[NDArray[np.float64]], margin_mm: float, name: str
) -> NDArray[np.float64]:
    """The top-down outline (N, 2; mm) of posed convex pieces grown by ``margin_mm``.

    Raises:
        ValueError: the silhouette has several parts or a hole (naming ``name``).
    """
    hulls = [MultiPoint(np.round(piece[:, :2], VERTEX_GRID_DECIMALS)).convex_hull
             for piece in pieces_mm]
    union = shapely.unary_union([h.buffer(margin_mm, quad_segs=4) for h in hulls])
    parts = [g for g in getattr(union, "geoms", [union]) if g.area > SLIVER_MM2]
    if len(parts) != 1:
        raise ValueError(f"mesh {name!r}: its silhouette has {len(parts)} separate parts, "
                         "not one object")
    holes = [ring for ring in parts[0].interiors if Polygon(ring).area > SLIVER_MM2]
    if holes:
        raise ValueError(f"mesh {name!r}: its silhouette has {len(holes)} hole(s) "
                         f"({Polygon(holes[0]).area:.0f} mm²), not a simple outline")
    outline = Polygon(parts[0].exterior).simplify(SIMPLIFY_MM, preserve_topology=True)
    return np.asarray(outline.exterior.coords)[:-1]
