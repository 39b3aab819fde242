"""Grasp synthesis: force closure by construction, two-finger geometry, invariances."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from planar_cases import Motion, cross, rigid_motions, side_regions

from grip_env.config import PerceptionConfig, SynthesisConfig
from grip_env.objects import PlanarObject, make_shape
from grip_env.objects.shapes import greek_cross, rectangle
from grip_env.params import GraspParams
from grip_env.perception.regions import Regions, find_regions
from grip_env.planning.grasps import (
    END_FRACTION,
    HALF_FINGER_BASE_MM,
    Grasps,
    largest_gap_rad,
    synthesize_grasps,
)

PARAMS = GraspParams()
ALL = SynthesisConfig(max_grasps=100_000)
FRICTIONAL = ALL.model_copy(update={"frictional_closure": True})


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


def _closes_with_friction(grasps: Grasps, mu: float) -> np.ndarray:
    """(G,) whether each three-finger grasp's normals positively span the plane, or the two
    normals that bound the largest gap make an antipodal pair: the line between their contacts
    within arctan(mu) of both normals (force closure with friction, whatever the third)."""
    angles = np.arctan2(grasps.normals[..., 1], grasps.normals[..., 0])
    order = np.argsort(angles, axis=1)
    sorted_angles = np.take_along_axis(angles, order, axis=1)
    gaps = np.diff(sorted_angles, axis=1, append=sorted_angles[:, :1] + 2 * np.pi)
    widest = gaps.argmax(axis=1)
    rows = np.arange(len(grasps))
    i, j = order[rows, widest], order[rows, (widest + 1) % 3]
    line = grasps.contacts[rows, j] - grasps.contacts[rows, i]
    line /= np.linalg.norm(line, axis=1, keepdims=True)
    inside = ((np.sum(line * grasps.normals[rows, i], axis=1) > math.cos(math.atan(mu)))
              & (np.sum(-line * grasps.normals[rows, j], axis=1) > math.cos(math.atan(mu))))
    return (gaps.max(axis=1) < np.pi) | inside


def _antipodal_widths(grasps: Grasps) -> np.ndarray:
    """Distances between the contacts of every pair with opposite normals, over all grasps."""
    pairs = ((0, 1), (0, 2), (1, 2))
    widths = [np.linalg.norm(grasps.contacts[:, a] - grasps.contacts[:, b], axis=1)[
        np.sum(grasps.normals[:, a] * grasps.normals[:, b], axis=1) < -1 + 1e-9] for a, b in pairs]
    return np.concatenate(widths)


@settings(max_examples=10, deadline=None)
@given(width=st.floats(24.0, 60.0), arm=st.floats(25.0, 60.0), angle=st.floats(-math.pi, math.pi),
       offset=st.tuples(st.floats(-200, 200), st.floats(-200, 200)))
def test_a_cross_has_antipodal_grasps_across_an_arm(width, arm, angle, offset):
    """Issue 44: a cross has only sides along its two axes, so no three of its normals
    positively span the plane: the recorded planner finds no three-finger grasp (and, on arms
    shorter than two fingers 50 mm apart, none at all). With friction, two opposite sides of an
    arm and its tip are force closure (the two sides' contacts face each other along their
    normals)."""
    obj = PlanarObject.from_polygon(greek_cross(width, width + 2 * arm)).transformed(angle, offset)
    regions = side_regions(obj)
    assert synthesize_grasps(regions, obj, PARAMS, ALL).two_finger.all()
    grasps = synthesize_grasps(regions, obj, PARAMS, FRICTIONAL)
    three = grasps.take(np.nonzero(~grasps.two_finger)[0])
    assert np.any(np.abs(_antipodal_widths(three) - width) < 1e-6)  # across an arm
    assert _closes_with_friction(three, PARAMS.mu).all()


@pytest.mark.parametrize("shape", ["star", "ellipse", "bean", "trapezoid", "l_shape"])
def test_frictional_closure_adds_only_grasps_that_close_with_friction(shape):
    obj = make_shape(shape)
    regions = find_regions(obj, PerceptionConfig(), PARAMS)
    spanning = synthesize_grasps(regions, obj, PARAMS, ALL)
    frictional = synthesize_grasps(regions, obj, PARAMS, FRICTIONAL)
    added = len(frictional) - len(spanning)
    assert added > 0 if shape in ("ellipse", "bean", "l_shape") else added >= 0
    three = frictional.take(np.nonzero(~frictional.two_finger)[0])
    assert _closes_with_friction(three, PARAMS.mu).all()
    # the recorded planner's grasps are among them
    key = {tuple(np.round(c, 9).ravel()) for c in frictional.contacts}
    assert all(tuple(np.round(c, 9).ravel()) in key for c in spanning.contacts)


def test_the_largest_gap_is_pi_without_friction_and_pi_plus_the_cone_with_it():
    assert largest_gap_rad(PARAMS, ALL) == pytest.approx(np.pi, abs=1e-5)
    assert largest_gap_rad(PARAMS, ALL) < np.pi
    assert largest_gap_rad(GraspParams(mu=0.3), FRICTIONAL) == pytest.approx(np.pi + math.atan(0.3))


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
