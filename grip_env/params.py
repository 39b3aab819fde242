"""The paper's grasping parameters (mu, lambda, W) and the normalisation constants DESIGN fixes.

``DEFAULT_PARAMS`` is the one default instance every module's signature uses.
``CONE_EDGE_TOLERANCE_RAD`` decides the friction-cone edge: a force deviation delta counts as
outside the cone only when delta > arctan(mu) + CONE_EDGE_TOLERANCE_RAD. The thumb search often
lands a force exactly on the edge, where two equivalent computations of delta differ by a rounding
error (about 1e-16 rad); without a margin C1's factor k would flip between 1 and 3 on that noise.
1e-9 rad is far above float64 rounding of angles and far below any angle the search resolves (its
grid step is about 1e-2 rad). Features, ``validate`` (which recomputes them) and the thumb search
all decide the edge with :func:`outside_cone`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field

#: Margin on the friction-cone edge (rad); see the module docstring.
CONE_EDGE_TOLERANCE_RAD = 1e-9


class GraspParams(BaseModel):
    """Parameters of the twelve quality measures.

    Lengths are in millimetres. Out-of-range values raise ``ValueError`` naming the field.

    >>> GraspParams().mu
    0.4
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    mu: float = Field(0.4, gt=0.0, le=2.0, description="assumed minimum finger-object friction")
    lam: float = Field(2.0, gt=0.0, le=50.0, description="positioning error threshold lambda (mm)")
    weight: float = Field(1.0, gt=0.0, le=10.0, description="object weight class W")
    eta: float = Field(101.5, gt=0.0, le=500.0, description="optimal maximum finger extension (mm)")
    rho_scale: float = Field(10.0, gt=0.0, le=1000.0, description="curvature scale for rho (mm)")
    feature_cap: float = Field(100.0, gt=1.0, le=1e6, description="stored for infinite values")

    @property
    def friction_angle(self) -> float:
        """Half-angle of the friction cone, arctan(mu) (rad)."""
        return math.atan(self.mu)


DEFAULT_PARAMS = GraspParams()


def outside_cone(delta: ArrayLike, friction_angle: float) -> NDArray[np.bool_]:
    """Whether deviations ``delta`` (rad) exceed ``friction_angle`` by more than the tolerance."""
    return np.asarray(delta) > friction_angle + CONE_EDGE_TOLERANCE_RAD
