"""Barrett BH8-280 planar kinematics and the configuration search (paper section III-B).

Hand frame (DESIGN): ``hand_yaw`` psi is the direction of the thumb force F3 = (cos psi, sin psi);
hand y = F3, hand x = F3 turned 90 degrees clockwise = (sin psi, -cos psi). Finger 1's spread axis
is at S1 = O + 25 x, finger 2's at S2 = O - 25 x, F1 = -sin(theta) x - cos(theta) y and
F2 = +sin(theta) x - cos(theta) y. The thumb's force line passes through the palm centre O with its
contact before O: P3 = O - e3 F3. Finger i's contact lies on the line through its spread axis
along F_i, and e_i = |P_i - O|. Lines 1 and 2 meet on the thumb line at C_C = O - 25 cot(theta) y.

Search: for each grasp and each choice of thumb contact, thumb directions psi are tried on a grid
of ``thumb_search_steps`` values within ``search_half_width(params)`` of the thumb's normal. For a
given psi the thumb line is fixed; C_C = P3 + c y lies on it, and the lines from C_C to P1 and to
P2 must be mirror images about the thumb line, so C_C is where the line through P1 and P2's mirror
image crosses the thumb line. Then theta follows from the direction C_C -> P1 and
O = C_C + 25 cot(theta) y. When P1 and P2 are already mirror images (any C_C works), C_C is taken
as the foot of the grasp focus C_G on the thumb line. One more psi per row is solved (Newton) so
that C_C lies as far along the thumb line as C_G: near-mirrored contacts, whose C_C swings through
every value within a sliver of psi, then reach the same grip as exactly mirrored ones (the
planner stays continuous under sub-micron noise). The psi with the best force-line value C1 =
(4k/3) sum(delta_i^2) / arctan(mu)^2 among the reachable ones is kept, and the search is then
refined over one grid step to either side of it (``REFINE_STEPS``).

Two-finger grasps: theta = 0, fingers on the lines 25 mm beside the thumb line, re-intersected with
their shared region for every psi. The palm centre's position along the thumb line is then free;
it is placed where e3 equals the finger extension at the fingers' mean depth d ahead of the thumb,
e3 = (25^2 + d^2) / (2 d), moved as little as needed to keep every extension >= min_extension_mm.

Reach is physical: finger i's contact lies on its force line at the reach r_i = (S_i - P_i) . F_i
from its line origin S_i (its spread axis; O for the thumb, so r3 = e3), and r_i must lie within
the fingertip reaches of the URDF finger's coupled closing (``FINGER_REACH_MM``,
``THUMB_REACH_MM``: joint 3 = joint 2 / 3 over ``CLOSING_JOINT2_RAD``, where the pad, a sphere
on the tip's pad corner, makes the contact). The check runs inside the thumb search, so a grasp
whose C1-best direction is out of reach can still give a configuration at another direction;
so does an optional further test of the reaches (``executable``, e.g. the executor's).
Two-finger grasps move the palm along the thumb line, as little as needed, into the interval
where all three reaches are within range.
e_i = |P_i - O| stays what the features (C3, C6) use.

Rejected: theta outside [0, max_spread_rad]; any e_i outside [min_extension_mm, max_extension_mm];
any reach r_i outside its finger's range; e3 <= 0; C_C behind the thumb; a force not pointing into
the object (delta_i >= pi/2); a finger or the thumb whose approach enters the object. The approach
is the finger's footprint swept back along its force line, from 1 mm to 60 mm behind the contact:
its centre line, and its two edges ``finger_width_mm / 2`` to either side from
``edge_start_mm(params, config)`` behind the contact. Closer than that, a flat fingertip on the
contacted face itself, met at up to the search's largest deviation, would reach it with its edge:
that is the contact's business (the point-contact model), not an obstacle on the way in.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from grip_env.config import DEFAULT_SYNTHESIS, SynthesisConfig
from grip_env.hand_geometry import (
    DISTAL_BEND_RAD,
    DISTAL_LINK_MM,
    DISTAL_PAD_MM,
    JOINT2_RANGE_RAD,
    JOINT3_RANGE_RAD,
    JOINT_COUPLING,
    KNUCKLE_RADIAL_MM,
    PAD_ANGLE_RANGE_RAD,
    PROXIMAL_LINK_MM,
    SPREAD_AXIS_OFFSET_MM,
    THUMB_KNUCKLE_MM,
    pad_contact_in_plane,
)
from grip_env.params import DEFAULT_PARAMS, GraspParams
from grip_env.planning.features import force_line_from_deviations
from grip_env.planning.grasps import ContactRegions

if TYPE_CHECKING:
    from grip_env.objects import PlanarObject
    from grip_env.planning.grasps import Grasps


def fingertip_reach(joint2: NDArray, knuckle_mm: float = KNUCKLE_RADIAL_MM) -> NDArray:
    """Reach (mm) of the fingertip pad's contact from the finger's line origin, coupled closing
    (joint 3 = joint 2 / 3; :func:`grip_env.hand_geometry.pad_contact_in_plane`)."""
    q2 = np.asarray(joint2, dtype=float)
    return pad_contact_in_plane(q2, JOINT_COUPLING * q2, knuckle_mm)[0]


#: Joint 2 over which the coupled closing touches with its pad: PAD_ANGLE_RANGE_RAD at
#: a = q2 + bend + q2 / 3, within joint 2's and joint 3's ranges. The reach falls monotonically.
_PAD_JOINT2 = [(a - DISTAL_BEND_RAD) / (1 + JOINT_COUPLING) for a in PAD_ANGLE_RANGE_RAD]
CLOSING_JOINT2_RAD = (
    float(max(JOINT2_RANGE_RAD[0], _PAD_JOINT2[0])),
    float(min(JOINT2_RANGE_RAD[1], JOINT3_RANGE_RAD[1] / JOINT_COUPLING, _PAD_JOINT2[1])),
)
#: Shortest and longest fingertip reach of fingers 1 and 2 from their spread axes (mm).
FINGER_REACH_MM = (float(fingertip_reach(CLOSING_JOINT2_RAD[1])),
                   float(fingertip_reach(CLOSING_JOINT2_RAD[0])))
#: Shortest and longest fingertip reach of the thumb from the palm centre (mm).
THUMB_REACH_MM = (float(fingertip_reach(CLOSING_JOINT2_RAD[1], THUMB_KNUCKLE_MM)),
                  float(fingertip_reach(CLOSING_JOINT2_RAD[0], THUMB_KNUCKLE_MM)))
REACH_RANGES_MM = (FINGER_REACH_MM, FINGER_REACH_MM, THUMB_REACH_MM)  #: in finger order 1, 2, 3
#: Slack on the reach range for rounding (mm): a palm placed exactly at a bound stays inside.
REACH_TOLERANCE_MM = 1e-9
_CLOSING_GRID = np.linspace(*CLOSING_JOINT2_RAD, 2001)


def closing_joint2(reach_mm: NDArray, knuckle_mm: float = KNUCKLE_RADIAL_MM) -> NDArray:
    """Joint 2 (rad) of the coupled closing whose pad's contact reaches ``reach_mm`` (inverse of
    :func:`fingertip_reach`, to well below a micrometre).

    Raises:
        ValueError: a reach outside [shortest, longest] of the finger (it is never clipped).
    """
    reach = np.asarray(reach_mm, dtype=float)
    shortest = float(fingertip_reach(CLOSING_JOINT2_RAD[1], knuckle_mm))
    longest = float(fingertip_reach(CLOSING_JOINT2_RAD[0], knuckle_mm))
    bad = ~((reach >= shortest - REACH_TOLERANCE_MM) & (reach <= longest + REACH_TOLERANCE_MM))
    if bad.any():
        raise ValueError(f"reach {float(reach[bad].flat[0])!r} mm outside the finger's range "
                         f"[{shortest:.3f}, {longest:.3f}] mm")
    grid = fingertip_reach(_CLOSING_GRID, knuckle_mm)
    q2 = np.interp(-reach, -grid, _CLOSING_GRID)
    for _ in range(2):  # Newton steps on the smooth, monotonic reach curve
        a = q2 + DISTAL_BEND_RAD + JOINT_COUPLING * q2
        slope = -PROXIMAL_LINK_MM * np.sin(q2) - (1.0 + JOINT_COUPLING) * (
            DISTAL_LINK_MM * np.sin(a) + DISTAL_PAD_MM * np.cos(a))
        q2 = np.clip(q2 - (fingertip_reach(q2, knuckle_mm) - reach) / slope, *CLOSING_JOINT2_RAD)
    return q2

#: The approach of a finger: its force line from APPROACH_START_MM to APPROACH_LENGTH_MM behind
#: its contact, sampled at APPROACH_SAMPLES points, must stay outside the object.
APPROACH_START_MM = 1.0
APPROACH_LENGTH_MM = 60.0
APPROACH_SAMPLES = 12
#: The edges are checked this far inside the finger's width (mm): an edge running exactly along a
#: side of the object grazes it, and rounding must not decide whether it enters.
APPROACH_GRAZE_MM = 1e-6
Array = NDArray[np.float64]
#: An extra test of the hand's reach: (n, 3) finger reaches -> (n,) whether the hand executes them.
ReachTest = Callable[[Array], NDArray[np.bool_]]


@dataclass(frozen=True)
class Configurations(ContactRegions):
    """C hand configurations; finger order 1, 2 (spreading), 3 (thumb).

    The :class:`~grip_env.planning.grasps.ContactRegions` arrays are per finger: ``contacts``
    P1, P2, P3 (mm), their ideal force directions ``normals`` N1, N2, N3, and the ``region``,
    ``region_a``, ``region_b`` and ``rho`` of each finger's region.

    Attributes:
        grasp: (C,) index of the generating grasp.
        thumb: (C,) which of the grasp's contacts (0, 1, 2) the thumb takes.
        two_finger: (C,) whether the configuration is a two-finger one.
        contact_index: (C, 3) which grasp contact fingers 1, 2 and the thumb sit on.
        grasp_focus: (C, 2) the grasp's force focus C_G (NaN for two-finger).
        forces: (C, 3, 2) real unit force directions F1, F2, F3.
        focus: (C, 2) real focus C_C (NaN for two-finger).
        extensions: (C, 3) finger extensions e_i (mm).
        spread: (C,) spread angle theta (rad).
        palm: (C, 2) palm centre O (mm).
        yaw: (C,) hand yaw psi, the direction of F3 (rad, in (-pi, pi]).
        force_line: (C,) the force-line value C1 the search minimised.
    """

    grasp: NDArray[np.int_]
    thumb: NDArray[np.int_]
    two_finger: NDArray[np.bool_]
    contact_index: NDArray[np.int_]
    grasp_focus: Array
    forces: Array
    focus: Array
    extensions: Array
    spread: Array
    palm: Array
    yaw: Array
    force_line: Array


def hand_axes(yaw: Array) -> tuple[Array, Array]:
    """Hand x and y axes (..., 2) for hand yaw ``psi``."""
    yaw = np.asarray(yaw, dtype=float)
    return np.stack([np.sin(yaw), -np.cos(yaw)], axis=-1), np.stack([np.cos(yaw), np.sin(yaw)], -1)


def finger_forces(yaw: Array, spread: Array) -> Array:
    """Real force directions (..., 3, 2) F1, F2, F3 of the hand at ``yaw`` and ``spread``."""
    x, y = hand_axes(yaw)
    s, c = np.sin(spread)[..., None], np.cos(spread)[..., None]
    return np.stack([-s * x - c * y, s * x - c * y, y], axis=-2)


def spread_axes(palm: Array, yaw: Array) -> Array:
    """Spread axes (..., 2, 2) of fingers 1 and 2 for palm centre ``palm`` and ``yaw``."""
    x, _ = hand_axes(yaw)
    offset = SPREAD_AXIS_OFFSET_MM * x
    return np.stack([palm + offset, palm - offset], axis=-2)


def search_half_width(params: GraspParams) -> float:
    """Half-width of the thumb-direction search around the thumb's normal: 2 arctan(mu) (rad)."""
    return min(2.0 * params.friction_angle, np.pi / 2 - 0.05)


