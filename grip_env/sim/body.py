"""``Body``: a body in a world of any engine, and the unit the engines convert to (``MM``).

Geometry crosses the simulation layer in millimetres; metres exist only inside an engine's
module (``grip_env.sim.world``, ``grip_env.sim.mujoco_world``).
"""

from __future__ import annotations

from dataclasses import dataclass

MM = 1e-3  # metres per millimetre


@dataclass(frozen=True)
class Body:
    """A body in a world: its id, the height of its top face (mm), its link ids.

    ``inertia_per_kg`` is the principal inertia of the whole body per kilogram (m²), so a new
    mass rescales it exactly; ``links`` lists every link id of the body (-1 is the base).
    """

    uid: int
    top_mm: float
    links: tuple[int, ...] = (-1,)
    inertia_per_kg: tuple[float, float, float] = (0.0, 0.0, 0.0)
