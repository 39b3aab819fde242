"""Named planar shapes and the object sets built from them (sizes fit the Barrett hand)."""

from __future__ import annotations

import difflib
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from grip_env.config import ObjectsConfig
from grip_env.objects.meshes import MESH_SET_NAMES
from grip_env.objects.planar import PlanarObject

Vertices = NDArray[np.float64]


def rectangle(width: float, height: float) -> Vertices:
    """Axis-aligned rectangle centred at the origin."""
    w, h = width / 2, height / 2
    return np.array([[-w, -h], [w, -h], [w, h], [-w, h]])


def regular_polygon(sides: int, radius: float, phase: float = 0.0) -> Vertices:
    """Regular polygon with the given circumradius."""
    angles = phase + 2 * np.pi * np.arange(sides) / sides
    return radius * np.column_stack([np.cos(angles), np.sin(angles)])


def ellipse(a: float, b: float, points: int = 96) -> Vertices:
    """Ellipse with semi-axes a (x) and b (y), sampled at ``points`` vertices."""
    t = 2 * np.pi * np.arange(points) / points
    return np.column_stack([a * np.cos(t), b * np.sin(t)])


def star(tips: int, outer: float, inner: float) -> Vertices:
    """Star polygon alternating outer and inner radii."""
    angles = np.pi / 2 + np.pi * np.arange(2 * tips) / tips
    radii = np.where(np.arange(2 * tips) % 2 == 0, outer, inner)
    return np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])


def greek_cross(arm_width: float, span: float) -> Vertices:
    """A cross of four equal arms ``arm_width`` wide, ``span`` from tip to opposite tip, centred
    at the origin with its arms along the axes."""
    if not 0 < arm_width < span:
        raise ValueError(f"a cross needs 0 < arm_width < span, got {arm_width} and {span}")
    h, r = arm_width / 2, span / 2
    return np.array([[-h, -r], [h, -r], [h, -h], [r, -h], [r, h], [h, h], [h, r], [-h, r],
                     [-h, h], [-r, h], [-r, -h], [-h, -h]], dtype=float)


def rounded_rectangle(width: float, height: float, radius: float, arc_points: int = 8) -> Vertices:
    """Rectangle with circular corners of the given radius."""
    w, h = width / 2 - radius, height / 2 - radius
    corners = [(w, -h, -np.pi / 2), (w, h, 0.0), (-w, h, np.pi / 2), (-w, -h, np.pi)]
    t = np.linspace(0, np.pi / 2, arc_points)
    arcs = [np.column_stack([cx + radius * np.cos(a0 + t), cy + radius * np.sin(a0 + t)])
            for cx, cy, a0 in corners]
    return np.vstack(arcs)


_SHAPES: dict[str, Callable[[], Vertices]] = {
    "rectangle": lambda: rectangle(90, 55),
    "square": lambda: rectangle(65, 65),
    "triangle": lambda: regular_polygon(3, 55, np.pi / 2),
    "right_triangle": lambda: np.array([[0, 0], [100, 0], [0, 65]], dtype=float),
    "trapezoid": lambda: np.array([[-55, -30], [55, -30], [30, 30], [-30, 30]], dtype=float),
    "parallelogram": lambda: np.array([[-50, -25], [35, -25], [50, 25], [-35, 25]], dtype=float),
    "pentagon": lambda: regular_polygon(5, 45, np.pi / 2),
    "hexagon": lambda: regular_polygon(6, 42),
    "l_shape": lambda: np.array(
        [[0, 0], [100, 0], [100, 40], [40, 40], [40, 110], [0, 110]], dtype=float),
    "t_shape": lambda: np.array(
        [[-18, -60], [18, -60], [18, 20], [55, 20], [55, 55], [-55, 55], [-55, 20], [-18, 20]],
        dtype=float),
    "cross": lambda: greek_cross(36, 110),
    "star": lambda: star(5, 65, 32),
    "notched_rectangle": lambda: np.array(
        [[-50, -30], [50, -30], [50, 30], [12, 30], [12, 12], [-12, 12], [-12, 30], [-50, 30]],
        dtype=float),
    "rounded_rectangle": lambda: rounded_rectangle(100, 60, 12),
    "ellipse": lambda: ellipse(55, 35),
    "disc": lambda: ellipse(38, 38, points=72),
    "u_shape": lambda: np.array(
        [[-50, -40], [50, -40], [50, 40], [25, 40], [25, -10], [-25, -10], [-25, 40], [-50, 40]],
        dtype=float),
    "bean": lambda: _bean(),
}


def _bean(points: int = 96) -> Vertices:
    """A kidney shape: an ellipse with a smooth concave dent on one long side."""
    t = 2 * np.pi * np.arange(points) / points
    x, y = 60 * np.cos(t), 35 * np.sin(t)
    y = y - 22 * np.exp(-((x / 25) ** 2)) * (np.sin(t) > 0)
    return np.column_stack([x, y])


SHAPE_NAMES: tuple[str, ...] = tuple(_SHAPES)

OBJECT_SETS: dict[str, tuple[str, ...]] = {
    "default": SHAPE_NAMES,
    "basic": ("rectangle", "triangle", "hexagon", "l_shape"),
}


def make_shape(name: str) -> PlanarObject:
    """One named shape, centred on its centroid."""
    if name not in _SHAPES:
        raise ValueError(f"unknown shape {name!r}; known shapes: {', '.join(SHAPE_NAMES)}")
    return PlanarObject.from_polygon(_SHAPES[name](), name=name).centred()


#: Loads a named set built above the geometry layer: ``(seed, objects config) -> objects``.
SetLoader = Callable[[int, ObjectsConfig | None], list[PlanarObject]]
_SET_LOADERS: dict[str, SetLoader] = {}


def register_object_set(name: str, loader: SetLoader) -> None:
    """Let :func:`load_object_set` load set ``name`` with ``loader`` (the mesh sets are
    registered by :mod:`grip_env.mesh_sets`, which ``import grip_env`` loads)."""
    _SET_LOADERS[name] = loader


def load_object_set(
    name: str = "default", seed: int = 0, config: ObjectsConfig | None = None
) -> list[PlanarObject]:
    """The objects of a named set, or the one object of a shape name.

    Sets: ``default`` (every named shape, ``SHAPE_NAMES``), ``basic``, and the sets of
    ``pybullet_data`` meshes (``MESH_SET_NAMES``): ``household``, ``random_urdfs`` (about 1,000
    meshes: minutes) and ``mesh`` (both). A mesh object is the silhouette of the mesh at rest on
    the table in PyBullet, sized in ``config.mesh_size_mm`` by ``seed`` (the run seed) as in a
    dataset; a mesh that does not rest stably or whose silhouette has several parts is skipped
    with a logged warning (:func:`grip_env.mesh_sets.mesh_set` lists them).

    Raises:
        ValueError: an unknown name.
    """
    if name in OBJECT_SETS:
        return [make_shape(shape) for shape in OBJECT_SETS[name]]
    if name in _SHAPES:
        return [make_shape(name)]
    if name in _SET_LOADERS:
        return _SET_LOADERS[name](seed, config)
    known = (*OBJECT_SETS, *MESH_SET_NAMES)
    close = difflib.get_close_matches(str(name), [*known, *SHAPE_NAMES], n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise ValueError(f"unknown object set {name!r}{hint} (sets: {', '.join(known)}, or a "
                     "shape name)")
