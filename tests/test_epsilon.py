"""Ferrari–Canny ε: hand-computed values, force closure, invariances, agreement with qhull."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from classifiers.evaluation.synthetic import synthetic_grips
from grip_env.params import GraspParams
from grip_env.planning.epsilon import add_epsilon, epsilon_quality


def grasp_row(points, normals, centroid=(0.0, 0.0), semi=(10.0, 10.0)) -> dict:
    row = {}
    for i, ((px, py), (nx, ny)) in enumerate(zip(points, normals, strict=True), start=1):
        norm = math.hypot(nx, ny)
        row |= {f"p{i}_x": px, f"p{i}_y": py, f"n{i}_x": nx / norm, f"n{i}_y": ny / norm}
    return row | {"centroid_x": centroid[0], "centroid_y": centroid[1],
                  "semi_major": semi[0], "semi_minor": semi[1]}  # fmt: skip


def circle_grasp(angles_deg, radius=10.0) -> dict:
    angles = np.radians(angles_deg)
    points = [(radius * np.cos(a), radius * np.sin(a)) for a in angles]
    return grasp_row(points, [(-x, -y) for x, y in points], semi=(radius, radius))


def transformed(row: dict, angle: float, offset: tuple[float, float]) -> dict:
    c, s = math.cos(angle), math.sin(angle)
    out = dict(row)
    for name in ("p1", "p2", "p3", "centroid"):
        x, y = row[f"{name}_x"], row[f"{name}_y"]
        out[f"{name}_x"], out[f"{name}_y"] = c * x - s * y + offset[0], s * x + c * y + offset[1]
    for name in ("n1", "n2", "n3"):
        x, y = row[f"{name}_x"], row[f"{name}_y"]
        out[f"{name}_x"], out[f"{name}_y"] = c * x - s * y, s * x + c * y
    return out


def eps(rows: list[dict], mu: float = 0.4, method: str = "vectorised") -> np.ndarray:
    return epsilon_quality(pd.DataFrame(rows), GraspParams(mu=mu), method=method)


def test_symmetric_three_contact_grasp_matches_hand_value():
    # Contacts at 120° on a circle of radius R, L = R, mu = tan 30°: the six edge wrenches are the
    # unit-circle points at 60° steps, alternately at tau/L = +1/2 and -1/2. The top and bottom
    # planes are at distance 1/2, the side facets at 3/(2 sqrt 5) > 1/2, so eps = 1/2.
    value = eps([circle_grasp([0, 120, 240])], mu=math.tan(math.radians(30)))
    assert value[0] == pytest.approx(0.5, abs=1e-12)


def test_equilateral_midpoint_grasp_beats_skewed_grasp():
    # Equilateral triangle with vertices on a circle of radius 20; contacts at edge midpoints.
    vertices = [(20 * math.cos(a), 20 * math.sin(a)) for a in np.radians([90, 210, 330])]
    mids = [((vertices[i][0] + vertices[(i + 1) % 3][0]) / 2,
             (vertices[i][1] + vertices[(i + 1) % 3][1]) / 2) for i in range(3)]  # fmt: skip
    normals = [(-x, -y) for x, y in mids]  # inward edge normals point at the centre
    centred = grasp_row(mids, normals, semi=(12.0, 12.0))
    # Skewed: contacts slid along their edges, same normals (still on the edges).
    skewed_points = [(x + 0.6 * (vx - x), y + 0.6 * (vy - y))
                     for (x, y), (vx, vy) in zip(mids, vertices, strict=True)]  # fmt: skip
    skewed = grasp_row(skewed_points, normals, semi=(12.0, 12.0))
    good, bad = eps([centred, skewed])
    assert good > 0.0
    assert good > bad


def test_normals_that_do_not_positively_span_give_zero():
    # All three contacts pushing in the same half-plane (+y): no force closure.
    row = grasp_row([(-10, -5), (0, -5), (10, -5)], [(0.1, 1), (0, 1), (-0.1, 1)])
    assert eps([row])[0] == 0.0
    # Two opposite contacts plus a parallel one, frictionless: flat wrench set, not closure.
    row = circle_grasp([0, 180, 90])
    assert eps([row], mu=1e-9)[0] == 0.0


@settings(max_examples=30, deadline=None)
@given(
    angle=st.floats(-math.pi, math.pi),
    dx=st.floats(-500, 500),
    dy=st.floats(-500, 500),
    gaps=st.tuples(st.floats(40, 160), st.floats(40, 160)),
)
def test_epsilon_invariant_under_rotation_and_translation(angle, dx, dy, gaps):
    row = circle_grasp([0, gaps[0], gaps[0] + gaps[1]])
    before, after = eps([row, transformed(row, angle, (dx, dy))])
    assert after == pytest.approx(before, abs=1e-9)


def test_epsilon_scale_invariant_and_grows_with_friction():
    small, large = circle_grasp([0, 110, 250], 10.0), circle_grasp([0, 110, 250], 80.0)
    assert eps([small])[0] == pytest.approx(eps([large])[0], abs=1e-12)
    assert eps([small], mu=0.8)[0] > eps([small], mu=0.3)[0] > 0.0


def test_vectorised_agrees_with_qhull_reference():
    table = synthetic_grips(15, seed=3)
    fast = epsilon_quality(table, GraspParams(mu=0.4))
    reference = epsilon_quality(table, GraspParams(mu=0.4), method="qhull")
    np.testing.assert_allclose(fast, reference, atol=1e-9)
    assert (fast > 0).any() and (fast == 0).any()


def test_add_epsilon_and_bad_input():
    table = synthetic_grips(3, seed=0)
    assert "eps" in add_epsilon(table).columns and "eps" not in table.columns
    with pytest.raises(ValueError, match="missing"):
        epsilon_quality(table.drop(columns=["n2_x"]))
    with pytest.raises(ValueError, match="finite"):
        epsilon_quality(table.assign(p1_x=np.nan))
    with pytest.raises(ValueError, match="method"):
        epsilon_quality(table, method="exact")
