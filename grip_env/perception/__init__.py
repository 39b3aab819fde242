"""Perception: from a polygon, a mask or a rendered image to contour, curvature and regions."""

from grip_env.objects.masks import contour_from_mask, mask_from_image_file, segment
from grip_env.perception.contour import resample_contour
from grip_env.perception.curvature import signed_curvature
from grip_env.perception.regions import MAX_ABS_RHO, Regions, find_regions
from grip_env.perception.render import contour_error_mm, perceive, render_mask

__all__ = [
    "MAX_ABS_RHO",
    "Regions",
    "contour_error_mm",
    "contour_from_mask",
    "find_regions",
    "mask_from_image_file",
    "perceive",
    "render_mask",
    "resample_contour",
    "segment",
    "signed_curvature",
]
