"""Simplifying a closed contour within a stated distance (Douglas-Peucker on a ring).

A mask's sub-pixel contour has a vertex every pixel or so, and every pixel step of it is a reflex
vertex: decomposed as it is, a detailed silhouette needs hundreds of convex pieces. Dropping the
vertices that lie within a tolerance of the chord that replaces them keeps the shape while the
pieces come down to what its real concavities need.

Bound: every dropped vertex lies within ``tolerance`` of its chord *segment*, so the whole original
chain lies in that segment's ``tolerance``-neighbourhood (a convex stadium), and every chord point
has a chain point within ``tolerance`` (the chain crosses the chord's perpendicular there). The
largest such vertex distance is therefore an upper bound on the Hausdorff distance between the two
contours; :func:`simplify_contour` returns it. Chords are also held to an area bound
(``AREA_SHIFT``), so that the simplified shape keeps the object's area, not only its outline.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry import Polygon

AREA_SHIFT = 0.1
"""A chord also replaces its chain only if the area between them, spread along the chord, is at
most this fraction of the tolerance: noise cancels and goes, while a smooth convex (or concave)
arc keeps the vertices that hold its area. The area then changes by at most
``AREA_SHIFT * tolerance * perimeter``."""


def simplify_contour(
    contour: NDArray[np.float64], tolerance_mm: float, name: str = "object"
) -> tuple[NDArray[np.float64], float]:
    """The contour with vertices within ``tolerance_mm`` of their chord removed.

    Args:
        contour: (N, 2) simple CCW polygon (mm), last vertex not repeated.
        tolerance_mm: largest distance allowed between the two contours (>= 0).
        name: the object's name, for error messages.

    Returns:
        ``(simplified, deviation_mm)``: the CCW simplified contour (a subset of the vertices, in
        order) and an upper bound on its Hausdorff distance to ``contour`` (<= ``tolerance_mm``).

    Raises:
        ValueError: a bad tolerance, or a simplified contour that self-intersects (two parts of
            the contour closer than the tolerance).
    """
    if not np.isfinite(tolerance_mm) or tolerance_mm < 0:
        raise ValueError(f"tolerance_mm must be finite and >= 0, got {tolerance_mm!r}")
    points = np.asarray(contour, dtype=float)
    if tolerance_mm == 0 or len(points) <= 4:
        return points.copy(), 0.0
    far = int(np.argmax(_lengths(points - points[0])))
    first = points[: far + 1]
    second = np.vstack([points[far:], points[:1]])
    keep_first, dev_first = _douglas_peucker(first, tolerance_mm)
    keep_second, dev_second = _douglas_peucker(second, tolerance_mm)
    simplified = np.vstack([first[keep_first][:-1], second[keep_second][:-1]])
    _check_simple(simplified, tolerance_mm, name)
    return simplified, max(dev_first, dev_second)


def _douglas_peucker(
    chain: NDArray[np.float64], tolerance: float
) -> tuple[NDArray[np.bool_], float]:
    """Kept-vertex mask of an open chain (ends always kept) and the largest dropped distance."""
    keep = np.zeros(len(chain), dtype=bool)
    keep[0] = keep[-1] = True
    deviation = 0.0
    stack = [(0, len(chain) - 1)]
    while stack:
        start, stop = stack.pop()
        if stop - start < 2:
            continue
        distances = _segment_distances(chain[start + 1 : stop], chain[start], chain[stop])
        worst = int(np.argmax(distances))
        span = float(_lengths(chain[stop] - chain[start]))
        shift = abs(_signed_area(chain[start : stop + 1])) / max(span, 1e-12)
        if distances[worst] > tolerance or shift > AREA_SHIFT * tolerance:
            split = start + 1 + worst
            keep[split] = True
            stack += [(start, split), (split, stop)]
        else:
            deviation = max(deviation, float(distances[worst]))
    return keep, deviation


def _signed_area(points: NDArray[np.float64]) -> float:
    """Signed area of the polygon the points close (last joined back to first)."""
    x, y = points[:, 0], points[:, 1]
    return 0.5 * math.fsum(x * np.roll(y, -1) - np.roll(x, -1) * y)  # exactly rounded


def _segment_distances(
    points: NDArray[np.float64], start: NDArray[np.float64], stop: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Each point's distance to the segment, in elementwise arithmetic only (see ``_lengths``)."""
    span = stop - start
    rel = points - start
    length2 = float(span[0] * span[0] + span[1] * span[1])
    along = rel[:, 0] * span[0] + rel[:, 1] * span[1]
    t = np.clip(along / length2, 0.0, 1.0) if length2 > 0 else np.zeros(len(points))
    return _lengths(rel - np.multiply.outer(t, span))


def _lengths(vectors: NDArray[np.float64]) -> NDArray[np.float64]:
    """Euclidean lengths of (..., 2) vectors with elementwise operations only: a BLAS product or
    a vectorised reduction rounds differently on another CPU, and a symmetric contour's tied
    distances then keep other vertices there (the same dataset on any x86-64 machine)."""
    x, y = vectors[..., 0], vectors[..., 1]
    return np.sqrt(x * x + y * y)


def _check_simple(simplified: NDArray[np.float64], tolerance_mm: float, name: str) -> None:
    hint = "lower objects.sim_tolerance_mm or widen the gap"
    if len(simplified) < 3:
        raise ValueError(
            f"object {name!r}: simplified within {tolerance_mm:g} mm it keeps "
            f"{len(simplified)} vertices: it is thinner than the tolerance"
        )
    polygon = Polygon(simplified)
    if not polygon.is_valid or polygon.area <= 0:
        reason = shapely.is_valid_reason(polygon)
        raise ValueError(
            f"object {name!r}: its contour self-intersects after simplification within "
            f"{tolerance_mm:g} mm ({reason}): two parts of it are closer than that; {hint}"
        )
