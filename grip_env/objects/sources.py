"""Turning a user's object specification (a shape name or a file) into a ``PlanarObject``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from grip_env.objects.planar import PlanarObject
from grip_env.objects.shapes import SHAPE_NAMES, make_shape

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


def object_from_spec(spec: str, mm_per_px: float = 1.0) -> PlanarObject:
    """A named shape, an image file (scaled by ``mm_per_px``), or a vertex file (.json or .csv)."""
    if spec in SHAPE_NAMES:
        return make_shape(spec)
    path = Path(spec)
    if not path.exists():
        raise ValueError(
            f"object {spec!r} is neither a known shape ({', '.join(SHAPE_NAMES)}) nor a file"
        )
    suffix = path.suffix.lower()
    if suffix in IMAGE_SUFFIXES:
        return PlanarObject.from_image(path, mm_per_px, name=path.stem)
    if suffix == ".json":
        return PlanarObject.from_polygon(json.loads(path.read_text()), name=path.stem)
    if suffix == ".csv":
        return PlanarObject.from_polygon(np.loadtxt(path, delimiter=",", ndmin=2), name=path.stem)
    raise ValueError(f"object file {path} has unknown type {suffix!r} (image, .json or .csv)")
