"""The twelve quality measures: hand values, halfway points, caps, invariances, reference."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grip_env.objects import make_shape
from grip_env.params import CONE_EDGE_TOLERANCE_RAD, GraspParams, outside_cone
from grip_env.planning.features import (
    FEATURE_NAMES,
    INDEX_NAMES,
    OUTPUT_NAMES,
    REQUIRED_COLUMNS,
    compute_features,
    features_from_arrays,
    force_line_from_deviations,
)
from tests.benchmarks.reference_features import random_grip_table, reference_features

PARAMS = GraspParams()
NU = math.atan(PARAMS.mu)
CAP = PARAMS.feature_cap


# ------------------------------------------------------------------------------- row builders
def _unit(angle: float) -> tuple[float, float]:
    return math.cos(angle), math.sin(angle)


def _set(row: dict, prefix: str, i: int, xy: tuple[float, float] | np.ndarray) -> None:
    row[f"{prefix}{i}_x"], row[f"{prefix}{i}_y"] = float(xy[0]), float(xy[1])


def ideal_triangle_row() -> dict:
    """The equilateral triangle grasped at its edge midpoints by the ideal configuration."""
    obj = make_shape("triangle")
    vertices, centre = obj.contour, obj.centroid
    row: dict = {"two_finger": False}
    for i in range(3):
        a, b = vertices[i], vertices[(i + 1) % 3]
        midpoint = (a + b) / 2
        inward = (centre - midpoint) / np.linalg.norm(centre - midpoint)
        _set(row, "p", i + 1, midpoint)
        _set(row, "n", i + 1, inward)
        _set(row, "f", i + 1, inward)
        row[f"r{i + 1}a_x"], row[f"r{i + 1}a_y"] = float(a[0]), float(a[1])
        row[f"r{i + 1}b_x"], row[f"r{i + 1}b_y"] = float(b[0]), float(b[1])
        row[f"rho{i + 1}"] = 0.0
        row[f"e{i + 1}"] = 80.0
    row["cg_x"] = row["cc_x"] = float(centre[0])
    row["cg_y"] = row["cc_y"] = float(centre[1])
    row["spread"] = math.pi / 3
    row.update(obj.descriptors())
    return row


def two_finger_row(thumb: tuple[float, float] = (0.0, 20.0)) -> dict:
    """Fingers 1, 2 at (-20, 0), (20, 0) on one region along y = 0, the thumb at ``thumb``."""
    row: dict = {"two_finger": True}
    _set(row, "p", 1, (-20.0, 0.0))
    _set(row, "p", 2, (20.0, 0.0))
    _set(row, "p", 3, thumb)
    for i, normal in ((1, (0.0, 1.0)), (2, (0.0, 1.0)), (3, (0.0, -1.0))):
        _set(row, "n", i, normal)
        _set(row, "f", i, normal)
    for i in (1, 2):
        row[f"r{i}a_x"], row[f"r{i}a_y"] = -50.0, 0.0
        row[f"r{i}b_x"], row[f"r{i}b_y"] = 50.0, 0.0
    row["r3a_x"], row["r3a_y"] = thumb[0] + 30.0, thumb[1]
    row["r3b_x"], row["r3b_y"] = thumb[0] - 30.0, thumb[1]
    for i in (1, 2, 3):
        row[f"rho{i}"] = 0.0
        row[f"e{i}"] = 60.0
    row.update(cg_x=np.nan, cg_y=np.nan, cc_x=np.nan, cc_y=np.nan, spread=0.05)
    row.update(area=6000.0, centroid_x=0.0, centroid_y=0.0, semi_major=40.0, semi_minor=20.0)
    return row


def features_of(*rows: dict, params: GraspParams = PARAMS) -> pd.DataFrame:
    return compute_features(pd.DataFrame(list(rows)), params)


def feature(row: dict, name: str, params: GraspParams = PARAMS) -> float:
    return float(features_of(row, params=params)[name].iloc[0])


def rotated_force(row: dict, i: int, delta: float) -> dict:
    """``row`` with F_i turned by ``delta`` from N_i."""
    angle = math.atan2(row[f"n{i}_y"], row[f"n{i}_x"]) + delta
    out = dict(row)
    _set(out, "f", i, _unit(angle))
    return out


# ------------------------------------------------------------------------------- ideal grip
def test_names() -> None:
    assert FEATURE_NAMES == ("S1", "S2", "S3", "S4", "G1", "G2", "C1", "C2", "C3", "C4", "C5", "C6")
    assert INDEX_NAMES == ("Q_G", "Q_C")
    assert OUTPUT_NAMES == FEATURE_NAMES + INDEX_NAMES


def test_ideal_equilateral_grip_is_best_everywhere() -> None:
    values = features_of(ideal_triangle_row()).iloc[0]
    expected = dict.fromkeys(FEATURE_NAMES, 0.0) | {"S2": 1.0, "S4": 1.0}
    for name, value in expected.items():
        assert values[name] == pytest.approx(value, abs=1e-9), name
    assert values["Q_G"] == pytest.approx(2.0)
    assert values["Q_C"] == pytest.approx(2.0)


def test_triangle_size_scales_with_weight_and_area() -> None:
    row = ideal_triangle_row()
    assert feature(row, "S2", GraspParams(weight=2.0)) == pytest.approx(2.0)
    row["area"] *= 3.0
    assert feature(row, "S2") == pytest.approx(3.0)


# ------------------------------------------------------------------------------- halfway values
def test_point_arrangement_hand_values() -> None:
    row = ideal_triangle_row()
    _set(row, "p", 1, (0.0, 0.0))
    _set(row, "p", 2, (10.0, 0.0))
    _set(row, "p", 3, (30.0, 0.0))  # a segment: the worst case
    assert feature(row, "S1") == pytest.approx(2.0)
    _set(row, "p", 3, (0.0, 10.0))  # right isosceles: pi/2, pi/4, pi/4
    assert feature(row, "S1") == pytest.approx(3 / (2 * math.pi) * (math.pi / 3))
    _set(row, "p", 2, (0.0, 0.0))  # two coincident contacts count as a segment
    assert feature(row, "S1") == pytest.approx(2.0)


def test_grasping_margin_hand_values() -> None:
    row = ideal_triangle_row()
    end = np.array([row["p1_x"], row["p1_y"]]) + np.array([1.0, 0.0]) * PARAMS.lam / 2
    row["r1a_x"], row["r1a_y"] = float(end[0]), float(end[1])
    assert feature(row, "S3") == pytest.approx(1.0)
    row["r3b_x"], row["r3b_y"] = row["p3_x"], row["p3_y"] + PARAMS.lam / 4
    assert feature(row, "S3") == pytest.approx(1.0 + 3.0)
    row["r2b_x"], row["r2b_y"] = row["p2_x"] + PARAMS.lam, row["p2_y"]  # d = lambda: no risk
    assert feature(row, "S3") == pytest.approx(4.0)


def test_contact_curvature() -> None:
    row = ideal_triangle_row()
    assert feature(row, "S4") == pytest.approx(1.0)
    row.update(rho1=0.1, rho2=0.2, rho3=-0.1)
    assert feature(row, "S4") == pytest.approx(0.8)


@pytest.mark.parametrize("order", [(0, 1, 2), (2, 0, 1), (1, 2, 0), (2, 1, 0)])
def test_force_arrangement_by_hand(order: tuple[int, int, int]) -> None:
    # directions at 0, pi/2, 5pi/4: gaps pi/2, 3pi/4, 3pi/4 -> (pi^3/27)/(pi^3/32) - 1 = 5/27
    angles = (0.0, math.pi / 2, 5 * math.pi / 4)
    row = ideal_triangle_row()
    for i, k in enumerate(order):
        _set(row, "n", i + 1, _unit(angles[k] + 0.3))
    assert feature(row, "G1") == pytest.approx(5 / 27)


def test_focus_centring_by_hand() -> None:
    row = ideal_triangle_row()
    row.update(semi_major=40.0, semi_minor=20.0, cg_x=row["centroid_x"] + 18.0)
    assert feature(row, "G2") == pytest.approx(2 * 18.0 / 60.0)
    assert feature(row, "G2", GraspParams(weight=0.5)) == pytest.approx(18.0 / 60.0)


def test_force_line_halfway_and_threshold_jump() -> None:
    row = ideal_triangle_row()
    for i, sign in ((1, 1.0), (2, -1.0), (3, 1.0)):
        row = rotated_force(row, i, sign * NU / 2)
    assert feature(row, "C1") == pytest.approx(1.0)
    inside = rotated_force(ideal_triangle_row(), 2, 0.99 * NU)
    outside = rotated_force(ideal_triangle_row(), 2, -1.01 * NU)
    assert feature(inside, "C1") == pytest.approx(4 / 3 * 0.99**2)
    assert feature(outside, "C1") == pytest.approx(4 * 1.01**2)  # k = 3


@pytest.mark.parametrize(
    ("excess", "k"),
    [(0.0, 1), (-1e-12, 1), (1e-16, 1), (0.5 * CONE_EDGE_TOLERANCE_RAD, 1),
     (2 * CONE_EDGE_TOLERANCE_RAD, 3), (1e-6, 3)],
    ids=["at", "just-inside", "at+rounding", "within-tolerance", "beyond-tolerance", "outside"],
)
def test_cone_edge_is_decided_by_one_tolerance(excess: float, k: int) -> None:
    delta = NU + excess
    assert bool(outside_cone(delta, NU)) == (k == 3)
    value = force_line_from_deviations([np.array([delta]), np.zeros(1), np.zeros(1)], NU)
    assert value[0] == pytest.approx(4 * k / 3 * delta**2 / NU**2, rel=1e-12)


@pytest.mark.parametrize(("scale", "k"), [(1.0, 1), (1.0 - 1e-7, 1), (1.0 + 1e-7, 3)])
def test_force_exactly_on_the_cone_edge_counts_inside(scale: float, k: int) -> None:
    """F turned by arctan(mu) from N (delta equal to the edge up to rounding) gives k = 1, both
    in the features and in the thumb search's value; just beyond the tolerance gives k = 3."""
    from grip_env.planning.barrett import force_line_value

    row = rotated_force(ideal_triangle_row(), 2, scale * NU)
    expected = 4 * k / 3 * scale**2
    assert feature(row, "C1") == pytest.approx(expected, rel=1e-9)
    forces = np.array([[[row[f"f{i}_x"], row[f"f{i}_y"]] for i in (1, 2, 3)]])
    normals = np.array([[[row[f"n{i}_x"], row[f"n{i}_y"]] for i in (1, 2, 3)]])
    assert force_line_value(forces, normals, NU)[0] == pytest.approx(expected, rel=1e-9)


