"""Signed curvature of a closed, evenly sampled contour (concave positive)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import gaussian_filter1d


def contour_derivatives(
    points: ArrayLike, sigma_mm: float, spacing_mm: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """First and second derivatives (per sample) of a closed curve smoothed by a Gaussian.

    Returns ``(d1, d2)``, each (M, 2). The curve is smoothed circularly with a normalised Gaussian,
    then differentiated by central differences, which is exact on straight stretches (truncated
    Gaussian-derivative kernels are not: their residual sum leaks position into the derivative).
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3:
        raise ValueError(f"points must have shape (M >= 3, 2), got {pts.shape}")
    if not np.isfinite(sigma_mm) or sigma_mm <= 0:
        raise ValueError(f"sigma_mm must be positive and finite, got {sigma_mm!r}")
    if not np.isfinite(spacing_mm) or spacing_mm <= 0:
        raise ValueError(f"spacing_mm must be positive and finite, got {spacing_mm!r}")
    sigma = sigma_mm / spacing_mm
    smooth = gaussian_filter1d(pts, sigma, axis=0, mode="wrap")
    after, before = np.roll(smooth, -1, axis=0), np.roll(smooth, 1, axis=0)
    return (after - before) / 2.0, after - 2.0 * smooth + before


def signed_curvature(points: ArrayLike, sigma_mm: float, spacing_mm: float) -> NDArray[np.float64]:
    """Curvature (1/mm) of a closed CCW contour sampled every ``spacing_mm``, Gaussian-smoothed
    at scale ``sigma_mm``; positive where the contour is concave, negative where convex.

    A CCW disc of radius R gives about -1/R everywhere.
    """
    d1, d2 = contour_derivatives(points, sigma_mm, spacing_mm)
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    speed = np.hypot(d1[:, 0], d1[:, 1])
    return -cross / np.maximum(speed, 1e-12) ** 3