def edge_start_mm(params: GraspParams, config: SynthesisConfig) -> float:
    """How far behind its contact a finger's approach edges are checked (mm).

    A flat fingertip ``finger_width_mm`` wide meeting a straight face at deviation delta has its
    edges width / 2 * tan(delta) behind the contact; this is that at the search's largest delta
    (about 12 mm for 25 mm and mu = 0.4), and never less than ``APPROACH_START_MM``.
    """
    half = 0.5 * config.finger_width_mm
    return max(APPROACH_START_MM, half * float(np.tan(search_half_width(params))))


def force_line_value(forces: Array, normals: Array, friction_angle: float) -> Array:
    """C1 = (4k/3) sum(delta_i^2) / arctan(mu)^2 for (..., 3, 2) forces and normals."""
    return _force_line_from_cos(np.moveaxis(np.sum(forces * normals, axis=-1), -1, 0),
                                friction_angle)


def configurations(
    grasps: Grasps,
    obj: PlanarObject,
    params: GraspParams = DEFAULT_PARAMS,
    config: SynthesisConfig = DEFAULT_SYNTHESIS,
    executable: ReachTest | None = None,
) -> Configurations:
    """The best reachable Barrett configuration for each grasp and thumb choice.

    Three-finger grasps give up to three configurations (one per thumb contact), two-finger
    grasps at most one. ``executable``, when given, is a further test of the finger reaches
    (for example the executor's, with the contact heights it plans): it runs inside the search,
    with the approach check, so a grasp keeps its best direction that passes it.
    """
    if config.min_extension_mm >= config.max_extension_mm:
        raise ValueError(
            f"min_extension_mm ({config.min_extension_mm}) must be below max_extension_mm "
            f"({config.max_extension_mm})")
    offsets = np.linspace(-1.0, 1.0, config.thumb_search_steps) * search_half_width(params)
    edge = edge_start_mm(params, config)

    def check(contacts: Array, forces: Array, palm: Array) -> NDArray[np.bool_]:
        ok = approach_clear(obj, contacts, forces, config.finger_width_mm, edge)
        if executable is not None and ok.any():
            ok[ok] = executable(reaches_of(contacts[ok], forces[ok], palm[ok]))
        return ok

    three = np.nonzero(~grasps.two_finger)[0]
    two = np.nonzero(grasps.two_finger)[0]
    coarse = _three_finger(grasps, np.repeat(three, 3), np.tile(np.arange(3), len(three)),
                           params, config, offsets, check)
    return Configurations.concatenate([
        _three_finger(grasps, coarse.grasp, coarse.thumb, params, config,
                      _refined_offsets(grasps, coarse, offsets, params), check),
        _two_finger(grasps, two, params, config, offsets, check),
    ])


