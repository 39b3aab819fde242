"""Objects from masks and images: grey image → object mask → sub-pixel outer contour in mm.

Perception (the render of an object, :mod:`grip_env.perception`) segments with these too.

Pixel convention (shared with ``World.render_top_down``): the centre of pixel (row r, column c) of
an H-row image lies at ``x = c * mm_per_px``, ``y = (H - 1 - r) * mm_per_px`` — the origin is the
centre of the bottom-left pixel and y points up (row 0 is the top of the image). The contour is
the 0.5 iso-line of the mask, so a binary mask's contour runs half-way between object and
background pixel centres.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from skimage.filters import threshold_otsu
from skimage.measure import find_contours

_MIN_CONTRAST = 1e-6  # grey-level range below which an image is uniform (no object)
SPECK_FRACTION = 1e-3
"""Parts and holes of a user's mask smaller than this fraction of the object are noise."""


def contour_from_mask(mask: ArrayLike, mm_per_px: float) -> NDArray[np.float64]:
    """The largest outer contour of a mask, in mm, counter-clockwise, shape (N, 2).

    Args:
        mask: 2-D bool array, or floats in [0, 1] (grey-level coverage); 1 is the object.
        mm_per_px: image scale (mm per pixel), positive and finite.

    Raises:
        ValueError: non-2-D, NaN, out-of-range or empty mask, or a bad ``mm_per_px``.
    """
    image = _validated_mask(mask)
    scale = _validated_scale(mm_per_px)
    padded = np.pad(image, 1, constant_values=0.0)  # every contour closes inside the padding
    contours = find_contours(padded, 0.5, fully_connected="high")
    if not contours:
        raise ValueError("mask is empty: no pixel is above 0.5")
    rows_cols = max(contours, key=lambda c: abs(_signed_area(c)))[:-1] - 1.0
    height = image.shape[0]
    xy = np.column_stack([rows_cols[:, 1], height - 1.0 - rows_cols[:, 0]]) * scale
    return xy if _signed_area(xy) > 0 else xy[::-1].copy()


def segment(grey: ArrayLike) -> NDArray[np.bool_]:
    """Object mask of a grey image: Otsu threshold, object = the class that does not dominate the
    image border, largest 8-connected component, holes filled.

    Raises:
        ValueError: non-2-D or non-finite image, or an image with no object (uniform, or nothing
            but border).
    """
    image = np.asarray(grey, dtype=float)
    if image.ndim != 2:
        raise ValueError(f"grey image must be 2-D, got shape {image.shape}")
    if not np.all(np.isfinite(image)):
        raise ValueError("grey image contains NaN or infinite values")
    if np.ptp(image) <= _MIN_CONTRAST * max(1.0, float(np.abs(image).max())):
        raise ValueError("image has no object: it is uniform")
    foreground = _foreground(image)
    labels, count = ndimage.label(foreground, structure=np.ones((3, 3)))
    if count == 0:
        raise ValueError("image has no object: no pixel differs from the background")
    sizes = np.bincount(labels.ravel())[1:]
    largest = labels == 1 + int(np.argmax(sizes))
    return ndimage.binary_fill_holes(largest)


def one_region(mask: ArrayLike) -> NDArray[np.float64]:
    """A user's object mask, checked to be one region without holes.

    Parts and holes smaller than ``SPECK_FRACTION`` of the object are noise: dropped and filled.

    Raises:
        ValueError: a bad or empty mask, several parts (8-connected) or holes (4-connected).
    """
    image = _validated_mask(mask).copy()
    inside = image > 0.5
    labels, _ = ndimage.label(inside, structure=np.ones((3, 3)))
    sizes = np.bincount(labels.ravel())[1:]
    speck = SPECK_FRACTION * sizes.max()
    if np.count_nonzero(sizes > speck) > 1:
        parts = sorted((int(n) for n in sizes[sizes > speck]), reverse=True)
        raise ValueError(
            f"mask has {len(parts)} separate parts ({', '.join(map(str, parts[:5]))} px): "
            "give one object per mask"
        )
    region = labels == 1 + int(np.argmax(sizes))
    filled = ndimage.binary_fill_holes(region)
    holes, _ = ndimage.label(filled & ~region)
    hole_sizes = np.bincount(holes.ravel())[1:]
    if np.any(hole_sizes > speck):
        found = sorted((int(n) for n in hole_sizes[hole_sizes > speck]), reverse=True)
        raise ValueError(
            f"mask has {len(found)} hole(s) ({', '.join(map(str, found[:5]))} px): "
            "a planar object here is one region without holes"
        )
    image[inside & ~region] = 0.0
    image[filled & ~inside] = 1.0
    return image


