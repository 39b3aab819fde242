"""Convex decomposition of a simple polygon, exact or within a distance, in a bounded piece count.

A simulated object is one PyBullet multibody with a convex prism per piece. PyBullet 3.2.7 builds
at most ``MAX_PIECES`` of them (the base and 127 links) and drops any further link without a word,
so the count is bounded here and a shape that does not fit is refused.
"""

from __future__ import annotations

import heapq

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry import Polygon

MAX_PIECES = 128
"""Most convex pieces one body may have: PyBullet's base plus its 127-link multibody limit."""

_MIN_AREA_MM2 = 1e-6

Piece = NDArray[np.float64]


def exact_pieces(contour: NDArray[np.float64]) -> list[Piece]:
    """Convex CCW pieces tiling a simple CCW polygon exactly: constrained Delaunay triangles merged
    across their diagonals while the union stays convex (Hertel-Mehlhorn)."""
    polygon = Polygon(contour)
    if np.isclose(polygon.convex_hull.area, polygon.area, rtol=1e-9):
        return [np.asarray(contour, dtype=float).copy()]
    triangles = shapely.constrained_delaunay_triangles(polygon)
    pieces = [ccw(np.asarray(t.exterior.coords)[:-1]) for t in triangles.geoms]
    return merge_convex([p for p in pieces if Polygon(p).area > _MIN_AREA_MM2])


def merge_convex(pieces: list[Piece]) -> list[Piece]:
    """Merge CCW convex pieces across shared edges while the union stays convex (Hertel-Mehlhorn).

    One pass over the shared edges suffices: merging only widens the angles at a piece's
    vertices, so an edge that cannot be removed now never can. Linear in the edge count.
    """
    polys: dict[int, list[tuple[float, float]]] = {
        i: [tuple(v) for v in piece] for i, piece in enumerate(pieces)
    }
    owner: dict[tuple, int] = {}
    for index, poly in polys.items():
        for k in range(len(poly)):
            owner[(poly[k], poly[(k + 1) % len(poly)])] = index
    for a, b in list(owner):
        i, j = owner.get((a, b)), owner.get((b, a))
        if i is None or j is None or i == j:
            continue
        union = _splice(polys[i], polys[j], a, b)
        if not _is_convex(union):
            continue
        if len(polys[i]) < len(polys[j]):
            i, j = j, i
        for k in range(len(polys[j])):
            owner[(polys[j][k], polys[j][(k + 1) % len(polys[j])])] = i
        del owner[(a, b)], owner[(b, a)], polys[j]
        polys[i] = union
    return [np.array(poly, dtype=float) for poly in polys.values()]


