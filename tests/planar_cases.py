"""What the planning tests share: flat regions on a polygon's sides, and a shape moved rigidly."""

from __future__ import annotations

import math
from typing import NamedTuple

from hypothesis import strategies as st

from grip_env.objects import PlanarObject, make_shape
from grip_env.perception.regions import Regions


def side_regions(obj: PlanarObject, inset: float = 3.0) -> Regions:
    """One region per polygon side, inset from the corners, flat (rho = 0)."""
    return Regions.from_polygon_sides(obj.contour, inset)


def cross(u, v):
    """The z component of the cross product of (..., 2) vectors."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


class Motion(NamedTuple):
    """A shape, the same shape turned by ``angle`` (rad) about the origin then shifted by
    ``offset`` (mm), and the motion itself."""

    obj: PlanarObject
    moved: PlanarObject
    angle: float
    offset: tuple[float, float]


@st.composite
def rigid_motions(draw: st.DrawFn, shapes: tuple[str, ...], reach: float) -> Motion:
    """One of the named ``shapes``, moved by any angle and by up to ``reach`` mm along each axis."""
    obj = make_shape(draw(st.sampled_from(shapes)))
    angle = draw(st.floats(-math.pi, math.pi))
    offset = draw(st.tuples(st.floats(-reach, reach), st.floats(-reach, reach)))
    return Motion(obj, obj.transformed(angle, offset), angle, offset)
