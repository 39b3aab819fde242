"""The Barrett URDF agrees with grip_env's planar kinematics and the hand controller's geometry."""

from __future__ import annotations

import numpy as np
import pybullet
import pytest

from grip_env.planning import barrett
from grip_env.planning.finger import DISTAL_PAD_MM, fingertip_in_plane
from grip_env.sim import HAND_URDF, World

# URDF link indices: (spread link or None, proximal, distal) of URDF fingers 1, 2, 3 (thumb).
PROXIMAL, DISTAL = (1, 4, 6), (2, 5, 7)


@pytest.fixture(scope="module")
def hand():
    with World() as world:
        uid = world.client.loadURDF(str(HAND_URDF), useFixedBase=True,
                                    flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        yield world.client, uid


def _pose(client, uid, spread, q2, q3):
    for joint in (0, 3):
        client.resetJointState(uid, joint, spread)
    for j2, j3 in ((1, 2), (4, 5), (6, 7)):
        client.resetJointState(uid, j2, q2)
        client.resetJointState(uid, j3, q3)


def _tip(client, uid, link):
    state = client.getLinkState(uid, link, computeForwardKinematics=True)
    matrix = np.array(client.getMatrixFromQuaternion(state[5])).reshape(3, 3)
    corner = np.array([barrett.DISTAL_LINK_MM, 0.0, DISTAL_PAD_MM]) / 1000
    return (np.asarray(state[4]) + matrix @ corner) * 1000


def _lines(spread):
    """Planar force lines in the hand frame: (origin S_i, direction F_i), URDF finger order."""
    s, c = np.sin(spread), np.cos(spread)
    offset = barrett.SPREAD_AXIS_OFFSET_MM
    return [(np.array([offset, 0.0]), np.array([-s, -c])),
            (np.array([-offset, 0.0]), np.array([s, -c])),
            (np.zeros(2), np.array([0.0, 1.0]))]


@pytest.mark.parametrize("spread", [0.0, np.pi / 6, np.pi / 3, 1.2, 1.5])
@pytest.mark.parametrize("q2", [0.0, 0.7, 1.3])
def test_knuckles_and_tips_lie_on_the_planar_force_lines(hand, spread, q2):
    client, uid = hand
    _pose(client, uid, spread, q2, q2 / 3)
    for (origin, force), proximal, distal in zip(_lines(spread), PROXIMAL, DISTAL, strict=True):
        knuckle = np.asarray(client.getLinkState(uid, proximal)[4]) * 1000
        tip = _tip(client, uid, distal)
        for point in (knuckle[:2], tip[:2]):
            offset = point - origin
            # on the line, to float32 precision of the link states (mm)
            assert abs(offset[0] * force[1] - offset[1] * force[0]) < 1e-3
        # The knuckle stands behind the contact side: back along F at the knuckle radius.
        back = -(knuckle[:2] - origin) @ force
        radius = barrett.KNUCKLE_RADIAL_MM if proximal != 6 else barrett.THUMB_KNUCKLE_MM
        assert back == pytest.approx(radius, abs=1e-3)


@pytest.mark.parametrize("q2", [0.2, 0.8, 1.25])
def test_controller_fingertip_model_matches_forward_kinematics(hand, q2):
    client, uid = hand
    _pose(client, uid, 0.4, q2, q2 / 3)
    reach, height = fingertip_in_plane(q2, q2 / 3)
    for (origin, force), distal in zip(_lines(0.4), DISTAL, strict=True):
        tip = _tip(client, uid, distal)
        assert -(tip[:2] - origin) @ force == pytest.approx(reach, abs=1e-3)
        assert tip[2] == pytest.approx(height, abs=1e-3)


def test_closing_moves_the_tip_along_its_force_direction(hand):
    client, uid = hand
    _pose(client, uid, 0.5, 0.5, 0.5 / 3)
    before = _tip(client, uid, 2)
    _pose(client, uid, 0.5, 0.6, 0.6 / 3)
    step = _tip(client, uid, 2)[:2] - before[:2]
    assert step @ _lines(0.5)[0][1] > 0


def test_masses_limits_and_structure(hand):
    client, uid = hand
    masses = [client.getDynamicsInfo(uid, link)[0] for link in range(8)]
    assert sum(masses) + 0.5 == pytest.approx(1.0, abs=0.05)  # + palm (fixed base reads 0)
    info = {client.getJointInfo(uid, j)[1].decode(): client.getJointInfo(uid, j)
            for j in range(client.getNumJoints(uid))}
    assert len(info) == 8 and "finger_3_spread" not in info
    for finger in (1, 2, 3):
        j2, j3 = info[f"finger_{finger}_joint_2"], info[f"finger_{finger}_joint_3"]
        assert (j2[8], j2[9]) == pytest.approx(barrett.JOINT2_RANGE_RAD)
        assert (j3[8], j3[9]) == pytest.approx(barrett.JOINT3_RANGE_RAD)
    for finger in (1, 2):
        spread = info[f"finger_{finger}_spread"]
        assert (spread[8], spread[9]) == pytest.approx((0.0, np.pi))
    assert info["finger_1_spread"][13] == pytest.approx((0, 0, -1))
    assert info["finger_2_spread"][13] == pytest.approx((0, 0, 1))
