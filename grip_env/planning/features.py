"""The twelve quality measures of a grip (paper section V) and the two global indexes Q_G, Q_C.

All grips are computed at once from the descriptor columns of the candidate table (DESIGN's
column contract). :func:`compute_features` takes the table; :func:`features_from_arrays` takes a
mapping from the same column names to 1-D arrays, for callers that already hold arrays.

Choices the paper leaves open follow DESIGN: interior angles of the contact triangle for S1 (the
two-finger form S1'' has alpha at the thumb contact P3), consecutive angles around the circle for
G1, unsigned deviation angles for C1, ``eta*mu/2`` in C2, C6 in millimetres, and any feature that is
infinite, undefined or above ``params.feature_cap`` stored as ``feature_cap``. Two-finger rows have
G1 = C2 = 0 and use the contact triangle's centroid C_T in G2 and C5. C1's cone edge: a deviation
counts as outside the friction cone only beyond ``grip_env.params.CONE_EDGE_TOLERANCE_RAD``, the
same rule the thumb search and ``validate`` use.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

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
from grip_env.params import DEFAULT_PARAMS, GraspParams, outside_cone

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

_FINGERS = ("1", "2", "3")
_TWO_PI = 2.0 * np.pi
_CHUNK_ROWS = 8192

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
        return pd.DataFrame(
            np.zeros((0, len(OUTPUT_NAMES))), index=table.index, columns=list(OUTPUT_NAMES)
        )
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
        (N, 14) float array (column-major), columns in :data:`OUTPUT_NAMES` order.

    Raises:
        ValueError: as :func:`compute_features`; bad rows are named by position or label.
    """
    arrays = _validated_arrays(columns, row_labels)
    count = len(arrays[TWO_FINGER])
    out = np.empty((len(OUTPUT_NAMES), count))
    for start in range(0, count, _CHUNK_ROWS):  # chunks keep the temporaries in cache
        rows = slice(start, start + _CHUNK_ROWS)
        _fill_outputs(out[:, rows], {name: v[rows] for name, v in arrays.items()}, params)
    return out.T


def _fill_outputs(out: Array, arrays: dict[str, Array], params: GraspParams) -> None:
    """Write the capped features and the two indexes of one chunk into ``out`` (14, n)."""
    for row, value in zip(out, _features(arrays, params), strict=False):
        np.fmin(value, params.feature_cap, out=row)  # fmin also turns NaN into the cap
    shared = out[0] + out[1] + out[2] + out[3]
    np.add(shared, out[4] + out[5], out=out[12])
    np.add(shared, out[6] + out[7] + out[8] + out[9] + out[10] + out[11], out=out[13])


# ------------------------------------------------------------------------------- the formulas
Vectors = tuple[Array, Array]  # x and y of n points or directions


def _features(a: dict[str, Array], params: GraspParams) -> list[Array]:
    """The twelve uncapped features of n grips; infinite where a formula is undefined."""
    two_finger = a[TWO_FINGER] != 0.0
    p, n, f = (_per_finger(a, prefix) for prefix in ("p", "n", "f"))
    ends = [(_vector(a, f"r{i}a"), _vector(a, f"r{i}b")) for i in _FINGERS]
    extensions = [a[name] for name in EXTENSIONS]
    triangle_centre = ((p[0][0] + p[1][0] + p[2][0]) / 3.0, (p[0][1] + p[1][1] + p[2][1]) / 3.0)
    grasp_focus = _where_two_finger(two_finger, triangle_centre, _vector(a, "cg"))
    real_focus = _where_two_finger(two_finger, triangle_centre, _vector(a, "cc"))
    centre, size = _vector(a, "centroid"), a["semi_major"] + a["semi_minor"]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return [
            point_arrangement(p, two_finger),
            triangle_size(p, a["area"], params.weight),
            grasping_margin(p, ends, params.lam),
            1.0 - (a["rho1"] + a["rho2"] + a["rho3"]),
            np.where(two_finger, 0.0, force_arrangement(n)),
            centring(grasp_focus, centre, size, params.weight),
            force_line(f, n, params.friction_angle),
            np.where(
                two_finger,
                0.0,
                _distance(_vector(a, "cg"), real_focus) / (params.eta * params.mu / 2.0),
            ),
            finger_extension(extensions, params.eta),
            finger_spread(a["spread"]),
            centring(real_focus, centre, size, params.weight),
            finger_limit(extensions, params.eta),
        ]


