"""Closed-contour resampling at uniform arc-length spacing."""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from grip_env.objects import PlanarObject


def resample_contour(contour: ArrayLike, spacing_mm: float = 1.0) -> NDArray[np.float64]:
    """Points evenly spaced along a closed polygon, starting at its first vertex.

    The step is the perimeter divided by ``round(perimeter / spacing_mm)`` (at least 3 points), so
    it is within half a step of ``spacing_mm`` and the curve closes evenly. Corners are cut by at
    most half a step.

    Args:
        contour: (N, 2) closed polygon (last vertex not repeated), mm.
        spacing_mm: wanted distance between consecutive points (mm), positive.

    Returns:
        (M, 2) points, in the contour's order.
    """
    points = np.asarray(contour, dtype=float)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 3:
        raise ValueError(f"contour must have shape (N >= 3, 2), got {points.shape}")
    if not np.all(np.isfinite(points)):
        raise ValueError("contour contains NaN or infinite coordinates")
    if not np.isfinite(spacing_mm) or spacing_mm <= 0:
        raise ValueError(f"spacing_mm must be positive and finite, got {spacing_mm!r}")
    closed = np.vstack([points, points[:1]])
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    perimeter = arc[-1]
    if perimeter <= 0:
        raise ValueError("contour has zero length")
    count = max(3, round(perimeter / spacing_mm))
    s = np.arange(count) * (perimeter / count)
    return np.column_stack([np.interp(s, arc, closed[:, 0]), np.interp(s, arc, closed[:, 1])])


def contour_error_mm(true_obj: PlanarObject, perceived_obj: PlanarObject) -> float:
    """Symmetric Hausdorff distance between two objects' contours (mm)."""
    true_ring = shapely.LinearRing(true_obj.contour)
    perceived_ring = shapely.LinearRing(perceived_obj.contour)
    return float(shapely.hausdorff_distance(true_ring, perceived_ring, densify=0.05))
