"""The paper's grasping parameters (mu, lambda, W) and the normalisation constants DESIGN fixes."""

from __future__ import annotations

import math

from pydantic import BaseModel, ConfigDict, Field


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
