"""A grip's image: the object's silhouette in the hand's frame, with the contacts and the fingers.

What an image-based evaluator sees, as GQ-CNN aligns its depth crop with the grasp (Mahler et al.,
Dex-Net 2.0, 2017): for each grip, the contour it was planned on (the dataset's
``perceived_contour``, or the true ``contour`` when the grips were planned on it) is filled,
cropped around the hand and rotated into the hand's frame. The palm centre ``(hand_x, hand_y)`` is
at the image's centre and the thumb's force F3 (the hand's y axis, at ``hand_yaw``) points up the
image, so fingers 1 and 2 close from the top and the thumb from the bottom; hand x points right.
The scale is fixed in millimetres per pixel and must show the hand's whole reach
(:data:`HAND_REACH_MM` from the centre), so the hand's own size is in the picture.

Channels (:data:`CHANNELS`), each the covered fraction of a pixel (``SUPERSAMPLE ** 2`` samples
a pixel, so a value is a multiple of ``1 / SUPERSAMPLE ** 2``):

- ``silhouette``: the object;
- ``contacts``: discs of ``CONTACT_RADIUS_PX`` pixels at the three planned contacts P1..P3;
- ``approach``: each finger's footprint behind its contact, ``FINGER_WIDTH_MM`` wide and
  ``APPROACH_LENGTH_MM`` long against its force direction F_i: the strip the planner checks is
  clear of the object (:func:`grip_env.planning.barrett.approach_clear`).

The grip table alone does not hold the contours: :func:`attach_contours` adds them as one column
whose cells share one array per object (:data:`CONTOUR_COLUMN`), and :func:`load_with_contours`
loads a dataset with it. The silhouette is rasterised once per object at ``RASTER_MM`` and then
sampled with each grip's affine map; images are cached per object in memory, keyed by their
content, so the folds of a grouped cross-validation draw each object once.
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from sklearn.base import BaseEstimator, TransformerMixin
from sklearn.utils import Tags

from grip_env.columns import CONTACTS, FORCES
from grip_env.hand_geometry import FINGER_WIDTH_MM, SPREAD_AXIS_OFFSET_MM
from grip_env.planning.barrett import APPROACH_LENGTH_MM, FINGER_REACH_MM

#: The grip-table column with the contour each grip was planned on ((V, 2) mm, shared per object).
CONTOUR_COLUMN = "planned_contour"
CHANNELS = ("silhouette", "contacts", "approach")
#: How far from the palm centre a finger can touch: its spread axis's offset plus its longest
#: fingertip reach (113.5 mm); an image must show at least this far to each side of its centre.
HAND_REACH_MM = SPREAD_AXIS_OFFSET_MM + FINGER_REACH_MM[1]
POSE = ("hand_x", "hand_y", "hand_yaw")
#: Every column an image is drawn from, beside the contour.
IMAGE_COLUMNS = POSE + CONTACTS + FORCES
SUPERSAMPLE = 2  #: samples per pixel along each axis
RASTER_MM = 0.25  #: cell of the silhouette's high-resolution raster
CONTACT_RADIUS_PX = 1.5  #: radius of a contact's disc, in pixels of the image
CACHE_BYTES = 256 * 2**20  #: the in-memory cache's bound (least recently used objects leave)
_CHUNK = 256  #: grips drawn at once (bounds the sample arrays to a few tens of MB)


def attach_contours(grips: pd.DataFrame, objects: pd.DataFrame,
                    on_render: bool | None = None) -> pd.DataFrame:
    """``grips`` with :data:`CONTOUR_COLUMN`: each grip's planned contour, one read-only (V, 2)
    float64 array per object shared by all its grips (11,202 references, 510 arrays).

    The contour is the objects table's ``perceived_contour`` where it is stored (the grips were
    planned on the render), else its ``contour`` (they were planned on the true one).
    ``on_render=True`` (the run planned on the render, as its manifest says) requires the
    perceived contour of every object; None takes what is stored. The column is for memory:
    Arrow writes its cells as lists (``[c.tolist() for c in column]``), not as 2-D arrays, and
    such a table read back draws the same images.

    Raises:
        ValueError: naming what is missing: the ``object_id`` column, the objects table's contour
            columns, an object of ``grips`` in it, or an object's (perceived) contour.
    """
    if "object_id" not in grips or "object_id" not in objects:
        raise ValueError("grip images attach contours by object_id: the grip table or the "
                         "objects table has no object_id column")
    ids = grips["object_id"].astype(str)
    wanted = objects[objects["object_id"].astype(str).isin(set(ids))]
    contours = object_contours(wanted, on_render)
    missing = sorted(set(ids) - set(contours))
    if missing:
        raise ValueError(f"no contour for {len(missing)} objects of the grip table in the objects "
                         f"table (first: {missing[:3]})")
    names = list(contours)
    shared = np.empty(len(names), dtype=object)
    for k, name in enumerate(names):  # one cell per object, not per grip
        shared[k] = contours[name]
    return grips.assign(**{CONTOUR_COLUMN: shared[pd.Index(names).get_indexer(ids)]})


def object_contours(objects: pd.DataFrame, on_render: bool | None = None
                    ) -> dict[str, NDArray[np.float64]]:
    """Object id -> the contour its grips were planned on (read-only (V, 2) mm); see
    :func:`attach_contours`."""
    accepted = ["perceived_contour"] if on_render else ["perceived_contour", "contour"]
    columns = [name for name in accepted if name in objects]
    if not columns:
        raise ValueError(f"the objects table has no contour column ({' or '.join(accepted)}): "
                         "grip images need the contour each grip was planned on")
    found = {}
    for row in objects[["object_id", *columns]].itertuples(index=False):
        stored = [c for c in row[1:] if c is not None and len(c) >= 3]
        if not stored:
            which = "perceived contour" if on_render else "contour"
            raise ValueError(f"object {row[0]!r} has no {which} in the objects table")
        contour = np.array([list(point) for point in stored[0]], dtype=np.float64)
        contour.flags.writeable = False
        found[str(row[0])] = contour
    return found


def load_with_contours(path: str | Path, **load_options: Any) -> pd.DataFrame:
    """A dataset's grip table (:func:`grip_env.dataset.load`) with :data:`CONTOUR_COLUMN`, the
    perceived contours required when the manifest says the run planned on the render."""
    from grip_env.dataset import load, read_objects

    grips = load(path, **load_options)
    config = grips.attrs["manifest"].get("config", {})
    on_render = (config.get("perception", {}).get("source") == "render"
                 or bool(config.get("uncertainty", {}).get("perceived_contour")))
    return attach_contours(grips, read_objects(Path(path)), on_render)


class GripImages(TransformerMixin, BaseEstimator):
    """Grip table -> images (n, C, H, W) float32 of each grip in its hand's frame.

    Args:
        size_px: height and width of an image (pixels).
        mm_per_px: its scale; ``size_px * mm_per_px / 2`` must be at least
            :data:`HAND_REACH_MM`, so the hand's reach fits.
        channels: which of :data:`CHANNELS` to draw, in this order.

    Stateless: ``fit`` only checks the parameters and the table. The table needs
    :data:`IMAGE_COLUMNS` and, for the silhouette, :data:`CONTOUR_COLUMN`
    (:func:`attach_contours`).
    """

    def __init__(self, size_px: int = 48, mm_per_px: float = 5.0,
                 channels: Sequence[str] = CHANNELS):
        self.size_px = size_px
        self.mm_per_px = mm_per_px
        self.channels = channels

    def __sklearn_tags__(self) -> Tags:
        tags = super().__sklearn_tags__()
        tags.requires_fit = False  # it draws by fixed rules, whatever it was fitted on
        return tags

    def fit(self, X: pd.DataFrame, y: Any = None) -> GripImages:
        """Check the parameters and that ``X`` holds what the images are drawn from."""
        check_image_settings(self.size_px, self.mm_per_px, self.channels)
        _checked_table(X, tuple(self.channels))
        self.image_shape_ = (len(self.channels), int(self.size_px), int(self.size_px))
        return self

    def transform(self, X: pd.DataFrame) -> NDArray[np.float32]:
        """The images, shape (len(X), C, size_px, size_px), values in [0, 1]."""
        return grip_images(X, self.size_px, self.mm_per_px, self.channels)


def check_image_settings(size_px: int, mm_per_px: float, channels: Sequence[str]) -> None:
    """ValueError naming the bad value: a size below 8 pixels, a scale that is not a positive
    number or does not fit the hand's reach, unknown or repeated channels."""
    if isinstance(size_px, bool) or not isinstance(size_px, int | np.integer) or size_px < 8:
        raise ValueError(f"size_px must be an integer of at least 8, got {size_px!r}")
    if not isinstance(mm_per_px, int | float | np.number) or not math.isfinite(mm_per_px) \
            or mm_per_px <= 0:
        raise ValueError(f"mm_per_px must be a positive number, got {mm_per_px!r}")
    half_width = size_px * mm_per_px / 2.0
    if half_width < HAND_REACH_MM:
        raise ValueError(
            f"mm_per_px {mm_per_px} with size_px {size_px} shows {half_width:.1f} mm each side of "
            f"the palm, less than the hand's reach {HAND_REACH_MM:.1f} mm: use mm_per_px >= "
            f"{math.ceil(2e3 * HAND_REACH_MM / size_px) / 1e3:.3f}"
        )
    channels = list(channels) if not isinstance(channels, str) else [channels]
    unknown = [name for name in channels if name not in CHANNELS]
    if unknown or not channels or len(set(channels)) != len(channels):
        raise ValueError(f"channels must be distinct names of {list(CHANNELS)}, got {channels}")


