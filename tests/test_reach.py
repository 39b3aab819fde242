"""Reach is physical: each planned contact is where the URDF finger, closed to it, puts its pad.

The planner (``grip_env.planning.barrett``) bounds each finger's reach from its own line origin
(spread axis;
O for the thumb) by the coupled closing of the URDF finger. These tests close the URDF in PyBullet
(``World`` + ``Hand``, joints set with ``resetJointState``, the distal link read back with
``getLinkState``) and compare where its pad (the sphere on the pad corner, read from the URDF)
touches with the planned contacts of the default objects.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pybullet
import pytest

from grip_env.config import Config
from grip_env.objects import load_object_set
from grip_env.perception.regions import find_regions
from grip_env.planning import barrett
from grip_env.planning.barrett import configurations
from grip_env.planning.finger import PAD_RADIUS_MM, pad_contact_in_plane
from grip_env.planning.grasps import synthesize_grasps
from grip_env.planning.pipeline import candidates, descriptor_columns
from grip_env.sim import hand as sim_hand
from grip_env.sim.hand import Hand
from grip_env.sim.world import World

PAD_TOLERANCE_MM = 1.0
SAMPLES_PER_OBJECT = 4


@pytest.fixture(scope="module")
def tables() -> dict[str, pd.DataFrame]:
    """Every configuration the planner's search gives on each default object, before the
    executor's own test (``pipeline.candidates`` keeps a subset of these): the descriptor columns
    of the candidate table."""
    config = Config()
    out = {}
    for obj in load_object_set("default"):
        regions = find_regions(obj, config.perception, config.grasp)
        grasps = synthesize_grasps(regions, obj, config.grasp, config.synthesis)
        confs = configurations(grasps, obj, config.grasp, config.synthesis)
        out[obj.name] = pd.DataFrame(descriptor_columns(obj, confs))
    return out


@pytest.fixture(scope="module")
def hand():
    with World() as world:
        yield Hand(world)


def _plan(table: pd.DataFrame) -> tuple[np.ndarray, ...]:
    """Line origins (n, 3, 2), forces (n, 3, 2) and contacts (n, 3, 2) of the planned grips."""
    yaw, spread = table["hand_yaw"].to_numpy(), table["spread"].to_numpy()
    palm = table[["hand_x", "hand_y"]].to_numpy()
    origins = np.concatenate([barrett.spread_axes(palm, yaw), palm[:, None]], axis=1)
    contacts = np.stack([table[[f"p{i}_x", f"p{i}_y"]].to_numpy() for i in "123"], axis=1)
    return origins, barrett.finger_forces(yaw, spread), contacts


def _reaches(origins, forces, contacts) -> np.ndarray:
    return np.einsum("nij,nij->ni", origins - contacts, forces)


def _postures(reaches: np.ndarray) -> np.ndarray:
    """Joint 2 of each finger (n, 3) in the coupled closing; raises if out of reach."""
    knuckles = (barrett.KNUCKLE_RADIAL_MM, barrett.KNUCKLE_RADIAL_MM, barrett.THUMB_KNUCKLE_MM)
    return np.stack([barrett.closing_joint2(reaches[:, i], k) for i, k in enumerate(knuckles)], 1)


def _pad_sphere(client, uid: int, link: int) -> tuple[np.ndarray, float]:
    """The distal link's pad sphere from the URDF: its centre (world mm) and radius (mm)."""
    (sphere,) = [s for s in client.getCollisionShapeData(uid, link) if s[2] == pybullet.GEOM_SPHERE]
    com, orientation = client.getLinkState(uid, link, computeForwardKinematics=True)[:2]
    rotation = np.array(client.getMatrixFromQuaternion(orientation)).reshape(3, 3)
    return (np.asarray(com) + rotation @ np.asarray(sphere[5])) * 1000, sphere[3][0] * 1000


def _urdf_pads(hand: Hand, row: pd.Series, joint2: np.ndarray) -> np.ndarray:
    """(3, 2) where the pads of the URDF closed to ``joint2`` touch a side square to their force
    lines (world mm, planar finger order): each pad sphere's point furthest along F_i."""
    client, uid = hand.world.client, hand.uid
    hand.teleport(np.array([row["hand_x"], row["hand_y"], 300.0]), float(row["hand_yaw"]))
    for joint in sim_hand.SPREAD_JOINTS:
        client.resetJointState(uid, joint, float(row["spread"]))
    forces = barrett.finger_forces(float(row["hand_yaw"]), float(row["spread"]))
    pads = []
    for joints, links, q2, force in zip(sim_hand.FLEX_JOINTS, sim_hand.FINGER_LINKS, joint2,
                                        forces, strict=True):
        client.resetJointState(uid, joints[0], float(q2))
        client.resetJointState(uid, joints[1], float(barrett.JOINT_COUPLING * q2))
        centre, radius = _pad_sphere(client, uid, links[-1])
        pads.append(centre[:2] + radius * force)
    return np.array(pads)


