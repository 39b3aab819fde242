"""Planar objects: known descriptors, validation, transforms, object sets."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grip_env.objects import (
    SHAPE_NAMES,
    PlanarObject,
    load_object_set,
    make_shape,
    procedural_objects,
    random_object,
)
from grip_env.objects.shapes import ellipse, rectangle, regular_polygon


def test_rectangle_descriptors_match_closed_form():
    obj = PlanarObject.from_polygon(rectangle(80, 40) + [10, -5])
    assert obj.area == pytest.approx(3200)
    np.testing.assert_allclose(obj.centroid, [10, -5], atol=1e-12)
    # variance of a uniform bar of length w is w^2/12; semi-axis = 2 * sqrt(variance)
    assert obj.inertia_semi_axes == pytest.approx((80 / math.sqrt(3), 40 / math.sqrt(3)))
    assert obj.major_axis_angle == pytest.approx(0.0, abs=1e-12)


def test_triangle_descriptors_match_closed_form():
    obj = PlanarObject.from_polygon([[0, 0], [60, 0], [0, 30]])
    assert obj.area == pytest.approx(900)
    np.testing.assert_allclose(obj.centroid, [20, 10])
    # right triangle legs a (x), b (y): var_x = a^2/18, var_y = b^2/18, cov = -a b / 36
    expected = np.array([[60**2 / 18, -60 * 30 / 36], [-60 * 30 / 36, 30**2 / 18]])
    np.testing.assert_allclose(obj.second_moments, expected, rtol=1e-12)


def test_ellipse_semi_axes_are_its_own():
    obj = PlanarObject.from_polygon(ellipse(50, 20, points=2000))
    assert obj.area == pytest.approx(math.pi * 50 * 20, rel=1e-4)
    assert obj.inertia_semi_axes == pytest.approx((50, 20), rel=1e-4)


def test_contour_is_stored_counter_clockwise():
    clockwise = rectangle(10, 20)[::-1]
    obj = PlanarObject.from_polygon(clockwise)
    x, y = obj.contour.T
    assert (x * np.roll(y, -1) - np.roll(x, -1) * y).sum() > 0
    assert obj.area == pytest.approx(200)


def test_closing_vertex_and_duplicates_are_dropped():
    square = [[0, 0], [10, 0], [10, 0], [10, 10], [0, 10], [0, 0]]
    assert len(PlanarObject.from_polygon(square).contour) == 4


@pytest.mark.parametrize(
    ("vertices", "message"),
    [
        ([[0, 0], [1, 0]], "at least 3"),
        ([[0, 0], [1, 0], [2, 0]], "zero area"),
        ([[0, 0], [10, 10], [10, 0], [0, 10]], "not simple"),
        ([[0, 0], [float("nan"), 0], [0, 1]], "not finite"),
        ([[0, 0], [float("inf"), 0], [0, 1]], "not finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "shape"),
        ("abc", "numbers"),
    ],
)
def test_bad_polygons_are_refused_with_a_named_reason(vertices, message):
    with pytest.raises(ValueError, match=message):
        PlanarObject.from_polygon(vertices, name="bad")


@settings(max_examples=40, deadline=None)
@given(
    angle=st.floats(-math.pi, math.pi),
    dx=st.floats(-500, 500),
    dy=st.floats(-500, 500),
    scale=st.floats(0.2, 5.0),
    shape=st.sampled_from(SHAPE_NAMES),
)
def test_descriptors_transform_with_the_object(angle, dx, dy, scale, shape):
    obj = make_shape(shape)
    moved = obj.transformed(angle, (dx, dy), scale)
    assert moved.area == pytest.approx(obj.area * scale**2, rel=1e-9)
    c, s = math.cos(angle), math.sin(angle)
    expected = scale * np.array([[c, -s], [s, c]]) @ obj.centroid + [dx, dy]
    np.testing.assert_allclose(moved.centroid, expected, atol=1e-6)
    np.testing.assert_allclose(
        moved.inertia_semi_axes, np.array(obj.inertia_semi_axes) * scale, rtol=1e-7
    )


@pytest.mark.parametrize("shape", SHAPE_NAMES)
def test_convex_pieces_tile_the_object_exactly(shape):
    obj = make_shape(shape)
    pieces = obj.convex_pieces()
    total = sum(PlanarObject.from_polygon(p).area for p in pieces)
    assert total == pytest.approx(obj.area, rel=1e-9)
    for piece in pieces:
        assert PlanarObject.from_polygon(piece).is_convex


def test_default_set_has_enough_hand_sized_shapes():
    objects = load_object_set("default")
    assert len(objects) >= 12
    assert len({o.name for o in objects}) == len(objects)
    for obj in objects:
        assert 40 <= obj.diameter <= 160, obj.name
        np.testing.assert_allclose(obj.centroid, 0, atol=1e-9)
    assert any(not o.is_convex for o in objects)


def test_unknown_set_is_refused():
    with pytest.raises(ValueError, match="unknown object set 'nope'"):
        load_object_set("nope")


def test_procedural_objects_are_seeded_and_sized():
    first = procedural_objects(12, seed=3, size_range_mm=(60, 120))
    again = procedural_objects(12, seed=3, size_range_mm=(60, 120))
    other = procedural_objects(12, seed=4, size_range_mm=(60, 120))
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a.contour, b.contour)
    assert any(not np.array_equal(a.contour, b.contour) for a, b in zip(first, other, strict=True))
    for obj in first:
        assert 59.9 <= np.ptp(obj.contour, axis=0).max() <= 120.1
    kinds = {random_object(i).name.split("_")[0] for i in range(30)}
    assert kinds == {"convex", "star", "blob"}


def test_procedural_prefix_does_not_depend_on_count():
    short = procedural_objects(3, seed=9)
    longer = procedural_objects(6, seed=9)
    for a, b in zip(short, longer, strict=False):
        np.testing.assert_array_equal(a.contour, b.contour)


def test_contains_is_strict_interior():
    obj = PlanarObject.from_polygon(regular_polygon(4, 10))
    assert obj.contains([[0, 0], [20, 0]]).tolist() == [True, False]


@pytest.mark.slow
def test_load_object_set_loads_a_mesh_set_as_a_dataset_does():
    # issue 44 item 12: it refused and pointed to grip_env.mesh_sets.named_set, on no docs page
    from grip_env.mesh_sets import named_set

    household = load_object_set("household")
    assert household and all(obj.mesh is not None for obj in household)
    expected = named_set("household").objects
    assert [obj.name for obj in household] == [obj.name for obj in expected]
    for obj, other in zip(household, expected, strict=True):
        np.testing.assert_array_equal(obj.contour, other.contour)


def test_an_unknown_set_name_gets_the_nearest_known_one():
    with pytest.raises(ValueError, match=r"'househld'; did you mean 'household'\?.*random_urdfs"):
        load_object_set("househld")