def grip_images(grips: pd.DataFrame, size_px: int = 48, mm_per_px: float = 5.0,
                channels: Sequence[str] = CHANNELS) -> NDArray[np.float32]:
    """The images of :class:`GripImages` (its ``transform``, as a function)."""
    check_image_settings(size_px, mm_per_px, channels)
    channels = tuple(channels)
    values = _checked_table(grips, channels)
    groups, contours = _contour_groups(grips, channels)
    counts = np.empty((len(grips), len(channels), size_px, size_px), dtype=np.uint8)
    settings = _settings_key(size_px, mm_per_px, channels)
    for group, contour in enumerate(contours):
        rows = np.flatnonzero(groups == group)
        key = _group_key(settings, contour, values[rows])
        cached = _CACHE.get(key)
        if cached is None:
            cached = _draw(values[rows], contour, size_px, mm_per_px, channels)
            _CACHE.put(key, cached)
        counts[rows] = cached
    images = counts.astype(np.float32)
    images *= np.float32(1.0 / SUPERSAMPLE**2)  # a power of two: exact
    return images


# ------------------------------------------------------------------------------- the table
def _checked_table(grips: pd.DataFrame, channels: tuple[str, ...]) -> NDArray[np.float64]:
    """The grips' :data:`IMAGE_COLUMNS` as (n, 15) float64; ValueError naming what is missing."""
    if not isinstance(grips, pd.DataFrame):
        raise ValueError(f"grip images take the grip table as a DataFrame, got "
                         f"{type(grips).__name__}")
    missing = [name for name in IMAGE_COLUMNS if name not in grips.columns]
    if "silhouette" in channels and CONTOUR_COLUMN not in grips.columns:
        missing.append(CONTOUR_COLUMN)
    if missing:
        hint = (f" (attach_contours(grips, objects) adds {CONTOUR_COLUMN})"
                if CONTOUR_COLUMN in missing else "")
        raise ValueError(f"the grip table lacks columns {missing} needed for grip images{hint}")
    values = grips[list(IMAGE_COLUMNS)].to_numpy(dtype=np.float64)
    finite = np.isfinite(values).all(axis=0)
    if not finite.all():
        bad = [name for name, ok in zip(IMAGE_COLUMNS, finite, strict=True) if not ok]
        raise ValueError(f"columns {bad} hold NaN or infinite values")
    return np.ascontiguousarray(values)


