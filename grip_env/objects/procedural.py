"""Seeded procedural planar shapes for large datasets: convex, star-shaped and smooth blobs."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from grip_env.objects.planar import PlanarObject

KINDS = ("convex", "star", "blob")


def random_object(
    seed: int | np.random.SeedSequence,
    size_range_mm: tuple[float, float] = (50.0, 150.0),
    kind: str | None = None,
    name: str | None = None,
) -> PlanarObject:
    """One random object, determined by ``seed``; ``kind`` is drawn when not given."""
    low, high = size_range_mm
    if not (0 < low <= high) or not np.isfinite(high):
        raise ValueError(f"size_range_mm must satisfy 0 < low <= high, got {size_range_mm!r}")
    if kind is not None and kind not in KINDS:
        raise ValueError(f"unknown procedural kind {kind!r}; choose from {', '.join(KINDS)}")
    rng = np.random.default_rng(seed)
    kind = kind or str(rng.choice(KINDS))
    vertices = {"convex": _convex, "star": _star, "blob": _blob}[kind](rng)
    size = rng.uniform(low, high)
    span = np.ptp(vertices, axis=0).max()
    label = name or f"{kind}_{rng.integers(1_000_000):06d}"
    obj = PlanarObject.from_polygon(vertices * size / span, name=label)
    return obj.centred()


def procedural_objects(
    count: int, seed: int = 0, size_range_mm: tuple[float, float] = (50.0, 150.0)
) -> list[PlanarObject]:
    """``count`` random objects; object ``i`` depends only on ``(seed, i)``."""
    if count < 0:
        raise ValueError(f"count must be >= 0, got {count}")
    children = np.random.SeedSequence(seed).spawn(count)
    return [
        random_object(child, size_range_mm, name=f"proc_{seed}_{i:05d}")
        for i, child in enumerate(children)
    ]


def _convex(rng: np.random.Generator) -> NDArray[np.float64]:
    sides = int(rng.integers(3, 9))
    angles = np.sort(rng.uniform(0, 2 * np.pi, sides))
    while np.diff(np.append(angles, angles[0] + 2 * np.pi)).min() < 0.3:
        angles = np.sort(rng.uniform(0, 2 * np.pi, sides))
    stretch = rng.uniform(0.5, 1.0)
    return np.column_stack([np.cos(angles), stretch * np.sin(angles)])


def _star(rng: np.random.Generator) -> NDArray[np.float64]:
    n = int(rng.integers(5, 13))
    angles = 2 * np.pi * (np.arange(n) + rng.uniform(-0.25, 0.25, n)) / n
    radii = rng.uniform(0.45, 1.0, n)
    return radii[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])


def _blob(rng: np.random.Generator, points: int = 96) -> NDArray[np.float64]:
    t = 2 * np.pi * np.arange(points) / points
    radius = np.ones(points)
    for k in range(2, 5):
        radius += rng.uniform(-0.18, 0.18) * np.cos(k * t + rng.uniform(0, 2 * np.pi))
    stretch = rng.uniform(0.55, 1.0)
    return radius[:, None] * np.column_stack([np.cos(t), stretch * np.sin(t)])