def test_real_focus_deviation_and_centring() -> None:
    row = ideal_triangle_row()
    row.update(semi_major=40.0, semi_minor=20.0)
    shift = PARAMS.eta * PARAMS.mu / 2
    row["cc_y"] = row["cg_y"] + shift
    assert feature(row, "C2") == pytest.approx(1.0)
    assert feature(row, "C5") == pytest.approx(2 * shift / 60.0)
    assert feature(row, "G2") == pytest.approx(0.0, abs=1e-12)


def test_finger_extension() -> None:
    row = ideal_triangle_row()
    row["e1"] = 80.0 + PARAMS.eta / math.sqrt(2)
    assert feature(row, "C3") == pytest.approx(1.0)
    row.update(e1=PARAMS.eta, e2=0.0, e3=0.0)  # the maximum
    assert feature(row, "C3") == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("spread", "expected"),
    [
        (0.0, 0.0),
        (0.4, 0.0),
        (math.pi / 3, 0.0),
        (math.pi / 2 - math.pi / 12, 1.0),
        (1.2, (math.pi / 6) / (math.pi / 2 - 1.2) - 1),
    ],
)
def test_finger_spread(spread: float, expected: float) -> None:
    row = ideal_triangle_row() | {"spread": spread}
    assert feature(row, "C4") == pytest.approx(expected, abs=1e-12)


