"""Grasp synthesis: force-closure contact triplets on grasping regions (paper section III-A, III-C).

A *grasp* is three contacts with ideal force directions N_i (the regions' inward normals).

Three-finger grasps: the three normal lines must meet in one point, the force focus C_G. For each
triplet of regions and each choice of the region that is solved last, contacts P_a, P_b are taken
on a grid along the first two regions, their normal lines are intersected to give C_G, and P_c is
the foot of the perpendicular from C_G onto the third region's line, so that its normal passes
through C_G by construction. A candidate is kept when P_c lies inside its region away from the
ends, C_G lies in front of every contact and inside the object, and the normals positively span
the plane (every gap between consecutive normal directions is below pi). With the lines exactly
concurrent and the focus in front of all contacts this is planar force closure for any mu > 0.
That rule asks for closure without friction, and a shape whose sides run along two axes only
(a cross, a notched rectangle) has no such triplet. ``config.frictional_closure`` asks for
closure with friction mu instead: the largest gap may reach pi + arctan(mu), where the two
normals that bound it form an antipodal pair within their friction cones
(:func:`largest_gap_rad`), e.g. the two sides of a cross's arm and its tip. It is off by default:
the recorded planner (the standard dataset's) has it off, and on it changes the candidates of
about half the standard dataset's objects (BENCHMARKS.md, "Frictional closure").
"In front" means by at least ``config.focus_margin_mm`` along each contact's normal (default one
pixel of the camera): a grasp whose focus sits within a pixel of a contact is on the edge of
that rule, and which side of it the grasp falls on is decided by sub-pixel detail of the contour
(measured: a 0.3 mm change of the bean's rendered regions moved one focus from 0.25 mm behind its
contact to 0.60 mm in front, and the best Q_C by 11 %).

Two-finger (virtual) grasps: the thumb on one region, fingers 1 and 2 together on another region
that is nearly antiparallel to it (angle between N_thumb and -N_fingers at most arctan(mu)) and
long enough for two fingers 50 mm apart, each at least lambda from the region's ends. The fingers
lie on the lines at +-25 mm beside the thumb's normal line, as the hand fixes the triangle base at
50 mm; ``contacts_per_region`` thumb positions are spread over the stretch of the thumb's region
where both fingers fit. Contact index 2 is the thumb; index 0
is the finger on the hand's +x side (hand x = thumb direction turned 90 degrees clockwise).

Grasps are ranked by a cheap centring score (lower is better): distance of the grasp centre
(C_G, or the contact triangle's centroid for two-finger grasps) from the object's centroid over
M_L + m_L, plus, for three-finger grasps, how far the largest gap between normal directions exceeds
2*pi/3, over pi/3. Repeats (same regions, contacts within 1% of their regions' lengths) are
removed among the best 4 * ``config.max_grasps`` candidates, then the best ``config.max_grasps``
are kept.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from itertools import combinations
from typing import Self

import numpy as np
from numpy.typing import NDArray

from grip_env.config import DEFAULT_SYNTHESIS, SynthesisConfig
from grip_env.hand_geometry import SPREAD_AXIS_OFFSET_MM
from grip_env.objects import PlanarObject
from grip_env.params import DEFAULT_PARAMS, GraspParams
from grip_env.perception.regions import Regions

#: Contacts sit at fractions of their region in [END_FRACTION, 1 - END_FRACTION].
END_FRACTION = 0.15
#: Lateral offset of fingers 1 and 2 from the thumb line in a two-finger grasp (mm): at spread 0
#: each finger's force line runs through its spread axis, 25 mm beside the palm centre.
HALF_FINGER_BASE_MM = SPREAD_AXIS_OFFSET_MM
#: Grasps on the same regions whose contacts all lie closer than this fraction of their regions'
#: lengths count as the same grasp.
DEDUP_FRACTION = 0.01
_TOLERANCE_MM = 1e-7  # slack on length limits for rounding noise
#: Normals whose largest gap is within this of pi do not span the plane: an antiparallel pair moved
#: by sub-micron noise (1e-6 mm on a 30 mm side turns a normal by ~3e-8 rad) stays one, so a
#: rectilinear shape keeps the same grasps exact and perturbed.
_GAP_SLACK_RAD = 1e-6
_SHORTLIST = 4  # best-ranked candidates examined per grasp kept (repeats come in up to threes)

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ContactRegions:
    """N rows of three contacts and the grasping regions they lie on: what a grasp and a hand
    configuration (:class:`~grip_env.planning.barrett.Configurations`, its grasp's contacts in
    finger order) both are.

    Attributes:
        contacts: (N, 3, 2) contact points (mm).
        normals: (N, 3, 2) unit inward region normals, the ideal force directions N_i.
        region: (N, 3) index of each contact's region.
        region_a, region_b: (N, 3, 2) endpoints of each contact's region (mm).
        rho: (N, 3) curvature of each contact's region.
    """

    contacts: Array
    normals: Array
    region: NDArray[np.int_]
    region_a: Array
    region_b: Array
    rho: Array

    def __len__(self) -> int:
        return len(self.contacts)

    def take(self, index: NDArray[np.int_]) -> Self:
        """The rows at ``index``, in that order (indices past the end are ignored)."""
        index = np.asarray(index)
        index = index[index < len(self)]
        return type(self)(**{name: getattr(self, name)[index] for name in _fields(self)})

    @classmethod
    def concatenate(cls, parts: list[Self]) -> Self:
        """All rows of ``parts``, in order."""
        return cls(**{name: np.concatenate([getattr(p, name) for p in parts])
                      for name in _fields(cls)})

    def regions_at(self, rows: NDArray[np.int_], columns: NDArray[np.int_]) -> dict[str, Array]:
        """Every array but ``contacts`` for the contacts ``columns`` (K, 3) of ``rows`` (K,), in
        that order: keyword arguments of another :class:`ContactRegions`."""
        return {name: getattr(self, name)[rows[:, None], columns]
                for name in _fields(ContactRegions) if name != "contacts"}


def _fields(rows: type[ContactRegions] | ContactRegions) -> tuple[str, ...]:
    return tuple(field.name for field in fields(rows))


@dataclass(frozen=True)
class Grasps(ContactRegions):
    """G grasps of one object: three contacts on their regions (the :class:`ContactRegions`
    arrays; in a two-finger grasp index 2 is the thumb), and their focus.

    Attributes:
        focus: (G, 2) force focus C_G (NaN for two-finger grasps).
        two_finger: (G,) whether the grasp is a virtual two-finger grasp.
    """

    focus: Array
    two_finger: NDArray[np.bool_]

    @classmethod
    def empty(cls) -> Grasps:
        """No grasps."""
        z = np.zeros((0, 3, 2))
        return cls(z, z, np.zeros((0, 3), dtype=int), z, z, np.zeros((0, 3)), np.zeros((0, 2)),
                   np.zeros(0, dtype=bool))


def _grasps_on(regions: Regions, contacts: Array, region: NDArray[np.int_], focus: Array,
               two_finger: bool) -> Grasps:
    return Grasps(contacts, regions.normal[region], region, regions.a[region], regions.b[region],
                  regions.rho[region], focus, np.full(len(region), two_finger))


def synthesize_grasps(
    regions: Regions,
    obj: PlanarObject,
    params: GraspParams = DEFAULT_PARAMS,
    config: SynthesisConfig = DEFAULT_SYNTHESIS,
) -> Grasps:
    """Force-closure three-finger grasps and virtual two-finger grasps on ``regions``.

    Returns at most ``config.max_grasps`` grasps, best cheap centring score first.
    """
    if not isinstance(regions, Regions):
        raise ValueError(f"regions must be a Regions instance, got {type(regions).__name__}")
    if len(regions) and not np.all(regions.length > 0):
        raise ValueError("regions must have positive lengths")
    t = np.linspace(END_FRACTION, 1.0 - END_FRACTION, config.contacts_per_region)
    if config.contacts_per_region == 1:
        t = np.array([0.5])
    grasps = Grasps.concatenate([
        _three_finger(regions, obj, t, _SHORTLIST * config.max_grasps, config.focus_margin_mm,
                      largest_gap_rad(params, config)),
        _two_finger(regions, obj, config.contacts_per_region, params),
    ])
    if len(grasps) == 0:
        return grasps
    # repeats share their score, so they sit together at the top of the ranking
    order = np.argsort(_score(grasps, obj), kind="stable")[: _SHORTLIST * config.max_grasps]
    return _deduplicated(grasps.take(order)).take(np.arange(config.max_grasps))


# ----------------------------------------------------------------------------- three fingers
def largest_gap_rad(params: GraspParams = DEFAULT_PARAMS,
                    config: SynthesisConfig = DEFAULT_SYNTHESIS) -> float:
    """Largest gap between consecutive normal directions a three-finger grasp may have (rad).

    Below pi (less a rounding slack) the normals positively span the plane: force closure without
    friction. With ``config.frictional_closure``, up to pi + arctan(mu): the two normals that
    bound the largest gap are then within arctan(mu) of antiparallel, and as their lines meet at
    the focus in front of both, the line between the two contacts lies inside both friction
    cones (the triangle's angles at the two contacts sum to gap - pi): an antipodal pair, force
    closure with friction mu, whatever the third contact.
    """
    if config.frictional_closure:
        return np.pi + params.friction_angle
    return np.pi - _GAP_SLACK_RAD


def _three_finger(regions: Regions, obj: PlanarObject, t: Array, limit: int,
                  margin: float, max_gap: float) -> Grasps:
    if len(regions) < 3:
        return Grasps.empty()
    triplets = np.array(list(combinations(range(len(regions)), 3)))
    # force closure (a property of the regions' normals alone; see largest_gap_rad)
    triplets = triplets[_largest_gap(regions.normal[triplets]) < max_gap]
    # every region of a triplet takes a turn at being the one solved last (index 2)
    ordered = np.concatenate([np.roll(triplets, shift, axis=1) for shift in range(3)])
    # the first two normals must cross: parallel ones have no focus
    ordered = ordered[np.abs(_cross(regions.normal[ordered[:, 0]],
                                    regions.normal[ordered[:, 1]])) > 1e-9]
    # one row per (ordered triplet, contact on a, contact on b)
    row, i, j = (g.ravel() for g in np.meshgrid(np.arange(len(ordered)), np.arange(len(t)),
                                                  np.arange(len(t)), indexing="ij"))
    ia, ib = ordered[row, 0], ordered[row, 1]
    pa, pb = regions.point(ia, t[i]), regions.point(ib, t[j])
    na, nb = regions.normal[ia], regions.normal[ib]
    denom = _cross(na, nb)
    sa, sb = _cross(pb - pa, nb) / denom, _cross(pb - pa, na) / denom
    ahead = (sa > margin) & (sb > margin)  # the focus lies in front of both contacts
    row, pa, pb, focus = row[ahead], pa[ahead], pb[ahead], (pa + sa[:, None] * na)[ahead]
    ic = ordered[row, 2]
    tc = np.sum((focus - regions.a[ic]) * regions.direction[ic], axis=1) / regions.length[ic]
    pc = regions.point(ic, tc)
    keep = (tc >= END_FRACTION - 1e-9) & (tc <= 1.0 - END_FRACTION + 1e-9)
    keep &= np.sum((focus - pc) * regions.normal[ic], axis=1) > margin
    keep[keep] = obj.contains(focus[keep])
    keep = np.nonzero(keep)[0]
    # only the best ``limit`` candidates can make the final cut
    region = ordered[row[keep]]
    best = np.argsort(_centring(focus[keep], obj) + _excess_gap(regions.normal[region]),
                      kind="stable")[:limit]
    keep, region = keep[best], region[best]
    contacts = np.stack([pa[keep], pb[keep], pc[keep]], axis=1)
    # canonical order by region index, so the three solving orders de-duplicate against each other
    order = np.argsort(region, axis=1)
    region = np.take_along_axis(region, order, axis=1)
    contacts = np.take_along_axis(contacts, order[..., None], axis=1)
    grasps = _grasps_on(regions, contacts, region, focus[keep], two_finger=False)
    return grasps


# ------------------------------------------------------------------------------- two fingers
def _two_finger(regions: Regions, obj: PlanarObject, count: int, params: GraspParams) -> Grasps:
    if len(regions) < 2:
        return Grasps.empty()
    margin = params.lam
    length = regions.length
    fingers, thumbs = np.nonzero(~np.eye(len(regions), dtype=bool))
    facing = np.sum(regions.normal[thumbs] * -regions.normal[fingers], axis=1)
    long_enough = length[fingers] >= 2 * (HALF_FINGER_BASE_MM + margin) - _TOLERANCE_MM
    pick = (facing >= np.cos(params.friction_angle) - 1e-12) & long_enough
    fingers, thumbs = fingers[pick], thumbs[pick]
    # thumb positions (along its region) whose +-25 mm neighbours project inside the finger region
    a_h, d_h = regions.a[thumbs], regions.direction[thumbs]
    u_a = np.sum((regions.a[fingers] - a_h) * d_h, axis=1)
    u_b = np.sum((regions.b[fingers] - a_h) * d_h, axis=1)
    reach = HALF_FINGER_BASE_MM + margin
    low = np.maximum(END_FRACTION * length[thumbs], np.minimum(u_a, u_b) + reach)
    high = np.minimum((1 - END_FRACTION) * length[thumbs], np.maximum(u_a, u_b) - reach)
    keep = low <= high + _TOLERANCE_MM
    fingers, thumbs, low, high = fingers[keep], thumbs[keep], low[keep], high[keep]
    if len(fingers) == 0:
        return Grasps.empty()
    fraction = np.linspace(0.0, 1.0, count) if count > 1 else np.array([0.5])
    u = low[:, None] + fraction[None, :] * np.maximum(high - low, 0.0)[:, None]  # (K, n)
    thumb_points = regions.a[thumbs][:, None, :] + u[..., None] * regions.direction[thumbs][:, None]
    thumb_normal = np.broadcast_to(regions.normal[thumbs][:, None, :], thumb_points.shape)
    fingers = np.broadcast_to(fingers[:, None], u.shape)
    thumbs = np.broadcast_to(thumbs[:, None], u.shape)
    p1, p2, ok = two_finger_contacts(regions.a[fingers], regions.b[fingers], thumb_points,
                                     thumb_normal, margin)
    flat = np.nonzero(ok)
    contacts = np.stack([p1[flat], p2[flat], thumb_points[flat]], axis=1)
    # the triangle between the thumb and the fingers must lie inside the object
    middles = (contacts[:, :2] + contacts[:, 2:]) / 2.0
    inside = obj.contains(middles).all(axis=1)
    region = np.stack([fingers[flat], fingers[flat], thumbs[flat]], axis=1)[inside]
    return _grasps_on(regions, contacts[inside], region, np.full((len(region), 2), np.nan),
                      two_finger=True)


def two_finger_contacts(
    a: Array, b: Array, thumb_point: Array, thumb_direction: Array, margin: float
) -> tuple[Array, Array, NDArray[np.bool_]]:
    """Contacts of fingers 1 and 2 for a thumb at ``thumb_point`` pushing along ``thumb_direction``.

    Fingers 1 and 2 lie on the lines parallel to the thumb's, 25 mm to its hand +x and -x sides,
    where these lines cross the fingers' region from ``a`` to ``b`` (all arrays (..., 2)).
    Returns P1, P2 (..., 2) and whether both lie on the region at least ``margin`` (mm) from its
    ends and in front of the thumb.
    """
    hand_x = np.stack([thumb_direction[..., 1], -thumb_direction[..., 0]], axis=-1)
    length = np.linalg.norm(b - a, axis=-1)
    d = (b - a) / length[..., None]
    denom = _cross(d, thumb_direction)
    points, ok = [], np.abs(denom) > 1e-9
    for side in (1.0, -1.0):
        base = thumb_point + side * HALF_FINGER_BASE_MM * hand_x
        with np.errstate(divide="ignore", invalid="ignore"):
            u = _cross(base - a, thumb_direction) / denom
        point = a + u[..., None] * d
        ahead = np.sum((point - thumb_point) * thumb_direction, axis=-1)
        ok &= (u >= margin - _TOLERANCE_MM) & (u <= length - margin + _TOLERANCE_MM)
        ok &= ahead > 0
        points.append(point)
    return points[0], points[1], ok


# ---------------------------------------------------------------------------------- helpers
def _score(grasps: Grasps, obj: PlanarObject) -> Array:
    centre = np.where(grasps.two_finger[:, None], grasps.contacts.mean(axis=1), grasps.focus)
    excess_gap = np.where(grasps.two_finger, 0.0, _excess_gap(grasps.normals))
    return _centring(centre, obj) + excess_gap


def _centring(centre: Array, obj: PlanarObject) -> Array:
    return np.linalg.norm(centre - obj.centroid, axis=1) / sum(obj.inertia_semi_axes)


def _excess_gap(normals: Array) -> Array:
    return np.maximum(_largest_gap(normals) - 2 * np.pi / 3, 0.0) / (np.pi / 3)


def _largest_gap(normals: Array) -> Array:
    """Largest angle between consecutive directions of (..., 3, 2) unit vectors."""
    angles = np.sort(np.arctan2(normals[..., 1], normals[..., 0]), axis=-1)
    gaps = np.diff(angles, axis=-1, append=angles[..., :1] + 2 * np.pi)
    return gaps.max(axis=-1)


def _deduplicated(grasps: Grasps) -> Grasps:
    """Drop repeated grasps: same regions and contacts within DEDUP_FRACTION of each other.

    Contacts are compared by their fraction along their region, which does not depend on where
    the object lies or on its scale. Grasps are taken in order (best ranked first), and one is
    dropped when it repeats one already kept, so a repeat goes whatever rounding noise does to its
    fractions (a key rounded to the noise grid splits repeats that straddle a step).
    """
    if len(grasps) == 0:
        return grasps
    span = grasps.region_b - grasps.region_a
    arc = np.sum((grasps.contacts - grasps.region_a) * span, axis=-1) / np.sum(span**2, axis=-1)
    repeats = np.all(grasps.region[:, None] == grasps.region[None], axis=-1)
    repeats &= np.all(np.abs(arc[:, None] - arc[None]) <= DEDUP_FRACTION, axis=-1)
    kept = np.zeros(len(grasps), dtype=bool)
    for i in range(len(grasps)):
        kept[i] = not np.any(repeats[i, :i] & kept[:i])
    return grasps.take(np.nonzero(kept)[0])


def _cross(u: Array, v: Array) -> Array:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