#: The thumb search is refined around each grid optimum over one grid step to either side with
#: this many directions per side: the best feasible direction often sits on a limit (spread,
#: extension, reach, approach) that moves with the object, and a grid-only optimum jumps by a
#: whole step's C1 when the limit crosses a grid direction.
REFINE_STEPS = 10


def _refined_offsets(grasps: Grasps, coarse: Configurations, offsets: Array,
                     params: GraspParams) -> Array:
    """(C, 2 REFINE_STEPS + 1) thumb offsets from the normal around each configuration's yaw."""
    step = float(offsets[1] - offsets[0]) if len(offsets) > 1 else 0.0
    normal = grasps.normals[coarse.grasp, coarse.thumb]
    centre = _wrapped(coarse.yaw - np.arctan2(normal[:, 1], normal[:, 0]))
    around = np.linspace(-step, step, 2 * REFINE_STEPS + 1)
    half_width = search_half_width(params)
    return np.clip(centre[:, None] + around[None, :], -half_width, half_width)


def reaches_of(contacts: Array, forces: Array, palm: Array) -> Array:
    """(..., 3) reach r_i = (S_i - P_i) . F_i of each finger from its line origin (S_1, S_2 the
    spread axes, O for the thumb), for (..., 3, 2) contacts and forces and (..., 2) palm centres."""
    thumb = forces[..., 2, :]
    x = np.stack([thumb[..., 1], -thumb[..., 0]], axis=-1)  # hand x: F3 turned 90 deg clockwise
    offset = SPREAD_AXIS_OFFSET_MM * x
    origins = np.stack([palm + offset, palm - offset, palm], axis=-2)
    return np.einsum("...ij,...ij->...i", origins - contacts, forces)


