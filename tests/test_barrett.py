"""Barrett BH8-280 planar kinematics and the configuration search, against hand-computed grips."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from grip_env.config import SynthesisConfig
from grip_env.objects import PlanarObject
from grip_env.objects.shapes import rectangle, regular_polygon
from grip_env.params import GraspParams
from grip_env.planning.barrett import (
    FINGER_REACH_MM,
    SPREAD_AXIS_OFFSET_MM,
    THUMB_REACH_MM,
    approach_clear,
    configurations,
    finger_forces,
    force_line_value,
    hand_axes,
    spread_axes,
)
from grip_env.planning.grasps import Grasps

PARAMS = GraspParams()
SYNTHESIS = SynthesisConfig(min_extension_mm=30.0, max_extension_mm=160.0, max_spread_rad=1.5,
                            thumb_search_steps=61)


def _grasps(contacts, normals, focus, two_finger=False, region_ends=None) -> Grasps:
    """A single hand-made grasp; each contact's region is a 20 mm segment through it."""
    contacts, normals = np.asarray(contacts, float)[None], np.asarray(normals, float)[None]
    if region_ends is None:
        tangent = np.stack([normals[..., 1], -normals[..., 0]], axis=-1)
        region_ends = (contacts - 10 * tangent, contacts + 10 * tangent)
    return Grasps(contacts, normals, np.array([[0, 1, 2]]), region_ends[0], region_ends[1],
                  np.zeros((1, 3)), np.asarray(focus, float)[None], np.array([two_finger]))


def _edge_midpoint_grasp(obj: PlanarObject) -> Grasps:
    """The grasp of an equilateral triangle at its edge midpoints (normals meet at the centre)."""
    a, b = obj.contour, np.roll(obj.contour, -1, axis=0)
    d = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    normals = np.stack([-d[:, 1], d[:, 0]], axis=1)
    return _grasps((a + b) / 2, normals, obj.centroid, region_ends=(a[None], b[None]))


def test_hand_frame_follows_design_convention():
    x, y = hand_axes(np.pi / 2)
    np.testing.assert_allclose(y, [0, 1], atol=1e-15)  # y = F3
    np.testing.assert_allclose(x, [1, 0], atol=1e-15)  # x = F3 turned 90 degrees clockwise
    forces = finger_forces(np.pi / 2, np.pi / 3)
    s, c = math.sin(np.pi / 3), math.cos(np.pi / 3)
    np.testing.assert_allclose(forces, [[-s, -c], [s, -c], [0, 1]], atol=1e-15)
    np.testing.assert_allclose(spread_axes(np.array([10.0, 0.0]), np.pi / 2), [[35, 0], [-15, 0]],
                               atol=1e-12)


def test_force_line_value_matches_paper_normalisation():
    nu = PARAMS.friction_angle
    normals = np.array([[0.0, 1.0]] * 3)
    half = np.array([[math.sin(nu / 2), math.cos(nu / 2)]] * 3)
    assert force_line_value(half, normals, nu) == pytest.approx(1.0)  # all at half the cone
    beyond = np.array([[math.sin(1.1 * nu), math.cos(1.1 * nu)], [0, 1], [0, 1]])
    assert force_line_value(beyond, normals, nu) == pytest.approx(4 * 1.1**2)  # k = 3


def test_equilateral_triangle_gives_the_symmetric_sixty_degree_configuration():
    r_in = 50.0  # circumradius 100 mm: fingers reach the edge midpoints
    obj = PlanarObject.from_polygon(regular_polygon(3, 2 * r_in, np.pi / 2))
    confs = configurations(_edge_midpoint_grasp(obj), obj, PARAMS, SYNTHESIS)
    assert len(confs) == 3  # every contact can take the thumb
    cot = 1 / math.tan(np.pi / 3)
    for i in range(3):
        assert confs.spread[i] == pytest.approx(np.pi / 3, abs=1e-9)
        assert confs.force_line[i] == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(confs.focus[i], obj.centroid, atol=1e-9)
        np.testing.assert_allclose(confs.forces[i], confs.normals[i], atol=1e-9)
        assert confs.extensions[i, 2] == pytest.approx(r_in + SPREAD_AXIS_OFFSET_MM * cot)
        expected_finger = math.hypot(r_in * math.cos(np.pi / 6),
                                     r_in * math.sin(np.pi / 6) - SPREAD_AXIS_OFFSET_MM * cot)
        np.testing.assert_allclose(confs.extensions[i, :2], expected_finger, rtol=1e-12)
    bottom = np.argmin(confs.contacts[:, 2, 1])  # thumb on the bottom edge pushes up
    assert confs.yaw[bottom] == pytest.approx(np.pi / 2)
    np.testing.assert_allclose(confs.palm[bottom], [0, SPREAD_AXIS_OFFSET_MM * cot], atol=1e-9)
    # finger 1 sits on the hand's +x side (world +x when the thumb pushes up)
    assert confs.contacts[bottom, 0, 0] > 0 > confs.contacts[bottom, 1, 0]


