"""``Hand``: the Barrett BH8-280 URDF in a world (any ``Engine``), held by its palm, driven like
the real hand.

The palm is carried by an idealised arm in the same articulation (``grip_env.sim.gantry``):
prismatic x, y, z and a yaw wrist, each position-controlled to its target within one step and
within the arm's force (never teleported while in contact). The two spread joints are both
position-controlled to the same angle (mirrored axes in the URDF). Each finger is one
finite-torque motor behind a worm gear:

* joint 2 is velocity-controlled towards closing with torque limit ``tau2``; joint 3 follows
  ``q3_0 + (q2 - q2_0) / 3`` through the gear train (the Barrett clutch before breakaway);
* the worm gear is not backdrivable: every joint's lower limit is raised, at every control
  update, to the furthest the joint has closed (its running peak). The limit is a one-sided
  stop of unbounded force (``HOLD_FACTOR``: the worm is self-locking) that the solver solves
  together with the contacts, while the motor keeps pushing forward with its own torque: a
  stalled finger keeps its squeeze and cannot be pushed back (measured: 0.02 mrad under 40 N,
  about 3x the motor; the thumb holds 400 N), with no switching between modes. The floor sits
  exactly at the peak, with no backlash: PyBullet's joint limit is active only for a joint at or
  past it when a step starts, so a floor even 0.2 mrad below the joint let a 40 N push carry the
  thumb 47 mrad back in one step. The stop does not correct position (the world's ``erp`` is
  0): a joint the solver let slip below its floor stays there. A correction towards the floor
  pumped squeeze into fingers the object had stopped, more at every added solver iteration
  (BENCHMARKS.md).
* once joint 2 is stopped while the finger touches the object, by either link, joint 3 is
  released from the coupling and closes on its own with torque limit ``tau3`` (breakaway),
  locked behind by its own worm gear. A fingertip grip thus stalls on its two motors, whose
  torques give exactly ``finger_force_n`` at the pad, not on a gear-train servo whose target
  the object blocks.

The torques of each finger are chosen from its planned contact posture so that the fingertip
presses horizontally with ``SimConfig.finger_force_n`` (tau_k = F times the height of the
fingertip above joint k in the finger's closing plane).

Each fingertip touches through its rubber pad (a sphere on the pad corner, one contact point),
a compliant contact of ``sim.pad_stiffness_n_per_m`` and ``sim.pad_damping_n_s_per_m``
(``grip_env.sim.pad``). A rigid contact is pushed out of penetration by Bullet's position
correction, and with the worm gear locked that push could only drive the finger back through its
stop: loaded fingers crept back by up to 5 mrad. A compliant pad keeps its penetration as the
rubber's deformation, and it makes a grip wedged between locked fingers statically determinate:
how hard the object wedges follows from how far the rubber is pressed, not from how far the
solver iterates (BENCHMARKS.md).

Planar finger ``i`` (grip_env's frame, seen from above) is the URDF's finger ``FINGER_LINKS[i]``:
with the palm facing down the hand frame is mirrored, so planar finger 1 is URDF finger 2.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from grip_env.config import SimConfig
from grip_env.planning.finger import (
    COUPLING,
    JOINT3_MAX,
    KNUCKLE_HEIGHT_MM,
    PROXIMAL_MM,
    fingertip_in_plane,
)
from grip_env.sim.body import MM
from grip_env.sim.engine import Engine
from grip_env.sim.gantry import ARM_JOINTS, MOUNT_JOINTS, PALM_LINK

#: The hand's URDF, package data (a file on disk in a wheel or an editable install alike).
HAND_URDF = Path(str(files("grip_env") / "assets" / "barrett_bh8_280.urdf"))

# The finger's geometry is grip_env.hand_geometry's (as in the URDF), through planning.finger.
GEAR_FACTOR = 5.0  # joint 3's gear-train torque before breakaway, relative to tau3
GEAR_GAIN = 0.5  # position gain of the gear train (stiff, still stable at 240 Hz)
ARM_GAIN = 1.0  # the arm's joints reach their targets in one step (within their force)
ARM_LEVER_M = 0.1  # the wrist's torque limit is the arm's force at this lever
GEAR_UPDATE_RAD = 1e-3  # joint 3's geared target follows joint 2 in steps this small
#: The worm gear's holding torque relative to the motor's: unbounded. Barrett's worms (single
#: start, 125:1 and 93.75:1) are self-locking: no load on the finger turns them back short of
#: breaking a tooth, and no source gives a finite figure (BENCHMARKS.md, "The worm gear's stop,
#: alike in both engines"). MuJoCo's stop, a joint limit, has no force bound either.
HOLD_FACTOR = math.inf
BREAKAWAY_SPEED = 0.1  # joint 2 slower than this share of the closing speed has stopped
#: The finger motor's rotor inertia (kg m^2; Barrett's BHand motor, as listed by the University of
#: Waterloo's WAM specification) and the motor-to-joint motion ratios (Barrett: 125:1 to joint 2,
#: 93.75:1 to joint 3). Seen from a joint, the rotor weighs ratio^2 times its own inertia.
ROTOR_INERTIA_KG_M2 = 1.41e-7
MOTION_RATIOS = (125.0, 93.75)
FLEX_AXIS = 1  # the flexion joints turn about their links' local y axis (URDF axis 0 -1 0)

# Joint indices of the mounted hand, listed in planar finger order (planar 1 = URDF finger 2, see
# module doc): the bare URDF's, after the arm's ``MOUNT_JOINTS``.
SPREAD_JOINTS = tuple(MOUNT_JOINTS + j for j in (3, 0))
FLEX_JOINTS = tuple(tuple(MOUNT_JOINTS + j for j in pair) for pair in ((4, 5), (1, 2), (6, 7)))
FINGER_LINKS = tuple(tuple(MOUNT_JOINTS + j for j in links)
                     for links in ((3, 4, 5), (0, 1, 2), (6, 7)))
ARM = list(range(len(ARM_JOINTS)))


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


@dataclass(frozen=True)
class HandState:
    """What the controller remembers beyond PyBullet's state: the gear's floors (running peaks),
    the gear origin, breakaway, the palm target."""

    peak: NDArray[np.float64]
    origin: NDArray[np.float64]
    broken_away: tuple[bool, ...]
    palm_target: tuple[tuple[float, ...], float]


@dataclass
class Hand:
    """The hand on its arm in ``world``; positions in mm, the palm frame at the palm base centre.

    ``max_palm_force_n`` bounds each of the arm's prismatic joints (and, at ``ARM_LEVER_M``, the
    wrist's torque)."""

    world: Engine
    config: SimConfig = field(default_factory=SimConfig)
    max_palm_force_n: float = 400.0

    def __post_init__(self) -> None:
        world = self.world
        self.uid = world.load_robot(HAND_URDF)
        pairs = zip(FLEX_JOINTS, FINGER_LINKS, strict=True)
        self.fingers = [_Finger(joints, links) for joints, links in pairs]
        self._flex = [j for f in self.fingers for j in f.joints]
        self._upper = [world.joint_limits(self.uid, j)[1] for j in self._flex]
        for link in range(world.link_count(self.uid)):
            world.set_pad_friction(self.uid, link, self.config.finger_friction,
                                   self.config.pad_torsion_mm)
        for finger in self.fingers:
            world.set_contact_compliance(self.uid, finger.links[-1],
                                         self.config.pad_stiffness_n_per_m,
                                         self.config.pad_damping_n_s_per_m)
        self._add_rotor_inertia()
        self.spread = 0.0
        self._peaks = [0.0] * 6  # running peak of each flexion joint, in ``_flex`` order
        self._origin = np.zeros((3, 2))
        self._target: tuple[tuple[float, ...], float] = ((0.0, 0.0, 0.0), 0.0)

    def _add_rotor_inertia(self) -> None:
        """Give each flexion joint its motor's reflected rotor inertia (armature): ratio^2 times
        the rotor's, 2.2e-3 kg m^2 at joint 2 and 1.2e-3 at joint 3, 10-100x the links' own.

        PyBullet has no armature, so it is added to the links' inertia about axes parallel to
        their joints: joint 3's to the distal link, the rest of joint 2's to the proximal link
        (the distal link turns with joint 2 too). Each joint's own inertia is then exact; the
        coupling of the two joints gains joint 3's share, which a geared rotor does not have.
        """
        joint2, joint3 = (ROTOR_INERTIA_KG_M2 * r**2 for r in MOTION_RATIOS)
        for finger in self.fingers:
            proximal, distal = finger.links[-2:]
            self.world.add_axis_inertia(self.uid, proximal, FLEX_AXIS, joint2 - joint3)
            self.world.add_axis_inertia(self.uid, distal, FLEX_AXIS, joint3)

    # ------------------------------------------------------------------ palm
    @staticmethod
    def _arm_targets(position_mm: NDArray, yaw: float) -> list[float]:
        x, y, z = (float(v) * MM for v in position_mm)
        return [x, y, z, float(yaw)]

    def teleport(self, position_mm: NDArray, yaw: float) -> None:
        """Put the palm base at ``position_mm`` (world) with ``yaw``, at rest; only when not in
        contact."""
        for joint, value in zip(ARM, self._arm_targets(position_mm, yaw), strict=True):
            self.world.set_joint(self.uid, joint, value)
        self.move(position_mm, yaw)

    def move(self, position_mm: NDArray, yaw: float) -> None:
        """Drive the palm towards a new pose: the arm's joints reach it in the next step unless
        that takes more than their force."""
        self._target = (tuple(float(v) for v in position_mm), float(yaw))
        force = self.max_palm_force_n
        self.world.position_motors(self.uid, ARM, self._arm_targets(position_mm, yaw),
                                   [force, force, force, force * ARM_LEVER_M], ARM_GAIN)

    def palm_pose_mm(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Palm base position (mm) and quaternion."""
        position, orientation = self.palm_pose_floats()
        return np.asarray(position), np.asarray(orientation)

    def palm_pose_floats(
        self,
    ) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
        """``palm_pose_mm`` as plain tuples (for per-step checks)."""
        return self.world.link_pose_floats_mm(self.uid, PALM_LINK)

    def palm_target_mm(self) -> NDArray[np.float64]:
        """Where the palm base is being driven to (mm)."""
        return np.asarray(self._target[0])

    # ------------------------------------------------------------------ fingers
    def preshape(self, spread: float, joint2: NDArray, joint3: NDArray | None = None) -> None:
        """Set the spread and each finger's joints at once, lock them there, start the motors.

        ``joint3`` defaults to the coupled ``joint2 / 3``.
        """
        world = self.world
        q2 = np.asarray(joint2, float)
        q3 = COUPLING * q2 if joint3 is None else np.asarray(joint3, float)
        self.spread = float(spread)
        for joint in SPREAD_JOINTS:
            world.set_joint(self.uid, joint, self.spread)
        for finger, a, b in zip(self.fingers, q2, q3, strict=True):
            world.set_joint(self.uid, finger.joints[0], a)
            world.set_joint(self.uid, finger.joints[1], b)
            finger.broken_away = False
        self._origin = np.stack([q2, q3], axis=1)
        self._peaks = self._origin.ravel().tolist()
        world.position_motors(self.uid, list(SPREAD_JOINTS), [self.spread] * 2, [10.0] * 2)
        self._command_motors()
        self._raise_floors(range(6))

    def set_finger_torques(self, contact_q2: NDArray, contact_q3: NDArray | None = None) -> None:
        """Motor torques giving ``finger_force_n`` at the fingertips in their contact postures.

        A horizontal fingertip force F needs tau_k = F * (height of the tip above joint k).
        """
        force = self.config.finger_force_n
        q2 = np.asarray(contact_q2, float)
        q3 = COUPLING * q2 if contact_q3 is None else np.asarray(contact_q3, float)
        _, tip_h = fingertip_in_plane(q2, q3)
        joint3_h = KNUCKLE_HEIGHT_MM + PROXIMAL_MM * np.sin(q2)
        for finger, h, h3 in zip(self.fingers, tip_h, joint3_h, strict=True):
            finger.tau2 = force * max(h - KNUCKLE_HEIGHT_MM, 20.0) * MM
            finger.tau3 = force * max(h - h3, 20.0) * MM
        self._command_motors()
        self._raise_floors(range(6))

    def joint_states(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Flexion joint positions and velocities, shape (3, 2) each, planar finger order."""
        q, dq, _ = self.world.joint_states(self.uid, self._flex)
        return q.reshape(3, 2), dq.reshape(3, 2)

    def motor_torques(self) -> NDArray[np.float64]:
        """Torque each flexion motor applied in the last step (3, 2), N·m."""
        return self.world.joint_states(self.uid, self._flex)[2].reshape(3, 2)

    def drive_fingers(self, touching: NDArray[np.bool_] | None = None) -> NDArray[np.float64]:
        """One control update of the finger motors; returns the flexion velocities (3, 2).

        A joint that closed beyond its floor raises the floor there (the non-backdrivable worm
        gear: it can be driven forward by its motor, never back by a load). Motors are
        re-commanded only when something changed.
        ``touching`` ((3, 2) proximal/distal contacts) triggers the breakaway of a finger whose
        joint 2 is stopped while it touches the object, by either link (``_break_away``).
        """
        q, dq = self.world.joint_positions_velocities(self.uid, self._flex)
        advanced = self._follow(q)
        broke = touching is not None and self._break_away(touching, dq)
        if advanced or broke:
            self._command_motors()
        return np.array(dq).reshape(3, 2)

    def _break_away(self, touching: NDArray[np.bool_], dq: list[float]) -> bool:
        """Release joint 3 from the gear train of each finger whose joint 2 has stopped while
        the finger touches the object; whether any finger broke away now.

        The Barrett clutch disengages when the proximal link cannot move on, whether the object
        stops it directly or through the distal link: the distal link then closes on its own
        torque ``tau3`` (and its worm gear). A finger stopped by its distal pad therefore presses
        with its two motors' torques, which ``set_finger_torques`` chose to give exactly
        ``finger_force_n`` there, not with a gear-train servo chasing a target the object blocks
        (on a pinned box that servo had added up to 5 N, growing with the solver's iterations).
        """
        broke = False
        for i, finger in enumerate(self.fingers):
            stopped = dq[2 * i] < BREAKAWAY_SPEED * self.config.close_speed_rad_s
            if not finger.broken_away and stopped and (touching[i, 0] or touching[i, 1]):
                finger.broken_away = broke = True
        return broke

    def hold_fingers(self) -> None:
        """``drive_fingers()`` without contacts, returning nothing: the per-step update while
        the fingers hold (lean: no arrays)."""
        if self._follow(self.world.joint_positions(self.uid, self._flex)):
            self._command_motors()

    def _follow(self, q: list[float]) -> bool:
        """Raise the floors of the joints that closed beyond their peaks; whether a joint 2
        advanced by more than ``GEAR_UPDATE_RAD`` (its joint 3's geared target then moves)."""
        peaks, advanced, closed = self._peaks, False, []
        for n, value in enumerate(q):
            if value > peaks[n]:
                advanced = advanced or (n % 2 == 0 and value > peaks[n] + GEAR_UPDATE_RAD)
                peaks[n] = value
                closed.append(n)
        if closed:
            self._raise_floors(closed)
        return advanced

    def _raise_floors(self, which: Iterable[int]) -> None:
        """Set the lower limit of the flexion joints ``which`` (indices into ``_flex``) to their
        peaks, holding ``HOLD_FACTOR`` times their motor torques (any load: it is infinite)."""
        joints, lowers, uppers, holds = [], [], [], []
        for n in which:
            finger = self.fingers[n // 2]
            joints.append(self._flex[n])
            lowers.append(self._peaks[n])
            uppers.append(self._upper[n])
            holds.append(HOLD_FACTOR * (finger.tau2, finger.tau3)[n % 2])
        self.world.joint_floors(self.uid, joints, lowers, uppers, holds)

    def _command_motors(self) -> None:
        """Joints close on their motors; joint 3 follows the gear train until breakaway."""
        velocity, velocity_forces, position, targets, position_forces = [], [], [], [], []
        for i, finger in enumerate(self.fingers):
            for k, tau in enumerate((finger.tau2, finger.tau3)):
                joint = finger.joints[k]
                if k == 1 and not finger.broken_away:
                    closed = self._peaks[2 * i] - self._origin[i, 0]
                    coupled = self._origin[i, 1] + COUPLING * closed
                    position.append(joint)
                    targets.append(min(coupled, JOINT3_MAX))
                    position_forces.append(GEAR_FACTOR * tau)
                else:
                    velocity.append(joint)
                    velocity_forces.append(tau)
        if velocity:
            self.world.velocity_motors(self.uid, velocity,
                                       [self.config.close_speed_rad_s] * len(velocity),
                                       velocity_forces)
        if position:
            self.world.position_motors(self.uid, position, targets, position_forces, GEAR_GAIN)

    def state(self) -> HandState:
        """The controller's own state, to restore together with a PyBullet state."""
        return HandState(np.reshape(self._peaks, (3, 2)), self._origin.copy(),
                         tuple(f.broken_away for f in self.fingers), self._target)

    def restore(self, state: HandState) -> None:
        """Bring the controller back to ``state`` (after ``restoreState`` of the same moment)
        and command its motors, stops and palm target again."""
        self.resume(state)
        self._command_motors()
        self._raise_floors(range(6))
        self.move(np.asarray(state.palm_target[0]), state.palm_target[1])

    def resume(self, state: HandState) -> None:
        """Bring the controller back to ``state`` after the world resumed the same moment with
        every command (``Engine.resume``): its memory only, nothing commanded again."""
        self._peaks, self._origin = state.peak.ravel().tolist(), state.origin.copy()
        for finger, broken in zip(self.fingers, state.broken_away, strict=True):
            finger.broken_away = broken
        self._target = state.palm_target

    def touching(self, body: int) -> NDArray[np.bool_]:
        """(3, 2): whether each finger's proximal and distal links (planar order) touch ``body``."""
        links = self.world.touching_links(self.uid, body)
        return np.array([[f.links[-2] in links, f.links[-1] in links] for f in self.fingers])
