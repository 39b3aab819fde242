"""The lean loop computes what the plain one did: float quaternions, the hold update."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from grip_env.config import Config
from grip_env.objects import make_shape
from grip_env.sim import TrialScene, pose


def test_palm_frame_pose_matches_scipy_rotations():
    rng = np.random.default_rng(3)
    for _ in range(200):
        palm_q, obj_q, ref_q = Rotation.random(3, random_state=rng).as_quat()
        palm_p, obj_p, ref_p = rng.normal(0, 100, (3, 3))
        to_palm = Rotation.from_quat(palm_q).inv()
        expected_p = to_palm.apply(obj_p - palm_p)
        expected_r = to_palm * Rotation.from_quat(obj_q)
        position, orientation = pose.in_frame(palm_p, 1.0001 * palm_q, obj_p, obj_q)
        np.testing.assert_allclose(position, expected_p, atol=1e-9)
        assert (Rotation.from_quat(orientation).inv() * expected_r).magnitude() < 1e-9
        reference = (tuple(ref_p), tuple(Rotation.from_quat(ref_q).as_quat()))
        drift, turn = pose.moved_from(reference, (position, orientation))
        assert drift == pytest.approx(np.linalg.norm(expected_p - ref_p), abs=1e-9)
        expected_turn = np.degrees((Rotation.from_quat(ref_q).inv() * expected_r).magnitude())
        assert turn == pytest.approx(expected_turn, abs=1e-7)


def test_hold_update_is_the_drive_update_without_contacts():
    """Two scenes, one stepped with ``hold_fingers``, one with ``drive_fingers()``: same physics."""
    states = []
    for lean in (True, False):
        with TrialScene(make_shape("rectangle"), Config()) as scene:
            hand = scene.hand
            hand.teleport(np.array([0.0, 0.0, 200.0]), 0.3)
            hand.preshape(0.2, np.array([0.5, 0.6, 0.7]))
            hand.set_finger_torques(np.array([0.9, 0.9, 0.9]))
            for _ in range(60):
                hand.hold_fingers() if lean else hand.drive_fingers()
                scene.world.step()
            q, dq = hand.joint_states()
            states.append((q, dq, hand.state().peak))
    for lean, plain in zip(*states, strict=True):
        np.testing.assert_array_equal(lean, plain)