def _contour_groups(grips: pd.DataFrame, channels: tuple[str, ...]
                    ) -> tuple[NDArray[np.intp], list[NDArray[np.float64] | None]]:
    """Each row's group (grips sharing one contour array) and the groups' contours; one group
    without a contour when no silhouette is drawn."""
    if "silhouette" not in channels:
        return np.zeros(len(grips), dtype=np.intp), [None]
    cells = grips[CONTOUR_COLUMN].to_numpy(dtype=object)
    # rows sharing one array share a group at once; equal copies are merged by their bytes
    shared, first_rows = _groups_of(np.fromiter(map(id, cells), dtype=np.int64, count=len(cells)))
    contours = [_checked_contour(cells[row], row) for row in first_rows]
    merged, first = _groups_of(np.array([hashlib.sha256(c.tobytes()).hexdigest() + str(c.shape)
                                         for c in contours]))
    return merged[shared], [contours[k] for k in first]


def _groups_of(keys: NDArray[Any]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Each key's group (numbered in order of first appearance) and each group's first index."""
    groups, _ = pd.factorize(keys)
    return groups.astype(np.intp), np.unique(groups, return_index=True)[1]


def _checked_contour(cell: Any, row: int) -> NDArray[np.float64]:
    """A cell as a (V, 2) float64 contour: an array, a list of [x, y] or, as pandas reads
    Parquet, an object array of points; ValueError naming the row otherwise."""
    try:
        points = list(cell) if isinstance(cell, np.ndarray) and cell.dtype == object else cell
        contour = np.ascontiguousarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        contour = np.empty((0,))
    if contour.ndim != 2 or contour.shape[1] != 2 or len(contour) < 3 \
            or not np.isfinite(contour).all():
        raise ValueError(f"{CONTOUR_COLUMN} of row {row} is not a contour (a list of at least "
                         f"three finite [x, y] points)")
    return contour


# ------------------------------------------------------------------------------ the cache
class _ImageCache:
    """Least-recently-used images of object groups, bounded by :data:`CACHE_BYTES`; safe to
    share between threads."""

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = max_bytes
        self.entries: OrderedDict[bytes, NDArray[np.uint8]] = OrderedDict()
        self.bytes = 0
        self.lock = threading.Lock()

    def get(self, key: bytes) -> NDArray[np.uint8] | None:
        with self.lock:
            found = self.entries.get(key)
            if found is not None:
                self.entries.move_to_end(key)
            return found

    def put(self, key: bytes, counts: NDArray[np.uint8]) -> None:
        counts.flags.writeable = False
        with self.lock:
            if key in self.entries:
                return
            self.entries[key] = counts
            self.bytes += counts.nbytes
            while self.bytes > self.max_bytes and len(self.entries) > 1:
                _, dropped = self.entries.popitem(last=False)
                self.bytes -= dropped.nbytes

    def clear(self) -> None:
        with self.lock:
            self.entries.clear()
            self.bytes = 0


_CACHE = _ImageCache(CACHE_BYTES)


def clear_image_cache() -> None:
    """Forget every cached image (the next transform draws afresh)."""
    _CACHE.clear()


def _settings_key(size_px: int, mm_per_px: float, channels: tuple[str, ...]) -> bytes:
    drawing = (SUPERSAMPLE, RASTER_MM, CONTACT_RADIUS_PX, FINGER_WIDTH_MM, APPROACH_LENGTH_MM)
    return repr((int(size_px), float(mm_per_px), channels, drawing)).encode()


def _group_key(settings: bytes, contour: NDArray[np.float64] | None,
               values: NDArray[np.float64]) -> bytes:
    digest = hashlib.sha256(settings)
    if contour is not None:
        digest.update(np.ascontiguousarray(contour).tobytes())
    digest.update(np.ascontiguousarray(values).tobytes())
    return digest.digest()


# ----------------------------------------------------------------------------- the drawing
#
# The samples lie on a grid in the hand's frame: u (right) is the same down a column, v (up)
# the same along a row. Every quantity below is a sum of a column term and a row term, so it is
# computed on (n, W*s) and (n, H*s) and added once on the full (n, H*s, W*s) grid.
def _draw(values: NDArray[np.float64], contour: NDArray[np.float64] | None, size_px: int,
          mm_per_px: float, channels: tuple[str, ...]) -> NDArray[np.uint8]:
    """Sample counts (n, C, H, W) uint8 of one object's grips (``values``: their image columns)."""
    counts = np.empty((len(values), len(channels), size_px, size_px), dtype=np.uint8)
    u, v = sample_axes(size_px, mm_per_px)
    raster = silhouette_raster(contour) if contour is not None else None
    for start in range(0, len(values), _CHUNK):
        hand = _HandFrames(values[start:start + _CHUNK])
        for k, name in enumerate(channels):
            if name == "silhouette":
                inside = raster.contains_grid(hand, u, v)
            elif name == "contacts":
                inside = _near_contacts(hand.contacts(), u, v, CONTACT_RADIUS_PX * mm_per_px)
            else:
                inside = _in_approach(hand.contacts(), hand.forces(), u, v)
            counts[start:start + len(inside), k] = _pixel_counts(inside, size_px)
    return counts


def sample_axes(size_px: int, mm_per_px: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Hand coordinates (mm) of the sub-pixel samples: u of each sample column (left to right)
    and v of each sample row (top to bottom), ``size_px * SUPERSAMPLE`` each; the palm centre is
    the image's centre."""
    steps = ((np.arange(size_px * SUPERSAMPLE) + 0.5) / SUPERSAMPLE - size_px / 2.0) * mm_per_px
    return steps, -steps


def _pixel_counts(inside: NDArray[np.bool_], size_px: int) -> NDArray[np.uint8]:
    """(n, H*s, W*s) samples -> (n, H, W) how many of a pixel's samples are inside."""
    s = SUPERSAMPLE
    samples = inside.view(np.uint8).reshape(len(inside), size_px, s, size_px, s)
    counts = np.zeros((len(inside), size_px, size_px), dtype=np.uint8)
    for i in range(s):
        for j in range(s):
            counts += samples[:, :, i, :, j]
    return counts


def _grid(columns: NDArray[np.float64], rows: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, W) column terms + (n, H) row terms -> (n, H, W), in float32 (a sample's test is
    against millimetres of a 5 mm pixel: float32's 1e-7 relative error is far below it)."""
    return rows.astype(np.float32)[:, :, None] + columns.astype(np.float32)[:, None, :]


class _HandFrames:
    """The hand frames of grips: palm centre O, axes x = (sin psi, -cos psi), y = F3 direction."""

    def __init__(self, values: NDArray[np.float64]) -> None:
        self.origin = values[:, 0:2]
        yaw = values[:, 2]
        self.x_axis = np.stack([np.sin(yaw), -np.cos(yaw)], axis=-1)
        self.y_axis = np.stack([np.cos(yaw), np.sin(yaw)], axis=-1)
        self.world_contacts = values[:, 3:9].reshape(-1, 3, 2)
        self.world_forces = values[:, 9:15].reshape(-1, 3, 2)

    def __len__(self) -> int:
        return len(self.origin)

    def world_terms(self, u: NDArray[np.float64], v: NDArray[np.float64], axis: int
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """World coordinate ``axis`` (0: x, 1: y) of the samples, as its column term (n, W*s),
        which holds the origin, and its row term (n, H*s)."""
        return (self.origin[:, axis, None] + u[None, :] * self.x_axis[:, axis, None],
                v[None, :] * self.y_axis[:, axis, None])

    def _hand(self, vectors: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.stack([np.einsum("nfk,nk->nf", vectors, self.x_axis),
                         np.einsum("nfk,nk->nf", vectors, self.y_axis)], axis=-1)

    def contacts(self) -> NDArray[np.float64]:
        """P1..P3 in hand coordinates, (n, 3, 2)."""
        return self._hand(self.world_contacts - self.origin[:, None, :])

    def forces(self) -> NDArray[np.float64]:
        """F1..F3 in hand coordinates, unit length, (n, 3, 2)."""
        forces = self._hand(self.world_forces)
        norm = np.linalg.norm(forces, axis=-1, keepdims=True)
        return forces / np.where(norm > 0, norm, 1.0)


def _near_contacts(contacts: NDArray[np.float64], u: NDArray[np.float64], v: NDArray[np.float64],
                   radius_mm: float) -> NDArray[np.bool_]:
    """(n, H*s, W*s): a sample within ``radius_mm`` of any contact."""
    inside = np.zeros((len(contacts), len(v), len(u)), dtype=bool)
    for finger in range(3):
        du = u[None, :] - contacts[:, finger, 0, None]
        dv = v[None, :] - contacts[:, finger, 1, None]
        inside |= _grid(du * du, dv * dv) <= radius_mm * radius_mm
    return inside


def _in_approach(contacts: NDArray[np.float64], forces: NDArray[np.float64],
                 u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.bool_]:
    """(n, H*s, W*s): a sample on a finger's footprint behind its contact, ``FINGER_WIDTH_MM``
    wide and ``APPROACH_LENGTH_MM`` long against its force direction."""
    inside = np.zeros((len(contacts), len(v), len(u)), dtype=bool)
    half_length, half_width = APPROACH_LENGTH_MM / 2.0, FINGER_WIDTH_MM / 2.0
    for finger in range(3):
        fu, fv = forces[:, finger, 0, None], forces[:, finger, 1, None]
        # measured from the strip's middle, half its length behind the contact
        du = u[None, :] - (contacts[:, finger, 0, None] - half_length * fu)
        dv = v[None, :] - (contacts[:, finger, 1, None] - half_length * fv)
        along = np.abs(_grid(du * fu, dv * fv))
        beside = np.abs(_grid(du * fv, -dv * fu))
        inside |= (along <= half_length) & (beside <= half_width)
    return inside


class SilhouetteRaster:
    """A contour filled on a grid of ``cell_mm`` cells (even-odd rule at the cells' centres),
    with a border of empty cells all round."""

    def __init__(self, mask: NDArray[np.bool_], origin: tuple[float, float], cell_mm: float):
        self.mask, self.origin, self.cell_mm = mask, origin, cell_mm

    def contains(self, x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether points (world mm, any shape) fall in a filled cell."""
        return self._lookup(self._cells(x, 0), self._cells(y, 1))


    def contains_grid(self, hand: _HandFrames, u: NDArray[np.float64], v: NDArray[np.float64]
                      ) -> NDArray[np.bool_]:
        """(n, H*s, W*s): whether each grip's samples fall in a filled cell."""
        cells = []
        for axis in (0, 1):
            columns, rows = hand.world_terms(u, v, axis)
            shift = self.origin[axis]
            cells.append(np.floor(_grid((columns - shift) / self.cell_mm, rows / self.cell_mm)))
        return self._lookup(*cells)

    def _cells(self, coordinate: NDArray[np.float64], axis: int) -> NDArray[np.float64]:
        return np.floor((np.asarray(coordinate, float) - self.origin[axis]) / self.cell_mm)

    def _lookup(self, col: NDArray[np.floating], row: NDArray[np.floating]) -> NDArray[np.bool_]:
        # the border cells are empty, so a point off the grid reads the nearest border cell
        rows, cols = self.mask.shape
        np.clip(col, 0, cols - 1, out=col)
        np.clip(row, 0, rows - 1, out=row)
        row *= cols
        row += col  # a whole number below 2**24: exact in float32
        return np.take(self.mask.ravel(), row.astype(np.int32))


def silhouette_raster(contour: NDArray[np.float64], cell_mm: float = RASTER_MM
                      ) -> SilhouetteRaster:
    """Fill ``contour`` (a closed polygon, (V, 2) mm) on a grid of ``cell_mm`` cells covering it
    with an empty cell to spare all round: a scanline fill, vectorised over rows and edges.
    Cells are coarsened for a contour more than a metre across, to at most 4,000 a side."""
    cell_mm = max(cell_mm, float(np.ptp(contour, axis=0).max()) / 4000.0)
    low = np.floor(contour.min(axis=0) / cell_mm) - 1
    high = np.ceil(contour.max(axis=0) / cell_mm) + 1
    cols, rows = (high - low).astype(int)
    origin = (float(low[0] * cell_mm), float(low[1] * cell_mm))
    start, end = contour, np.roll(contour, -1, axis=0)
    y = origin[1] + (np.arange(rows) + 0.5) * cell_mm
    crosses = (start[None, :, 1] <= y[:, None]) != (end[None, :, 1] <= y[:, None])
    row, edge = np.nonzero(crosses)
    a, b = start[edge], end[edge]
    x = a[:, 0] + (y[row] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    # a cell is inside when an odd number of crossings lie left of its centre
    first_col = np.clip(np.ceil((x - origin[0]) / cell_mm - 0.5), 0, cols).astype(np.intp)
    toggles = np.bincount(row * (cols + 1) + first_col, minlength=rows * (cols + 1)) % 2
    parity = np.bitwise_xor.accumulate(toggles.astype(np.uint8).reshape(rows, cols + 1), axis=1)
    mask = parity[:, :cols].astype(bool)
    return SilhouetteRaster(mask, origin, cell_mm)
