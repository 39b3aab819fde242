"""Grasp synthesis: force closure by construction, two-finger geometry, invariances."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from planar_cases import Motion, cross, rigid_motions, side_regions

from grip_env.config import SynthesisConfig
from grip_env.objects import PlanarObject, make_shape
from grip_env.objects.shapes import rectangle
from grip_env.params import GraspParams
from grip_env.perception.regions import Regions
from grip_env.planning.grasps import END_FRACTION, HALF_FINGER_BASE_MM, Grasps, synthesize_grasps

PARAMS = GraspParams()
ALL = SynthesisConfig(max_grasps=100_000)


def _focus_depths(grasps: Grasps) -> np.ndarray:
    """(G, 3) how far each three-finger grasp's focus lies in front of each contact."""
    three = ~grasps.two_finger
    to_focus = grasps.focus[three][:, None, :] - grasps.contacts[three]
    return np.sum(to_focus * grasps.normals[three], axis=-1)


def _assert_well_formed(grasps: Grasps, regions: Regions, obj: PlanarObject,
                        margin: float = ALL.focus_margin_mm) -> None:
    three = ~grasps.two_finger
    # three-finger: normal lines meet at the focus, in front of every contact, inside the object
    to_focus = grasps.focus[three][:, None, :] - grasps.contacts[three]
    np.testing.assert_allclose(cross(to_focus, grasps.normals[three]), 0.0, atol=1e-7)
    assert np.all(_focus_depths(grasps) > margin)
    assert obj.contains(grasps.focus[three]).all()
    angles = np.sort(np.arctan2(grasps.normals[three, :, 1], grasps.normals[three, :, 0]), axis=1)
    gaps = np.diff(np.concatenate([angles, angles[:, :1] + 2 * np.pi], axis=1), axis=1)
    assert np.all(gaps < np.pi)  # normals positively span the plane
    assert np.all(np.isnan(grasps.focus[grasps.two_finger]))
    # every contact on its region, with the region's inward normal
    np.testing.assert_allclose(grasps.normals, regions.normal[grasps.region])
    t = np.sum((grasps.contacts - regions.a[grasps.region]) * regions.direction[grasps.region],
               axis=-1) / regions.length[grasps.region]
    off = cross(grasps.contacts - regions.a[grasps.region], regions.direction[grasps.region])
    np.testing.assert_allclose(off, 0.0, atol=1e-7)
    assert np.all((t >= -1e-9) & (t <= 1 + 1e-9))
    assert np.all((t[three] >= END_FRACTION - 1e-9) & (t[three] <= 1 - END_FRACTION + 1e-9))
    assert np.all(grasps.region[three, 0] < grasps.region[three, 1])
    assert np.all(grasps.region[three, 1] < grasps.region[three, 2])


def test_equilateral_triangle_has_the_edge_midpoint_grasp():
    obj = make_shape("triangle")
    regions = side_regions(obj)
    grasps = synthesize_grasps(regions, obj, PARAMS, ALL)
    assert len(grasps) > 0 and not grasps.two_finger.any()
    _assert_well_formed(grasps, regions, obj)
    midpoints = (obj.contour + np.roll(obj.contour, -1, axis=0)) / 2
    distance = np.linalg.norm(grasps.contacts[:, :, None] - midpoints[None, None], axis=-1)
    at_midpoints = np.all(distance.min(axis=2) < 1e-9, axis=1)
    assert at_midpoints.sum() == 1
    np.testing.assert_allclose(grasps.focus[at_midpoints][0], obj.centroid, atol=1e-9)
    # the centred grasp ranks first
    assert at_midpoints[0]


def test_the_focus_lies_in_front_of_every_contact_by_the_margin():
    """The triangle's side grasps include six whose focus sits 0.44 mm in front of a contact."""
    obj = make_shape("triangle")
    regions = side_regions(obj)
    loose = synthesize_grasps(regions, obj, PARAMS, ALL.model_copy(update={"focus_margin_mm": 0.0}))
    kept = synthesize_grasps(regions, obj, PARAMS, ALL)
    near = (_focus_depths(loose) <= ALL.focus_margin_mm).any(axis=1)
    assert near.sum() == 6 and len(kept) == len(loose) - near.sum()
    _assert_well_formed(kept, regions, obj)