def test_hand_limits_reject_configurations():
    obj = PlanarObject.from_polygon(regular_polygon(3, 100, np.pi / 2))
    grasp = _edge_midpoint_grasp(obj)
    narrow = SYNTHESIS.model_copy(update={"max_spread_rad": 0.5})
    short = SYNTHESIS.model_copy(update={"max_extension_mm": 40.0})
    long_ = SYNTHESIS.model_copy(update={"min_extension_mm": 70.0})
    for config in (narrow, short, long_):
        confs = configurations(grasp, obj, PARAMS, config)
        assert len(confs) == 0 or np.all(confs.force_line > 0.5)  # the ideal one is gone
        assert np.all(confs.spread <= config.max_spread_rad)
        assert np.all(confs.extensions >= config.min_extension_mm)
        assert np.all(confs.extensions <= config.max_extension_mm)


def test_small_triangle_is_out_of_reach():
    obj = PlanarObject.from_polygon(regular_polygon(3, 5, np.pi / 2))
    assert len(configurations(_edge_midpoint_grasp(obj), obj, PARAMS, SYNTHESIS)) == 0


def test_two_finger_rectangle_configuration_by_hand():
    obj = PlanarObject.from_polygon(rectangle(120, 55))
    top_a, top_b = np.array([50.0, 27.5]), np.array([-50.0, 27.5])  # CCW: object below the top
    thumb = np.array([0.0, -27.5])
    contacts = [[25.0, 27.5], [-25.0, 27.5], thumb]
    normals = [[0, -1], [0, -1], [0, 1]]
    ends = (np.array([[top_a, top_a, [-50, -27.5]]]), np.array([[top_b, top_b, [50, -27.5]]]))
    grasp = _grasps(contacts, normals, [np.nan, np.nan], two_finger=True, region_ends=ends)
    confs = configurations(grasp, obj, PARAMS, SYNTHESIS)
    assert len(confs) == 1
    depth = 55.0
    palm_y = (25**2 + depth**2) / (2 * depth)  # e3 equal to the fingers' extension
    assert confs.spread[0] == 0.0
    assert confs.yaw[0] == pytest.approx(np.pi / 2)
    assert confs.force_line[0] == pytest.approx(0.0)
    np.testing.assert_allclose(confs.contacts[0], contacts, atol=1e-9)
    np.testing.assert_allclose(confs.palm[0], thumb + [0, palm_y], atol=1e-9)
    np.testing.assert_allclose(confs.extensions[0], [palm_y] * 3, rtol=1e-12)
    assert np.all(np.isnan(confs.focus[0]))


def _bar_grasp(thickness: float) -> tuple[PlanarObject, Grasps]:
    """A 120 mm bar ``thickness`` thick: thumb below, both fingers on the top side."""
    half = thickness / 2
    obj = PlanarObject.from_polygon(rectangle(120, thickness))
    ends = (np.array([[[50, half], [50, half], [-50, -half]]]),
            np.array([[[-50, half], [-50, half], [50, -half]]]))
    grasp = _grasps([[25, half], [-25, half], [0, -half]], [[0, -1], [0, -1], [0, 1]],
                    [np.nan, np.nan], two_finger=True, region_ends=ends)
    return obj, grasp


def _reaches(confs) -> np.ndarray:
    """(C, 3) reach of each finger from its line origin along its force, from a configuration."""
    origins = np.concatenate([spread_axes(confs.palm, confs.yaw), confs.palm[:, None]], axis=1)
    return np.einsum("cij,cij->ci", origins - confs.contacts, confs.forces)