def test_finger_limit_in_millimetres() -> None:
    row = ideal_triangle_row() | {"e1": PARAMS.eta + 3.0, "e2": PARAMS.eta - 5.0, "e3": 120.0}
    assert feature(row, "C6") == pytest.approx(3.0 + (120.0 - PARAMS.eta))


def test_indexes_sum_their_features() -> None:
    values = compute_features(random_grip_table(50, seed=3))
    shared = values[["S1", "S2", "S3", "S4"]].sum(axis=1)
    np.testing.assert_allclose(values["Q_G"], shared + values[["G1", "G2"]].sum(axis=1))
    configuration = values[["C1", "C2", "C3", "C4", "C5", "C6"]].sum(axis=1)
    np.testing.assert_allclose(values["Q_C"], shared + configuration)


# ------------------------------------------------------------------------------- two-finger grips
@pytest.mark.parametrize(
    ("thumb", "expected"),
    [
        ((0.0, 20.0), 1.0),  # beta = gamma = pi/4, alpha = pi/2
        ((0.0, 20.0 * math.sqrt(3)), 2 / 3),  # equilateral: alpha = pi/3
        ((20.0, 20.0), 2 - 4 * math.atan(0.5) / math.pi),
    ],  # beta = atan(1/2), gamma = pi/2
)
def test_two_finger_point_arrangement(thumb: tuple[float, float], expected: float) -> None:
    assert feature(two_finger_row(thumb), "S1") == pytest.approx(expected)


