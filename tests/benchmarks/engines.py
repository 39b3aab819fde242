"""PyBullet beside MuJoCo (run by hand): the analytic cases, and the cost of the same trials.

    python -m tests.benchmarks.engines --cases            # the analytic cases, both engines
    python -m tests.benchmarks.engines --grips 20 --seed 0  # cost on the standard dataset
    python -m tests.benchmarks.engines --grips 20 --servo-peaks  # ... and the arm servos' forces

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

import numpy as np
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


def sampled_work(grips: int, seed: int) -> list[tuple[PlanarObject, pd.DataFrame, Config]]:
    """A seeded sample of the standard dataset's recorded grips (as ``grip-env validate
    --resimulate`` draws it): each object with its picked grips, re-planned, and its config."""
    from grip_env.dataset.resimulation import _as_planned, _sample, kept_grips
    from grip_env.datasets import standard_path

    work = []
    for check in _sample(standard_path(), grips, seed):
        chosen = check.recorded.iloc[list(check.picked)]
        planned = _as_planned(chosen, kept_grips(check.task), check.task.object_id)
        work.append((check.task.obj, planned, check.task.config))
    return work


def cost(grips: int, seed: int, servo_peaks: bool = False) -> None:
    from grip_env.sim import run_trial_outcomes

    work = sampled_work(grips, seed)
    outcomes = {}
    servo_peaks = _record_servo_peaks() if servo_peaks and "mujoco" in ENGINES else []
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
    if servo_peaks:
        peaks = np.array([p for p, _ in servo_peaks])
        print(f"\nMuJoCo's arm servos (x, y, z N; wrist N m), largest force in a trial: median "
              f"{np.round(np.median(peaks, axis=0), 1).tolist()}, max "
              f"{np.round(peaks.max(axis=0), 1).tolist()}; worlds whose servos exceeded their "
              f"force limit: {sum(n for _, n in servo_peaks)} of {len(peaks)}")
    if len(ENGINES) < 2:
        return
    a, b = (outcomes[e] for e in ENGINES)
    print(f"\nsuccess alike in {int((a['success'] == b['success']).sum())} of {len(a)} trials; "
          f"held alike in {int((a['held'] == b['held']).sum())}")
    print(f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()}")


def _record_servo_peaks() -> list[tuple[np.ndarray, int]]:
    """Collect each MuJoCo world's largest arm servo forces and its substeps over the servos'
    force limits when it closes (one world a trial)."""
    from grip_env.sim.mujoco_world import MujocoWorld

    found: list[tuple[np.ndarray, int]] = []
    close = MujocoWorld.close

    def recording_close(world: MujocoWorld) -> None:
        if world._model is not None and len(world.servo_peak_n):
            found.append((world.servo_peak_n.copy(), int(not world.servos_within_limits())))
        close(world)

    MujocoWorld.close = recording_close
    MujocoWorld.watch_servos = True
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", action="store_true")
    parser.add_argument("--grips", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--servo-peaks", action="store_true",
                        help="also record MuJoCo's arm servo forces (costs about a tenth)")
    args = parser.parse_args()
    if args.cases:
        cases()
    if args.grips:
        cost(args.grips, args.seed, args.servo_peaks)


if __name__ == "__main__":
    main()