def test_two_finger_palm_respects_minimum_extension():
    # a 40 mm bar: the balanced palm position (e = 27.8 mm) is too close; the palm moves beyond
    obj, grasp = _bar_grasp(40.0)
    config = SYNTHESIS.model_copy(update={"min_extension_mm": 28.0})
    confs = configurations(grasp, obj, PARAMS, config)
    assert len(confs) == 1
    lateral = math.sqrt(28**2 - 25**2)
    np.testing.assert_allclose(confs.extensions[0], [28, 28, 40 + lateral], rtol=1e-12)
    # 2 mm further past their axes than the fingers' shortest reach: beyond the finger
    lateral = 2.0 - FINGER_REACH_MM[0]
    beyond = SYNTHESIS.model_copy(update={"min_extension_mm": math.hypot(25.0, lateral)})
    assert len(configurations(grasp, obj, PARAMS, beyond)) == 0


def test_two_finger_palm_moves_into_the_fingers_reach():
    # a 10 mm bar: the balanced palm (e3 = 36.25 mm) needs the fingers 26 mm past their axes;
    # the palm moves towards the thumb until the fingers' reach is their shortest
    obj, grasp = _bar_grasp(10.0)
    config = SYNTHESIS.model_copy(update={"min_extension_mm": 15.0})
    confs = configurations(grasp, obj, PARAMS, config)
    assert len(confs) == 1
    shortest = FINGER_REACH_MM[0]
    np.testing.assert_allclose(_reaches(confs)[0], [shortest, shortest, 10 - shortest],
                               atol=1e-9)
    np.testing.assert_allclose(confs.extensions[0, 2], 10 - shortest, atol=1e-9)


def test_reach_bounds_every_configuration_and_rejects_beyond():
    obj = PlanarObject.from_polygon(regular_polygon(3, 100, np.pi / 2))
    confs = configurations(_edge_midpoint_grasp(obj), obj, PARAMS, SYNTHESIS)
    reaches = _reaches(confs)
    assert (reaches[:, :2] >= FINGER_REACH_MM[0]).all()
    assert (reaches[:, :2] <= FINGER_REACH_MM[1]).all()
    assert (reaches[:, 2] >= THUMB_REACH_MM[0]).all() and (reaches[:, 2] <= THUMB_REACH_MM[1]).all()
    np.testing.assert_allclose(reaches[:, 2], confs.extensions[:, 2])  # the thumb's reach is e3


def _exact_grasp(yaw, spread, palm, reach):
    """Contacts on the hand's own force lines with normals = forces, and their triangle object."""
    palm = np.asarray(palm, float)
    forces = finger_forces(yaw, spread)
    axes = spread_axes(palm, yaw)
    contacts = np.stack([axes[0] - reach[0] * forces[0], axes[1] - reach[1] * forces[1],
                         palm - reach[2] * forces[2]])
    focus = palm - SPREAD_AXIS_OFFSET_MM / math.tan(spread) * forces[2]
    corners = [_meet(contacts[i], forces[i], contacts[j], forces[j])
               for i, j in ((0, 1), (1, 2), (2, 0))]
    return _grasps(contacts, forces, focus), PlanarObject.from_polygon(corners)


def test_reach_is_checked_inside_the_thumb_search():
    """The C1-best direction puts finger 1 21 mm past its axis, beyond the finger: the search
    keeps the best direction the hand can reach instead of dropping the grasp."""
    config = SYNTHESIS.model_copy(update={"min_extension_mm": 5.0})
    inside = configurations(*_exact_grasp(np.pi / 2, 1.2, (0, 0), (-10, 20, 70)), PARAMS, config)
    assert inside.force_line[inside.thumb == 2] == pytest.approx([0.0], abs=1e-12)
    grasp, obj = _exact_grasp(np.pi / 2, 1.2, (0, 0), (-21, 20, 70))
    assert FINGER_REACH_MM[0] > -21
    confs = configurations(grasp, obj, PARAMS, config)
    i = np.nonzero(confs.thumb == 2)[0]
    assert len(i) == 1
    assert confs.force_line[i[0]] > 0.1  # not the exact (unreachable) configuration
    assert _reaches(confs)[i[0], 0] >= FINGER_REACH_MM[0]


