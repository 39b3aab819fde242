"""Occlusion sensitivity (Zeiler and Fergus, 2014): which pixels of an image a model's prediction
depends on. A grey square is slid over the image; each position's drop in the predicted success
is spread over the pixels it hid, and a pixel's value is the mean drop of the squares that hid it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: A model of images: (n, C, H, W) -> (n,) scores; or anything with ``predict_proba`` (its
#: column 1, the success probability, is the score).
ImageModel = Callable[[NDArray[np.float32]], NDArray[np.floating]] | Any


def occlusion_maps(model: ImageModel, images: NDArray[np.floating], patch_px: int = 8,
                   stride_px: int = 4, fill: float = 0.5, batch_size: int = 1024
                   ) -> NDArray[np.float64]:
    """Per-pixel drop in the predicted success when a ``patch_px`` square around it is set to
    ``fill`` in every channel, (n, H, W); positive where hiding the pixels lowers the score.

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
    score = _scorer(model)
    hidden = patch_masks(height, width, patch_px, stride_px)  # (P, H, W)
    base = _batched(score, images, batch_size)
    per_image = max(1, batch_size // len(hidden))
    drops = np.empty((len(images), len(hidden)))
    for start in range(0, len(images), per_image):
        part = images[start:start + per_image]
        occluded = np.where(hidden[None, :, None], np.float32(fill), part[:, None])
        scores = _batched(score, occluded.reshape(-1, *images.shape[1:]), batch_size)
        drops[start:start + len(part)] = base[start:start + len(part), None] - scores.reshape(
            len(part), len(hidden))
    weights = hidden.astype(np.float64)
    return np.einsum("np,phw->nhw", drops, weights) / weights.sum(axis=0)


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
