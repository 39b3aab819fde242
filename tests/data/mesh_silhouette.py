"""Regenerate the mesh silhouettes in this folder from meshes shipped with ``pybullet_data``.

Each mask is the union of a mesh's triangles projected along the mesh's z axis (the axis PyBullet's
own URDFs stand them on: ``teddy_vhacd.urdf`` lays the teddy on its back, so this is its top-down
silhouette at rest), rasterised at pixel centres, the longer side about ``LONG_SIDE_PX`` pixels
with a white margin of 4-5 pixels. Object black (0), table white (255). Usage::

    .venv/bin/python tests/data/mesh_silhouette.py
"""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pybullet_data
from skimage.draw import polygon

LONG_SIDE_PX = 330
MESHES = {"teddy.png": "teddy2_VHACD_CHs.obj", "duck.png": "duck.obj"}


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) and triangles (T, 3, zero-based) of a Wavefront OBJ file (faces fanned)."""
    vertices, triangles = [], []
    for line in path.read_text().splitlines():
        fields = line.split()
        if fields and fields[0] == "v":
            vertices.append([float(x) for x in fields[1:4]])
        elif fields and fields[0] == "f":
            corners = [int(f.split("/")[0]) for f in fields[1:]]
            fan = range(1, len(corners) - 1)
            triangles += [[corners[0], corners[k], corners[k + 1]] for k in fan]
    v, t = np.array(vertices), np.array(triangles)
    return v, np.where(t < 0, len(v) + t, t - 1)


def silhouette(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Binary mask (True = object) of the triangles projected on the mesh's x-y plane."""
    xy = vertices[:, :2] - vertices[:, :2].min(axis=0)
    scale = (LONG_SIDE_PX - 8) / xy.max()
    points = xy * scale + 4.0
    height, width = (np.ceil(points.max(axis=0)) + 5).astype(int)[::-1]
    mask = np.zeros((height, width), dtype=bool)
    for triangle in triangles:
        rows, cols = polygon(height - 1 - points[triangle, 1], points[triangle, 0], mask.shape)
        mask[rows, cols] = True
    return mask


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    for name, mesh in MESHES.items():
        mask = silhouette(*read_obj(Path(pybullet_data.getDataPath()) / mesh))
        iio.imwrite(here / name, np.where(mask, 0, 255).astype(np.uint8))
        print(f"{name}: {mask.shape[1]} x {mask.shape[0]} px, {mask.sum()} object pixels")
