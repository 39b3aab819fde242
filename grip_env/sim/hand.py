"""``Hand``: the Barrett BH8-280 URDF in a ``World``, held by its palm, driven like the real hand.

The palm hangs from a fixed constraint to the world that is moved with ``changeConstraint``
(never teleported while in contact). The two spread joints are both position-controlled to the
same angle (mirrored axes in the URDF). Each finger is one finite-torque "motor":

* free closing: joint 2 is velocity-controlled towards closing with torque limit ``tau2``, joint 3
  is position-controlled to ``q2 / 3`` (the Barrett clutch before breakaway);
* once the finger is stopped by the object (in contact, joint 2 no longer advancing), joint 3 is
  released from the coupling and closes on its own with torque limit ``tau3`` (breakaway). A
  stalled finger keeps pressing with its motor torques: the real hand's worm gears would lock it
  instead, so this model is a little softer than the real hand under load.

The torques of each finger are chosen from its planned closing posture so that the fingertip
presses horizontally with ``SimConfig.finger_force_n`` (tau_k = F times the height of the
fingertip above joint k in the finger's closing plane).

Planar finger ``i`` (grip_env's frame, seen from above) is the URDF's finger ``FINGER_LINKS[i]``:
with the palm facing down the hand frame is mirrored, so planar finger 1 is URDF finger 2.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pybullet
from numpy.typing import NDArray

from grip_env import barrett
from grip_env.config import SimConfig
from grip_env.sim.world import MM, World

HAND_URDF = Path(__file__).resolve().parents[1] / "assets" / "barrett_bh8_280.urdf"

# Finger geometry in its closing plane (mm, rad): grip_env.barrett's figures, as in the URDF.
SPREAD_AXIS_OFFSET_MM = barrett.SPREAD_AXIS_OFFSET_MM
KNUCKLE_RADIUS_MM = barrett.KNUCKLE_RADIAL_MM  # knuckle from the finger's line origin (S_i or O)
KNUCKLE_HEIGHT_MM = 75.4  # knuckle height along the palm normal (41.5 + 33.9)
PROXIMAL_MM = barrett.PROXIMAL_LINK_MM
DISTAL_MM = barrett.DISTAL_LINK_MM
DISTAL_PAD_MM = 8.0  # half thickness of the distal link: the pad face is this far inside
DISTAL_BEND_RAD = np.deg2rad(42.0)
COUPLING = 1.0 / 3.0
BACKLASH_RAD = 0.005  # a joint pushed back further than this is held by its worm gear
HOLD_FACTOR = 5.0  # worm-gear holding torque relative to the motor torque
HOLD_GAIN = 0.5  # position gain of a held joint (stiff, still stable at 240 Hz)
JOINT3_MAX = barrett.JOINT3_RANGE_RAD[1]

# URDF joint indices, listed in planar finger order (planar 1 = URDF finger 2, see module doc).
SPREAD_JOINTS = (3, 0)
FLEX_JOINTS = ((4, 5), (1, 2), (6, 7))
FINGER_LINKS = ((3, 4, 5), (0, 1, 2), (6, 7))


def fingertip_in_plane(q2: NDArray, q3: NDArray) -> tuple[NDArray, NDArray]:
    """Fingertip pad corner in a finger's closing plane: (reach r, height h) in mm.

    ``r`` is measured outwards from the finger's line origin (its spread axis; O for the thumb),
    ``h`` along the palm normal from the palm base.
    """
    q2, q3 = np.asarray(q2, float), np.asarray(q3, float)
    a = q2 + DISTAL_BEND_RAD + q3
    r = (KNUCKLE_RADIUS_MM + PROXIMAL_MM * np.cos(q2) + DISTAL_MM * np.cos(a)
         - DISTAL_PAD_MM * np.sin(a))
    h = (KNUCKLE_HEIGHT_MM + PROXIMAL_MM * np.sin(q2) + DISTAL_MM * np.sin(a)
         + DISTAL_PAD_MM * np.cos(a))
    return r, h


def fingertip_depth(q2: NDArray, q3: NDArray) -> NDArray:
    """How far the distal link reaches along the palm normal (mm): its deeper tip corner."""
    a = np.asarray(q2, float) + DISTAL_BEND_RAD + np.asarray(q3, float)
    _, pad_h = fingertip_in_plane(q2, q3)
    return pad_h + np.maximum(0.0, -2 * DISTAL_PAD_MM * np.cos(a))


_Q2_GRID = np.linspace(0.0, 1.5, 601)
_R_GRID, _H_GRID = fingertip_in_plane(_Q2_GRID, COUPLING * _Q2_GRID)
_DEPTH_GRID = fingertip_depth(_Q2_GRID, COUPLING * _Q2_GRID)


def closing_depth(q2_from: NDArray, q2_to: NDArray) -> NDArray:
    """Deepest reach of each finger along the palm normal while closing from q2_from to q2_to."""
    lo, hi = np.minimum(q2_from, q2_to), np.maximum(q2_from, q2_to)
    inside = (lo[..., None] <= _Q2_GRID) & (hi[..., None] >= _Q2_GRID)
    ends = np.maximum(np.interp(lo, _Q2_GRID, _DEPTH_GRID), np.interp(hi, _Q2_GRID, _DEPTH_GRID))
    return np.maximum(ends, np.where(inside, _DEPTH_GRID, -np.inf).max(axis=-1))


def closing_posture(reach_mm: NDArray) -> tuple[NDArray, NDArray]:
    """Joint-2 angle (coupled closing) at which the fingertip reaches ``reach_mm``, and its height.

    ``reach`` decreases monotonically with q2 on the grid used; reaches outside it are clipped.
    """
    reach = np.asarray(reach_mm, float)
    q2 = np.interp(-reach, -_R_GRID, _Q2_GRID)
    return q2, np.interp(q2, _Q2_GRID, _H_GRID)


def palm_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """Palm facing down (hand z = -world z) with the thumb pushing along (cos yaw, sin yaw).

    That rotation maps hand x, y, z to (-sin, cos, 0), (cos, sin, 0), (0, 0, -1): a half turn
    about the horizontal axis (sin phi, cos phi, 0) with phi = pi/4 - yaw/2.
    """
    phi = np.pi / 4 - yaw / 2
    return (float(np.sin(phi)), float(np.cos(phi)), 0.0, 0.0)


def palm_to_world(yaw: float, vector: NDArray) -> NDArray[np.float64]:
    """A palm-frame vector expressed in the world for a palm at ``yaw`` facing down."""
    c, s = np.cos(yaw), np.sin(yaw)
    x, y, z = vector
    return np.array([-s * x + c * y, c * x + s * y, -z])


@dataclass
class _Finger:
    joints: tuple[int, int]
    links: tuple[int, ...]
    tau2: float = 1.0
    tau3: float = 0.5
    broken_away: bool = False


@dataclass
class Hand:
    """The hand loaded into ``world``; positions in mm, the palm frame at the palm base centre."""

    world: World
    config: SimConfig = field(default_factory=SimConfig)
    max_palm_force_n: float = 400.0
    close_speed_rad_s: float = 1.5

    def __post_init__(self) -> None:
        c = self.world.client
        self.uid = c.loadURDF(
            str(HAND_URDF), basePosition=[0, 0, 1], flags=pybullet.URDF_USE_INERTIA_FROM_FILE
        )
        self._com_offset = np.asarray(c.getDynamicsInfo(self.uid, -1)[3])
        pairs = zip(FLEX_JOINTS, FINGER_LINKS, strict=True)
        self.fingers = [_Finger(joints, links) for joints, links in pairs]
        for link in range(c.getNumJoints(self.uid)):
            c.changeDynamics(self.uid, link, lateralFriction=self.config.finger_friction,
                             spinningFriction=0.002, frictionAnchor=1)
        self.constraint = c.createConstraint(
            self.uid, -1, -1, -1, pybullet.JOINT_FIXED, [0, 0, 0], [0, 0, 0], [0, 0, 1]
        )
        self.spread = 0.0

    # ------------------------------------------------------------------ palm
    def _com_target(self, position_mm: NDArray, yaw: float) -> tuple[list[float], tuple]:
        com = np.asarray(position_mm, float) * MM + palm_to_world(yaw, self._com_offset)
        return com.tolist(), palm_quaternion(yaw)

    def teleport(self, position_mm: NDArray, yaw: float) -> None:
        """Put the palm base at ``position_mm`` (world) with ``yaw``; only when not in contact."""
        c = self.world.client
        c.resetBasePositionAndOrientation(
            self.uid, (np.asarray(position_mm, float) * MM).tolist(), palm_quaternion(yaw)
        )
        c.resetBaseVelocity(self.uid, [0, 0, 0], [0, 0, 0])
        self.move(position_mm, yaw)

    def move(self, position_mm: NDArray, yaw: float) -> None:
        """Drive the palm constraint towards a new pose (the solver moves it within its force)."""
        com, orn = self._com_target(position_mm, yaw)
        self.world.client.changeConstraint(
            self.constraint, jointChildPivot=com, jointChildFrameOrientation=orn,
            maxForce=self.max_palm_force_n,
        )

    def palm_pose_mm(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Palm base position (mm) and quaternion."""
        return self.world.pose_mm(self.uid)

    # ------------------------------------------------------------------ fingers
    def preshape(self, spread: float, joint2: NDArray) -> None:
        """Set the spread and each finger's joint 2 (joint 3 coupled) at once, then hold them."""
        c = self.world.client
        self.spread = float(spread)
        for joint in SPREAD_JOINTS:
            c.resetJointState(self.uid, joint, self.spread)
        for finger, q2 in zip(self.fingers, np.asarray(joint2, float), strict=True):
            c.resetJointState(self.uid, finger.joints[0], q2)
            c.resetJointState(self.uid, finger.joints[1], COUPLING * q2)
            finger.broken_away = False
        self._peak, _ = self.joint_states()
        self._hold_spread()
        c.setJointMotorControlArray(
            self.uid, [j for f in self.fingers for j in f.joints], pybullet.VELOCITY_CONTROL,
            targetVelocities=[0.0] * 6, forces=[5.0] * 6,
        )

    def _hold_spread(self) -> None:
        self.world.client.setJointMotorControlArray(
            self.uid, list(SPREAD_JOINTS), pybullet.POSITION_CONTROL,
            targetPositions=[self.spread] * 2, forces=[10.0] * 2,
        )

    def set_finger_torques(self, planned_joint2: NDArray) -> None:
        """Motor torques giving ``finger_force_n`` at the fingertips in their planned postures.

        A horizontal fingertip force F needs tau_k = F * (height of the tip above joint k).
        """
        force = self.config.finger_force_n
        q2 = np.asarray(planned_joint2, float)
        _, tip_h = fingertip_in_plane(q2, COUPLING * q2)
        joint3_h = KNUCKLE_HEIGHT_MM + PROXIMAL_MM * np.sin(q2)
        for finger, h, h3 in zip(self.fingers, tip_h, joint3_h, strict=True):
            finger.tau2 = force * max(h - KNUCKLE_HEIGHT_MM, 20.0) * MM
            finger.tau3 = force * max(h - h3, 20.0) * MM

    def joint_states(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Flexion joint positions and velocities, shape (3, 2) each, planar finger order."""
        joints = [j for f in self.fingers for j in f.joints]
        states = self.world.client.getJointStates(self.uid, joints)
        q = np.array([s[0] for s in states]).reshape(3, 2)
        dq = np.array([s[1] for s in states]).reshape(3, 2)
        return q, dq

    def drive_fingers(self, touching: NDArray[np.bool_] | None = None) -> NDArray[np.float64]:
        """One control update of the finger motors; returns the flexion velocities (3, 2).

        Each joint pushes towards closing with its motor torque; a joint pushed back more than
        ``BACKLASH_RAD`` behind the furthest it has closed is held there with ``HOLD_FACTOR``
        times that torque (the non-backdrivable worm gear). Before breakaway joint 3 follows
        q2 / 3 through the gear train (held with the same stiffness): a finger stopped at its
        distal link stalls as a whole. ``touching`` ((3, 2) proximal/distal contacts) triggers
        the breakaway of a finger whose proximal link is stopped by contact.
        """
        q, dq = self.joint_states()
        self._peak = np.maximum(self._peak, q)
        backdriven = q < self._peak - BACKLASH_RAD
        speed = self.close_speed_rad_s
        joints, modes, targets, forces = [], [], [], []
        for i, finger in enumerate(self.fingers):
            if touching is not None and touching[i, 0] and dq[i, 0] < 0.1 * speed:
                finger.broken_away = True
            for k, tau in enumerate((finger.tau2, finger.tau3)):
                joints.append(finger.joints[k])
                if k == 1 and not finger.broken_away:
                    target = min(COUPLING * self._peak[i, 0], JOINT3_MAX)
                    modes.append(("pos", target, HOLD_FACTOR * tau))
                elif backdriven[i, k]:
                    modes.append(("pos", self._peak[i, k], HOLD_FACTOR * tau))
                else:
                    modes.append(("vel", speed, tau))
        c = self.world.client
        for kind, mode in (("pos", pybullet.POSITION_CONTROL), ("vel", pybullet.VELOCITY_CONTROL)):
            chosen = [(j, m) for j, m in zip(joints, modes, strict=True) if m[0] == kind]
            if not chosen:
                continue
            targets = [m[1] for _, m in chosen]
            forces = [m[2] for _, m in chosen]
            ids = [j for j, _ in chosen]
            if kind == "pos":
                c.setJointMotorControlArray(self.uid, ids, mode, targetPositions=targets,
                                            forces=forces, positionGains=[HOLD_GAIN] * len(ids))
            else:
                c.setJointMotorControlArray(self.uid, ids, mode, targetVelocities=targets,
                                            forces=forces)
        return dq

    def touching(self, body: int) -> NDArray[np.bool_]:
        """(3, 2): whether each finger's proximal and distal links (planar order) touch ``body``."""
        contacts = self.world.client.getContactPoints(bodyA=self.uid, bodyB=body)
        links = {point[3] for point in contacts}
        return np.array([[f.links[-2] in links, f.links[-1] in links] for f in self.fingers])

