"""``PlanarObject``: a flat part given by its outer contour, with its descriptors."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry import Polygon

from grip_env.objects.decomposition import ccw, exact_pieces
from grip_env.objects.masks import contour_from_mask, mask_from_image_file, one_region
from grip_env.objects.simulated import DEFAULT_TOLERANCE_MM, SimulatedShape, simulated_shape

if TYPE_CHECKING:
    from grip_env.objects.meshes import MeshPose

_MIN_AREA_MM2 = 1e-6


@dataclass(frozen=True, eq=False)
class PlanarObject:
    """A planar object: a simple polygon in millimetres, stored counter-clockwise.

    Build one with :meth:`from_polygon`, :meth:`from_mask` or :meth:`from_image`; the constructor
    validates its input the same way. ``mesh`` is the resting mesh whose silhouette the contour
    is (:mod:`grip_env.objects.meshes`), None for a planar object.
    """

    contour: NDArray[np.float64]
    name: str = "object"
    source: str = "polygon"
    mesh: MeshPose | None = None
    _polygon: Polygon = field(init=False, repr=False)

    def __post_init__(self) -> None:
        contour = _validated_contour(self.contour, self.name)
        object.__setattr__(self, "contour", contour)
        object.__setattr__(self, "_polygon", Polygon(contour))

    # ----------------------------------------------------------------- constructors
    @classmethod
    def from_polygon(cls, vertices_mm: ArrayLike, name: str = "polygon") -> PlanarObject:
        """An object from its polygon vertices (mm), in either orientation."""
        return cls(vertices_mm, name=name, source="polygon")

    @classmethod
    def from_mask(cls, mask: ArrayLike, mm_per_px: float, name: str = "mask") -> PlanarObject:
        """An object from a binary (or grey-level in [0, 1]) image, row 0 at the top.

        The contour is the 0.5 iso-line of the image (sub-pixel), in mm with y pointing up.

        Raises:
            ValueError: a bad or empty mask, or one with several parts or holes.
        """
        return cls(contour_from_mask(one_region(mask), mm_per_px), name=name, source="mask")

    @classmethod
    def from_image(
        cls, path: str | Path, mm_per_px: float, name: str | None = None
    ) -> PlanarObject:
        """An object from an image file showing it on a contrasting background."""
        path = Path(path)
        return cls.from_mask(mask_from_image_file(path), mm_per_px, name=name or path.stem)

    # ----------------------------------------------------------------- descriptors
    @cached_property
    def area(self) -> float:
        """Area (mm²)."""
        return float(self._moments[0])

    @cached_property
    def centroid(self) -> NDArray[np.float64]:
        """Centroid C (mm)."""
        return self._moments[1]

    @cached_property
    def second_moments(self) -> NDArray[np.float64]:
        """Area-normalised second central moment matrix (mm²)."""
        return self._moments[2]

    @cached_property
    def inertia_semi_axes(self) -> tuple[float, float]:
        """``(M_L, m_L)``: semi-axes of the uniform ellipse with the same second moments (mm)."""
        l2, l1 = np.linalg.eigvalsh(self.second_moments)
        return 2.0 * float(np.sqrt(max(l1, 0.0))), 2.0 * float(np.sqrt(max(l2, 0.0)))

    @cached_property
    def major_axis_angle(self) -> float:
        """Direction of the major inertia axis (rad, in [0, pi))."""
        _, vectors = np.linalg.eigh(self.second_moments)
        major = vectors[:, 1]
        return float(np.arctan2(major[1], major[0]) % np.pi)

    @cached_property
    def diameter(self) -> float:
        """Largest distance between two contour vertices (mm)."""
        hull = np.asarray(self._polygon.convex_hull.exterior.coords)[:-1]
        d = np.linalg.norm(hull[:, None, :] - hull[None, :, :], axis=-1)
        return float(d.max())

    @property
    def polygon(self) -> Polygon:
        """The shapely polygon (read-only use)."""
        return self._polygon

    @cached_property
    def is_convex(self) -> bool:
        """Whether the contour is convex."""
        return bool(np.isclose(self._polygon.convex_hull.area, self.area, rtol=1e-9))

    def descriptors(self) -> dict[str, float]:
        """The object columns of the candidate table."""
        semi_major, semi_minor = self.inertia_semi_axes
        return {
            "area": self.area,
            "centroid_x": float(self.centroid[0]),
            "centroid_y": float(self.centroid[1]),
            "semi_major": semi_major,
            "semi_minor": semi_minor,
        }

    def contains(self, points: ArrayLike) -> NDArray[np.bool_]:
        """Whether each point (…, 2) lies strictly inside the object."""
        pts = np.asarray(points, dtype=float)
        flat = pts.reshape(-1, 2)
        inside = shapely.contains_xy(self._polygon, flat[:, 0], flat[:, 1])
        return inside.reshape(pts.shape[:-1])

    def convex_pieces(self) -> list[NDArray[np.float64]]:
        """Exact convex pieces tiling the contour (the contour itself when convex), unbounded in
        number; the simulated body uses :meth:`simulated_shape` instead."""
        return [piece.copy() for piece in self._convex_pieces]

    @cached_property
    def _convex_pieces(self) -> list[NDArray[np.float64]]:
        return exact_pieces(self.contour)

    def simulated_shape(self, tolerance_mm: float = DEFAULT_TOLERANCE_MM) -> SimulatedShape:
        """The shape its simulated body has: at most ``MAX_PIECES`` convex pieces within
        ``tolerance_mm`` (Hausdorff) of the contour (cached per tolerance).

        Raises:
            ValueError: the shape cannot be simulated whole within the tolerance.
        """
        key = float(tolerance_mm)
        if key not in self._simulated:
            self._simulated[key] = simulated_shape(self.contour, key, self.name)
        return self._simulated[key]

    @cached_property
    def _simulated(self) -> dict[float, SimulatedShape]:
        return {}

    # ----------------------------------------------------------------- transforms
    def transformed(
        self, angle: float = 0.0, offset: ArrayLike = (0.0, 0.0), scale: float = 1.0
    ) -> PlanarObject:
        """A copy rotated by ``angle`` about the origin, scaled, then moved by ``offset``.

        A moved mesh object moves its mesh; a turned or scaled one is a planar object only (its
        contour is no longer that mesh's silhouette at rest).
        """
        if not np.isfinite(scale) or scale <= 0:
            raise ValueError(f"scale must be a positive finite number, got {scale!r}")
        c, s = np.cos(angle), np.sin(angle)
        rotation = np.array([[c, -s], [s, c]])
        shift = np.asarray(offset, dtype=float)
        contour = scale * self.contour @ rotation.T + shift
        moved_only = angle == 0.0 and scale == 1.0
        mesh = self.mesh.shifted(shift) if self.mesh is not None and moved_only else None
        return PlanarObject(contour, name=self.name, source=self.source, mesh=mesh)

    def centred(self) -> PlanarObject:
        """A copy with its centroid at the origin."""
        return self.transformed(offset=-self.centroid)

    # ----------------------------------------------------------------- internals
    @cached_property
    def _moments(self) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
        return polygon_moments(self.contour)

    def __repr__(self) -> str:
        return (
            f"PlanarObject(name={self.name!r}, vertices={len(self.contour)}, "
            f"area={self.area:.1f} mm², source={self.source!r})"
        )


def polygon_moments(
    vertices: NDArray[np.float64],
) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Area, centroid and area-normalised central second moments of a CCW simple polygon."""
    x, y = vertices[:, 0], vertices[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = cross.sum() / 2.0
    cx = ((x + xn) * cross).sum() / (6.0 * area)
    cy = ((y + yn) * cross).sum() / (6.0 * area)
    ixx = ((x * x + x * xn + xn * xn) * cross).sum() / 12.0
    iyy = ((y * y + y * yn + yn * yn) * cross).sum() / 12.0
    ixy = ((x * yn + 2 * x * y + 2 * xn * yn + xn * y) * cross).sum() / 24.0
    mxx = ixx / area - cx * cx
    myy = iyy / area - cy * cy
    mxy = ixy / area - cx * cy
    return float(area), np.array([cx, cy]), np.array([[mxx, mxy], [mxy, myy]])


def _validated_contour(contour: ArrayLike, name: str) -> NDArray[np.float64]:
    try:
        pts = np.array(contour, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"object {name!r}: vertices must be numbers, got {contour!r}") from exc
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"object {name!r}: vertices must have shape (N, 2), got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        bad = np.argwhere(~np.isfinite(pts))[0][0]
        raise ValueError(f"object {name!r}: vertex {bad} is not finite: {pts[bad].tolist()}")
    if len(pts) > 1 and np.allclose(pts[0], pts[-1]):
        pts = pts[:-1]
    keep = np.linalg.norm(pts - np.roll(pts, 1, axis=0), axis=1) > 1e-9
    pts = pts[keep] if keep.any() else pts[:1]
    if len(pts) < 3:
        raise ValueError(
            f"object {name!r}: a polygon needs at least 3 distinct vertices, got {len(pts)}"
        )
    polygon = Polygon(pts)
    if np.linalg.matrix_rank(pts - pts.mean(axis=0), tol=1e-9) < 2:
        raise ValueError(f"object {name!r}: polygon has zero area (collinear vertices)")
    if not polygon.is_valid:
        reason = shapely.is_valid_reason(polygon)
        raise ValueError(f"object {name!r}: polygon is not simple ({reason})")
    if polygon.area <= _MIN_AREA_MM2:
        raise ValueError(f"object {name!r}: polygon has zero area")
    return ccw(pts)
