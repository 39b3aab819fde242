"""The twelve quality measures of a grip (paper section V) and the two global indexes Q_G, Q_C.

All grips are computed at once from the descriptor columns of the candidate table (DESIGN's
column contract). :func:`compute_features` takes the table; :func:`features_from_arrays` takes a
mapping from the same column names to 1-D arrays, for callers that already hold arrays.

Choices the paper leaves open follow DESIGN: interior angles of the contact triangle for S1 (the
two-finger form S1'' has alpha at the thumb contact P3), consecutive angles around the circle for
G1, unsigned deviation angles for C1, ``eta*mu/2`` in C2, C6 in millimetres, and any feature that is
infinite, undefined or above ``params.feature_cap`` stored as ``feature_cap``. Two-finger rows have
G1 = C2 = 0 and use the contact triangle's centroid C_T in G2 and C5.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from grip_env.columns import (
    CONTACTS,
    CURVATURES,
    FEATURES,
    FORCES,
    INDEXES,
    NORMALS,
    OBJECT,
    REGIONS,
)
from grip_env.params import GraspParams

FEATURE_NAMES: tuple[str, ...] = FEATURES
INDEX_NAMES: tuple[str, ...] = INDEXES
OUTPUT_NAMES: tuple[str, ...] = FEATURE_NAMES + INDEX_NAMES

GRASP_FOCUS = ("cg_x", "cg_y")
REAL_FOCUS = ("cc_x", "cc_y")
EXTENSIONS = ("e1", "e2", "e3")
TWO_FINGER = "two_finger"
#: Descriptors that must be finite in every row (the foci may be NaN in two-finger rows).
FINITE_COLUMNS: tuple[str, ...] = (
    CONTACTS + NORMALS + FORCES + REGIONS + CURVATURES + EXTENSIONS + ("spread",) + OBJECT
)
FOCUS_COLUMNS: tuple[str, ...] = GRASP_FOCUS + REAL_FOCUS
#: Every column the features are computed from.
REQUIRED_COLUMNS: tuple[str, ...] = FINITE_COLUMNS + FOCUS_COLUMNS + (TWO_FINGER,)

DEFAULT_PARAMS = GraspParams()
_FINGERS = ("1", "2", "3")
_TWO_PI = 2.0 * np.pi

Columns = Mapping[str, ArrayLike]
Array = NDArray[np.float64]


def compute_features(table: pd.DataFrame, params: GraspParams = DEFAULT_PARAMS) -> pd.DataFrame:
    """Compute S1..C6, Q_G and Q_C for every row of a candidate table.

    Args:
        table: one row per grip with the descriptor columns of :data:`REQUIRED_COLUMNS`.
        params: grasping parameters (mu, lam, weight, eta, feature_cap).

    Returns:
        A DataFrame with columns :data:`OUTPUT_NAMES` and the same index as ``table``. A table with
        no rows gives an empty result.

    Raises:
        ValueError: a required column is missing, or a descriptor is non-finite or degenerate
            (the message names the column and the row's index label).
    """
    if len(table) == 0:
        return pd.DataFrame(np.zeros((0, len(OUTPUT_NAMES))), index=table.index,
                            columns=list(OUTPUT_NAMES))
    _require_columns(table.columns)
    columns = {name: table[name].to_numpy() for name in REQUIRED_COLUMNS}
    values = features_from_arrays(columns, params, row_labels=table.index)
    return pd.DataFrame(values, index=table.index, columns=list(OUTPUT_NAMES))


def features_from_arrays(
    columns: Columns,
    params: GraspParams = DEFAULT_PARAMS,
    row_labels: ArrayLike | None = None,
) -> Array:
    """Compute the features from 1-D arrays named like the table's columns.

    Args:
        columns: mapping from each name in :data:`REQUIRED_COLUMNS` to an array of N values.
        params: grasping parameters.
        row_labels: optional labels used to name bad rows in errors (default: positions).

    Returns:
        (N, 14) float array, columns in :data:`OUTPUT_NAMES` order.
    """
    arrays = _validated_arrays(columns, row_labels)
    features = _features(arrays, params)
    capped = np.where(features <= params.feature_cap, features, params.feature_cap)
    q_grasp = capped[0:6].sum(axis=0)
    q_config = capped[0:4].sum(axis=0) + capped[6:12].sum(axis=0)
    return np.vstack([capped, q_grasp, q_config]).T


# ------------------------------------------------------------------------------- the formulas
def _features(a: dict[str, Array], params: GraspParams) -> Array:
    """(12, N) uncapped features; infinite or NaN where a formula is undefined."""
    two_finger = a[TWO_FINGER].astype(bool)
    px, py = _stack(a, "p")
    triangle_centre = (px.mean(axis=0), py.mean(axis=0))
    object_centre = (a["centroid_x"], a["centroid_y"])
    object_size = a["semi_major"] + a["semi_minor"]
    grasp_focus = _where_two_finger(two_finger, triangle_centre, (a["cg_x"], a["cg_y"]))
    real_focus = _where_two_finger(two_finger, triangle_centre, (a["cc_x"], a["cc_y"]))
    extensions = np.vstack([a[name] for name in EXTENSIONS])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.vstack([
            point_arrangement(px, py, two_finger),
            triangle_size(px, py, a["area"], params.weight),
            grasping_margin(px, py, _region_ends(a), params.lam),
            1.0 - (a["rho1"] + a["rho2"] + a["rho3"]),
            np.where(two_finger, 0.0, force_arrangement(*_stack(a, "n"))),
            centring(grasp_focus, object_centre, object_size, params.weight),
            force_line(_stack(a, "f"), _stack(a, "n"), params.friction_angle),
            np.where(two_finger, 0.0, _distance(a["cg_x"], a["cg_y"], *real_focus)
                     / (params.eta * params.mu / 2.0)),
            finger_extension(extensions, params.eta),
            finger_spread(a["spread"]),
            centring(real_focus, object_centre, object_size, params.weight),
            np.maximum(extensions - params.eta, 0.0).sum(axis=0),
        ])


def point_arrangement(px: Array, py: Array, two_finger: NDArray[np.bool_]) -> Array:
    """S1 from the interior angles of the contact triangle; S1'' in two-finger rows.

    ``px``, ``py`` are (3, N) contact coordinates. A triangle with two coincident contacts counts
    as degenerate to a segment (S1 = 2).
    """
    ux, uy = np.roll(px, -1, axis=0) - px, np.roll(py, -1, axis=0) - py
    vx, vy = np.roll(px, -2, axis=0) - px, np.roll(py, -2, axis=0) - py
    angles = np.arctan2(np.abs(ux * vy - uy * vx), ux * vx + uy * vy)  # at P1, P2, P3
    three = (3.0 / (2.0 * np.pi)) * np.abs(angles - np.pi / 3.0).sum(axis=0)
    beta, gamma, alpha = angles
    two = (2.0 / np.pi) * (np.abs(beta - gamma) + alpha)
    coincident = ((ux == 0.0) & (uy == 0.0)).any(axis=0)
    return np.where(coincident, 2.0, np.where(two_finger, two, three))


def triangle_size(px: Array, py: Array, area: Array, weight: float) -> Array:
    """S2 = W * A / (4 * A_T)."""
    triangle_area = 0.5 * np.abs(
        (px[1] - px[0]) * (py[2] - py[0]) - (py[1] - py[0]) * (px[2] - px[0])
    )
    return weight * area / (4.0 * triangle_area)


def grasping_margin(px: Array, py: Array, ends: tuple[Array, Array], lam: float) -> Array:
    """S3: sum over the six contact-to-region-end distances d of (lam/d - 1 if d < lam else 0).

    ``ends`` holds (2, 3, N) x and y of the region ends a, b of each finger.
    """
    ex, ey = ends
    d = np.sqrt((ex - px) ** 2 + (ey - py) ** 2)
    return np.where(d < lam, lam / d - 1.0, 0.0).sum(axis=(0, 1))


def force_arrangement(nx: Array, ny: Array) -> Array:
    """G1 from the three angles between consecutive force directions around the circle.

    Infinite when an angle reaches pi (the forces no longer span the plane).
    """
    a0, a1, a2 = np.arctan2(ny, nx)
    low = np.minimum(np.minimum(a0, a1), a2)
    high = np.maximum(np.maximum(a0, a1), a2)
    middle = np.maximum(np.minimum(a0, a1), np.minimum(np.maximum(a0, a1), a2))
    gap1, gap2 = middle - low, high - middle
    gap3 = _TWO_PI - (high - low)
    product = (np.pi - gap1) * (np.pi - gap2) * (np.pi - gap3)
    no_closure = (gap1 >= np.pi) | (gap2 >= np.pi) | (gap3 >= np.pi)
    return np.where(no_closure, np.inf, (np.pi**3 / 27.0) / product - 1.0)


def centring(
    centre: tuple[Array, Array], object_centre: tuple[Array, Array], size: Array, weight: float
) -> Array:
    """G2 / C5 = 2W |centre - C| / (M_L + m_L)."""
    return 2.0 * weight * _distance(*centre, *object_centre) / size


def force_line(
    forces: tuple[Array, Array], normals: tuple[Array, Array], friction_angle: float
) -> Array:
    """C1 = (4k/3) sum(delta_i^2) / arctan^2(mu), k = 3 if any delta_i > arctan(mu) else 1."""
    (fx, fy), (nx, ny) = forces, normals
    delta = np.arctan2(np.abs(fx * ny - fy * nx), fx * nx + fy * ny)
    k = np.where((delta > friction_angle).any(axis=0), 3.0, 1.0)
    return (4.0 * k / 3.0) * (delta**2).sum(axis=0) / friction_angle**2


def finger_extension(extensions: Array, eta: float) -> Array:
    """C3 = ((e1-e2)^2 + (e2-e3)^2 + (e3-e1)^2) / eta^2 for (3, N) extensions."""
    e1, e2, e3 = extensions
    return ((e1 - e2) ** 2 + (e2 - e3) ** 2 + (e3 - e1) ** 2) / eta**2


def finger_spread(spread: Array) -> Array:
    """C4 = 0 for theta <= pi/3, (pi/6)/(pi/2 - theta) - 1 above; infinite at theta >= pi/2."""
    value = (np.pi / 6.0) / (np.pi / 2.0 - spread) - 1.0
    value = np.where(spread >= np.pi / 2.0, np.inf, value)
    return np.where(spread <= np.pi / 3.0, 0.0, value)


# ------------------------------------------------------------------------------- array helpers
def _stack(a: dict[str, Array], prefix: str) -> tuple[Array, Array]:
    """(3, N) x and y of the per-finger vectors ``<prefix>1..3``."""
    return (np.vstack([a[f"{prefix}{i}_x"] for i in _FINGERS]),
            np.vstack([a[f"{prefix}{i}_y"] for i in _FINGERS]))


def _region_ends(a: dict[str, Array]) -> tuple[Array, Array]:
    """(2, 3, N) x and y of the region ends a and b of fingers 1..3."""
    def axis(name: str) -> Array:
        return np.stack([np.vstack([a[f"r{i}{end}_{name}"] for i in _FINGERS]) for end in "ab"])
    return axis("x"), axis("y")


def _where_two_finger(
    two_finger: NDArray[np.bool_], if_two: tuple[Array, Array], if_three: tuple[Array, Array]
) -> tuple[Array, Array]:
    return (np.where(two_finger, if_two[0], if_three[0]),
            np.where(two_finger, if_two[1], if_three[1]))


def _distance(x0: Array, y0: Array, x1: Array, y1: Array) -> Array:
    return np.sqrt((x0 - x1) ** 2 + (y0 - y1) ** 2)


# ------------------------------------------------------------------------------- validation
def _require_columns(names: object) -> None:
    present = set(names)  # type: ignore[call-overload]
    missing = [name for name in REQUIRED_COLUMNS if name not in present]
    if missing:
        raise ValueError(f"grip table is missing required column(s): {', '.join(missing)}")


def _validated_arrays(columns: Columns, row_labels: ArrayLike | None) -> dict[str, Array]:
    """Float 1-D arrays of equal length, finite where the formulas need them."""
    _require_columns(columns.keys())
    arrays = {name: _as_vector(name, columns[name]) for name in REQUIRED_COLUMNS}
    lengths = {len(v) for v in arrays.values()}
    if len(lengths) > 1:
        raise ValueError(f"descriptor arrays have different lengths: {sorted(lengths)}")
    labels = np.arange(lengths.pop()) if row_labels is None else np.asarray(row_labels)

    def fail(name: str, bad: NDArray[np.bool_], what: str) -> None:
        row = labels[int(np.argmax(bad))]
        raise ValueError(f"column {name!r} has {what} at row {row!r}")

    for name in (*FINITE_COLUMNS, TWO_FINGER):
        if not np.isfinite(arrays[name]).all():
            fail(name, ~np.isfinite(arrays[name]), "a non-finite value")
    three_finger = arrays[TWO_FINGER] == 0.0
    for name in FOCUS_COLUMNS:
        bad = three_finger & ~np.isfinite(arrays[name])
        if bad.any():
            fail(name, bad, "a non-finite value in a three-finger row")
    for prefix in ("n", "f"):
        for i in _FINGERS:
            bad = (arrays[f"{prefix}{i}_x"] == 0.0) & (arrays[f"{prefix}{i}_y"] == 0.0)
            if bad.any():
                fail(f"{prefix}{i}_x", bad, "a zero-length direction")
    for name in ("area", "semi_major"):
        if not (arrays[name] > 0.0).all():
            fail(name, ~(arrays[name] > 0.0), "a value that is not positive")
    return arrays


def _as_vector(name: str, values: ArrayLike) -> Array:
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"column {name!r} is not numeric: {error}") from None
    if array.ndim != 1:
        raise ValueError(f"column {name!r} must be 1-D, got shape {array.shape}")
    return array
