"""The hand mounted on an idealised arm: a Cartesian gantry with a yaw wrist, one articulation.

The palm is carried by four actuated joints, prismatic x, y, z and a revolute yaw about the
vertical, then a fixed mount that turns the palm to face down. Being one articulation with the
fingers, the arm's joints are exact (Featherstone's reduced coordinates, not a constraint the
solver iterates on) and its motors track their targets with their own gains, so the solver's
global position correction (``erp``) can be switched off: the worm gear's stops then never push a
finger forward (``grip_env.sim.hand``; BENCHMARKS.md, "The arm, stops that do not push, the
rotor's inertia").

``mounted_urdf`` writes the hand's URDF with that arm as its root and returns the file's path.
Link and joint indices of the hand are those of the bare URDF shifted by ``MOUNT_JOINTS``.
"""

from __future__ import annotations

import functools
import hashlib
import math
import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

#: The arm's actuated joints, in the order of their indices (0 .. 3).
ARM_JOINTS = ("gantry_x", "gantry_y", "gantry_z", "wrist_yaw")
#: Joints before the hand's own: the four of the arm and the fixed palm mount.
MOUNT_JOINTS = len(ARM_JOINTS) + 1
#: The palm's link index in the mounted body.
PALM_LINK = MOUNT_JOINTS - 1
#: Mass of each carriage (kg): the arm moves with inertia, as a real arm's would.
CARRIAGE_KG = 1.0
#: Mount rotation: hand x, y, z to world y, x, -z at yaw 0 (``hand.palm_quaternion(0)``).
MOUNT_RPY = (math.pi, 0.0, math.pi / 2)


def _link(robot: ET.Element, name: str) -> None:
    """A carriage of ``CARRIAGE_KG`` (the base's mass never acts: it is fixed to the world)."""
    inertial = ET.SubElement(ET.SubElement(robot, "link", name=name), "inertial")
    ET.SubElement(inertial, "mass", value=str(CARRIAGE_KG))
    ET.SubElement(inertial, "inertia", ixx="1e-3", iyy="1e-3", izz="1e-3",
                  ixy="0", ixz="0", iyz="0")


def _joint(robot: ET.Element, name: str, kind: str, parent: str, child: str,
           axis: str | None = None, rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
    joint = ET.SubElement(robot, "joint", name=name, type=kind)
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)
    ET.SubElement(joint, "origin", xyz="0 0 0", rpy=" ".join(repr(a) for a in rpy))
    if axis is not None:
        ET.SubElement(joint, "axis", xyz=axis)
    if kind == "prismatic":
        ET.SubElement(joint, "limit", lower="-10", upper="10", effort="1000", velocity="10")


def mounted_tree(hand_urdf: str | Path) -> ET.ElementTree:
    """The hand's URDF with the arm as its root (``gantry_base``, fixed to the world)."""
    tree = ET.parse(hand_urdf)
    hand = tree.getroot()
    robot = ET.Element("robot", name=f"{hand.get('name')}_on_gantry")
    _link(robot, "gantry_base")
    parent = "gantry_base"
    for name, axis in zip(ARM_JOINTS, ("1 0 0", "0 1 0", "0 0 1", "0 0 1"), strict=True):
        child = f"{name}_carriage"
        _link(robot, child)
        _joint(robot, name, "continuous" if name == "wrist_yaw" else "prismatic", parent, child,
               axis)
        parent = child
    _joint(robot, "palm_mount", "fixed", parent, "palm", rpy=MOUNT_RPY)
    robot.extend(list(hand))
    return ET.ElementTree(robot)


@functools.cache
def mounted_urdf(hand_urdf: str | Path) -> Path:
    """Path of the mounted URDF in the temporary folder, named by its content's hash (written
    atomically, so concurrent workers share one file)."""
    text = ET.tostring(mounted_tree(hand_urdf).getroot(), encoding="unicode")
    digest = hashlib.sha256(text.encode()).hexdigest()[:16]
    path = Path(tempfile.gettempdir()) / f"grip_env_{Path(hand_urdf).stem}_on_gantry_{digest}.urdf"
    if not path.exists():
        partial = path.with_suffix(f".{os.getpid()}.part")
        partial.write_text('<?xml version="1.0"?>\n' + text)
        os.replace(partial, path)
    return path
