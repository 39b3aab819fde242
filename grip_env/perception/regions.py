"""Grasping regions: short straight stretches of the contour where a finger can be placed."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import maximum_filter1d, minimum_filter1d

from grip_env.config import PerceptionConfig
from grip_env.params import GraspParams
from grip_env.perception.contour import resample_contour
from grip_env.perception.curvature import contour_derivatives, signed_curvature

if TYPE_CHECKING:
    from grip_env.objects import PlanarObject

MAX_ABS_RHO = 1.0 / 3.0  # DESIGN: regions with |rho| above this are not grasping regions
#: The heading that places the cuts between pieces is smoothed this many times more than the
#: curvature: a cut moves by heading noise / curvature, and twice the smoothing halves the noise
#: of a rendered contour (its sub-pixel wobble).
HEADING_SMOOTHING = 2.0


@dataclass(frozen=True)
class Regions:
    """R grasping regions of one object, in contour (counter-clockwise) order.

    Attributes:
        a, b: (R, 2) straight-segment endpoints (mm); walking from ``a`` to ``b`` follows the
            contour counter-clockwise, so the object lies to the left.
        normal: (R, 2) unit inward normal of each segment.
        rho: (R,) mean signed curvature over the region times ``rho_scale`` (concave positive).
    """

    a: NDArray[np.float64]
    b: NDArray[np.float64]
    normal: NDArray[np.float64]
    rho: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.a)

    @property
    def length(self) -> NDArray[np.float64]:
        """(R,) segment lengths (mm)."""
        return np.linalg.norm(self.b - self.a, axis=1)

    @property
    def direction(self) -> NDArray[np.float64]:
        """(R, 2) unit tangents from ``a`` to ``b``."""
        return (self.b - self.a) / self.length[:, None]

    def point(self, index: NDArray[np.int_], t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Points at fraction ``t`` along regions ``index``."""
        return self.a[index] + t[..., None] * (self.b[index] - self.a[index])

    @classmethod
    def from_polygon_sides(cls, contour: NDArray[np.float64], inset_mm: float = 3.0) -> Regions:
        """Idealised regions: one flat region per side of a CCW polygon, inset from its corners.

        Sides shorter than ``2 * inset_mm + 1`` mm are left out. Useful to study grasps on exact
        geometry, without the curvature estimate of :func:`find_regions`.
        """
        a, b = contour, np.roll(contour, -1, axis=0)
        length = np.linalg.norm(b - a, axis=1)
        direction = (b - a) / length[:, None]
        keep = length > 2 * inset_mm + 1
        normal = np.stack([-direction[:, 1], direction[:, 0]], axis=1)
        return cls(
            (a + inset_mm * direction)[keep], (b - inset_mm * direction)[keep], normal[keep],
            np.zeros(int(keep.sum())),
        )

    @classmethod
    def empty(cls) -> Regions:
        """No regions."""
        z = np.zeros((0, 2))
        return cls(z, z.copy(), z.copy(), np.zeros(0))


def find_regions(
    obj_or_contour: PlanarObject | ArrayLike,
    config: PerceptionConfig | None = None,
    params: GraspParams | None = None,
) -> Regions:
    """Grasping regions of an object, cut from its curvature (paper sections III-IV, VIII-A S3).

    The contour is resampled every ``config.contour_spacing_mm`` and its signed curvature kappa
    (concave positive) estimated at scale ``sigma = config.curvature_sigma_mm``. Then:

    1. Irregular points: where kappa varies by more than ``config.curvature_jump`` within one
       smoothing footprint (+-sigma) — curvature steps and corner spikes. They belong to no region,
       so regions stop about 2-3 sigma before a polygon corner.
    2. Each run of regular points is cut where the tangent has turned by more than
       ``config.max_turn_rad`` since the piece began.
    3. Each piece becomes a straight segment: total-least-squares line through its points,
       endpoints = projections of its first and last points (a -> b counter-clockwise, object on
       the left), inward normal = left normal of a -> b, rho = mean kappa * ``params.rho_scale``.
    4. Segments shorter than ``config.min_region_mm`` and those with ``|rho| > MAX_ABS_RHO`` go.

    Args:
        obj_or_contour: a ``PlanarObject`` or (N, 2) polygon vertices (mm).
        config: perception settings (defaults when None).
        params: grasp parameters, for ``rho_scale`` (defaults when None).
    """
    from grip_env.objects import PlanarObject

    config = config or PerceptionConfig()
    params = params or GraspParams()
    obj = (
        obj_or_contour if isinstance(obj_or_contour, PlanarObject)
        else PlanarObject.from_polygon(obj_or_contour, name="contour")
    )
    points = resample_contour(obj.contour, config.contour_spacing_mm)
    closed = np.vstack([points, points[:1]])
    step = float(np.linalg.norm(np.diff(closed, axis=0), axis=1).sum()) / len(points)
    kappa = signed_curvature(points, config.curvature_sigma_mm, step)
    d1, _ = contour_derivatives(points, HEADING_SMOOTHING * config.curvature_sigma_mm, step)
    heading = np.arctan2(d1[:, 1], d1[:, 0])
    regular = ~_irregular(kappa, round(config.curvature_sigma_mm / step), config.curvature_jump)
    pieces = _pieces(regular, heading, points[:, 1], config.max_turn_rad)
    if len(pieces.starts) == 0:
        return Regions.empty()
    return _segments(points, kappa, pieces, config.min_region_mm, params.rho_scale)


