"""Grasping regions: short straight stretches of the contour where a finger can be placed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

MAX_ABS_RHO = 1.0 / 3.0  # DESIGN: regions with |rho| above this are not grasping regions


@dataclass(frozen=True)
class Regions:
    """R grasping regions of one object, in contour (counter-clockwise) order.

    Attributes:
        a, b: (R, 2) straight-segment endpoints (mm); walking from ``a`` to ``b`` follows the
            contour counter-clockwise, so the object lies to the left.
        normal: (R, 2) unit inward normal of each segment.
        rho: (R,) mean signed curvature over the region times ``rho_scale`` (concave positive).
    """

    a: NDArray[np.float64]
    b: NDArray[np.float64]
    normal: NDArray[np.float64]
    rho: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.a)

    @property
    def length(self) -> NDArray[np.float64]:
        """(R,) segment lengths (mm)."""
        return np.linalg.norm(self.b - self.a, axis=1)

    @property
    def direction(self) -> NDArray[np.float64]:
        """(R, 2) unit tangents from ``a`` to ``b``."""
        return (self.b - self.a) / self.length[:, None]

    def point(self, index: NDArray[np.int_], t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Points at fraction ``t`` along regions ``index``."""
        return self.a[index] + t[..., None] * (self.b[index] - self.a[index])

    @classmethod
    def empty(cls) -> Regions:
        """No regions."""
        z = np.zeros((0, 2))
        return cls(z, z.copy(), z.copy(), np.zeros(0))
