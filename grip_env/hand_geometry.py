"""The Barrett BH8-280's figures, once: what the planner, the finger kinematics and the URDF share.

Sources: docs/barrett-bh8-280.md (the manufacturer's kinematics, ROS ``barrett_hand_description``
and published kinematics modules); where they differ the pick is the one the URDF's header names.
Millimetres and radians. This module imports nothing else from grip_env, so every layer can use it.
"""

from __future__ import annotations

import math

SPREAD_AXIS_OFFSET_MM = 25.0  #: spread axes of fingers 1 and 2 at (+-25, 0) in the palm
KNUCKLE_RADIAL_MM = 50.0  #: joint 2 from its spread axis, radially
THUMB_KNUCKLE_MM = 50.0  #: thumb joint 2 from the palm centre
KNUCKLE_HEIGHT_MM = 75.4  #: joint 2 along the palm normal from the palm base (41.5 + 33.9)
PROXIMAL_LINK_MM = 70.0  #: joint 2 to joint 3 (manufacturer)
DISTAL_LINK_MM = 50.0  #: joint 3 to fingertip (manufacturer's A3)
DISTAL_PAD_MM = 8.0  #: half thickness of the distal link: its pad face is this far off its axis
DISTAL_BEND_RAD = math.radians(42.0)  #: distal link bent towards the palm at joint 3 = 0
FINGER_WIDTH_MM = 25.0  #: finger (and pad) width, as the URDF's links
PALM_HEIGHT_MM = 84.0  #: palm base to finger plane (manufacturer's Dw)
PALM_DEPTH_MM = 75.0  #: the palm's body along its normal from the base (the URDF's cylinder)
MAX_SPREAD_RAD = math.pi  #: mechanical spread range is [0, pi]
JOINT2_RANGE_RAD = (0.0, 2.44)
JOINT3_RANGE_RAD = (0.0, 0.84)
JOINT_COUPLING = 1.0 / 3.0  #: joint 3 follows joint 2 / 3 until breakaway (the Barrett clutch)
#: Direction of the distal link in its closing plane (from the palm plane outwards) at which its
#: pad corner is what touches an object's side: 5 degrees past vertical (the link leans inwards
#: below the corner), up to pointing straight back at the finger's axis.
PAD_ANGLE_RANGE_RAD = (math.radians(95.0), math.pi)
