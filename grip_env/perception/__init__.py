"""Perception: from an object's contour (a polygon, a mask, the camera's segmented render:
:mod:`grip_env.sim.camera`) to curvature and grasping regions."""

from grip_env.objects.masks import contour_from_mask, mask_from_image_file, segment
from grip_env.perception.contour import contour_error_mm, resample_contour
from grip_env.perception.curvature import signed_curvature
from grip_env.perception.regions import MAX_ABS_RHO, Regions, find_regions

__all__ = [
    "MAX_ABS_RHO",
    "Regions",
    "contour_error_mm",
    "contour_from_mask",
    "find_regions",
    "mask_from_image_file",
    "resample_contour",
    "segment",
    "signed_curvature",
]