def test_approach_through_the_object_is_detected():
    obj = PlanarObject.from_polygon(rectangle(60, 60))
    contacts = np.array([[[-30.0, 0], [30, 0], [0, -30]]])
    inward = np.array([[[1.0, 0], [-1, 0], [0, 1]]])
    assert approach_clear(obj, contacts, inward).all()
    outward = inward * [[[-1], [1], [1]]]  # finger 1 would come from inside the object
    assert not approach_clear(obj, contacts, outward).any()


@settings(max_examples=40, deadline=None)
@given(
    yaw=st.floats(-math.pi, math.pi),
    spread=st.floats(0.35, 1.3),
    palm=st.tuples(st.floats(-200, 200), st.floats(-200, 200)),
    reach=st.tuples(st.floats(10, 60), st.floats(10, 60), st.floats(35, THUMB_REACH_MM[1])),
)
def test_configuration_of_an_exact_barrett_grasp_is_recovered(yaw, spread, palm, reach):
    """Contacts on the hand's own force lines, normals = forces: the search finds the hand."""
    palm = np.array(palm)
    forces = finger_forces(yaw, spread)
    axes = spread_axes(palm, yaw)
    contacts = np.stack([axes[0] - reach[0] * forces[0], axes[1] - reach[1] * forces[1],
                         palm - reach[2] * forces[2]])
    extensions = np.linalg.norm(contacts - palm, axis=1)
    if extensions.min() < SYNTHESIS.min_extension_mm or extensions.max() > 150:
        return
    focus = palm - SPREAD_AXIS_OFFSET_MM / math.tan(spread) * forces[2]
    # the object: the triangle bounded by the three contact lines (inward normals = forces)
    corners = [_meet(contacts[i], forces[i], contacts[j], forces[j])
               for i, j in ((0, 1), (1, 2), (2, 0))]
    obj = PlanarObject.from_polygon(corners)
    if not obj.contains(focus[None])[0]:
        return
    confs = configurations(_grasps(contacts, forces, focus), obj, PARAMS, SYNTHESIS)
    thumb_on_2 = np.nonzero(confs.thumb == 2)[0]
    assert len(thumb_on_2) == 1
    i = thumb_on_2[0]
    assert confs.force_line[i] == pytest.approx(0.0, abs=1e-9)
    assert confs.spread[i] == pytest.approx(spread, abs=1e-7)
    assert math.remainder(confs.yaw[i] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(confs.palm[i], palm, atol=1e-6)
    np.testing.assert_allclose(confs.focus[i], focus, atol=1e-6)
    np.testing.assert_allclose(confs.extensions[i], extensions, atol=1e-6)
    np.testing.assert_allclose(confs.contacts[i], contacts, atol=1e-9)


def _meet(p, n, q, m):
    """Intersection of the lines through p and q perpendicular to n and m."""
    matrix = np.array([n, m])
    return np.linalg.solve(matrix, [n @ p, m @ q])


def test_two_finger_grasp_base_matches_the_hands_spread_axes():
    from grip_env.planning import barrett, grasps

    assert grasps.HALF_FINGER_BASE_MM == barrett.SPREAD_AXIS_OFFSET_MM


def test_an_executable_test_runs_inside_the_search():
    """A further reach test (the executor's, in the pipeline) that refuses the C1-best direction:
    the search keeps the best direction that passes it, not nothing."""
    config = SYNTHESIS.model_copy(update={"min_extension_mm": 5.0})
    grasp, obj = _exact_grasp(np.pi / 2, 1.2, (0, 0), (-10, 20, 70))
    asked = []

    def finger_1_above_minus_8(reaches):
        asked.append(reaches.copy())
        return reaches[:, 0] >= -8.0

    confs = configurations(grasp, obj, PARAMS, config, finger_1_above_minus_8)
    i = np.nonzero(confs.thumb == 2)[0]
    assert len(i) == 1
    assert confs.force_line[i[0]] > 0.1
    np.testing.assert_allclose(_reaches(confs)[i], asked[-1][-1:], atol=1e-9)
    assert _reaches(confs)[i[0], 0] >= -8.0
    assert any((r[:, 0] < -8.0).any() for r in asked)  # the exact direction was asked and refused