def test_two_finger_forms() -> None:
    row = two_finger_row((0.0, 30.0))
    values = features_of(row).iloc[0]
    assert values["G1"] == 0.0  # the three-finger formula would cap these opposed forces
    assert values["C2"] == 0.0
    centre_distance = 10.0  # C_T = (0, 30/3), C = (0, 0)
    assert values["G2"] == pytest.approx(2 * centre_distance / 60.0)
    assert values["C5"] == pytest.approx(2 * centre_distance / 60.0)
    assert values["S2"] == pytest.approx(6000.0 / (4 * 0.5 * 40.0 * 30.0))
    three = row | {"two_finger": False, "cg_x": 0.0, "cg_y": 5.0, "cc_x": 0.0, "cc_y": 5.0}
    assert feature(three, "G1") == CAP


# ------------------------------------------------------------------------------- caps
def test_caps() -> None:
    row = ideal_triangle_row()
    touching = row | {"r2a_x": row["p2_x"], "r2a_y": row["p2_y"]}
    assert feature(touching, "S3") == CAP
    opposed = dict(row)
    for i, direction in ((1, (1.0, 0.0)), (2, (-1.0, 0.0)), (3, (0.0, 1.0))):
        _set(opposed, "n", i, direction)
    assert feature(opposed, "G1") == CAP
    for spread in (math.pi / 2, 1.7):
        assert feature(row | {"spread": spread}, "C4") == CAP
    assert feature(row | {"spread": math.pi / 2 - 1e-9}, "C4") == CAP  # huge, above the cap
    segment = row | {"p3_x": 2 * row["p2_x"] - row["p1_x"], "p3_y": 2 * row["p2_y"] - row["p1_y"]}
    assert feature(segment, "S2") == CAP
    assert feature(touching, "S3", GraspParams(feature_cap=7.0)) == 7.0
    assert features_of(touching)["Q_G"].iloc[0] == pytest.approx(CAP + 1.0 + 1.0)


# ------------------------------------------------------------------------------- invariances
POINT_PREFIXES = ("p1", "p2", "p3", "r1a", "r1b", "r2a", "r2b", "r3a", "r3b", "cg", "cc")
POINT_PREFIXES += ("centroid",)
DIRECTION_PREFIXES = ("n1", "n2", "n3", "f1", "f2", "f3")


def moved(
    table: pd.DataFrame, angle: float, offset: tuple[float, float], scale: float
) -> pd.DataFrame:
    """Rotate, scale and translate every point; rotate every direction; scale every length."""
    out = table.copy()
    c, s = math.cos(angle), math.sin(angle)
    for prefix in POINT_PREFIXES + DIRECTION_PREFIXES:
        x, y = table[f"{prefix}_x"], table[f"{prefix}_y"]
        is_point = prefix in POINT_PREFIXES
        k = scale if is_point else 1.0
        out[f"{prefix}_x"] = k * (c * x - s * y) + (offset[0] if is_point else 0.0)
        out[f"{prefix}_y"] = k * (s * x + c * y) + (offset[1] if is_point else 0.0)
    for name in ("e1", "e2", "e3", "semi_major", "semi_minor"):
        out[name] = scale * table[name]
    out["area"] = scale**2 * table["area"]
    return out


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    angle=st.floats(-math.pi, math.pi),
    offset=st.tuples(st.floats(-500, 500), st.floats(-500, 500)),
)
def test_rigid_motion_changes_nothing(seed: int, angle: float, offset: tuple[float, float]) -> None:
    table = random_grip_table(40, seed=seed)
    before = compute_features(table)
    after = compute_features(moved(table, angle, offset, 1.0))
    np.testing.assert_allclose(after, before, rtol=1e-7, atol=1e-7)


