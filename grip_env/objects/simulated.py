"""``SimulatedShape``: the shape an object's simulated body has, within a stated tolerance of it.

Features and planning use the object's contour; PyBullet simulates a union of convex prisms. The
two are kept the same object within ``tolerance_mm`` (Hausdorff): the contour is simplified within
it (:mod:`~grip_env.objects.simplify`), decomposed exactly into convex pieces, and, only when
those exceed the engine's piece limit, neighbouring pieces are replaced by their convex hull while
it stays within the tolerance of the object (:mod:`~grip_env.objects.decomposition`). A shape
that still needs more pieces is refused, never truncated.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry import Polygon

from grip_env.config import ObjectsConfig
from grip_env.objects.decomposition import MAX_PIECES, bounded_pieces, ccw, exact_pieces
from grip_env.objects.simplify import simplify_contour

DEFAULT_TOLERANCE_MM: float = ObjectsConfig.model_fields["sim_tolerance_mm"].default


@dataclass(frozen=True, eq=False)
class SimulatedShape:
    """The simulated body's outline: convex pieces whose union is within ``deviation_mm`` of the
    object's contour.

    Attributes:
        contour: the simplified contour (mm, CCW) the pieces were cut from.
        pieces: convex CCW pieces (mm); they tile ``contour`` exactly unless ``approximate``.
        tolerance_mm: the tolerance asked for.
        deviation_mm: upper bound on the Hausdorff distance between the object's contour and the
            pieces' union (<= ``tolerance_mm``).
        approximate: whether pieces were replaced by hulls to fit the piece limit.
    """

    contour: NDArray[np.float64]
    pieces: tuple[NDArray[np.float64], ...]
    tolerance_mm: float
    deviation_mm: float
    approximate: bool
    _eroded: dict[float, tuple[NDArray[np.float64], ...]] = field(
        default_factory=dict, init=False, repr=False
    )

    @property
    def area(self) -> float:
        """Area of the pieces' union (mm²)."""
        return float(shapely.unary_union([Polygon(p) for p in self.pieces]).area)

    def collision_pieces(self, margin_mm: float) -> tuple[NDArray[np.float64], ...]:
        """Convex pieces of the shape eroded by ``margin_mm``, for an engine that grows every
        convex piece by that margin (Bullet does): it then collides with the shape's opening by a
        disc of that radius. Faces and concave corners are exact, a convex corner of angle a is
        rounded off by ``margin (1 / sin(a/2) - 1)``, parts thinner than twice the margin go.

        Raises:
            ValueError: nothing is left, or more than ``MAX_PIECES`` pieces.
        """
        if margin_mm <= 0:
            return self.pieces
        if margin_mm not in self._eroded:
            self._eroded[margin_mm] = self._erode(margin_mm)
        return self._eroded[margin_mm]

    def _erode(self, margin_mm: float) -> tuple[NDArray[np.float64], ...]:
        union = shapely.unary_union([Polygon(p) for p in self.pieces])
        eroded = union.buffer(-margin_mm, join_style="mitre", mitre_limit=1e6)
        parts = [g for g in getattr(eroded, "geoms", [eroded]) if g.area > 1e-6]
        if not parts:
            raise ValueError(f"the object is nowhere thicker than twice {margin_mm:g} mm")
        pieces = [p for g in parts for p in exact_pieces(ccw(np.asarray(g.exterior.coords)[:-1]))]
        if len(pieces) > MAX_PIECES:
            pieces = bounded_pieces(pieces, eroded.buffer(self.tolerance_mm), MAX_PIECES)
        return tuple(pieces)

    def record(self) -> dict[str, float | int | bool]:
        """The simulated-shape columns of the objects table."""
        return {
            "sim_tolerance_mm": self.tolerance_mm,
            "sim_deviation_mm": self.deviation_mm,
            "sim_vertices": len(self.contour),
            "sim_pieces": len(self.pieces),
            "sim_approximate": self.approximate,
            "sim_area": self.area,
        }


def simulated_shape(
    contour: NDArray[np.float64], tolerance_mm: float = DEFAULT_TOLERANCE_MM,
    name: str = "object", max_pieces: int = MAX_PIECES,
) -> SimulatedShape:
    """The simulated shape of a simple CCW contour (mm), within ``tolerance_mm`` of it.

    Raises:
        ValueError: a bad tolerance, a contour that self-intersects once simplified, or a shape
            that needs more than ``max_pieces`` convex pieces within the tolerance.
    """
    simplified, deviation = simplify_contour(contour, tolerance_mm, name)
    pieces = exact_pieces(simplified)
    approximate = len(pieces) > max_pieces
    if approximate:
        allowed = Polygon(contour).buffer(tolerance_mm, quad_segs=16)
        try:
            pieces = bounded_pieces(pieces, allowed, max_pieces)
        except ValueError as exc:
            raise ValueError(
                f"object {name!r} cannot be simulated whole: within {tolerance_mm:g} mm {exc}; "
                "raise objects.sim_tolerance_mm or simplify the object"
            ) from None
        deviation = tolerance_mm
    return SimulatedShape(simplified, tuple(pieces), float(tolerance_mm), deviation, approximate)
