"""The camera: a top-down PyBullet view of an object on the table, and the object as the robot
perceives it (render, then segment with :mod:`grip_env.perception`).

The camera looks straight down on the object's top face (scale ``mm_per_px`` holds on that plane).
Pixel (row r, column c) of an n-pixel image centred on ``centre_mm`` looks at
``centre + (c - (n-1)/2, (n-1)/2 - r) * mm_per_px``, which is the segmentation's pixel convention
shifted by ``centre - (n-1)/2 * mm_per_px`` on both axes.

If the object does not fit in the image (with a margin of ``_MARGIN_PX`` pixels on each side),
``mm_per_px`` is enlarged automatically to the smallest scale that fits; the scale used is returned.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from grip_env.config import PerceptionConfig
from grip_env.objects import PlanarObject
from grip_env.objects.masks import contour_from_mask, segment
from grip_env.perception.corners import sharpen_corners
from grip_env.portable_process import portable
from grip_env.sim.world import World

_MARGIN_PX = 4  # background pixels kept around the object on each side
_CAMERA_HEIGHT_MM = 20_000.0


def render_mask(
    obj: PlanarObject, config: PerceptionConfig | None = None, thickness_mm: float = 30.0,
    seed: int = 0, world: World | None = None,
) -> tuple[NDArray[np.uint8], float, NDArray[np.float64]]:
    """Render ``obj`` (extruded to ``thickness_mm``) on a white table, seen from above.

    Each pixel averages the light over its area (``config.supersample`` samples per side), as a
    camera's sensor does: edge pixels take grey levels in proportion to the object's cover, which
    is what puts the segmented contour within a fraction of a pixel of the true one.

    Returns:
        ``(grey, mm_per_px, centre_mm)``: the uint8 grey image (dark object on a bright table, with
        Gaussian grey-level noise of std ``config.pixel_noise`` in units of full scale, seeded),
        the scale used on the top face, and the plane point at the image centre.

    ``world`` (optional) is reset and reused, which saves a PyBullet connection per call.
    """
    config = config or PerceptionConfig()
    if not np.isfinite(thickness_mm) or thickness_mm <= 0:
        raise ValueError(f"thickness_mm must be positive and finite, got {thickness_mm!r}")
    n, supersample = config.resolution_px, config.supersample
    low, high = obj.contour.min(axis=0), obj.contour.max(axis=0)
    centre = (low + high) / 2.0
    mm_per_px = image_scale(obj, config)
    own_world = world is None
    world = World() if own_world else world
    try:
        world.reset()
        world.add_table()
        world.add_object(obj, thickness_mm=thickness_mm)
        fine = world.render_top_down(
            centre, n * supersample, mm_per_px / supersample, plane_z_mm=thickness_mm,
            height_mm=_CAMERA_HEIGHT_MM,
        )
    finally:
        if own_world:
            world.close()
    grey = fine.reshape(n, supersample, n, supersample).mean(axis=(1, 3))
    if config.pixel_noise > 0:
        noise = np.random.default_rng(seed).normal(0.0, 255.0 * config.pixel_noise, grey.shape)
        grey = grey + noise
    return np.clip(grey, 0, 255).round().astype(np.uint8), mm_per_px, centre


def image_scale(obj: PlanarObject, config: PerceptionConfig) -> float:
    """The scale (mm/px) ``obj`` is rendered at: ``config.mm_per_px``, or larger if it must be
    to fit the object with the margin."""
    low, high = obj.contour.min(axis=0), obj.contour.max(axis=0)
    needed = float(np.max(high - low)) / (config.resolution_px - 1 - 2 * _MARGIN_PX)
    return max(config.mm_per_px, needed)


@portable(stays_here=("world",))
def perceive(
    obj: PlanarObject, config: PerceptionConfig | None = None, thickness_mm: float = 30.0,
    seed: int = 0, world: World | None = None,
) -> PlanarObject:
    """The object as the camera sees it: render, segment, extract the contour, back to the plane.

    Corners the pixel grid rounded off are restored where two straight edges meet
    (:func:`~grip_env.perception.corners.sharpen_corners`).

    The result keeps ``obj.name``, has ``source="render"`` and lives in the object's plane frame
    (mm). ``world`` (optional) is reset and reused for the rendering.
    """
    config = config or PerceptionConfig()
    grey, mm_per_px, centre = render_mask(obj, config, thickness_mm, seed, world=world)
    coverage = object_coverage(grey, segment(grey))
    n = grey.shape[0]
    contour = contour_from_mask(coverage, mm_per_px) + centre - (n - 1) / 2.0 * mm_per_px
    contour = sharpen_corners(contour, mm_per_px, config)
    return PlanarObject(contour, name=obj.name, source="render")


def object_coverage(grey: NDArray, mask: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Fraction of each pixel covered by the object, in [0, 1], from the grey levels.

    Object and background levels are the medians inside and outside ``mask``; pixels farther
    than one pixel from ``mask`` are background, so other blobs and far noise are ignored.
    """
    grey = np.asarray(grey, dtype=float)
    near = ndimage.binary_dilation(mask, structure=np.ones((3, 3)))
    inside, outside = np.median(grey[mask]), np.median(grey[~near])
    coverage = np.clip((grey - outside) / (inside - outside), 0.0, 1.0)
    return np.where(near, coverage, 0.0)