def _assert_pads_on_contacts(table: pd.DataFrame, name: str) -> None:
    """Every row's contacts on their force lines, within reach, where the closed finger's pad is."""
    origins, forces, contacts = _plan(table)
    offset = contacts - origins
    off_line = np.abs(offset[..., 0] * forces[..., 1] - offset[..., 1] * forces[..., 0])
    assert off_line.max(initial=0) < 1e-6, name
    reaches = _reaches(origins, forces, contacts)
    tol = barrett.REACH_TOLERANCE_MM
    for i, (shortest, longest) in enumerate(barrett.REACH_RANGES_MM):
        assert (reaches[:, i] >= shortest - tol).all(), name
        assert (reaches[:, i] <= longest + tol).all(), name
    joint2 = _postures(reaches)
    knuckles = np.array([barrett.KNUCKLE_RADIAL_MM] * 2 + [barrett.THUMB_KNUCKLE_MM])
    pads = origins - barrett.fingertip_reach(joint2, knuckles)[..., None] * forces
    assert np.linalg.norm(pads - contacts, axis=-1).max(initial=0) < PAD_TOLERANCE_MM, name
    np.testing.assert_allclose(table[["e1", "e2", "e3"]].to_numpy(),
                               np.linalg.norm(contacts - origins[:, 2:3], axis=-1), atol=1e-9)


def test_every_configuration_contact_is_on_its_finger_line_within_reach(tables):
    """Vectorised planar check of every configuration of every default object."""
    for name, table in tables.items():
        _assert_pads_on_contacts(table, name)
    assert sum(len(t) for t in tables.values()) > 1000


def test_candidates_after_the_executors_test_too():
    """``pipeline.candidates`` (the executor's test inside the search) on some default objects."""
    for obj in load_object_set("default")[:6]:
        _assert_pads_on_contacts(candidates(obj), obj.name)


def test_urdf_fingers_closed_to_the_posture_put_their_pads_on_the_contacts(tables, hand):
    """Forward kinematics of the URDF for a sample of candidates of every default object: the
    shortest and the longest reach of each, and random others."""
    rng = np.random.default_rng(0)
    checked = 0
    for name, table in tables.items():
        if table.empty:
            continue
        origins, forces, contacts = _plan(table)
        reaches = _reaches(origins, forces, contacts)
        extremes = [int(np.argmin(reaches.min(axis=1))), int(np.argmax(reaches.max(axis=1)))]
        rows = set(extremes) | set(rng.choice(len(table), min(len(table), SAMPLES_PER_OBJECT - 2),
                                              replace=False).tolist())
        joint2 = _postures(reaches[sorted(rows)])
        for k, row in enumerate(sorted(rows)):
            pads = _urdf_pads(hand, table.iloc[row], joint2[k])
            error = np.linalg.norm(pads - contacts[row], axis=-1)
            assert error.max() < PAD_TOLERANCE_MM, (name, row, error)
            checked += 1
    assert checked >= 2 * len([t for t in tables.values() if len(t)])


def test_reach_bounds_are_the_urdf_fingers_coupled_closing(hand):
    """Shortest and longest reach: the URDF finger at the two ends of CLOSING_JOINT2_RAD."""
    row = pd.Series({"hand_x": 0.0, "hand_y": 0.0, "hand_yaw": np.pi / 2, "spread": 0.5})
    forces = barrett.finger_forces(np.pi / 2, 0.5)
    origins = np.concatenate([barrett.spread_axes(np.zeros(2), np.pi / 2), np.zeros((1, 2))])
    low, high = barrett.CLOSING_JOINT2_RAD
    for q2, index in ((high, 0), (low, 1)):
        pads = _urdf_pads(hand, row, np.full(3, q2))
        reach = np.einsum("ij,ij->i", origins - pads, forces)
        expected = [barrett.FINGER_REACH_MM[index]] * 2 + [barrett.THUMB_REACH_MM[index]]
        np.testing.assert_allclose(reach, expected, atol=1e-3)
    grid = np.linspace(low, high, 500)
    reach = barrett.fingertip_reach(grid)
    assert np.all(np.diff(reach) < 0)  # one posture per reach
    assert reach[0] == barrett.FINGER_REACH_MM[1] and reach[-1] == barrett.FINGER_REACH_MM[0]
    # the executor's fingertip model is the planner's
    sim_reach, _ = pad_contact_in_plane(grid, grid / 3)
    np.testing.assert_allclose(sim_reach, reach, atol=1e-9)