# ----------------------------------------------------------------------------- three fingers
def _three_finger(grasps, grasp, thumb, params, config, offsets, check) -> Configurations:
    # one row per (grasp, thumb choice), one column per thumb direction; hand-frame components.
    # Contacts a, b are the two non-thumb contacts; finger 1 is the one on the hand's +x side.
    # ``offsets`` from the thumb normal: (S,) for every row, or (rows, S).
    others = np.stack([(thumb + 1) % 3, (thumb + 2) % 3], axis=1)
    p3, n3 = grasps.contacts[grasp, thumb], grasps.normals[grasp, thumb]
    normal_yaw = np.arctan2(n3[:, 1], n3[:, 0])
    # the grid of thumb directions, and one more column: the direction whose real focus lies as
    # far along the thumb line as the grasp's (see _focus_depth_yaw)
    focus_depth = np.sum((grasps.focus[grasp] - p3) * n3, axis=1)
    extra, solved = _focus_depth_yaw(grasps.contacts[grasp, others[:, 0]] - p3,
                                     grasps.contacts[grasp, others[:, 1]] - p3, normal_yaw,
                                     focus_depth)
    solved &= np.abs(extra - normal_yaw) <= search_half_width(params)
    extra = np.where(solved, extra, normal_yaw)
    grid = normal_yaw[:, None] + np.broadcast_to(offsets, (len(grasp), np.shape(offsets)[-1]))
    yaw = np.concatenate([grid, extra[:, None]], axis=1)
    thumb_deviation = yaw - normal_yaw[:, None]
    frame = _HandFrame(yaw)
    ax, ay = frame.coordinates(grasps.contacts[grasp, others[:, 0]] - p3)
    bx, by = frame.coordinates(grasps.contacts[grasp, others[:, 1]] - p3)
    nax, nay = frame.coordinates(grasps.normals[grasp, others[:, 0]])
    nbx, nby = frame.coordinates(grasps.normals[grasp, others[:, 1]])
    a_is_one = ax > 0
    x1, y1, n1x, n1y = (np.where(a_is_one, u, v) for u, v in
                        ((ax, bx), (ay, by), (nax, nbx), (nay, nby)))
    x2, y2, n2x, n2y = (np.where(a_is_one, v, u) for u, v in
                        ((ax, bx), (ay, by), (nax, nbx), (nay, nby)))
    # C_C = P3 + c y lies on the line through P1 and P2's mirror image (-x2, y2)
    _, focus_y = frame.coordinates(grasps.focus[grasp] - p3)
    dx = x1 + x2
    mirrored = np.hypot(dx, y1 - y2) <= 1e-9 * (np.abs(x1) + np.abs(x2) + 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(mirrored, focus_y, (x1 * y2 + x2 * y1) / dx)
        c[:, -1] = focus_depth  # the extra column was solved for this focus
        reach = np.hypot(x1, y1 - c)
        sin_t, cos_t = x1 / reach, (y1 - c) / reach
        palm_y = c + SPREAD_AXIS_OFFSET_MM * cos_t / sin_t
    e1, e2 = np.hypot(x1, y1 - palm_y), np.hypot(x2, y2 - palm_y)
    # reach r_i = (S_i - P_i) . F_i with S_1,2 = (+-25, palm_y), F_1,2 = (-+sin, -cos); r3 = e3
    offset = SPREAD_AXIS_OFFSET_MM
    reaches = ((x1 - offset) * sin_t + (y1 - palm_y) * cos_t,
               -(x2 + offset) * sin_t + (y2 - palm_y) * cos_t, palm_y)
    cos_delta = (-sin_t * n1x - cos_t * n1y, sin_t * n2x - cos_t * n2y,
                 np.cos(thumb_deviation))
    feasible = (x1 > 0) & (x2 < 0) & (c > 0) & (sin_t > 0)
    feasible &= cos_t >= np.cos(config.max_spread_rad)
    feasible &= _reachable((e1, e2, palm_y), reaches, cos_delta, config)
    feasible[:, -1] &= solved
    cost = _force_line_from_cos(cos_delta, params.friction_angle)

    def finger_of(rows, cols):
        one = a_is_one[rows, cols]
        return np.stack([np.where(one, others[rows, 0], others[rows, 1]),
                         np.where(one, others[rows, 1], others[rows, 0]), thumb[rows]], axis=1)

    def assemble(rows, cols):
        palm = p3[rows] + palm_y[rows, cols, None] * frame.y[rows, cols]
        contacts = grasps.contacts[grasp[rows, None], finger_of(rows, cols)]
        spread = np.arctan2(sin_t[rows, cols], cos_t[rows, cols])
        return contacts, finger_forces(yaw[rows, cols], spread), palm

    rows, cols, contacts, forces, palm = _best_clear(cost, feasible, assemble, check)
    pick = (rows, cols)
    return _configurations(
        grasps, grasp[rows], finger_of(rows, cols), contacts=contacts, forces=forces,
        focus=p3[rows] + c[pick][:, None] * frame.y[pick],
        extensions=np.stack([e1[pick], e2[pick], palm_y[pick]], axis=1),
        spread=np.arctan2(sin_t[pick], cos_t[pick]), palm=palm, yaw=_wrapped(yaw[pick]),
        force_line=cost[pick])


def _focus_depth_yaw(a: Array, b: Array, yaw: Array, depth: Array,
                     steps: int = 8) -> tuple[Array, NDArray[np.bool_]]:
    """Thumb direction near ``yaw`` at which the real focus C_C = P3 + depth y serves both fingers.

    ``a``, ``b`` (K, 2) are the two finger contacts relative to the thumb contact. At yaw psi they
    have hand coordinates (x_a, y_a), (x_b, y_b); C_C = (0, depth) sends mirror-image finger lines
    through both when h = x_a y_b + x_b y_a - depth (x_a + x_b) = 0 (P_a and P_b's mirror image
    collinear with C_C). Newton steps from ``yaw`` (dx/dpsi = y, dy/dpsi = -x) find the root.

    The grid of directions alone cannot do this: near a symmetric grasp the finger lines fix C_C
    only within a sliver of psi of the width of the asymmetry, so the exact polygon reaches the
    ideal C_C = C_G (any C_C fits exact mirror images) and an object moved by 1e-6 mm does not.
    Returns the directions and whether each is a root (|h| within rounding of the scale).
    """
    psi = np.asarray(yaw, dtype=float).copy()
    for _ in range(steps):
        s, c = np.sin(psi), np.cos(psi)
        xa, ya = a[:, 0] * s - a[:, 1] * c, a[:, 0] * c + a[:, 1] * s
        xb, yb = b[:, 0] * s - b[:, 1] * c, b[:, 0] * c + b[:, 1] * s
        h = xa * yb + xb * ya - depth * (xa + xb)
        slope = 2.0 * (ya * yb - xa * xb) - depth * (ya + yb)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(np.abs(slope) > 1e-12, h / slope, 0.0)
        psi = psi - np.clip(np.nan_to_num(step), -0.5, 0.5)
    s, c = np.sin(psi), np.cos(psi)
    xa, ya = a[:, 0] * s - a[:, 1] * c, a[:, 0] * c + a[:, 1] * s
    xb, yb = b[:, 0] * s - b[:, 1] * c, b[:, 0] * c + b[:, 1] * s
    scale = np.linalg.norm(a, axis=1) + np.linalg.norm(b, axis=1) + np.abs(depth)
    solved = np.abs(xa * yb + xb * ya - depth * (xa + xb)) <= 1e-9 * scale**2
    return psi, solved & np.isfinite(psi)


# ------------------------------------------------------------------------------- two fingers
def _two_finger(grasps, index, params, config, offsets, check) -> Configurations:
    p3, n3 = grasps.contacts[index, 2], grasps.normals[index, 2]
    yaw = np.arctan2(n3[:, 1], n3[:, 0])[:, None] + offsets[None, :]
    frame = _HandFrame(yaw)
    a, b = grasps.region_a[index, 0], grasps.region_b[index, 0]  # the fingers' shared region
    ax, ay = frame.coordinates(a - p3)
    bx, by = frame.coordinates(b - p3)
    length = np.linalg.norm(b - a, axis=1)[:, None]
    fractions, depths = [], []
    feasible = np.ones(yaw.shape, dtype=bool)
    for side in (1.0, -1.0):  # finger 1 on the line x = +25, finger 2 on x = -25
        with np.errstate(divide="ignore", invalid="ignore"):
            u = (side * SPREAD_AXIS_OFFSET_MM - ax) / (bx - ax)
        feasible &= (u * length >= params.lam - 1e-7) & ((1.0 - u) * length >= params.lam - 1e-7)
        fractions.append(u)
        depths.append(ay + u * (by - ay))
    feasible &= (depths[0] > 0) & (depths[1] > 0)
    palm_y = _within_reach(_two_finger_palm(0.5 * (depths[0] + depths[1]),
                                            config.min_extension_mm), depths)
    extensions = np.stack([np.hypot(SPREAD_AXIS_OFFSET_MM, depths[0] - palm_y),
                           np.hypot(SPREAD_AXIS_OFFSET_MM, depths[1] - palm_y), palm_y], -1)
    reaches = (depths[0] - palm_y, depths[1] - palm_y, palm_y)  # F_1,2 = -y, S_1,2 at palm_y
    _, nfy = frame.coordinates(grasps.normals[index, 0])
    cos_delta = (-nfy, -nfy, np.cos(offsets))
    feasible &= _reachable(tuple(np.moveaxis(extensions, -1, 0)), reaches, cos_delta, config)
    cost = _force_line_from_cos(cos_delta, params.friction_angle)

    def assemble(rows, cols):
        ends = a[rows], b[rows]
        fingers = [ends[0] + u[rows, cols, None] * (ends[1] - ends[0]) for u in fractions]
        contacts = np.stack([*fingers, p3[rows]], axis=1)
        palm = p3[rows] + palm_y[rows, cols, None] * frame.y[rows, cols]
        return contacts, finger_forces(yaw[rows, cols], np.zeros(len(rows))), palm

    rows, cols, contacts, forces, palm = _best_clear(cost, feasible, assemble, check)
    pick = (rows, cols)
    return _configurations(
        grasps, index[rows], np.tile(np.arange(3), (len(rows), 1)), contacts=contacts,
        forces=forces, focus=np.full((len(rows), 2), np.nan), extensions=extensions[pick],
        spread=np.zeros(len(rows)), palm=palm, yaw=_wrapped(yaw[pick]), force_line=cost[pick])


def _configurations(
    grasps: Grasps, grasp: NDArray[np.int_], contact_index: NDArray[np.int_], **solved: Array
) -> Configurations:
    """Configurations of ``grasp`` with fingers on ``contact_index``; grasp data in finger order."""
    return Configurations(
        grasp=grasp, thumb=contact_index[:, 2], two_finger=grasps.two_finger[grasp],
        contact_index=contact_index, grasp_focus=grasps.focus[grasp],
        **grasps.regions_at(grasp, contact_index), **solved)


def _two_finger_palm(depth: Array, min_extension: float) -> Array:
    """Palm centre's distance ahead of the thumb contact for fingers ``depth`` ahead of it.

    The thumb's extension e3 = u is made equal to the fingers' sqrt(25^2 + (depth - u)^2), i.e.
    u = (25^2 + depth^2) / (2 depth); when that leaves an extension below ``min_extension``, u is
    moved to the nearest value where all extensions reach it.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        balanced = (SPREAD_AXIS_OFFSET_MM**2 + depth**2) / (2.0 * depth)
    lateral = np.sqrt(max(min_extension**2 - SPREAD_AXIS_OFFSET_MM**2, 0.0))
    behind = depth - lateral  # largest u with the fingers' extension still >= min_extension
    beyond = np.maximum(min_extension, depth + lateral)
    ok = (balanced >= min_extension) & (np.abs(depth - balanced) >= lateral)
    behind_ok = behind >= min_extension
    use_behind = behind_ok & (np.abs(balanced - behind) < np.abs(beyond - balanced))
    return np.where(ok, balanced, np.where(use_behind, behind, beyond))


def _within_reach(palm_y: Array, depths: list[Array]) -> Array:
    """``palm_y`` moved as little as needed so that the thumb's reach palm_y and the fingers'
    reaches depth_i - palm_y are all within range (unchanged when no such palm_y exists)."""
    low = np.maximum(THUMB_REACH_MM[0], np.maximum(*depths) - FINGER_REACH_MM[1])
    high = np.minimum(THUMB_REACH_MM[1], np.minimum(*depths) - FINGER_REACH_MM[0])
    return np.where(low <= high, np.clip(palm_y, low, np.maximum(low, high)), palm_y)


# ---------------------------------------------------------------------------------- helpers
class _HandFrame:
    """Hand axes for a (K, S) grid of yaws, and hand coordinates of (K, 2) world vectors."""

    def __init__(self, yaw: Array) -> None:
        self.cos, self.sin = np.cos(yaw), np.sin(yaw)
        self.y = np.stack([self.cos, self.sin], axis=-1)

    def coordinates(self, vectors: Array) -> tuple[Array, Array]:
        vx, vy = vectors[..., 0], vectors[..., 1]
        if vx.ndim == 1:  # one vector per row, the same for every column
            vx, vy = vx[:, None], vy[:, None]
        return vx * self.sin - vy * self.cos, vx * self.cos + vy * self.sin


def _reachable(extensions, reaches, cos_delta, config: SynthesisConfig) -> NDArray[np.bool_]:
    """Extensions (e1, e2, e3) within the configured range, e3 > 0, reaches (r1, r2, r3) within
    the fingers' physical range, and every force into the object (delta < pi/2)."""
    ok = extensions[2] > 0
    for e in extensions:
        ok &= (e >= config.min_extension_mm) & (e <= config.max_extension_mm)
    for reach, (shortest, longest) in zip(reaches, REACH_RANGES_MM, strict=True):
        ok &= (reach >= shortest - REACH_TOLERANCE_MM) & (reach <= longest + REACH_TOLERANCE_MM)
    for cosine in cos_delta:
        ok &= cosine > 0
    return ok


def _force_line_from_cos(cos_delta, friction_angle: float) -> Array:
    """C1 from the cosines (cos delta_1, cos delta_2, cos delta_3) of the force deviations."""
    deltas = [np.arccos(np.clip(cosine, -1.0, 1.0)) for cosine in cos_delta]
    return force_line_from_deviations(deltas, friction_angle)


def _best_clear(cost, feasible, assemble, check):
    """Per row, the cheapest feasible column that passes ``check(contacts, forces, palm)`` (its
    finger approaches are clear of the object, and any further reach test).

    Checks run lazily: the cheapest column of every open row at once, then the next cheapest for
    the rows whose candidate failed, and so on. Returns the rows that found one, their columns,
    and ``assemble(rows, cols)`` (contacts, forces, palm) for them.
    """
    cost = np.where(feasible, cost, np.inf)
    best = np.full(len(cost), -1)
    open_rows = np.nonzero(np.isfinite(cost).any(axis=1))[0]
    while len(open_rows):
        column = np.argmin(cost[open_rows], axis=1)
        clear = check(*assemble(open_rows, column))
        best[open_rows[clear]] = column[clear]
        cost[open_rows[~clear], column[~clear]] = np.inf
        open_rows = open_rows[~clear]
        open_rows = open_rows[np.isfinite(cost[open_rows]).any(axis=1)]
    rows = np.nonzero(best >= 0)[0]
    return rows, best[rows], *assemble(rows, best[rows])


def approach_clear(
    obj: PlanarObject, contacts: Array, forces: Array, width_mm: float = 0.0,
    edge_start: float = APPROACH_START_MM,
) -> NDArray[np.bool_]:
    """Whether every finger's approach behind its contact stays outside the object.

    The centre line is sampled from ``APPROACH_START_MM`` to ``APPROACH_LENGTH_MM`` behind the
    contact; with ``width_mm`` > 0 the finger's two edges, ``width_mm / 2`` to either side, are
    sampled from ``edge_start`` to ``APPROACH_LENGTH_MM``. ``contacts`` and ``forces`` are
    (..., 3, 2); returns (...,) booleans.
    """
    behind = np.linspace(APPROACH_START_MM, APPROACH_LENGTH_MM, APPROACH_SAMPLES)
    samples = contacts[..., None, :] - behind[:, None] * forces[..., None, :]
    if width_mm > 0:
        half = max(0.5 * width_mm - APPROACH_GRAZE_MM, 0.0)
        side = half * np.stack([-forces[..., 1], forces[..., 0]], axis=-1)
        edge = np.linspace(edge_start, APPROACH_LENGTH_MM, APPROACH_SAMPLES)
        line = contacts[..., None, :] - edge[:, None] * forces[..., None, :]
        samples = np.concatenate([samples, line + side[..., None, :], line - side[..., None, :]],
                                 axis=-2)
    return ~obj.contains(samples).any(axis=(-1, -2))


def _wrapped(angle: Array) -> Array:
    return np.arctan2(np.sin(angle), np.cos(angle))
