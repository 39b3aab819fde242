"""The fingertip's rubber pad as a compliant contact: its stiffness and its damping.

The paper's hand has rubber-covered fingers (its mu >= 0.4 is rubber's). A rubber fingertip
pressed on a rigid side deforms like a Hertz contact, ``F = 4/3 E* sqrt(R) d^(3/2)`` with
``E* = E / (1 - nu^2)``; the simulator linearises it at the fingertip force, whose tangent
stiffness is ``dF/dd = 3/2 F / d``. Its damping is rubber's loss factor at the pad's natural
frequency with the object it holds, ``c = eta * sqrt(k m)``. Sources and figures: BENCHMARKS.md,
"The simulator's constants and where they come from".
"""

from __future__ import annotations

import math

#: Young's modulus of the pad's rubber (Pa): natural rubber of Shore hardness about 55 A, 3 MPa by
#: Gent's relation between Shore A hardness and modulus (Gent, *Engineering with Rubber*).
RUBBER_MODULUS_PA = 3.0e6
RUBBER_POISSON = 0.5  #: rubber is nearly incompressible
#: Loss factor of natural rubber at room temperature and tens of hertz (textbook range 0.1-0.3).
RUBBER_LOSS_FACTOR = 0.2


def hertz_stiffness(modulus_pa: float, radius_m: float, force_n: float,
                    poisson: float = RUBBER_POISSON) -> float:
    """Tangent stiffness (N/m) of a Hertz contact of a sphere of ``radius_m`` pressing a rigid
    flat with ``force_n``, the sphere's material of Young's modulus ``modulus_pa``.

    Raises:
        ValueError: a modulus, radius or force that is not positive, or a Poisson ratio outside
            [0, 0.5].
    """
    for name, value in (("modulus_pa", modulus_pa), ("radius_m", radius_m),
                        ("force_n", force_n)):
        if not value > 0:
            raise ValueError(f"{name} must be positive, got {value!r}")
    if not 0.0 <= poisson <= 0.5:
        raise ValueError(f"poisson must lie in [0, 0.5], got {poisson!r}")
    reduced = modulus_pa / (1.0 - poisson**2)
    depth = (3.0 * force_n / (4.0 * reduced * math.sqrt(radius_m))) ** (2.0 / 3.0)
    return 1.5 * force_n / depth


def loss_damping(stiffness_n_per_m: float, mass_kg: float,
                 loss_factor: float = RUBBER_LOSS_FACTOR) -> float:
    """Viscous damping (N s/m) with ``loss_factor`` at the natural frequency of a pad of
    ``stiffness_n_per_m`` against ``mass_kg``: ``eta * k / omega = eta * sqrt(k m)``.

    Raises:
        ValueError: a stiffness or mass that is not positive, or a negative loss factor.
    """
    if not stiffness_n_per_m > 0 or not mass_kg > 0:
        raise ValueError(f"stiffness and mass must be positive, got {stiffness_n_per_m!r}, "
                         f"{mass_kg!r}")
    if not loss_factor >= 0:
        raise ValueError(f"loss_factor must be >= 0, got {loss_factor!r}")
    return loss_factor * math.sqrt(stiffness_n_per_m * mass_kg)