def _distal_angle(q2: float) -> float:
    return q2 * (1 + barrett.JOINT_COUPLING) + barrett.DISTAL_BEND_RAD


def test_outside_the_closing_range_the_pad_corner_is_not_what_touches():
    """Within CLOSING_JOINT2_RAD the pad corner is the distal link's innermost point at and above
    the contact; past its far end the back corner is further in, before its near end the link
    leans outwards below joint 3, so the link above the contact is further in than the pad."""
    low, high = barrett.CLOSING_JOINT2_RAD
    assert np.cos(_distal_angle(low)) < 0  # past vertical
    assert _distal_angle(high) == pytest.approx(np.pi) or high < barrett.JOINT2_RANGE_RAD[1]
    pad = barrett.DISTAL_PAD_MM
    for q2, inside in ((high - 0.05, True), (high + 0.05, False)):
        corner = barrett.fingertip_reach(q2) + PAD_RADIUS_MM
        back = corner + 2 * pad * np.sin(_distal_angle(q2))
        assert (corner < back) == inside
    for q2, inside in ((low + 0.05, True), (low - 0.2, False)):
        corner = barrett.fingertip_reach(q2) + PAD_RADIUS_MM
        joint3_pad = corner - barrett.DISTAL_LINK_MM * np.cos(_distal_angle(q2))
        assert (corner < joint3_pad) == inside


def test_pad_angle_range_is_the_executors():
    finger = pytest.importorskip("grip_env.planning.finger")
    assert abs(barrett.PAD_ANGLE_RANGE_RAD[0] - finger.MIN_PAD_ANGLE) < 1e-12
    assert abs(barrett.DISTAL_BEND_RAD - finger.DISTAL_BEND_RAD) < 1e-12
    assert barrett.DISTAL_PAD_MM == finger.DISTAL_PAD_MM
    assert barrett.JOINT_COUPLING == finger.COUPLING


def test_closing_joint2_inverts_the_reach_and_refuses_beyond():
    reach = np.linspace(*barrett.FINGER_REACH_MM, 301)
    np.testing.assert_allclose(barrett.fingertip_reach(barrett.closing_joint2(reach)), reach,
                               atol=1e-6)
    for bad in (barrett.FINGER_REACH_MM[0] - 0.01, barrett.FINGER_REACH_MM[1] + 0.01):
        with pytest.raises(ValueError, match="outside the finger's range"):
            barrett.closing_joint2(np.array([bad]))


def test_the_planners_finger_width_is_the_urdf_distal_links(hand):
    """synthesis.finger_width_mm (the approach check's footprint) is the URDF pads' width, and
    each distal link carries one pad sphere of ``PAD_RADIUS_MM`` centred on its pad corner."""
    client = hand.world.client
    for links in sim_hand.FINGER_LINKS:
        shapes = client.getCollisionShapeData(hand.uid, links[-1])
        (box,) = [s for s in shapes if s[2] == pybullet.GEOM_BOX]
        (sphere,) = [s for s in shapes if s[2] == pybullet.GEOM_SPHERE]
        box_mm = np.asarray(box[3]) * 1000  # (length, width, thickness)
        assert box_mm[1] == pytest.approx(Config().synthesis.finger_width_mm)
        assert box_mm[2] == pytest.approx(2 * barrett.DISTAL_PAD_MM)
        assert sphere[3][0] * 1000 == pytest.approx(PAD_RADIUS_MM)
        # both in the link's inertial frame: the sphere sits on the box's far pad-side edge
        offset_mm = (np.asarray(sphere[5]) - np.asarray(box[5])) * 1000
        np.testing.assert_allclose(offset_mm, [box_mm[0] / 2, 0.0, box_mm[2] / 2], atol=1e-6)


def test_fingers_footprints_do_not_overlap(tables):
    """Seen from above, each finger covers its line from the contact out past its knuckle
    (60 mm reach), finger_width_mm wide; no two fingers of any configuration overlap, so the
    URDF's self-collision has nothing to stop."""
    import shapely

    half = Config().synthesis.finger_width_mm / 2
    for name, table in tables.items():
        origins, forces, contacts = _plan(table)
        side = half * np.stack([-forces[..., 1], forces[..., 0]], axis=-1)
        outer = origins - 60.0 * forces
        corners = np.stack([contacts + side, outer + side, outer - side, contacts - side], axis=-2)
        fingers = shapely.polygons(corners)  # (n, 3)
        for i, j in ((0, 1), (0, 2), (1, 2)):
            overlap = shapely.area(shapely.intersection(fingers[:, i], fingers[:, j]))
            assert overlap.max(initial=0) < 1.0, (name, i, j)