SCALE_FREE = ["S1", "S2", "S4", "G1", "G2", "C1", "C4", "C5"]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), scale=st.floats(0.25, 4.0), angle=st.floats(-3.2, 3.2))
def test_scaling_lengths(seed: int, scale: float, angle: float) -> None:
    table = random_grip_table(40, seed=seed)
    before = compute_features(table)
    scaled = moved(table, angle, (3.0, -7.0), scale)
    after = compute_features(scaled)
    np.testing.assert_allclose(after[SCALE_FREE], before[SCALE_FREE], rtol=1e-7, atol=1e-7)
    # the length thresholds scale with the object: then S3, C2, C3 are unchanged and C6 scales
    uncapped = GraspParams(feature_cap=1e6)
    params = GraspParams(lam=PARAMS.lam * scale, eta=PARAMS.eta * scale, feature_cap=1e6)
    before, rescaled = compute_features(table, uncapped), compute_features(scaled, params)
    np.testing.assert_allclose(
        rescaled[["S3", "C2", "C3"]], before[["S3", "C2", "C3"]], rtol=1e-7, atol=1e-7
    )
    np.testing.assert_allclose(rescaled["C6"], scale * before["C6"], rtol=1e-7, atol=1e-7)


# ------------------------------------------------------------------------------- reference
@pytest.mark.parametrize(
    "params", [PARAMS, GraspParams(mu=0.2, lam=5.0, weight=2.0, eta=90.0, feature_cap=30.0)]
)
def test_matches_per_grip_reference(params: GraspParams) -> None:
    table = random_grip_table(400, seed=11)
    hand_rows = pd.DataFrame([ideal_triangle_row(), two_finger_row(), two_finger_row((9.0, 14.0))])
    table = pd.concat(
        [table, hand_rows[table.columns.intersection(hand_rows.columns)]], ignore_index=True
    )
    pd.testing.assert_frame_equal(
        compute_features(table, params), reference_features(table, params), rtol=1e-9, atol=1e-9
    )


def test_arrays_entry_matches_table_entry() -> None:
    table = random_grip_table(30, seed=5)
    arrays = {name: table[name].to_numpy() for name in REQUIRED_COLUMNS}
    np.testing.assert_array_equal(features_from_arrays(arrays), compute_features(table).to_numpy())


# ------------------------------------------------------------------------------- bad input
def test_keeps_the_index_and_handles_empty_tables() -> None:
    table = random_grip_table(4, seed=1)
    table.index = [10, 20, 30, 40]
    assert list(compute_features(table).index) == [10, 20, 30, 40]
    empty = compute_features(table.iloc[:0])
    assert list(empty.columns) == list(OUTPUT_NAMES)
    assert len(empty) == 0


def test_missing_columns_are_named() -> None:
    table = random_grip_table(3).drop(columns=["p2_y", "semi_minor"])
    with pytest.raises(ValueError, match=r"p2_y, semi_minor"):
        compute_features(table)


def test_non_finite_descriptors_name_column_and_row() -> None:
    table = random_grip_table(5, seed=2, two_finger_share=0.0)
    table.index = list("abcde")
    bad = table.copy()
    bad.loc["c", "f2_y"] = np.inf
    with pytest.raises(ValueError, match=r"'f2_y'.*row 'c'"):
        compute_features(bad)
    bad = table.copy()
    bad.loc["d", "cc_x"] = np.nan  # a three-finger row needs its real focus
    with pytest.raises(ValueError, match=r"'cc_x'.*row 'd'"):
        compute_features(bad)
    bad = table.copy()
    bad.loc["b", ["n3_x", "n3_y"]] = 0.0
    with pytest.raises(ValueError, match=r"'n3_x'.*zero-length.*row 'b'"):
        compute_features(bad)
    bad = table.copy()
    bad.loc["e", "area"] = 0.0
    with pytest.raises(ValueError, match=r"'area'.*row 'e'"):
        compute_features(bad)


def test_two_finger_rows_may_have_no_foci() -> None:
    row = two_finger_row()
    assert math.isnan(row["cg_x"]) and math.isnan(row["cc_y"])
    assert np.isfinite(features_of(row).to_numpy()).all()
