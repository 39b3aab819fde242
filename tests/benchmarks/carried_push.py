"""The pushed block with a second push across the first: Coulomb's circle against a box of
friction (run by hand; issue 45).

    python -m tests.benchmarks.carried_push --carried 0 0.6

``grip_env.sim.analytic.pushed_block`` with one load more: the block on the table (mu 0.4) is
pushed along y by ``carried`` times mu m g throughout, and along x by a push raised to the slip.
That is a held grip's contact under the ramp: its friction carries one load (the object's
weight) while the disturbance loads it across. Coulomb's law bounds the two together, so the
x push at slip is ``sqrt(1 - carried^2)`` times mu m g (0.8 at 0.6); friction bounded in each
direction alone (a box, or a pyramid) leaves it at mu m g. MuJoCo's elliptic cone is the circle;
this measures which PyBullet's lateral friction is.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import time

import numpy as np

from grip_env.config import Config
from grip_env.sim import analytic


def carried_push(config: Config, carried: float, mu: float = 0.4) -> float:
    """The x push (in mu m g) at which the block slides, pushed along y by ``carried`` mu m g."""
    weight = analytic.BLOCK_KG * analytic.GRAVITY
    across = carried * mu * weight

    def slides(pushes: float) -> bool:
        world, uid = analytic._block_world(config, mu)
        try:
            def load() -> None:
                world.push(uid, np.array([pushes * mu * weight, across, 0.0]))
            return analytic._slides(world, uid, load, config.sim.timestep)
        finally:
            world.close()

    return analytic.critical_load(slides, 0.1, 1.5)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--carried", type=float, nargs="+", default=[0.0, 0.6])
    args = parser.parse_args()
    print("| engine | carried (of mu m g) | x push at slip (of mu m g) | Coulomb circle | box "
          "| CPU s |")
    print("| --- " * 6 + "|")
    for engine in ("pybullet", "mujoco"):
        config = Config().override(sim={"engine": engine})  # as ``engines --cases``
        for carried in args.carried:
            started = time.process_time()
            found = carried_push(config, carried)
            print(f"| {engine} | {carried:.2f} | {found:.4f} | {np.sqrt(1 - carried**2):.4f} "
                  f"| 1.0000 | {time.process_time() - started:.1f} |", flush=True)


if __name__ == "__main__":
    main()