def point_arrangement(p: Sequence[Vectors], two_finger: NDArray[np.bool_]) -> Array:
    """S1 from the interior angles of the contact triangle P1 P2 P3; S1'' in two-finger rows.

    A triangle with two coincident contacts counts as degenerate to a segment (S1 = 2).
    """
    beta, gamma, alpha = (_interior_angle(p[i], p[(i + 1) % 3], p[(i + 2) % 3]) for i in range(3))
    third = np.pi / 3.0
    three = (3.0 / (2.0 * np.pi)) * (
        np.abs(alpha - third) + np.abs(beta - third) + np.abs(gamma - third)
    )
    two = (2.0 / np.pi) * (np.abs(beta - gamma) + alpha)
    coincident = _same(p[0], p[1]) | _same(p[1], p[2]) | _same(p[2], p[0])
    return np.where(coincident, 2.0, np.where(two_finger, two, three))


def triangle_size(p: Sequence[Vectors], area: Array, weight: float) -> Array:
    """S2 = W * A / (4 * A_T)."""
    (x0, y0), (x1, y1), (x2, y2) = p
    triangle_area = 0.5 * np.abs((x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0))
    return weight * area / (4.0 * triangle_area)


def grasping_margin(
    p: Sequence[Vectors], ends: Sequence[tuple[Vectors, Vectors]], lam: float
) -> Array:
    """S3: sum over the six contact-to-region-end distances d of (lam/d - 1 if d < lam else 0)."""
    total = np.zeros_like(p[0][0])
    for contact, region in zip(p, ends, strict=True):
        for end in region:
            total += np.maximum(lam / _distance(contact, end) - 1.0, 0.0)
    return total


def force_arrangement(n: Sequence[Vectors]) -> Array:
    """G1 from the three angles between consecutive force directions around the circle.

    Infinite when an angle reaches pi (the forces no longer span the plane).
    """
    a0, a1, a2 = (np.arctan2(y, x) for x, y in n)
    low = np.minimum(np.minimum(a0, a1), a2)
    high = np.maximum(np.maximum(a0, a1), a2)
    middle = np.maximum(np.minimum(a0, a1), np.minimum(np.maximum(a0, a1), a2))
    gap1, gap2 = middle - low, high - middle
    gap3 = _TWO_PI - (high - low)
    product = (np.pi - gap1) * (np.pi - gap2) * (np.pi - gap3)
    no_closure = (gap1 >= np.pi) | (gap2 >= np.pi) | (gap3 >= np.pi)
    return np.where(no_closure, np.inf, (np.pi**3 / 27.0) / product - 1.0)


def centring(centre: Vectors, object_centre: Vectors, size: Array, weight: float) -> Array:
    """G2 / C5 = 2W |centre - C| / (M_L + m_L)."""
    return (2.0 * weight) * _distance(centre, object_centre) / size


def force_line(f: Sequence[Vectors], n: Sequence[Vectors], friction_angle: float) -> Array:
    """C1 = (4k/3) sum(delta_i^2) / arctan^2(mu), k = 3 if any delta_i > arctan(mu) else 1."""
    deltas = [_angle_between(fi, ni) for fi, ni in zip(f, n, strict=True)]
    return force_line_from_deviations(deltas, friction_angle)


def force_line_from_deviations(deltas: Sequence[Array], friction_angle: float) -> Array:
    """C1 from the three deviations delta_i (rad); the cone edge is decided by ``outside_cone``.

    A delta within ``CONE_EDGE_TOLERANCE_RAD`` of arctan(mu) counts as inside (k = 1).
    """
    d0, d1, d2 = deltas
    outside = (outside_cone(d0, friction_angle) | outside_cone(d1, friction_angle)
               | outside_cone(d2, friction_angle))
    k = np.where(outside, 3.0, 1.0)
    return (4.0 / (3.0 * friction_angle**2)) * k * (d0 * d0 + d1 * d1 + d2 * d2)