def test_rectangle_gives_only_two_finger_grasps_across_its_width():
    obj = PlanarObject.from_polygon(rectangle(100, 50))
    regions = side_regions(obj)
    grasps = synthesize_grasps(regions, obj, PARAMS, ALL)
    assert len(grasps) > 0 and grasps.two_finger.all()  # no concurrent positively spanning triplet
    _assert_well_formed(grasps, regions, obj)
    p1, p2, p3 = grasps.contacts[:, 0], grasps.contacts[:, 1], grasps.contacts[:, 2]
    np.testing.assert_allclose(np.linalg.norm(p1 - p2, axis=1), 2 * HALF_FINGER_BASE_MM)
    np.testing.assert_allclose(np.abs(p1[:, 1] - p3[:, 1]), 50.0)  # across the width
    np.testing.assert_allclose((p1 + p2)[:, 0] / 2, p3[:, 0], atol=1e-9)  # thumb opposite
    # finger 1 on the hand's +x side: hand x = thumb normal turned clockwise
    n3 = grasps.normals[:, 2]
    hand_x = np.stack([n3[:, 1], -n3[:, 0]], axis=1)
    assert np.all(np.sum((p1 - p3) * hand_x, axis=1) > 0)
    # the short sides (44 mm regions) cannot carry two fingers 50 mm apart
    assert np.all(np.abs(grasps.normals[:, 2, 1]) == 1.0)


def test_square_too_small_for_two_fingers_and_triangle_too_few_regions():
    small = PlanarObject.from_polygon(rectangle(50, 50))
    assert len(synthesize_grasps(side_regions(small), small, PARAMS, ALL)) == 0
    two_sides = Regions(np.array([[0.0, 0], [10, 80]]), np.array([[10.0, 0], [0, 80]]),
                        np.array([[0.0, 1], [0, -1]]), np.zeros(2))
    assert len(synthesize_grasps(two_sides, small, PARAMS, ALL)) == 0
    assert len(synthesize_grasps(Regions.empty(), small, PARAMS, ALL)) == 0


def test_tilted_regions_pair_only_within_the_friction_cone():
    # a trapezoid whose slanted side is tilted beyond arctan(mu) from the opposite one
    steep = PlanarObject.from_polygon([[0, 0], [120, 0], [120, 60], [0, 60 + 120 * 0.5]])
    shallow = PlanarObject.from_polygon([[0, 0], [120, 0], [120, 60], [0, 60 + 120 * 0.3]])
    assert math.atan(0.3) < PARAMS.friction_angle < math.atan(0.5)
    for obj, expected in ((steep, False), (shallow, True)):
        grasps = synthesize_grasps(side_regions(obj), obj, PARAMS, ALL)
        pairs = {tuple(r) for r in grasps.region[grasps.two_finger][:, [0, 2]]}
        assert (({(0, 2), (2, 0)} & pairs) != set()) is expected


def test_max_grasps_keeps_the_best_ranked():
    obj = make_shape("pentagon")
    regions = side_regions(obj)
    every = synthesize_grasps(regions, obj, PARAMS, ALL)
    few = synthesize_grasps(regions, obj, PARAMS, SynthesisConfig(max_grasps=7))
    assert len(every) > 7 and len(few) == 7
    np.testing.assert_allclose(few.contacts, every.contacts[:7])


def test_bad_regions_are_refused():
    obj = make_shape("square")
    with pytest.raises(ValueError, match="Regions"):
        synthesize_grasps(obj.contour, obj, PARAMS, ALL)


@settings(max_examples=25, deadline=None)
@given(rigid_motions(("triangle", "pentagon", "trapezoid", "star", "rectangle", "hexagon"), 300))
def test_grasps_move_with_the_object(motion: Motion):
    obj, moved, angle, offset = motion
    grasps = synthesize_grasps(side_regions(obj), obj, PARAMS, ALL)
    moved_grasps = synthesize_grasps(side_regions(moved), moved, PARAMS, ALL)
    assert len(moved_grasps) == len(grasps)
    rotation = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
    expected = grasps.contacts @ rotation.T + np.array(offset)
    np.testing.assert_allclose(_sorted(moved_grasps.contacts), _sorted(expected), atol=1e-6)


@pytest.mark.parametrize("scale", [0.7, 1.6])
def test_three_finger_grasps_scale_with_the_object(scale):
    obj = make_shape("pentagon")
    big = obj.transformed(scale=scale)
    grasps = synthesize_grasps(side_regions(obj, 3.0), obj, PARAMS, ALL)
    # the focus margin is a length too: it scales with the object
    big_config = ALL.model_copy(update={"focus_margin_mm": ALL.focus_margin_mm * scale})
    scaled = synthesize_grasps(side_regions(big, 3.0 * scale), big, PARAMS, big_config)
    assert len(scaled) == len(grasps) > 0
    np.testing.assert_allclose(_sorted(scaled.contacts), _sorted(grasps.contacts * scale),
                               atol=1e-6)


def _sorted(contacts: np.ndarray) -> np.ndarray:
    flat = contacts.reshape(len(contacts), -1).round(4)
    return flat[np.lexsort(flat.T[::-1])]
