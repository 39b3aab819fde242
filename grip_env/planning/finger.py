"""Finger kinematics of the Barrett BH8-280 in a finger's closing plane (pure numpy).

Each finger closes in the vertical plane through its line origin (its spread axis; O for the
thumb). A point of the finger is given as (reach r, height h): r outwards from the line origin,
h along the palm normal from the palm base. The figures are the URDF's (its header names their
sources); the planner and the simulator both use this module, so the contacts that are planned
are the contacts that are executed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from grip_env import hand_geometry as hg
from grip_env.hand_geometry import fingertip_in_plane, pad_contact_in_plane
from grip_env.planning import barrett

KNUCKLE_RADIUS_MM = hg.KNUCKLE_RADIAL_MM  # knuckle from the finger's line origin (S_i or O)
KNUCKLE_HEIGHT_MM = hg.KNUCKLE_HEIGHT_MM
PROXIMAL_MM = hg.PROXIMAL_LINK_MM
DISTAL_MM = hg.DISTAL_LINK_MM
DISTAL_PAD_MM = hg.DISTAL_PAD_MM
PAD_RADIUS_MM = hg.PAD_RADIUS_MM
DISTAL_BEND_RAD = hg.DISTAL_BEND_RAD
COUPLING = hg.JOINT_COUPLING
JOINT2_MAX = hg.JOINT2_RANGE_RAD[1]
JOINT3_MAX = hg.JOINT3_RANGE_RAD[1]
PALM_DEPTH_MM = hg.PALM_DEPTH_MM
_HEIGHT_RANGE = (60.0, 260.0)  # palm heights above the contact plane that are searched
_HEIGHT_STEP_MM = 2.0  # palm heights tried, this far apart
_TABLE_STEPS = (489, 169)  # closing sweep depth tabulated every 5 mrad of joints 2 and 3
_MAX_OPENING_RAD = 1.5  # the pre-shape opens joint 2 by at most this
_OPENING_BISECTIONS = 17


def fingertip_depth(q2: NDArray, q3: NDArray) -> NDArray:
    """How far the distal link reaches along the palm normal (mm): its deeper tip corner, or
    the bottom of its pad sphere."""
    a = np.asarray(q2, float) + DISTAL_BEND_RAD + np.asarray(q3, float)
    _, pad_h = fingertip_in_plane(q2, q3)
    return pad_h + np.maximum(PAD_RADIUS_MM, -2 * DISTAL_PAD_MM * np.cos(a))


@dataclass(frozen=True)
class ContactPosture:
    """Where each finger touches: joints (rad) and the palm height above the contact plane (mm).

    ``q2``, ``q3`` have shape (..., 3) in planar finger order; ``height_mm`` (...,) is the distance
    along the palm normal from the palm base to the plane in which all three pads touch.
    """

    q2: NDArray[np.float64]
    q3: NDArray[np.float64]
    height_mm: NDArray[np.float64]
    plane_z_mm: NDArray[np.float64] | float = np.nan


MIN_PAD_ANGLE, MAX_PAD_ANGLE = hg.PAD_ANGLE_RANGE_RAD  # the pad corner is what touches
_PAD_LINK_MM = float(np.hypot(DISTAL_MM, DISTAL_PAD_MM))
_PAD_LINK_ANGLE = float(np.arctan2(DISTAL_PAD_MM, DISTAL_MM))


def _pad_ik(reach: NDArray, height: NDArray) -> tuple[NDArray, NDArray]:
    """Joints putting the pad's contact at (reach, height), tip first (the pad corner
    ``PAD_RADIUS_MM`` further out, ``pad_contact_in_plane``); NaN where impossible."""
    x, y = reach + PAD_RADIUS_MM - KNUCKLE_RADIUS_MM, height - KNUCKLE_HEIGHT_MM
    cos_bend = (x * x + y * y - PROXIMAL_MM**2 - _PAD_LINK_MM**2) / (2 * PROXIMAL_MM * _PAD_LINK_MM)
    bend = np.arccos(np.clip(cos_bend, -1.0, 1.0))
    best_q2 = np.full(np.broadcast(x, y).shape, np.nan)
    best_q3 = best_q2.copy()
    for sign in (-1.0, 1.0):  # the elbow-out solution wins where both are valid
        q2 = np.arctan2(y, x) - np.arctan2(_PAD_LINK_MM * np.sin(sign * bend),
                                           PROXIMAL_MM + _PAD_LINK_MM * np.cos(sign * bend))
        link = q2 + sign * bend - _PAD_LINK_ANGLE
        q3 = link - q2 - DISTAL_BEND_RAD
        ok = ((np.abs(cos_bend) <= 1.0) & (q2 >= 0.0) & (q2 <= JOINT2_MAX) & (q3 >= 0.0)
              & (q3 <= JOINT3_MAX) & (link >= MIN_PAD_ANGLE) & (link <= MAX_PAD_ANGLE))
        best_q2 = np.where(ok, q2, best_q2)
        best_q3 = np.where(ok, q3, best_q3)
    return best_q2, best_q3


def contact_postures(
    reach_mm: NDArray, contact_z_mm: float | NDArray, clearance_mm: float, palm_floor_mm: float,
    gap_mm: float,
) -> tuple[ContactPosture, NDArray[np.bool_]]:
    """All three pads in one plane, for many grips: postures (n, 3) and which exist (n,).

    Args:
        reach_mm: (n, 3) reach of each finger from its line origin along -F_i.
        contact_z_mm: height of the contact plane above the table; a sequence of heights is
            tried lowest first, each grip taking the lowest it can reach.
        clearance_mm: lowest any finger point may come above the table, while closing from
            the pre-shape ``gap_mm`` further out (``opening_posture``) onto the contact.
        palm_floor_mm: lowest the palm's face may come above the table (above the object).

    Among the palm heights (``_HEIGHT_STEP_MM`` apart) whose inverse kinematics puts all three
    pad corners on the plane (distal link past vertical, so the corner touches) and whose
    closing clears the table, the one closest to the Barrett's natural coupling q3 = q2 / 3 is
    chosen. Rows without any such height are NaN and False in the mask.
    """
    reach = np.asarray(reach_mm, float)
    if reach.ndim not in (1, 2) or reach.shape[-1] != 3:
        raise ValueError(f"reaches must have shape (3,) or (n, 3), got {reach.shape}")
    reach = reach.reshape(-1, 3)
    planes = np.sort(np.atleast_1d(np.asarray(contact_z_mm, float)))
    heights = np.arange(_HEIGHT_RANGE[0], _HEIGHT_RANGE[1], _HEIGHT_STEP_MM)
    heights = heights[heights + planes.max() - PALM_DEPTH_MM >= palm_floor_mm]
    q2, q3 = _pad_ik(reach[:, :, None], heights[None, None, :])  # (n, 3, H): plane-independent
    solved = ~np.isnan(q2).any(axis=1)  # (n, H)
    depth = np.where(np.isnan(q2), np.inf, closing_sweep_depth(q2, q3, gap_mm)).max(axis=1)
    cost = np.abs(q3 - COUPLING * q2).sum(axis=1)
    n = len(reach)
    best = np.zeros(n, int)
    plane = np.full(n, np.nan)
    found = np.zeros(n, bool)
    for z in planes:
        valid = (solved & (heights + z - depth >= clearance_mm)
                 & (heights + z - PALM_DEPTH_MM >= palm_floor_mm) & ~found[:, None])
        hit = valid.any(axis=1)
        best[hit] = np.argmin(np.where(valid, cost, np.inf), axis=1)[hit]
        plane[hit] = z
        found |= hit
    pick = best[:, None, None].repeat(3, axis=1)
    chosen2 = np.where(found[:, None], np.take_along_axis(q2, pick, 2)[..., 0], np.nan)
    chosen3 = np.where(found[:, None], np.take_along_axis(q3, pick, 2)[..., 0], np.nan)
    height = np.where(found, heights[best] if heights.size else np.nan, np.nan)
    return ContactPosture(chosen2, chosen3, height, plane), found


def opening_posture(q2: NDArray, q3: NDArray, gap_mm: float) -> tuple[NDArray, NDArray]:
    """The pre-shape ``gap_mm`` further out, on the coupled path that closes onto (q2, q3).

    The path opens joint 2 by ``s`` and joint 3 by ``s / 3`` (neither below 0); ``s`` is found by
    bisection to 0.01 mrad, the first opening whose reach is ``gap_mm`` beyond the contact's.
    """
    q2, q3 = np.asarray(q2, float), np.asarray(q3, float)
    target = pad_contact_in_plane(q2, q3)[0] + gap_mm

    def along(s: NDArray) -> tuple[NDArray, NDArray]:
        return np.maximum(q2 - s, 0.0), np.maximum(q3 - COUPLING * s, 0.0)

    low, high = np.zeros_like(q2), np.minimum(q2, _MAX_OPENING_RAD)
    for _ in range(_OPENING_BISECTIONS):
        mid = (low + high) / 2
        short = pad_contact_in_plane(*along(mid))[0] < target
        low, high = np.where(short, mid, low), np.where(short, high, mid)
    return along(high)


@lru_cache(maxsize=8)
def _sweep_table(gap_mm: float) -> tuple[NDArray, NDArray, NDArray]:
    """Deepest point (mm) of the closing from ``opening_posture`` onto (q2, q3), on a grid."""
    q2 = np.linspace(0.0, JOINT2_MAX, _TABLE_STEPS[0])
    q3 = np.linspace(0.0, JOINT3_MAX, _TABLE_STEPS[1])
    g2, g3 = np.meshgrid(q2, q3, indexing="ij")
    open2, open3 = opening_posture(g2, g3, gap_mm)
    return q2, q3, sweep_depth(open2, open3, g2, g3)


def closing_sweep_depth(q2: NDArray, q3: NDArray, gap_mm: float) -> NDArray:
    """``sweep_depth`` from the pre-shape ``gap_mm`` out onto (q2, q3), interpolated from a
    cached grid (0.1 mm of the direct computation: the depth is smooth in the joints)."""
    grid2, grid3, table = _sweep_table(float(gap_mm))
    q2 = np.clip(np.nan_to_num(np.asarray(q2, float)), 0.0, JOINT2_MAX)
    q3 = np.clip(np.nan_to_num(np.asarray(q3, float)), 0.0, JOINT3_MAX)
    f2 = q2 / JOINT2_MAX * (len(grid2) - 1)
    f3 = q3 / JOINT3_MAX * (len(grid3) - 1)
    i2 = np.minimum(f2.astype(int), len(grid2) - 2)
    i3 = np.minimum(f3.astype(int), len(grid3) - 2)
    t2, t3 = f2 - i2, f3 - i3
    return ((1 - t2) * (1 - t3) * table[i2, i3] + t2 * (1 - t3) * table[i2 + 1, i3]
            + (1 - t2) * t3 * table[i2, i3 + 1] + t2 * t3 * table[i2 + 1, i3 + 1])


def sweep_depth(q2_from: NDArray, q3_from: NDArray, q2_to: NDArray, q3_to: NDArray) -> NDArray:
    """Deepest reach along the palm normal of each finger on the coupled path between postures."""
    t = np.linspace(0.0, 1.0, 9)
    q2 = q2_from[..., None] + (q2_to - q2_from)[..., None] * t
    q3 = q3_from[..., None] + (q3_to - q3_from)[..., None] * t
    return fingertip_depth(q2, q3).max(axis=-1)


CONTACT_COLUMNS = ("p1_x", "p1_y", "p2_x", "p2_y", "p3_x", "p3_y")


def finger_reaches(grips: Mapping) -> NDArray[np.float64]:
    """(n, 3) reach of each finger from its line origin to its contact, from the grip columns.

    ``grips`` is a DataFrame or a mapping of column arrays (hand_x, hand_y, hand_yaw, spread,
    p1_x ... p3_y).
    """
    yaw = np.asarray(grips["hand_yaw"], float)
    spread = np.asarray(grips["spread"], float)
    palm = np.stack([np.asarray(grips["hand_x"], float), np.asarray(grips["hand_y"], float)], -1)
    forces = barrett.finger_forces(yaw, spread)
    origins = np.concatenate([barrett.spread_axes(palm, yaw), palm[:, None, :]], axis=1)
    contacts = np.stack([np.asarray(grips[c], float) for c in CONTACT_COLUMNS], -1)
    return np.einsum("nij,nij->ni", origins - contacts.reshape(-1, 3, 2), forces)


def executable(reaches: NDArray, thickness_mm: float, rise_mm: float, clearance_mm: float,
               palm_clearance_mm: float, gap_mm: float) -> NDArray[np.bool_]:
    """(n,) whether the hand can put all three pads in one plane (``planar_contacts``)."""
    return planar_contacts(reaches, thickness_mm, rise_mm, clearance_mm, palm_clearance_mm,
                           gap_mm)[1]


def planar_contacts(
    reaches: NDArray, thickness_mm: float, rise_mm: float, clearance_mm: float,
    palm_clearance_mm: float, gap_mm: float, planes: int = 5,
) -> tuple[ContactPosture, NDArray[np.bool_]]:
    """Postures with all pads in one plane, as close above mid-thickness as the hand allows.

    The plane is tried at ``planes`` heights from the object's mid-thickness up to ``rise_mm``
    above it, lowest first; each grip takes the lowest plane it can reach. A curled fingertip's
    back corner sits up to twice the pad inset below its pad, so the lowest planes are often
    out of reach without sweeping a fingertip through the table.
    """
    planes_z = thickness_mm / 2 + np.linspace(0.0, rise_mm, planes if rise_mm > 0 else 1)
    return contact_postures(reaches, planes_z, clearance_mm, thickness_mm + palm_clearance_mm,
                            gap_mm)
