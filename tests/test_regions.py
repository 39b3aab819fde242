"""Grasping regions cut from the contour's curvature."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grip_env import GraspParams
from grip_env.config import PerceptionConfig
from grip_env.objects import PlanarObject, load_object_set, make_shape
from grip_env.objects.shapes import rectangle, regular_polygon, star
from grip_env.perception import MAX_ABS_RHO, Regions, find_regions
from grip_env.sim.camera import perceive

CONFIG = PerceptionConfig()
PARAMS = GraspParams()
SIGMA = CONFIG.curvature_sigma_mm
DEFAULT_OBJECTS = load_object_set("default")


def _assert_regions_are_the_sides(regions: Regions, vertices: np.ndarray) -> None:
    """One region per polygon side: a near the side's start, b near its end, on the side,
    inward normal, flat."""
    assert len(regions) == len(vertices)
    starts, ends = vertices, np.roll(vertices, -1, axis=0)
    for start, end in zip(starts, ends, strict=True):
        side = (end - start) / np.linalg.norm(end - start)
        match = np.argmin(np.linalg.norm(regions.a - start, axis=1))
        a, b = regions.a[match], regions.b[match]
        # regions stop ~2.5 sigma before a corner, give or take one resampling step
        assert np.linalg.norm(a - start) <= 3 * SIGMA + CONFIG.contour_spacing_mm
        assert np.linalg.norm(b - end) <= 3 * SIGMA + CONFIG.contour_spacing_mm
        for point in (a, b):  # on the side's line
            offset = point - start
            assert abs(side[0] * offset[1] - side[1] * offset[0]) < 1e-6
        np.testing.assert_allclose(regions.normal[match], [-side[1], side[0]], atol=1e-9)
        assert abs(regions.rho[match]) < 0.02


def _ccw(vertices: np.ndarray) -> np.ndarray:
    return PlanarObject.from_polygon(vertices).contour


@given(
    width=st.floats(40, 150), height=st.floats(40, 150), angle=st.floats(-np.pi, np.pi),
    dx=st.floats(-200, 200), dy=st.floats(-200, 200),
)
@settings(max_examples=30, deadline=None)
def test_rectangle_gives_its_four_sides(width, height, angle, dx, dy) -> None:
    obj = PlanarObject.from_polygon(rectangle(width, height)).transformed(angle, (dx, dy))
    _assert_regions_are_the_sides(find_regions(obj, CONFIG, PARAMS), obj.contour)


@given(sides=st.integers(3, 8), radius=st.floats(42, 90), phase=st.floats(0, np.pi))
@settings(max_examples=30, deadline=None)
def test_regular_polygon_gives_one_region_per_side(sides, radius, phase) -> None:
    vertices = _ccw(regular_polygon(sides, radius, phase))
    _assert_regions_are_the_sides(find_regions(vertices, CONFIG, PARAMS), vertices)


@pytest.mark.parametrize(("name", "count"), [("rectangle", 4), ("triangle", 3), ("hexagon", 6)])
def test_named_polygons(name: str, count: int) -> None:
    obj = make_shape(name)
    assert len(find_regions(obj, CONFIG, PARAMS)) == count
    _assert_regions_are_the_sides(find_regions(obj, CONFIG, PARAMS), obj.contour)


@given(radius=st.floats(40, 120))  # arcs of max_turn_rad * R - 1 step >= 13 mm: long enough
@settings(max_examples=20, deadline=None)
def test_disc_regions_are_curved_arcs(radius: float) -> None:
    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    disc = radius * np.column_stack([np.cos(t), np.sin(t)])
    regions = find_regions(disc, CONFIG, PARAMS)
    # turn split evenly: ceil(2 pi / max_turn) arcs of equal turn, all long enough
    assert len(regions) == pytest.approx(np.ceil(2 * np.pi / CONFIG.max_turn_rad), abs=1)
    np.testing.assert_allclose(regions.rho, -PARAMS.rho_scale / radius, rtol=0.02)
    chord = 2 * radius * np.sin(CONFIG.max_turn_rad / 2)
    assert np.all(regions.length <= chord + 1e-6)
    centres = (regions.a + regions.b) / 2  # normals of chords point to the centre
    towards_centre = -centres / np.linalg.norm(centres, axis=1)[:, None]
    np.testing.assert_allclose(regions.normal, towards_centre, atol=0.02)


def test_small_disc_is_too_curved_to_grasp() -> None:
    radius = PARAMS.rho_scale / MAX_ABS_RHO * 0.8  # |rho| = 1.25 / 3
    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    assert len(find_regions(radius * np.column_stack([np.cos(t), np.sin(t)]))) == 0


def test_ellipse_regions_are_convex_and_flattest_on_the_long_sides() -> None:
    regions = find_regions(make_shape("ellipse"), CONFIG, PARAMS)
    assert len(regions) >= 4
    assert np.all(regions.rho < 0) and np.all(np.abs(regions.rho) <= MAX_ABS_RHO)
    middle = (regions.a + regions.b) / 2
    flattest = np.argmax(regions.rho)  # least negative: on a long side (|y| large, |x| small)
    assert abs(middle[flattest, 1]) > abs(middle[flattest, 0])


def test_star_is_cut_at_its_corners() -> None:
    vertices = _ccw(star(5, 65, 32))
    regions = find_regions(vertices, CONFIG, PARAMS)
    assert len(regions) == 10  # one per edge: both tips and concave corners cut
    _assert_regions_are_the_sides(regions, vertices)


def test_notch_bottom_is_flat_and_cut_from_its_walls() -> None:
    regions = find_regions(make_shape("notched_rectangle"), CONFIG, PARAMS)
    bottom = [i for i in range(len(regions)) if np.allclose(regions.normal[i], [0, -1])
              and abs(regions.a[i, 0]) < 12]
    assert len(bottom) == 1  # the notch floor: y = 12 for |x| < 12, object below it
    i = bottom[0]
    assert abs(regions.rho[i]) < 0.03 and -12 < regions.b[i, 0] < regions.a[i, 0] < 12


def test_concave_dent_has_positive_rho() -> None:
    regions = find_regions(make_shape("bean"), CONFIG, PARAMS)
    middle = (regions.a + regions.b) / 2
    dent = np.argmin(np.linalg.norm(middle - [0.0, 35.0 - 22.0], axis=1))  # dent floor (0, 13)
    assert regions.rho[dent] > 0 and np.all(regions.rho[np.arange(len(regions)) != dent] < 0)


def _as_set(regions: Regions) -> np.ndarray:
    return np.column_stack([regions.a, regions.b, regions.normal, regions.rho])


def _one_regular_run(obj: PlanarObject) -> bool:
    from grip_env.perception.contour import resample_contour
    from grip_env.perception.curvature import signed_curvature
    from grip_env.perception.regions import _irregular

    points = resample_contour(obj.contour, CONFIG.contour_spacing_mm)
    step = obj.polygon.exterior.length / len(points)
    kappa = signed_curvature(points, SIGMA, step)
    return not _irregular(kappa, round(SIGMA / step), CONFIG.curvature_jump).any()


@pytest.mark.parametrize("turns", [1, 5, 9])
def test_a_closed_regular_contour_is_cut_the_same_wherever_its_sampling_starts(turns) -> None:
    obj = make_shape("ellipse")
    assert _one_regular_run(obj)
    shifted = PlanarObject(np.roll(obj.contour, 7 * turns, axis=0), name="shifted")
    got, want = find_regions(shifted, CONFIG, PARAMS), find_regions(obj, CONFIG, PARAMS)
    assert len(got) == len(want)
    for row in _as_set(want):  # the samples differ (resampling starts at the first vertex)
        assert np.min(np.abs(_as_set(got) - row).max(axis=1)) <= 0.3


@given(
    obj=st.sampled_from(DEFAULT_OBJECTS), angle=st.floats(-np.pi, np.pi),
    dx=st.floats(-300, 300), dy=st.floats(-300, 300),
)
@settings(max_examples=40, deadline=None)
def test_regions_move_with_the_object(obj: PlanarObject, angle, dx, dy) -> None:
    if _one_regular_run(obj):
        angle = 0.0  # cut at absolute headings (so that the sampling's start does not matter)
    moved = find_regions(obj.transformed(angle, (dx, dy)), CONFIG, PARAMS)
    original = find_regions(obj, CONFIG, PARAMS)
    assert len(moved) == len(original)
    c, s = np.cos(angle), np.sin(angle)
    rotation = np.array([[c, -s], [s, c]])
    expected = Regions(original.a @ rotation.T + (dx, dy), original.b @ rotation.T + (dx, dy),
                       original.normal @ rotation.T, original.rho)
    got, want = _as_set(moved), _as_set(expected)
    for row in want:  # compare as sets: every expected region has a moved twin
        closest = np.min(np.abs(got - row).max(axis=1))
        assert closest <= 0.5


@pytest.mark.parametrize("obj", DEFAULT_OBJECTS, ids=lambda o: o.name)
def test_region_invariants(obj: PlanarObject) -> None:
    regions = find_regions(obj, CONFIG, PARAMS)
    assert len(regions) >= 3
    assert np.all(regions.length >= CONFIG.min_region_mm - 1e-9)
    assert np.all(np.abs(regions.rho) <= MAX_ABS_RHO)
    np.testing.assert_allclose(np.linalg.norm(regions.normal, axis=1), 1.0)
    # the normal is the left normal of a -> b, and points into the object
    left = np.column_stack([-regions.direction[:, 1], regions.direction[:, 0]])
    np.testing.assert_allclose(regions.normal, left, atol=1e-12)
    middle = (regions.a + regions.b) / 2
    assert np.all(obj.contains(middle + 1.0 * regions.normal))
    # regions hug the contour: endpoints off it by at most the arc's sagitta L^2 |kappa| / 8
    import shapely

    sagitta = regions.length**2 * np.abs(regions.rho) / PARAMS.rho_scale / 8
    for ends in (regions.a, regions.b):
        off = shapely.distance(obj.polygon.exterior, shapely.points(ends))
        assert np.all(off <= sagitta + 0.5)


def test_regions_of_a_rendered_rectangle_match_the_polygon() -> None:
    obj = make_shape("rectangle").transformed(angle=0.3)
    seen = find_regions(perceive(obj, PerceptionConfig(resolution_px=128)), CONFIG, PARAMS)
    _assert_sides_close(seen, obj.contour, tolerance=3 * SIGMA + 1.0)


def _assert_sides_close(regions: Regions, vertices: np.ndarray, tolerance: float) -> None:
    assert len(regions) == len(vertices)
    for start, end in zip(vertices, np.roll(vertices, -1, axis=0), strict=True):
        match = np.argmin(np.linalg.norm(regions.a - start, axis=1))
        assert np.linalg.norm(regions.a[match] - start) <= tolerance
        assert np.linalg.norm(regions.b[match] - end) <= tolerance
        assert abs(regions.rho[match]) < 0.05


def test_bad_contour_is_refused() -> None:
    with pytest.raises(ValueError, match="at least 3"):
        find_regions(np.array([[0.0, 0.0], [1.0, 0.0]]))
    with pytest.raises(ValueError, match="not finite"):
        find_regions(np.array([[0.0, 0.0], [1.0, np.nan], [0.0, 1.0]]))


def test_find_regions_speed(benchmark) -> None:
    obj = make_shape("bean")
    regions = benchmark(find_regions, obj, CONFIG, PARAMS)
    assert len(regions) > 0


def test_polygon_side_regions_are_inset_flat_and_face_inwards() -> None:
    regions = Regions.from_polygon_sides(PlanarObject.from_polygon(rectangle(80, 40)).contour, 3.0)
    assert len(regions) == 4
    np.testing.assert_allclose(sorted(regions.length), [34, 34, 74, 74])
    np.testing.assert_array_equal(regions.rho, 0)
    midpoints = (regions.a + regions.b) / 2
    assert np.all(np.einsum("ij,ij->i", regions.normal, -midpoints) > 0)  # towards the centre
