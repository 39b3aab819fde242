"""How far a pressed fingertip gives under a sideways load below its friction bound (run by hand).

    python -m tests.benchmarks.pad_shear

The uncut block of ``analytic.tip_across_seam``: the hand's fingertip pad (its sphere, friction,
torsion and rubber) pressed with ``SQUEEZE_N`` on a face and loaded along it with a share of mu F
that it holds, ramped in over ``RAMP_S`` and held; the tip's move along the face relative to the
block, after the ramp and at the end, in each engine. By Coulomb's law a contact below its bound
does not slip at all; a rubber pad shears elastically (Mindlin: a tangential stiffness of
2 (1 - nu) / (2 - nu) of the normal one, 2/3 for rubber's nu = 0.5), so it gives share x mu F
/ (2/3 k) and then stays.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

from dataclasses import replace

import numpy as np

from grip_env.config import Config
from grip_env.sim import analytic, pose
from grip_env.sim.engine import make_world
from tests.benchmarks.engines import ENGINES

MU = 0.4
SHARES = (0.25, 0.5, 0.75, 0.9)
HOLD_S = 1.0
#: Mindlin's tangential over normal stiffness of an elastic contact, at rubber's Poisson ratio.
MINDLIN = 2 * (1 - 0.5) / (2 - 0.5)


def shear_mm(engine: str, share: float) -> tuple[float, float]:
    """The tip's move (mm) along the face after the ramp and after ``HOLD_S`` more."""
    sim = Config().override(sim={"engine": engine}).sim
    world = make_world(sim)
    try:
        block = analytic.seam_block(cut=False)
        body = world.add_object(block, analytic.BLOCK_THICKNESS_MM, analytic.SEAM_BLOCK_KG,
                                friction=MU, tolerance_mm=0.0)
        depth = analytic.SQUEEZE_N / sim.pad_stiffness_n_per_m * 1e3
        x, y = analytic.SEAM_POINT_MM
        tip = world.add_sphere(analytic.PAD_RADIUS_MM, analytic.FINGERTIP_KG, 1.0,
                               np.array([x - 10.0, y + analytic.PAD_RADIUS_MM - depth,
                                         analytic.BLOCK_THICKNESS_MM / 2]),
                               analytic.FINGERTIP_INERTIA_KG_M2)
        body = replace(body, inertia_per_kg=tuple(analytic.SEAM_BLOCK_TURN_INERTIA * i
                                                  for i in body.inertia_per_kg))
        world.set_dynamics(body, analytic.SEAM_BLOCK_KG, MU)  # turning as if 1000 times heavier
        world.set_pad_friction(tip.uid, -1, 1.0, sim.pad_torsion_mm)
        world.set_contact_compliance(tip.uid, -1, sim.pad_stiffness_n_per_m,
                                     sim.pad_damping_n_s_per_m)
        world.set_gravity((0.0, 0.0, 0.0))

        def along() -> float:
            return pose.in_frame(*world.pose_floats_mm(body.uid),
                                 *world.pose_floats_mm(tip.uid))[0][0]

        def run(seconds: float, load: float) -> None:
            for step in range(round(seconds / sim.timestep)):
                ramp = min(1.0, (step + 1) * sim.timestep / analytic.RAMP_S) if load else 0.0
                force = np.array([ramp * load * MU, -1.0, 0.0]) * analytic.SQUEEZE_N
                world.push(tip.uid, force)
                world.push(body.uid, -force)
                world.step()

        run(analytic.TWIST_SETTLE_S, 0.0)
        start = along()
        run(analytic.RAMP_S, share)
        ramped = along() - start
        run(HOLD_S, share)
        return ramped, along() - start
    finally:
        world.close()


def main() -> None:
    k = Config().sim.pad_stiffness_n_per_m
    print("| share of mu F | Mindlin's elastic shear (mm) | " + " | ".join(
        f"{e} after the ramp / after {HOLD_S:g} s more (mm)" for e in ENGINES) + " |")
    print("| --- | --- | " + " | ".join("---" for _ in ENGINES) + " |")
    for share in SHARES:
        elastic = share * MU * analytic.SQUEEZE_N / (MINDLIN * k) * 1e3
        moves = [shear_mm(e, share) for e in ENGINES]
        print(f"| {share:g} | {elastic:.3f} | " + " | ".join(
            f"{a:.3f} / {b:.3f}" for a, b in moves) + " |")


if __name__ == "__main__":
    main()
