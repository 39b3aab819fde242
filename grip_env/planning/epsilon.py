"""Ferrari–Canny ε quality of each grip's three contacts, in the planar wrench space.

Model (fixed here, the paper does not use ε):

- Contact ``i`` at ``P_i`` with inward unit normal ``N_i`` and Coulomb friction ``mu``: in 2-D the
  friction cone is spanned exactly by its two edge forces, ``N_i`` turned by ``±arctan(mu)``. Each
  edge force has unit length (unit force per contact).
- A force ``f`` at ``P`` gives the wrench ``(f_x, f_y, tau / L)``, torque ``tau = (P - C) × f``
  about the object centroid ``C`` and ``L = (semi_major + semi_minor) / 2`` (mm), so that all three
  components are dimensionless and ε does not depend on the object's scale or pose.
- The grasp wrench space is the convex hull of the union of the six edge wrenches (the L1 or "sum"
  variant: total contact force at most 1). ε is the distance from the origin to the nearest hull
  facet when the origin lies strictly inside the hull (force closure), else 0.

The hull of six points in 3-D is computed for all rows at once by enumerating the 20 candidate
triangles: a triangle is a facet when all six points lie on one side of its plane. This agrees with
``scipy.spatial.ConvexHull`` (``method="qhull"``, one call per row, kept as the reference).
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pandas as pd
from scipy.spatial import ConvexHull, QhullError

from grip_env.params import GraspParams

EPSILON_COLUMN = "eps"
_REQUIRED = (
    "p1_x", "p1_y", "p2_x", "p2_y", "p3_x", "p3_y",
    "n1_x", "n1_y", "n2_x", "n2_y", "n3_x", "n3_y",
    "centroid_x", "centroid_y", "semi_major", "semi_minor",
)  # fmt: skip
_TRIANGLES = np.array(list(combinations(range(6), 3)))
_TOLERANCE = 1e-9


def contact_wrenches(table: pd.DataFrame, params: GraspParams) -> np.ndarray:
    """The six friction-cone edge wrenches of each row, shape ``(rows, 6, 3)``."""
    _check_columns(table)
    points = table[["p1_x", "p1_y", "p2_x", "p2_y", "p3_x", "p3_y"]].to_numpy(float)
    points = points.reshape(-1, 3, 2)
    normals = table[["n1_x", "n1_y", "n2_x", "n2_y", "n3_x", "n3_y"]].to_numpy(float)
    normals = normals.reshape(-1, 3, 2)
    normals = normals / np.linalg.norm(normals, axis=2, keepdims=True)
    centroid = table[["centroid_x", "centroid_y"]].to_numpy(float)[:, None, :]
    scale = 0.5 * (table["semi_major"].to_numpy(float) + table["semi_minor"].to_numpy(float))
    if np.any(~np.isfinite(scale)) or np.any(scale <= 0.0):
        raise ValueError("semi_major + semi_minor must be positive and finite for every row")
    half_angle = np.arctan(params.mu)
    edges = [_rotated(normals, sign * half_angle) for sign in (1.0, -1.0)]
    forces = np.concatenate(edges, axis=1)  # (rows, 6, 2): contact order 1,2,3,1,2,3
    arms = np.concatenate([points - centroid] * 2, axis=1)
    torque = arms[..., 0] * forces[..., 1] - arms[..., 1] * forces[..., 0]
    return np.concatenate([forces, (torque / scale[:, None])[..., None]], axis=2)


def epsilon_quality(
    table: pd.DataFrame, params: GraspParams | None = None, method: str = "vectorised"
) -> np.ndarray:
    """Ferrari–Canny ε of every row (0 where the grip is not force closure).

    ``method`` is ``"vectorised"`` (facet enumeration for all rows at once) or ``"qhull"``
    (``scipy.spatial.ConvexHull`` per row, the slow reference).
    """
    params = params or GraspParams()
    wrenches = contact_wrenches(table, params)
    if method == "vectorised":
        return _epsilon_enumerated(wrenches)
    if method == "qhull":
        return np.array([_epsilon_qhull(points) for points in wrenches])
    raise ValueError(f"unknown epsilon method {method!r}; use 'vectorised' or 'qhull'")


def add_epsilon(table: pd.DataFrame, params: GraspParams | None = None) -> pd.DataFrame:
    """A copy of ``table`` with the column ``eps``."""
    return table.assign(**{EPSILON_COLUMN: epsilon_quality(table, params)})


def _check_columns(table: pd.DataFrame) -> None:
    missing = [name for name in _REQUIRED if name not in table.columns]
    if missing:
        raise ValueError(f"epsilon needs the columns {missing}, missing from the table")
    values = table[list(_REQUIRED)].to_numpy(float)
    if not np.all(np.isfinite(values)):
        raise ValueError("epsilon: contacts, normals and object descriptors must be finite")


def _rotated(vectors: np.ndarray, angle: float) -> np.ndarray:
    cos, sin = np.cos(angle), np.sin(angle)
    x, y = vectors[..., 0], vectors[..., 1]
    return np.stack([cos * x - sin * y, sin * x + cos * y], axis=-1)


def _epsilon_enumerated(wrenches: np.ndarray) -> np.ndarray:
    """ε by testing every triangle of the six points as a candidate hull facet."""
    a, b, c = (wrenches[:, _TRIANGLES[:, k]] for k in range(3))  # (rows, 20, 3)
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=2)
    valid = length > _TOLERANCE
    unit = normal / np.where(valid, length, 1.0)[..., None]
    offset = np.einsum("rtk,rtk->rt", unit, a)  # plane: unit . w = offset
    side = np.einsum("rtk,rpk->rtp", unit, wrenches) - offset[..., None]  # (rows, 20, 6)
    below = np.all(side <= _TOLERANCE, axis=2)
    above = np.all(side >= -_TOLERANCE, axis=2)
    flat = np.all(np.abs(side) <= _TOLERANCE, axis=2)
    facet = valid & (below | above) & ~flat
    # Orient each facet plane outwards; the origin's margin to it is offset (or -offset).
    margin = np.where(below, offset, -offset)
    margin = np.where(facet, margin, np.inf)
    epsilon = np.min(margin, axis=1)
    degenerate = ~np.any(facet, axis=1) | np.any(flat & valid, axis=1)
    return np.where(degenerate | (epsilon <= _TOLERANCE), 0.0, epsilon)


def _epsilon_qhull(points: np.ndarray) -> float:
    try:
        hull = ConvexHull(points)
    except QhullError:
        return 0.0  # flat wrench set: the origin cannot be strictly inside
    # hull.equations rows are (unit outward normal, offset) with normal . x + offset <= 0 inside.
    margin = -hull.equations[:, 3]
    epsilon = float(np.min(margin))
    return epsilon if epsilon > _TOLERANCE else 0.0
