"""The object's pose in the palm frame, in plain floats: the judgement's per-step arithmetic.

Quaternions are (x, y, z, w), as PyBullet gives them; products compose like rotations
(``multiply(a, b)`` rotates by ``b`` first). The ramp asks every step whether the object moved,
so this avoids building ``scipy`` rotations and numpy arrays per step (same values to rounding).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

Quaternion = tuple[float, float, float, float]
Vector = tuple[float, float, float]


def normalized(q: Sequence[float]) -> Quaternion:
    """``q`` scaled to unit length."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    return (x / n, y / n, z / n, w / n)


def conjugate(q: Quaternion) -> Quaternion:
    """The inverse rotation of a unit quaternion."""
    return (-q[0], -q[1], -q[2], q[3])


def multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """The rotation ``b`` followed by ``a`` (Hamilton product, scalar last)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def rotate(q: Quaternion, v: Sequence[float]) -> Vector:
    """``v`` rotated by the unit quaternion ``q``."""
    x, y, z, w = q
    vx, vy, vz = v
    # t = 2 u x v; v' = v + w t + u x t
    tx, ty, tz = 2 * (y * vz - z * vy), 2 * (z * vx - x * vz), 2 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty,
            vy + w * ty + z * tx - x * tz,
            vz + w * tz + x * ty - y * tx)


def angle(q: Quaternion) -> float:
    """The rotation angle (rad, in [0, pi]) of a unit quaternion."""
    return 2.0 * math.atan2(math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2), abs(q[3]))


def in_frame(frame_position: Sequence[float], frame_orientation: Sequence[float],
             position: Sequence[float], orientation: Sequence[float]) -> tuple[Vector, Quaternion]:
    """A pose (position, quaternion) expressed in the frame at ``frame_position`` and
    ``frame_orientation`` (all in the same world coordinates)."""
    to_frame = conjugate(normalized(frame_orientation))
    offset = (position[0] - frame_position[0], position[1] - frame_position[1],
              position[2] - frame_position[2])
    return rotate(to_frame, offset), multiply(to_frame, normalized(orientation))


def moved_from(reference: tuple[Vector, Quaternion],
               current: tuple[Vector, Quaternion]) -> tuple[float, float]:
    """Distance between two poses' positions and the angle (degrees) between their rotations."""
    (p, q), (r, s) = current, reference
    drift = math.sqrt((p[0] - r[0]) ** 2 + (p[1] - r[1]) ** 2 + (p[2] - r[2]) ** 2)
    return drift, math.degrees(angle(multiply(conjugate(s), q)))
