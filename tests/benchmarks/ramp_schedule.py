"""What the ramp's order of directions costs (run by hand; issue 45 item 4).

    python -m tests.benchmarks.ramp_schedule --grips 60 --engine mujoco

The ramp (``grip_env.sim.disturbance.robustness``) raises one direction after another, each up
to the weakest level found so far. Every direction must hold every level below the weakest, so
that much is needed in any order; what an order adds is the levels that directions ramped before
the weakest one climb past it. This runs trial 0 of the seeded sample of standard grips that
``tests.benchmarks.engines --grips`` draws with every direction raised to the ceiling
(``crosscheck_directions.every_direction``), and counts, per trial, the levels the protocol's
order attempts against the fewest any order could (every direction up to the weakest level, and
one failing level): the most a schedule that raises all directions level by level
could save. Levels, not steps: a level lasts from ``sim.ramp_steps_per_level`` steps on.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse

import numpy as np

import grip_env.sim.trial as trial_module
from grip_env.sim import run_trial_outcomes
from tests.benchmarks.crosscheck_directions import every_direction
from tests.benchmarks.engines import sampled_work


def attempted_levels(held: list[int], ceiling: int) -> tuple[int, int]:
    """(levels the protocol's order attempts, the fewest any order attempts) for one trial whose
    directions, in the protocol's order, hold ``held`` levels each (``ceiling`` when all)."""
    weakest, protocol = ceiling, 0
    for count in held:
        protocol += min(count + 1, weakest)  # the failing level too, unless capped
        weakest = min(weakest, count)
    fewest = len(held) * weakest + (weakest < ceiling)  # every direction to the weakest level
    return protocol, fewest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grips", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--engine", default="mujoco", choices=("pybullet", "mujoco"))
    args = parser.parse_args()
    found: list[dict[str, float]] = []
    trial_module.robustness = every_direction(found)
    work = sampled_work(args.grips, args.seed)
    from grip_env.sim.disturbance import ramp_levels

    levels = ramp_levels(work[0][2].sim)
    counts = []
    for obj, table, config in work:
        start = len(found)
        run_trial_outcomes(obj, table, config.override(sim={"engine": args.engine}), trials=1,
                           seed=config.dataset.seed)
        for held in found[start:]:  # held trials only (the ramp runs when held)
            index = [int(np.searchsorted(levels, g, side="right")) for g in held.values()]
            counts.append(attempted_levels(index, len(levels)))
    protocol, fewest = np.array(counts).sum(axis=0)
    print(f"{args.engine}: {len(counts)} held trials; levels attempted in the protocol's order "
          f"{protocol}, fewest in any order {fewest}: an order could save "
          f"{1 - fewest / protocol:.1%} of the ramp's levels")


if __name__ == "__main__":
    main()
