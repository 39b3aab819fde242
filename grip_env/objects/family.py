"""The family an object comes from, the unit a family-holdout evaluation holds out whole."""

from __future__ import annotations

import re

from grip_env.objects.planar import PlanarObject
from grip_env.objects.shapes import SHAPE_NAMES

#: ``named``: the hand-drawn shapes; ``procedural``: seeded random shapes; ``mesh``: resting
#: silhouettes of meshes; ``file``: the user's images or vertex files; ``polygon``: any other.
FAMILIES = ("named", "procedural", "mesh", "file", "polygon")
_PROCEDURAL = re.compile(r"^(proc_\d+_\d+|(convex|star|blob)_\d{6})$")


def object_family(obj: PlanarObject) -> str:
    """The object's family (one of ``FAMILIES``)."""
    if obj.mesh is not None:
        return "mesh"
    if obj.source not in ("polygon", "mask"):
        return "file"
    if obj.name in SHAPE_NAMES:
        return "named"
    if _PROCEDURAL.match(obj.name):
        return "procedural"
    return "polygon"