def finger_extension(e: Sequence[Array], eta: float) -> Array:
    """C3 = ((e1-e2)^2 + (e2-e3)^2 + (e3-e1)^2) / eta^2."""
    e1, e2, e3 = e
    return ((e1 - e2) ** 2 + (e2 - e3) ** 2 + (e3 - e1) ** 2) / eta**2


def finger_spread(spread: Array) -> Array:
    """C4 = 0 for theta <= pi/3, (pi/6)/(pi/2 - theta) - 1 above; infinite at theta >= pi/2."""
    value = np.where(spread >= np.pi / 2.0, np.inf, (np.pi / 6.0) / (np.pi / 2.0 - spread) - 1.0)
    return np.where(spread <= np.pi / 3.0, 0.0, value)


def finger_limit(e: Sequence[Array], eta: float) -> Array:
    """C6 = sum of the extensions beyond eta (mm)."""
    e1, e2, e3 = e
    return np.maximum(e1 - eta, 0.0) + np.maximum(e2 - eta, 0.0) + np.maximum(e3 - eta, 0.0)


# ------------------------------------------------------------------------------- vector helpers
def _vector(a: dict[str, Array], prefix: str) -> Vectors:
    return a[f"{prefix}_x"], a[f"{prefix}_y"]


def _per_finger(a: dict[str, Array], prefix: str) -> list[Vectors]:
    return [_vector(a, f"{prefix}{i}") for i in _FINGERS]


def _where_two_finger(two_finger: NDArray[np.bool_], if_two: Vectors, if_three: Vectors) -> Vectors:
    return (
        np.where(two_finger, if_two[0], if_three[0]),
        np.where(two_finger, if_two[1], if_three[1]),
    )


def _distance(u: Vectors, v: Vectors) -> Array:
    return np.sqrt((u[0] - v[0]) ** 2 + (u[1] - v[1]) ** 2)


def _same(u: Vectors, v: Vectors) -> NDArray[np.bool_]:
    return (u[0] == v[0]) & (u[1] == v[1])


def _angle_between(u: Vectors, v: Vectors) -> Array:
    """Unsigned angle in [0, pi] between directions u and v."""
    return np.arctan2(np.abs(u[0] * v[1] - u[1] * v[0]), u[0] * v[0] + u[1] * v[1])


def _interior_angle(at: Vectors, to1: Vectors, to2: Vectors) -> Array:
    """Angle at ``at`` between the sides towards ``to1`` and ``to2``."""
    return _angle_between((to1[0] - at[0], to1[1] - at[1]), (to2[0] - at[0], to2[1] - at[1]))


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

    def check(name: str, ok: NDArray[np.bool_], what: str) -> None:
        if not ok.all():
            row = labels[int(np.argmin(ok))]
            raise ValueError(f"column {name!r} has {what} at row {row!r}")

    for name in (*FINITE_COLUMNS, TWO_FINGER):
        if not np.isfinite(arrays[name].sum()):  # fast path: a finite sum means finite values
            check(name, np.isfinite(arrays[name]), "a non-finite value")
    two_finger = arrays[TWO_FINGER] != 0.0
    for name in FOCUS_COLUMNS:
        if not np.isfinite(arrays[name].sum()):
            check(
                name,
                two_finger | np.isfinite(arrays[name]),
                "a non-finite value in a three-finger row",
            )
    for prefix in ("n", "f"):
        for i in _FINGERS:
            x, y = _vector(arrays, f"{prefix}{i}")
            check(f"{prefix}{i}_x", np.logical_or(x, y), "a zero-length direction")
    for name in ("area", "semi_major"):
        check(name, arrays[name] > 0.0, "a value that is not positive")
    return arrays


def _as_vector(name: str, values: ArrayLike) -> Array:
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"column {name!r} is not numeric: {error}") from None
    if array.ndim != 1:
        raise ValueError(f"column {name!r} must be 1-D, got shape {array.shape}")
    return array
