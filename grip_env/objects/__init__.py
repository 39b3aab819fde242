"""Planar objects: polygons, masks and images; named sets and procedural shapes."""

from grip_env.objects.planar import PlanarObject, polygon_moments
from grip_env.objects.procedural import procedural_objects, random_object
from grip_env.objects.shapes import OBJECT_SETS, SHAPE_NAMES, load_object_set, make_shape
from grip_env.objects.sources import object_from_spec

__all__ = [
    "OBJECT_SETS",
    "SHAPE_NAMES",
    "PlanarObject",
    "load_object_set",
    "make_shape",
    "object_from_spec",
    "polygon_moments",
    "procedural_objects",
    "random_object",
]