def bounded_pieces(
    pieces: list[Piece], allowed: Polygon, max_pieces: int = MAX_PIECES
) -> list[Piece]:
    """At most ``max_pieces`` convex pieces covering ``pieces``, each inside ``allowed``.

    Neighbouring pieces (sharing an edge) are replaced by the convex hull of the two, cheapest
    added area first, as long as the hull stays inside ``allowed`` (the object grown by its
    tolerance): an approximate convex decomposition whose union covers the object and lies within
    the tolerance of it. The pieces may overlap. A merged piece's pairs are queued at their old
    pairs' cost and costed when their turn comes (lazy greedy): a piece with hundreds of
    neighbours then costs a few hulls per merge, not hundreds.

    Raises:
        ValueError: no such merge is left and there are still more than ``max_pieces``.
    """
    live = {i: np.asarray(p, dtype=float) for i, p in enumerate(pieces)}
    if len(live) <= max_pieces:
        return list(live.values())
    shapely.prepare(allowed)
    area = {i: Polygon(p).area for i, p in live.items()}
    neighbours = _neighbours(pieces)
    pairs = [(i, j) for i, others in neighbours.items() for j in others if i < j]
    costs = dict(zip(pairs, _merge_costs(live, area, pairs), strict=True))
    heap = [(cost, True, i, j) for (i, j), cost in costs.items()]
    heapq.heapify(heap)
    next_id = len(pieces)
    while len(live) > max_pieces and heap:
        _, costed, i, j = heapq.heappop(heap)
        if i not in live or j not in live:
            continue
        if not costed:  # queued at an old pair's cost: cost it now, then take its turn
            costs[(i, j)] = _merge_costs(live, area, [(i, j)])[0]
            heapq.heappush(heap, (costs[(i, j)], True, i, j))
            continue
        hull = _hulls([np.vstack([live[i], live[j]])])[0]
        if not allowed.covers(hull):
            continue
        live[next_id], area[next_id] = ccw(np.asarray(hull.exterior.coords)[:-1]), hull.area
        neighbours[next_id] = (neighbours.pop(i) | neighbours.pop(j)) - {i, j}
        for k in neighbours[next_id]:
            neighbours[k] -= {i, j}
            neighbours[k].add(next_id)
            old = min(costs.get(_key(k, i), np.inf), costs.get(_key(k, j), np.inf))
            heapq.heappush(heap, (old, False, k, next_id))
        del live[i], live[j]
        next_id += 1
    if len(live) > max_pieces:
        raise ValueError(
            f"{len(live)} convex pieces needed, more than the {max_pieces} one simulated body "
            "can have"
        )
    return list(live.values())


def ccw(vertices: NDArray[np.float64]) -> NDArray[np.float64]:
    """The vertices in counter-clockwise order."""
    x, y = vertices[:, 0], vertices[:, 1]
    signed = (x * np.roll(y, -1) - np.roll(x, -1) * y).sum()
    return vertices if signed > 0 else vertices[::-1].copy()


def _neighbours(pieces: list[Piece]) -> dict[int, set[int]]:
    """Pieces sharing an edge (in opposite directions), by index."""
    owner = {}
    for index, piece in enumerate(pieces):
        poly = [tuple(v) for v in piece]
        for k in range(len(poly)):
            owner[(poly[k], poly[(k + 1) % len(poly)])] = index
    neighbours: dict[int, set[int]] = {i: set() for i in range(len(pieces))}
    for (a, b), i in owner.items():
        j = owner.get((b, a))
        if j is not None and j != i:
            neighbours[i].add(j)
    return neighbours


def _key(i: int, j: int) -> tuple[int, int]:
    return (i, j) if i < j else (j, i)


def _merge_costs(
    live: dict[int, Piece], area: dict[int, float], pairs: list[tuple[int, int]]
) -> list[float]:
    """Area the convex hull of each pair of pieces adds to the two (vectorised)."""
    if not pairs:
        return []
    hulls = _hulls([np.vstack([live[i], live[j]]) for i, j in pairs])
    added = shapely.area(hulls) - np.array([area[i] + area[j] for i, j in pairs])
    return added.tolist()


def _hulls(point_sets: list[NDArray[np.float64]]) -> NDArray[np.object_]:
    """Convex hull polygons of several point sets, in one vectorised call."""
    index = np.repeat(np.arange(len(point_sets)), [len(p) for p in point_sets])
    return shapely.convex_hull(shapely.multipoints(np.vstack(point_sets), indices=index))


def _splice(first: list, second: list, a: tuple, b: tuple) -> list:
    """Union of two CCW polygons sharing the edge a->b in ``first`` (b->a in ``second``)."""
    i = first.index(b)
    rotated_first = first[i:] + first[:i]  # starts at b, ends at a
    j = second.index(a)
    rotated_second = second[j:] + second[:j]  # starts at a, ends at b
    return rotated_first + rotated_second[1:-1]


def _is_convex(poly: list) -> bool:
    pts = np.asarray(poly, dtype=float)
    d1 = np.roll(pts, -1, axis=0) - pts
    d2 = np.roll(d1, -1, axis=0)
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    return bool(np.all(cross >= -1e-9 * np.abs(d1).max() ** 2))
