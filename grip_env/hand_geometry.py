"""The Barrett BH8-280's figures, once, and its fingertip's forward kinematics: what the planner,
the finger kinematics and the URDF share.

Sources: docs/barrett-bh8-280.md (the manufacturer's kinematics, ROS ``barrett_hand_description``
and published kinematics modules); where they differ the pick is the one the URDF's header names.
Millimetres and radians. This module imports nothing else from grip_env, so every layer can use it.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

SPREAD_AXIS_OFFSET_MM = 25.0  #: spread axes of fingers 1 and 2 at (+-25, 0) in the palm
KNUCKLE_RADIAL_MM = 50.0  #: joint 2 from its spread axis, radially
THUMB_KNUCKLE_MM = 50.0  #: thumb joint 2 from the palm centre
KNUCKLE_HEIGHT_MM = 75.4  #: joint 2 along the palm normal from the palm base (41.5 + 33.9)
PROXIMAL_LINK_MM = 70.0  #: joint 2 to joint 3 (manufacturer)
DISTAL_LINK_MM = 50.0  #: joint 3 to fingertip (manufacturer's A3)
DISTAL_PAD_MM = 8.0  #: half thickness of the distal link: its pad face is this far off its axis
#: The rubber pad: a sphere of this radius centred on the pad corner, so that a fingertip touches
#: an object's side at one point (a box edge gives the contact solver one, two or four points, and
#: a compliant contact counts each). It touches a side facing the finger this far inside the
#: corner's reach, at the corner's height.
PAD_RADIUS_MM = 3.0
DISTAL_BEND_RAD = math.radians(42.0)  #: distal link bent towards the palm at joint 3 = 0
FINGER_WIDTH_MM = 25.0  #: finger (and pad) width, as the URDF's links
PALM_HEIGHT_MM = 84.0  #: palm base to finger plane (manufacturer's Dw)
PALM_DEPTH_MM = 75.0  #: the palm's body along its normal from the base (the URDF's cylinder)
MAX_SPREAD_RAD = math.pi  #: mechanical spread range is [0, pi]
JOINT2_RANGE_RAD = (0.0, 2.44)
JOINT3_RANGE_RAD = (0.0, 0.84)
JOINT_COUPLING = 1.0 / 3.0  #: joint 3 follows joint 2 / 3 until breakaway (the Barrett clutch)
#: Direction of the distal link in its closing plane (from the palm plane outwards) at which its
#: pad, on its corner, is what touches an object's side: 5 degrees past vertical (the link leans
#: inwards below the corner), up to pointing straight back at the finger's axis.
PAD_ANGLE_RANGE_RAD = (math.radians(95.0), math.pi)


def fingertip_in_plane(
    q2: ArrayLike, q3: ArrayLike, knuckle_mm: float = KNUCKLE_RADIAL_MM
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Fingertip pad corner in a finger's closing plane: (reach r, height h) in mm.

    ``r`` is measured outwards from the finger's line origin (its spread axis; O for the thumb,
    whose knuckle is ``THUMB_KNUCKLE_MM`` out), ``h`` along the palm normal from the palm base.
    The distal link points at a = q2 + bend + q3 and the pad corner sits ``DISTAL_PAD_MM`` off
    its tip on the closing side.
    """
    q2, q3 = np.asarray(q2, float), np.asarray(q3, float)
    a = q2 + DISTAL_BEND_RAD + q3
    r = (knuckle_mm + PROXIMAL_LINK_MM * np.cos(q2) + DISTAL_LINK_MM * np.cos(a)
         - DISTAL_PAD_MM * np.sin(a))
    h = (KNUCKLE_HEIGHT_MM + PROXIMAL_LINK_MM * np.sin(q2) + DISTAL_LINK_MM * np.sin(a)
         + DISTAL_PAD_MM * np.cos(a))
    return r, h


def pad_contact_in_plane(
    q2: ArrayLike, q3: ArrayLike, knuckle_mm: float = KNUCKLE_RADIAL_MM
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Where the fingertip's pad touches a side that faces the finger, in its closing plane:
    (reach r, height h) in mm, ``PAD_RADIUS_MM`` inside the pad corner (the pad sphere's centre,
    :func:`fingertip_in_plane`) at its height.

    Exact for a side square to the finger's force line; a side at an angle d to it is touched
    ``PAD_RADIUS_MM * sin(d)`` beside the line and ``PAD_RADIUS_MM * (1 - cos(d))`` further out.
    """
    r, h = fingertip_in_plane(q2, q3, knuckle_mm)
    return r - PAD_RADIUS_MM, h
