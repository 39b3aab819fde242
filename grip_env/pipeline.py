"""``candidates(obj, params)``: the candidate table of an object (public path of
:mod:`grip_env.planning.pipeline`, kept by the design's contract)."""

from grip_env.planning.pipeline import candidates, descriptor_columns

__all__ = ["candidates", "descriptor_columns"]