def _irregular(kappa: NDArray[np.float64], half_width: int, jump: float) -> NDArray[np.bool_]:
    """Points whose curvature range within +-half_width samples exceeds ``jump``."""
    size = 2 * max(half_width, 1) + 1
    high = maximum_filter1d(kappa, size, mode="wrap")
    low = minimum_filter1d(kappa, size, mode="wrap")
    return (high - low) > jump


@dataclass(frozen=True)
class _Pieces:
    """Pieces of the contour: sample ``starts`` (inclusive) and ``stops`` (exclusive) for the
    line fit, and the positions of their ends in fractional samples (``first``, ``last``).
    Indices are unwrapped: they may exceed the sample count and are meant modulo it."""

    starts: NDArray[np.int_]
    stops: NDArray[np.int_]
    first: NDArray[np.float64]
    last: NDArray[np.float64]


class _Cutter:
    """Collects pieces; consecutive pieces of a run meet at their cut, where the heading crosses
    the turn (interpolated between samples); each piece's line is fitted to the samples between
    its ends."""

    def __init__(self) -> None:
        self.starts: list[int] = []
        self.stops: list[int] = []
        self.first: list[float] = []
        self.last: list[float] = []

    def cut(self, angle: NDArray[np.float64], run_start: int, run_stop: int, reference: float,
            turn: float, ends: tuple[float, float] | None = None) -> None:
        """Cut ``angle[run_start:run_stop]`` wherever the heading leaves the band of +-``turn``
        around the piece's reference; the next reference is one turn on. ``ends``: fractional
        positions of the run's first and last points (default: its first and last samples)."""
        first, last = ends if ends is not None else (float(run_start), float(run_stop - 1))
        begin, position = run_start, first
        while True:
            offset = angle[begin:run_stop] - reference
            turned = np.abs(offset) > turn
            if not turned.any():
                self._add(begin, run_stop, position, last)
                return
            end = begin + int(np.argmax(turned))
            crossing = reference + np.sign(offset[end - begin]) * turn
            reference = crossing
            if end == begin:  # already past the next turn: move the reference on, cut nothing
                continue
            before, after = angle[end - 1], angle[end]
            fraction = (crossing - before) / (after - before) if after != before else 1.0
            cut = max(end - 1 + float(np.clip(fraction, 0.0, 1.0)), position)
            self._add(begin, end, position, cut)
            begin, position = end, cut

    def _add(self, start: int, stop: int, first: float, last: float) -> None:
        self.starts.append(start)
        self.stops.append(stop)
        self.first.append(first)
        self.last.append(last)

    def pieces(self, origin: int) -> _Pieces:
        starts, stops = np.asarray(self.starts, int), np.asarray(self.stops, int)
        first, last = np.asarray(self.first, float), np.asarray(self.last, float)
        return _Pieces(starts + origin, stops + origin, first + origin, last + origin)