def grey_from_rgb(image: NDArray) -> NDArray[np.float64]:
    """Luminance in [0, 1] of a grey, RGB or RGBA image (alpha ignored), integer or float."""
    data = np.asarray(image)
    scale = float(np.iinfo(data.dtype).max) if np.issubdtype(data.dtype, np.integer) else 1.0
    data = data.astype(float) / scale
    if data.ndim == 3 and data.shape[2] in (3, 4):
        data = data[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
    elif data.ndim == 3 and data.shape[2] in (1, 2):
        data = data[..., 0]
    if data.ndim != 2:
        raise ValueError(f"image must be grey, RGB or RGBA, got shape {np.asarray(image).shape}")
    return data


def mask_from_image_file(path: str | Path) -> NDArray[np.bool_]:
    """Object mask of an image file showing one object on a contrasting background.

    Raises:
        ValueError: missing or unreadable file, or an image with no object.
    """
    import imageio.v3 as iio

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"image file not found: {path}")
    try:
        image = iio.imread(path)
    except Exception as exc:  # imageio raises many types for unreadable data
        raise ValueError(f"cannot read image file {path}: {exc}") from None
    try:
        return one_region(_foreground(_validated_grey(grey_from_rgb(image)))) > 0.5
    except ValueError as exc:
        raise ValueError(f"image file {path}: {exc}") from None


def _validated_grey(image: NDArray[np.float64]) -> NDArray[np.float64]:
    if not np.all(np.isfinite(image)):
        raise ValueError("grey image contains NaN or infinite values")
    if np.ptp(image) <= _MIN_CONTRAST * max(1.0, float(np.abs(image).max())):
        raise ValueError("image has no object: it is uniform")
    return image


def _foreground(image: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Otsu threshold; the object is the class that does not dominate the image border.

    Otsu runs on the histogram of the image's own grey levels: on 256 bins over the image's range
    the threshold is a bin centre, and levels in that bin above its centre (an object face a shade
    lighter than the rest) fell on the table's side.
    """
    levels, counts = np.unique(image, return_counts=True)
    bright = image > threshold_otsu(hist=(counts, levels))
    border = np.concatenate([bright[0], bright[-1], bright[1:-1, 0], bright[1:-1, -1]])
    return ~bright if border.mean() > 0.5 else bright


def _validated_mask(mask: ArrayLike) -> NDArray[np.float64]:
    try:
        image = np.asarray(mask, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"mask must be a numeric 2-D array: {exc}") from None
    if image.ndim != 2:
        raise ValueError(f"mask must be 2-D, got shape {image.shape}")
    if image.size == 0:
        raise ValueError("mask is empty: it has no pixels")
    if not np.all(np.isfinite(image)):
        raise ValueError("mask contains NaN or infinite values")
    if image.min() < 0.0 or image.max() > 1.0:
        raise ValueError(
            f"mask values must lie in [0, 1], got [{image.min():g}, {image.max():g}]"
        )
    if image.max() <= 0.5:
        raise ValueError("mask is empty: no pixel is above 0.5")
    return image


def _validated_scale(mm_per_px: float) -> float:
    try:
        scale = float(mm_per_px)
    except (TypeError, ValueError):
        raise ValueError(f"mm_per_px must be a number, got {mm_per_px!r}") from None
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"mm_per_px must be positive and finite, got {mm_per_px!r}")
    return scale


def _signed_area(points: NDArray[np.float64]) -> float:
    x, y = points[:, 0], points[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
