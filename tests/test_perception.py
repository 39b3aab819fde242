"""Perception: masks and images to contours, top-down rendering, resampling and curvature."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from grip_env.config import PerceptionConfig
from grip_env.objects import PlanarObject, load_object_set, make_shape
from grip_env.perception import (
    contour_error_mm,
    contour_from_mask,
    mask_from_image_file,
    resample_contour,
    segment,
    signed_curvature,
)
from grip_env.perception.curvature import contour_derivatives
from grip_env.sim.camera import perceive, render_mask

# ----------------------------------------------------------------------------- masks


def _signed_area(points: np.ndarray) -> float:
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_single_pixel_contour_is_centred_on_the_pixel_centre() -> None:
    mask = np.zeros((7, 9), dtype=bool)
    mask[2, 5] = True  # row 2 of 7 -> y = (7 - 1 - 2) * s
    contour = contour_from_mask(mask, 2.0)
    np.testing.assert_allclose(contour.mean(axis=0), [5 * 2.0, 4 * 2.0])
    assert _signed_area(contour) > 0  # counter-clockwise


@given(
    top=st.integers(0, 20), left=st.integers(0, 20),
    rows=st.integers(3, 30), cols=st.integers(3, 30), scale=st.floats(0.1, 5.0),
)
@settings(max_examples=40, deadline=None)
def test_rasterised_rectangle_area_and_centroid(top, left, rows, cols, scale) -> None:
    height = top + rows + 5
    mask = np.zeros((height, left + cols + 5), dtype=bool)
    mask[top:top + rows, left:left + cols] = True
    obj = PlanarObject.from_mask(mask, scale)
    # the 0.5 iso-line cuts each of the 4 corners by a 1/8 px triangle
    assert obj.area == pytest.approx((rows * cols - 0.5) * scale**2, rel=1e-9)
    expected = [(left + (cols - 1) / 2) * scale, (height - 1 - (top + (rows - 1) / 2)) * scale]
    np.testing.assert_allclose(obj.centroid, expected, atol=1e-9 * scale)
    assert obj.source == "mask"


def test_rasterised_disc_area_and_centroid() -> None:
    rows, cols = np.mgrid[:200, :220]
    cx, cy, radius = 101.3, 88.6, 60.0
    mask = (cols - cx) ** 2 + (rows - cy) ** 2 < radius**2
    obj = PlanarObject.from_mask(mask, 0.5)
    assert obj.area == pytest.approx(np.pi * (radius * 0.5) ** 2, rel=0.005)
    np.testing.assert_allclose(obj.centroid, [cx * 0.5, (199 - cy) * 0.5], atol=0.02)


def test_grey_level_mask_gives_sub_pixel_edge() -> None:
    mask = np.zeros((10, 10))
    mask[3:7, 3:7] = 1.0
    mask[3:7, 7] = 0.75
    contour = contour_from_mask(mask, 1.0)
    # 0.5 is crossed a third of the way from column 7 (0.75) to column 8 (0)
    assert contour[:, 0].max() == pytest.approx(7 + 1 / 3)


def test_a_mask_of_several_parts_is_refused() -> None:
    mask = np.zeros((40, 40), dtype=bool)
    mask[2:6, 2:6] = True
    mask[10:30, 10:35] = True
    with pytest.raises(ValueError, match="2 separate parts"):
        PlanarObject.from_mask(mask, 1.0)


@pytest.mark.parametrize(
    ("mask", "scale", "message"),
    [
        (np.zeros((5, 5), dtype=bool), 1.0, "empty"),
        (np.zeros((0, 5)), 1.0, "empty"),
        (np.ones(5, dtype=bool), 1.0, "2-D"),
        (np.full((4, 4), np.nan), 1.0, "NaN"),
        (np.full((4, 4), 2.0), 1.0, r"\[0, 1\]"),
        (np.ones((4, 4), dtype=bool), 0.0, "mm_per_px"),
        (np.ones((4, 4), dtype=bool), -1.0, "mm_per_px"),
        (np.ones((4, 4), dtype=bool), np.inf, "mm_per_px"),
        (np.ones((4, 4), dtype=bool), "abc", "mm_per_px"),
    ],
)
def test_bad_masks_are_refused(mask, scale, message) -> None:
    with pytest.raises(ValueError, match=message):
        contour_from_mask(mask, scale)


def test_segment_finds_dark_and_bright_objects() -> None:
    grey = np.full((30, 40), 200.0)
    grey[5:20, 10:30] = 30.0
    grey[25:27, 2:4] = 30.0  # a small speck: not the object
    dark = segment(grey)
    assert dark.sum() == 15 * 20 and dark[10, 15]
    np.testing.assert_array_equal(segment(255 - grey), dark)


def test_segment_refuses_uniform_image() -> None:
    with pytest.raises(ValueError, match="no object"):
        segment(np.full((10, 10), 7.0))


@pytest.mark.parametrize("rgb", [False, True])
def test_image_file_round_trip(tmp_path, rgb: bool) -> None:
    rows, cols = np.mgrid[:120, :160]
    inside = (np.abs(cols - 80) < 40) & (np.abs(rows - 60) < 25)  # 79 x 49 px
    grey = np.where(inside, 40, 230).astype(np.uint8)
    image = np.repeat(grey[..., None], 3, axis=2) if rgb else grey
    path = tmp_path / "part.png"
    iio.imwrite(path, image)
    obj = PlanarObject.from_image(path, mm_per_px=0.5)
    assert obj.name == "part"
    assert obj.area == pytest.approx((79 * 49 - 0.5) * 0.25)
    np.testing.assert_allclose(obj.centroid, [80 * 0.5, (119 - 60) * 0.5])
    np.testing.assert_array_equal(mask_from_image_file(path), inside)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # imageio probing its legacy plugins
def test_missing_and_unreadable_image_files(tmp_path) -> None:
    with pytest.raises(ValueError, match="not found"):
        mask_from_image_file(tmp_path / "nothing.png")
    junk = tmp_path / "junk.png"
    junk.write_text("not an image")
    with pytest.raises(ValueError, match="cannot read"):
        mask_from_image_file(junk)
    blank = tmp_path / "blank.png"
    iio.imwrite(blank, np.full((20, 20), 128, dtype=np.uint8))
    with pytest.raises(ValueError, match="no object"):
        PlanarObject.from_image(blank, 1.0)


# ----------------------------------------------------------------------------- rendering

DEFAULT_OBJECTS = load_object_set("default")


@pytest.fixture(scope="module")
def perceived() -> dict[str, PlanarObject]:
    from grip_env.sim.world import World

    with World() as world:
        return {obj.name: perceive(obj, world=world) for obj in DEFAULT_OBJECTS}


@pytest.mark.parametrize("obj", DEFAULT_OBJECTS, ids=lambda o: o.name)
def test_perceived_contour_within_a_pixel(obj: PlanarObject, perceived) -> None:
    seen = perceived[obj.name]
    assert seen.name == obj.name and seen.source == "render"
    error = contour_error_mm(obj, seen)
    # the 0.5 iso-line never strays from the true contour by more than half a pixel diagonal, and
    # restored corners (where acute tips were lost to the grid) by no more than a pixel
    assert _distances(obj, seen.contour).max() <= 1.0
    assert error <= 1.0
    # edges through pixel centres (ties) may add a row: at most a half-pixel band (+ corners)
    assert abs(seen.area - obj.area) <= 0.5 * obj.polygon.exterior.length + 1.0


def _distances(obj: PlanarObject, points: np.ndarray) -> np.ndarray:
    import shapely

    return shapely.distance(obj.polygon.exterior, shapely.points(points))


def test_rendered_image_geometry() -> None:
    obj = make_shape("square")  # 65 x 65 mm, centred at the origin
    config = PerceptionConfig(resolution_px=96, mm_per_px=1.0)
    grey, scale, centre = render_mask(obj, config)
    assert grey.shape == (96, 96) and grey.dtype == np.uint8 and scale == 1.0
    np.testing.assert_allclose(centre, [0, 0], atol=1e-9)
    mask = grey < 128
    # pixel centres at -47.5 ... 47.5 mm: the square covers the 65 columns with |x| < 32.5 (ties
    # at exactly +-32.5 go either way)
    assert 64 <= mask.sum(axis=1).max() <= 66 and 64 <= mask.sum(axis=0).max() <= 66
    assert mask[48, 48] and not mask[0, 0] and not mask[95, 95]


def test_offset_object_lands_where_it_is() -> None:
    obj = make_shape("l_shape").transformed(angle=0.7, offset=(143.2, -61.7))
    seen = perceive(obj, PerceptionConfig(resolution_px=160))
    assert contour_error_mm(obj, seen) <= 1.0
    np.testing.assert_allclose(seen.centroid, obj.centroid, atol=0.2)


def test_large_object_enlarges_the_scale() -> None:
    obj = make_shape("rectangle").transformed(scale=3.0)  # 270 mm wide
    config = PerceptionConfig(resolution_px=64, mm_per_px=1.0)
    _, scale, _ = render_mask(obj, config)
    assert 270.0 / 63 < scale < 270.0 / 50
    seen = perceive(obj, config)
    assert contour_error_mm(obj, seen) <= scale


def test_pixel_noise_is_seeded() -> None:
    obj = make_shape("hexagon")
    config = PerceptionConfig(resolution_px=128, pixel_noise=0.1)
    first, _, _ = render_mask(obj, config, seed=3)
    again, _, _ = render_mask(obj, config, seed=3)
    other, _, _ = render_mask(obj, config, seed=4)
    np.testing.assert_array_equal(first, again)
    assert np.any(first != other)
    assert contour_error_mm(obj, perceive(obj, config, seed=3)) <= 1.5


def test_contour_error_is_symmetric_hausdorff() -> None:
    small = PlanarObject.from_polygon([[0, 0], [10, 0], [10, 10], [0, 10]])
    big = PlanarObject.from_polygon([[0, 0], [12, 0], [12, 10], [0, 10]])
    assert contour_error_mm(small, small) == 0.0
    assert contour_error_mm(small, big) == pytest.approx(2.0)
    assert contour_error_mm(big, small) == pytest.approx(2.0)


# ----------------------------------------------------------------------------- contour, curvature


@given(st.sampled_from(DEFAULT_OBJECTS), st.floats(0.3, 4.0))
@settings(max_examples=30, deadline=None)
def test_resampling_is_even_and_on_the_contour(obj: PlanarObject, spacing: float) -> None:
    points = resample_contour(obj.contour, spacing)
    steps = np.linalg.norm(np.diff(np.vstack([points, points[:1]]), axis=0), axis=1)
    perimeter = obj.polygon.exterior.length
    assert abs(perimeter / len(points) - spacing) <= spacing / 2 + 1e-9 or len(points) == 3
    assert steps.max() <= perimeter / len(points) + 1e-9  # chords never exceed the arc step
    np.testing.assert_allclose(points[0], obj.contour[0])
    assert _distances(obj, points).max() < 1e-9


def test_resampling_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match="spacing_mm"):
        resample_contour(np.eye(3, 2), 0.0)
    with pytest.raises(ValueError, match="shape"):
        resample_contour(np.zeros((2, 2)), 1.0)
    with pytest.raises(ValueError, match="NaN"):
        resample_contour(np.array([[0, 0], [1, np.nan], [0, 1]]), 1.0)


@given(st.floats(10.0, 200.0), st.floats(0.5, 2.0), st.floats(1.0, 4.0))
@settings(max_examples=30, deadline=None)
def test_disc_curvature_is_minus_one_over_radius(radius, spacing, sigma) -> None:
    assume(sigma >= spacing)  # smoothing narrower than the sampling step is not a use case
    t = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    disc = radius * np.column_stack([np.cos(t), np.sin(t)])
    points = resample_contour(disc, spacing)
    step = 2 * np.pi * radius / len(points)
    kappa = signed_curvature(points, sigma, step)
    # Gaussian smoothing shrinks a circle by exp(-sigma^2 / 2R^2): curvature grows by the inverse;
    # central differences over a chord angle h add a factor 1 / cos^2(h / 2) ~ 1 + h^2 / 4
    expected = -np.exp(sigma**2 / (2 * radius**2)) / radius
    np.testing.assert_allclose(kappa, expected, rtol=0.004 + (spacing / radius) ** 2 / 4)


@given(st.sampled_from(DEFAULT_OBJECTS), st.floats(-np.pi, np.pi))
@settings(max_examples=20, deadline=None)
def test_total_curvature_of_a_closed_ccw_contour(obj: PlanarObject, angle: float) -> None:
    points = resample_contour(obj.transformed(angle=angle).contour, 1.0)
    d1, _ = contour_derivatives(points, 2.0, 1.0)
    kappa = signed_curvature(points, 2.0, 1.0)
    total = float(np.sum(kappa * np.linalg.norm(d1, axis=1)))  # integral of kappa ds
    # -2 pi up to the finite-difference error at sharp tips (a 33 degree tip turns 0.6 rad/sample)
    assert total == pytest.approx(-2 * np.pi, rel=0.03)


def test_curvature_sign_concave_notch_positive_convex_negative() -> None:
    # a 60 mm square with a V notch in its top side, tip at (30, 45)
    square = np.array([[0, 0], [60, 0], [60, 60], [40, 60], [30, 45], [20, 60], [0, 60]], float)
    points = resample_contour(square, 0.5)
    kappa = signed_curvature(points, 2.0, 0.5)
    at = lambda xy: kappa[np.argmin(np.linalg.norm(points - xy, axis=1))]  # noqa: E731
    assert at([30, 45]) > 0.1  # notch tip: concave
    assert at([40, 60]) < -0.1 and at([60, 0]) < -0.1  # outer corners: convex
    assert abs(at([60, 30])) < 1e-9  # straight side


def test_straight_sides_have_zero_curvature() -> None:
    points = resample_contour(make_shape("rectangle").contour, 1.0)
    kappa = signed_curvature(points, 2.0, 1.0)
    sides = np.abs(points[:, 0]) < 30  # far from the corners along the long sides
    np.testing.assert_allclose(kappa[sides], 0.0, atol=1e-12)


def test_sharpening_restores_acute_tips_and_leaves_curves_alone() -> None:
    from grip_env.perception.corners import sharpen_corners

    star_tip = make_shape("star")
    mm_per_px = 1.0
    for obj, should_improve in ((star_tip, True), (make_shape("disc"), False)):
        seen = perceive(obj)
        raw = PlanarObject(_raw_perceived_contour(obj), name="raw")
        sharpened = PlanarObject(sharpen_corners(raw.contour, mm_per_px), name="sharp")
        before, after = contour_error_mm(obj, raw), contour_error_mm(obj, sharpened)
        if should_improve:
            assert before > 1.0 >= after
        else:
            np.testing.assert_array_equal(sharpened.contour, raw.contour)
        assert contour_error_mm(obj, seen) == pytest.approx(after)


def _raw_perceived_contour(obj: PlanarObject) -> np.ndarray:
    from grip_env.objects.masks import contour_from_mask, segment
    from grip_env.sim.camera import object_coverage, render_mask

    grey, mm_per_px, centre = render_mask(obj, PerceptionConfig(), 30.0, 0)
    coverage = object_coverage(grey, segment(grey))
    n = grey.shape[0]
    return contour_from_mask(coverage, mm_per_px) + centre - (n - 1) / 2.0 * mm_per_px