def _pieces(
    regular: NDArray[np.bool_], heading: NDArray[np.float64], height: NDArray[np.float64],
    max_turn: float,
) -> _Pieces:
    """The pieces of the contour's regular runs.

    A run of regular points turning by ``spread`` is cut into ``ceil(spread / max_turn)`` pieces
    of equal turn: each cut is where the heading first leaves the band of +-turn around the
    piece's reference heading, and the next reference is one turn on, so noise in the heading
    moves a cut by the noise alone and never accumulates along the run. A contour with no
    irregular point is one closed run whose cuts sit at absolute headings (multiples of the
    turn, starting at the lowest point where the tangent points along +x), so where its sampling
    starts does not matter.
    """
    count = len(regular)
    cutter = _Cutter()
    if not regular.any():
        return cutter.pieces(0)
    if regular.all():
        return _closed_run_pieces(heading, height, max_turn)
    origin = int(np.flatnonzero(~regular)[0])
    order = (origin + np.arange(count)) % count  # start on an irregular point: no run wraps
    flags = np.concatenate([[False], regular[order], [False]]).astype(np.int8)
    edges = np.diff(flags)
    run_starts, run_stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    angle = np.unwrap(heading[order])
    for run_start, run_stop in zip(run_starts, run_stops, strict=True):
        spread = float(np.ptp(angle[run_start:run_stop]))
        turn = spread / max(np.ceil(spread / max_turn), 1.0) * (1 + 1e-9) if spread else max_turn
        cutter.cut(angle, int(run_start), int(run_stop), float(angle[run_start]), turn)
    return cutter.pieces(origin)


def _closed_run_pieces(
    heading: NDArray[np.float64], height: NDArray[np.float64], max_turn: float
) -> _Pieces:
    """Pieces of a contour that is one regular run: equal turns at absolute headings."""
    count = len(heading)
    turn = 2.0 * np.pi / np.ceil(2.0 * np.pi / max_turn)
    # cuts at phase + k turn: a straight stretch whose heading lay on a cut would be cut
    # anywhere along it by noise, so the phase keeps cuts off the headings of axis-aligned and
    # 45-degree sides (2.5 degrees off them for the default 20-degree turn)
    phase = turn / 8.0
    wrapped = np.mod(heading - phase, 2.0 * np.pi)
    # samples where the heading passes up through the phase (mod 2 pi); the lowest one is the origin
    up = np.flatnonzero(np.roll(wrapped, 1) - wrapped > np.pi)
    if len(up) == 0:  # a contour that never turns through +x: cut from its first sample
        up = np.array([1])
    origin = int(up[np.argmin(height[up % count])]) - 1  # the last sample before the crossing
    order = (origin + np.arange(count + 1)) % count  # once round, back to the origin
    angle = np.unwrap(heading[order] - phase)
    angle += (wrapped[origin % count] - 2.0 * np.pi) - angle[0]  # just below the phase
    crossing = float(np.clip(-angle[0] / (angle[1] - angle[0]), 0.0, 1.0))  # where it is 0
    cutter = _Cutter()
    cutter.cut(angle, 1, count + 1, 0.0, turn, ends=(crossing, count + crossing))
    return cutter.pieces(origin)


def _segments(
    points: NDArray[np.float64], kappa: NDArray[np.float64], pieces: _Pieces, min_length: float,
    rho_scale: float,
) -> Regions:
    """Total-least-squares segments of the pieces, filtered by length and curvature."""
    count = len(points)
    starts, stops = pieces.starts, pieces.stops
    sizes = stops - starts
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    index = (np.repeat(starts - offsets, sizes) + np.arange(sizes.sum())) % count
    xy = points[index]
    mean = np.add.reduceat(xy, offsets, axis=0) / sizes[:, None]
    centred = xy - np.repeat(mean, sizes, axis=0)
    sxx, syy, sxy = (
        np.add.reduceat(centred[:, i] * centred[:, j], offsets) for i, j in ((0, 0), (1, 1), (0, 1))
    )
    angle = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    direction = np.column_stack([np.cos(angle), np.sin(angle)])
    first, last = _at(points, pieces.first), _at(points, pieces.last)
    backwards = np.einsum("ij,ij->i", last - first, direction) < 0
    direction[backwards] *= -1.0
    a = mean + np.einsum("ij,ij->i", first - mean, direction)[:, None] * direction
    b = mean + np.einsum("ij,ij->i", last - mean, direction)[:, None] * direction
    rho = np.add.reduceat(kappa[index], offsets) / sizes * rho_scale
    normal = np.column_stack([-direction[:, 1], direction[:, 0]])
    keep = (np.linalg.norm(b - a, axis=1) >= min_length) & (np.abs(rho) <= MAX_ABS_RHO)
    order = np.argsort(starts[keep] % count, kind="stable")
    return Regions(a[keep][order], b[keep][order], normal[keep][order], rho[keep][order])


def _at(points: NDArray[np.float64], position: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points of the closed sampled curve at fractional sample positions (unwrapped)."""
    count = len(points)
    below = np.floor(position).astype(int)
    t = (position - below)[:, None]
    return (1.0 - t) * points[below % count] + t * points[(below + 1) % count]
