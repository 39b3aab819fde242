"""``candidates(obj, params)``: the candidate table of an object (public path of
:mod:`grip_env.planning.pipeline`, kept by the design's contract).

``candidates`` plans on the object it is given: for a polygon, a mask or an image, its true
outline. ``grip-env generate`` plans on the contour the camera perceives (rendered from above and
segmented, ``perception.source: render``, the default), seeded by the object's place in the run;
:func:`grip_env.dataset.planned_candidates` is that plan, and what ``grip-env show`` and
``grip-env candidates`` plan by default.
"""

from grip_env.planning.pipeline import candidates, descriptor_columns

__all__ = ["candidates", "descriptor_columns"]
