"""Occlusion sensitivity (Zeiler and Fergus, 2014): which pixels of an image a model's prediction
depends on. A grey square is slid over the image; each position's drop in the predicted success
is spread over the pixels it hid, and a pixel's value is the mean drop of the squares that hid it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from sklearn.pipeline import Pipeline

from classifiers.learners.grip_images import CHANNELS, GripImages

#: A model of images: (n, C, H, W) -> (n,) scores; or anything with ``predict_proba`` (its
#: column 1, the success probability, is the score).
ImageModel = Callable[[NDArray[np.float32]], NDArray[np.floating]] | Any


def occlusion_maps(model: ImageModel, images: NDArray[np.floating], patch_px: int = 8,
                   stride_px: int = 4, fill: float | Sequence[float] | str = "mean",
                   batch_size: int = 1024) -> NDArray[np.float64]:
    """Per-pixel drop in the predicted success when a ``patch_px`` square around it is greyed,
    (n, H, W); positive where hiding the pixels lowers the score.

    The grey is ``fill``: one value for every channel, one per channel, or ``"mean"``, each
    channel's mean over the image itself (so an image's map does not depend on the others). On
    these sparse pictures a mid grey of 0.5 would add half a contact wherever it lands; the mean
    adds as much as the image's average pixel holds.

    Squares start every ``stride_px`` pixels, and a last one at each far edge, so every pixel is
    hidden by at least one. The model sees at most ``batch_size`` images a call.

    Raises:
        ValueError: images not (n, C, H, W), or a patch, stride or batch size out of range.
    """
    images = np.asarray(images, dtype=np.float32)
    if images.ndim != 4:
        raise ValueError(f"images must be (n, C, H, W), got shape {images.shape}")
    height, width = images.shape[2:]
    if not 1 <= patch_px <= min(height, width):
        raise ValueError(f"patch_px must be within 1..{min(height, width)}, got {patch_px}")
    if stride_px < 1 or batch_size < 1:
        raise ValueError(f"stride_px and batch_size must be positive, got {stride_px}, "
                         f"{batch_size}")
    grey = _grey(fill, images)
    score = _scorer(model)
    hidden = patch_masks(height, width, patch_px, stride_px)  # (P, H, W)
    base = _batched(score, images, batch_size)
    per_image = max(1, batch_size // len(hidden))
    drops = np.empty((len(images), len(hidden)))
    for start in range(0, len(images), per_image):
        part = images[start:start + per_image]
        shade = grey[start:start + len(part), None, :, None, None]
        occluded = np.where(hidden[None, :, None], shade, part[:, None])
        scores = _batched(score, occluded.reshape(-1, *images.shape[1:]), batch_size)
        drops[start:start + len(part)] = base[start:start + len(part), None] - scores.reshape(
            len(part), len(hidden))
    weights = hidden.astype(np.float64)
    return np.einsum("np,phw->nhw", drops, weights) / weights.sum(axis=0)


def grip_occlusion_maps(pipeline: Pipeline, grips: pd.DataFrame, **options: Any
                        ) -> tuple[NDArray[np.float32], NDArray[np.float64]]:
    """The images of ``grips`` and their :func:`occlusion_maps` under a fitted ``pipeline`` that
    draws them with a :class:`~classifiers.learners.grip_images.GripImages` step: the steps after
    it score the occluded images. ``options`` go to :func:`occlusion_maps`.

    Raises:
        ValueError: ``pipeline`` is not a Pipeline with a GripImages step before its model.
    """
    steps = [k for k, (_, step) in enumerate(getattr(pipeline, "steps", []))
             if isinstance(step, GripImages)]
    if not isinstance(pipeline, Pipeline) or not steps or steps[0] == len(pipeline) - 1:
        raise ValueError(f"occlusion of grips needs a Pipeline with a GripImages step before its "
                         f"model, got {type(pipeline).__name__}")
    images = pipeline[:steps[0] + 1].transform(grips)
    return images, occlusion_maps(pipeline[steps[0] + 1:], images, **options)


def map_shares(maps: NDArray[np.floating], images: NDArray[np.floating],
               channels: tuple[str, ...] = CHANNELS) -> pd.DataFrame:
    """Where each map's positive part (pixels whose hiding lowers the predicted success) lies:
    its shares on the contacts' discs, on the fingers' approach (off the discs), on the rest of
    the silhouette, and on the empty ground; one row per image, each row summing to 1 (NaN when
    no pixel lowers the prediction). ``images`` must hold all three :data:`CHANNELS`."""
    missing = [name for name in CHANNELS if name not in channels]
    if missing:
        raise ValueError(f"map_shares needs the channels {missing} in the images")
    layer = {name: np.asarray(images)[:, channels.index(name)] > 0 for name in CHANNELS}
    contacts = layer["contacts"]
    approach = layer["approach"] & ~contacts
    silhouette = layer["silhouette"] & ~contacts & ~approach
    ground = ~(contacts | approach | silhouette)
    positive = np.clip(np.asarray(maps, dtype=np.float64), 0.0, None)
    total = positive.sum(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        shares = {name: (positive * where).sum(axis=(1, 2)) / total for name, where in
                  (("contacts", contacts), ("approach", approach),
                   ("silhouette", silhouette), ("ground", ground))}
    return pd.DataFrame(shares)


def patch_masks(height: int, width: int, patch_px: int, stride_px: int) -> NDArray[np.bool_]:
    """(P, H, W): the pixels each square hides, row by row of positions."""
    rows = _starts(height, patch_px, stride_px)
    cols = _starts(width, patch_px, stride_px)
    inside_rows = (np.arange(height)[None, :] >= rows[:, None]) & \
        (np.arange(height)[None, :] < rows[:, None] + patch_px)
    inside_cols = (np.arange(width)[None, :] >= cols[:, None]) & \
        (np.arange(width)[None, :] < cols[:, None] + patch_px)
    return (inside_rows[:, None, :, None] & inside_cols[None, :, None, :]).reshape(
        -1, height, width)


def _grey(fill: float | Sequence[float] | str, images: NDArray[np.float32]) -> NDArray[np.float32]:
    """(n, C) the grey of each image's channels."""
    if isinstance(fill, str):
        if fill != "mean":
            raise ValueError(f"fill must be a number, one per channel or 'mean', got {fill!r}")
        return images.mean(axis=(2, 3), dtype=np.float64).astype(np.float32)
    grey = np.broadcast_to(np.asarray(fill, dtype=np.float32), images.shape[1:2])
    return np.ascontiguousarray(np.broadcast_to(grey, images.shape[:2]))


def _starts(size: int, patch_px: int, stride_px: int) -> NDArray[np.intp]:
    starts = np.arange(0, size - patch_px + 1, stride_px)
    return np.unique(np.append(starts, size - patch_px))


def _scorer(model: ImageModel) -> Callable[[NDArray[np.float32]], NDArray[np.float64]]:
    if hasattr(model, "predict_proba"):
        return lambda batch: np.asarray(model.predict_proba(batch), dtype=np.float64)[:, 1]
    if callable(model):
        return lambda batch: np.asarray(model(batch), dtype=np.float64).reshape(len(batch))
    raise ValueError(f"the model must be callable or have predict_proba, got "
                     f"{type(model).__name__}")


def _batched(score: Callable[[NDArray[np.float32]], NDArray[np.float64]],
             images: NDArray[np.float32], batch_size: int) -> NDArray[np.float64]:
    return np.concatenate([score(images[start:start + batch_size])
                           for start in range(0, len(images), batch_size)]) \
        if len(images) else np.empty(0)
