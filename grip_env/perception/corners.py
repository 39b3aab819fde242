"""Restoring sharp corners that the pixel grid rounds off a perceived contour.

An image cannot hold a tip narrower than a pixel, so the sub-pixel iso-contour of a rendered polygon
cuts every acute corner short (by more than a pixel for tips under about 70 degrees). Where two
straight grasping regions meet at a clear corner, the corner is where their lines cross: this
module puts it back, which is what a vision system fitting lines to edges would do.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from grip_env.config import PerceptionConfig
from grip_env.perception.regions import Regions, find_regions

#: Only corners whose edges turn by at least this much are restored (rad); gentler bends lose
#: less than a pixel to the grid, and arcs cut into regions must not grow false corners.
MIN_CORNER_TURN = 0.9


def sharpen_corners(
    contour: NDArray[np.float64], mm_per_px: float, config: PerceptionConfig | None = None
) -> NDArray[np.float64]:
    """The contour with each rounded corner between two straight regions replaced by the
    intersection of their lines, when that point lies within two pixels of the contour.

    Edges are found as grasping regions smoothed at no less than three pixels, so the pixel
    staircase does not break them up.
    """
    config = config or PerceptionConfig()
    sigma = max(config.curvature_sigma_mm, 3.0 * mm_per_px)
    config = config.model_copy(update={"curvature_sigma_mm": sigma})
    tolerance_mm = 2.0 * mm_per_px
    regions = find_regions(contour, config)
    if len(regions) < 2:
        return contour
    max_stretch = 10.0 * config.curvature_sigma_mm
    replacements = _corner_replacements(contour, regions, tolerance_mm, max_stretch)
    return _apply(contour, replacements)


def _corner_replacements(
    contour: NDArray[np.float64], regions: Regions, tolerance_mm: float, max_stretch_mm: float
) -> list[tuple[int, int, NDArray[np.float64]]]:
    n = len(contour)
    starts = _nearest_index(contour, regions.a)
    ends = _nearest_index(contour, regions.b)
    direction = regions.direction
    found = []
    for k in range(len(regions)):
        j = (k + 1) % len(regions)
        turn = np.arccos(np.clip(direction[k] @ direction[j], -1.0, 1.0))
        if not MIN_CORNER_TURN <= turn < np.pi - 1e-6:
            continue  # a gentle bend, or a spike whose edges are parallel (no corner point)
        corner = _line_intersection(regions.a[k], direction[k], regions.a[j], direction[j])
        first, last = ends[k], starts[j]
        stretch = contour[np.arange(first, first + (last - first) % n + 1) % n]
        length = np.linalg.norm(np.diff(stretch, axis=0), axis=1).sum()
        if length > max_stretch_mm:
            continue  # a long bend: an arc between regions, not a rounded-off corner
        near_corner = np.min(np.linalg.norm(stretch - corner, axis=1)) <= tolerance_mm
        hugs_edges = np.all(
            np.minimum(_segment_distance(stretch, regions.b[k], corner),
                       _segment_distance(stretch, corner, regions.a[j])) <= tolerance_mm / 2
        )
        if near_corner and hugs_edges and _lines_reach(contour, regions, k, j, first, last,
                                                       tolerance_mm / 4):
            found.append((first, last, corner))
    return found


def _lines_reach(
    contour: NDArray[np.float64], regions: Regions, k: int, j: int, first: int, last: int,
    tolerance_mm: float,
) -> bool:
    """Whether both edge lines pass within ``tolerance_mm`` of the contour where they end: a
    region fitted across a bend ends off the contour, and its line would misplace the corner."""
    normal_k, normal_j = regions.normal[k], regions.normal[j]
    off_k = abs((contour[first] - regions.a[k]) @ normal_k)
    off_j = abs((contour[last] - regions.a[j]) @ normal_j)
    return bool(max(off_k, off_j) <= tolerance_mm)


def _apply(
    contour: NDArray[np.float64], replacements: list[tuple[int, int, NDArray[np.float64]]]
) -> NDArray[np.float64]:
    """Replace each stretch (first..last, cyclic) by its corner point."""
    n = len(contour)
    corner_at: dict[int, NDArray[np.float64]] = {}
    dropped = np.zeros(n, dtype=bool)
    for first, last, corner in replacements:
        stretch = np.arange(first, first + (last - first) % n + 1) % n
        dropped[stretch] = True
        corner_at[int(stretch[len(stretch) // 2])] = corner
    points = [corner_at[i] if i in corner_at else contour[i]
              for i in range(n) if not dropped[i] or i in corner_at]
    return np.asarray(points, dtype=float)


def _segment_distance(
    points: NDArray[np.float64], start: NDArray[np.float64], end: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distance of each point to the segment start-end."""
    span = end - start
    t = np.clip((points - start) @ span / max(float(span @ span), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points - (start + t[:, None] * span), axis=1)


def _nearest_index(contour: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.int_]:
    distances = np.linalg.norm(contour[None, :, :] - points[:, None, :], axis=2)
    return distances.argmin(axis=1)


def _line_intersection(
    p: NDArray[np.float64], u: NDArray[np.float64], q: NDArray[np.float64], v: NDArray[np.float64]
) -> NDArray[np.float64]:
    cross = u[0] * v[1] - u[1] * v[0]
    t = ((q - p)[0] * v[1] - (q - p)[1] * v[0]) / cross
    return p + t * u
