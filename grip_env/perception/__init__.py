"""Perception: from a polygon, a mask or a rendered image to contour, curvature and regions."""

from grip_env.perception.regions import MAX_ABS_RHO, Regions

__all__ = ["MAX_ABS_RHO", "Regions"]
