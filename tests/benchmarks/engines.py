"""PyBullet beside MuJoCo (run by hand): the analytic cases, and the cost of the same trials.

    python -m tests.benchmarks.engines --cases            # the analytic cases, both engines
    python -m tests.benchmarks.engines --grips 20 --seed 0  # cost on the standard dataset

``--cases`` prints each case's critical load in each engine beside Coulomb's answer
(``grip_env.sim.analytic``). ``--grips`` draws a seeded sample of the standard dataset's recorded
grips (as ``grip-env validate --resimulate`` draws it), runs trial 0 of each (its recorded draw)
in each engine in one process, one engine after the other, and prints the process's CPU time per
trial and per step, the steps, and how many trials the engines judge alike (a side figure on a
few grips: the cross-check of a whole sample is not built yet).
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import platform
import time
from datetime import UTC, datetime

import pandas as pd

from grip_env.config import Config
from grip_env.objects import PlanarObject, load_object_set
from grip_env.planning.pipeline import candidates
from grip_env.sim.analytic import run_cases

ENGINES = ("pybullet", "mujoco")


def held_box_grip(config: Config) -> tuple[PlanarObject, pd.DataFrame]:
    """The default rectangle and its best grip by Q_C at the paper's mu = 0.4."""
    box = next(o for o in load_object_set("default") if o.name == "rectangle")
    config = config.override(grasp={"mu": 0.4})
    return box, candidates(box, config=config).sort_values("Q_C", kind="stable").head(1)


def cases() -> None:
    print("| case | engine | Coulomb | simulated | error | note |")
    print("| --- | --- | --- | --- | --- | --- |")
    box, grip = held_box_grip(Config())
    for r in run_cases(Config(), box, grip, ENGINES):
        print(f"| {r.case} ({r.quantity}) | {r.engine} | {r.analytic:.4g} | {r.simulated:.4g} "
              f"| {r.error:+.2%} | {r.detail} |")


def cost(grips: int, seed: int) -> None:
    from grip_env.dataset.resimulation import _as_planned, _sample, kept_grips
    from grip_env.datasets import standard_path
    from grip_env.sim import run_trial_outcomes

    checks = _sample(standard_path(), grips, seed)
    work = []
    for check in checks:
        chosen = check.recorded.iloc[list(check.picked)]
        planned = _as_planned(chosen, kept_grips(check.task), check.task.object_id)
        work.append((check.task.obj, planned, check.task.config))
    outcomes = {}
    print("| engine | trials | steps | CPU s | ms / trial | µs / step | held | success |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for engine in ENGINES:
        started = time.process_time()
        rows = [run_trial_outcomes(obj, table, config.override(sim={"engine": engine}), trials=1,
                                   seed=config.dataset.seed) for obj, table, config in work]
        seconds = time.process_time() - started
        table = pd.concat(rows, ignore_index=True)
        outcomes[engine] = table
        steps = int(table["steps"].sum())
        print(f"| {engine} | {len(table)} | {steps} | {seconds:.2f} | "
              f"{1e3 * seconds / len(table):.0f} | {1e6 * seconds / steps:.0f} | "
              f"{int(table['held'].sum())} | {int(table['success'].sum())} |")
    a, b = (outcomes[e] for e in ENGINES)
    print(f"\nsuccess alike in {int((a['success'] == b['success']).sum())} of {len(a)} trials; "
          f"held alike in {int((a['held'] == b['held']).sum())}")
    print(f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", action="store_true")
    parser.add_argument("--grips", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.cases:
        cases()
    if args.grips:
        cost(args.grips, args.seed)


if __name__ == "__main__":
    main()
