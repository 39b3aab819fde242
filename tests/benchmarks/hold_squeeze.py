"""How each engine closes on and holds a family's grips, by the force-line measure C1 (run by hand).

    python -m tests.benchmarks.hold_squeeze --family mesh --workers 2

Every grip of the standard dataset's 80-object cross-check sample in ``--family`` runs trial 0
(its recorded draw) in both engines, and the trial's phases are read: how far the close moves the
object in the palm frame, the sum of the hand's normal forces on it after the close and after the
lift and hold, the links touching it then, the drift and turn of the lift, and the robustness.
Printed by engine, and by the tertile of C1 within each object (low: the real finger forces near
the ideal ones).
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import pandas as pd

from tests.benchmarks.engines import ENGINES

SAMPLE = 80
COLUMNS = ["robustness", "held", "close_mm", "close_deg", "squeeze_closed_n", "squeeze_held_n",
           "links_held", "lift_mm", "lift_deg"]


def _checks(family: str) -> list:
    from grip_env.dataset.resimulation import _retest_sample
    from grip_env.datasets import standard_path
    from grip_env.objects.family import object_family

    return [c for c in _retest_sample(standard_path(), SAMPLE, 0)
            if object_family(c.task.obj) == family]


def _read(phase: str, scene: Any, seen: dict[str, Any]) -> None:
    """At the approach, the close and the hold: the object in the palm, the squeeze, the links."""
    if phase in ("approach", "closed", "held"):
        hand, uid = scene.hand.uid, scene.object.uid
        seen[phase] = scene._object_in_palm()
        seen[f"{phase}_n"] = scene.world.contact_normal_force_n(hand, uid)
        seen[f"{phase}_links"] = len(scene.world.touching_links(hand, uid))


def run_object(item: tuple[str, str]) -> list[dict[str, Any]]:
    """Every grip of one object, trial 0, in both engines."""
    from grip_env.sim import pose
    from grip_env.sim.execution import grip_keys, object_key
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import trial_noises

    family, object_id = item
    check = next(c for c in _checks(family) if c.task.object_id == object_id)
    config, obj = check.task.config, check.task.obj
    grips = check.recorded.assign(object_id=object_id).reset_index(drop=True)
    draws = trial_noises(config, config.dataset.seed, object_key(obj, grips), grip_keys(grips),
                         range(1))
    rows = []
    for engine in ENGINES:
        with TrialScene(obj, config.override(sim={"engine": engine})) as scene:
            for k, (plan, noise) in enumerate(zip(grip_plans(grips), draws, strict=True)):
                seen: dict[str, Any] = {}
                result = scene.run(plan, noise[0],
                                   on_phase=lambda p, s, seen=seen: _read(p, s, seen))
                close_mm, close_deg = pose.moved_from(seen["approach"], seen["closed"])
                rows.append({"engine": engine, "object_id": object_id, "grip": k,
                             "C1": float(grips.C1[k]), "robustness": result.robustness_g,
                             "held": result.held, "close_mm": close_mm, "close_deg": close_deg,
                             "squeeze_closed_n": seen["closed_n"],
                             "squeeze_held_n": seen["held_n"], "links_held": seen["held_links"],
                             "lift_mm": result.drift_mm, "lift_deg": result.rotation_deg})
    return rows


def family_table(doc: str, run: Callable[[tuple[str, str]], list[dict[str, Any]]],
                 ) -> tuple[pd.DataFrame, str]:
    """Parse ``--family``, ``--workers``, ``--out`` and ``--converged``, run ``run`` on every
    object of the family (in a process pool) and return its rows (kept in ``--out``) and the
    family."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--family", default="mesh")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", help="a Parquet file of every trial's row")
    parser.add_argument("--converged", action="store_true",
                        help="MuJoCo at the converged integration of tests.benchmarks."
                             "mujoco_lean (16 substeps, NoSlip 20, Newton 200 at 1e-10)")
    args = parser.parse_args()
    if args.converged:  # the workers fork from here and keep the patch
        from tests.benchmarks import mujoco_lean

        mujoco_lean.apply(mujoco_lean.settings(mujoco_lean.reference_of("lean")))
    items = [(args.family, c.task.object_id) for c in _checks(args.family)]
    with ProcessPoolExecutor(args.workers) as pool:
        table = pd.DataFrame([row for rows in pool.map(run, items) for row in rows])
    if args.out:
        table.to_parquet(args.out)
    return table, args.family


def main() -> None:
    table, family = family_table(__doc__, run_object)
    table["C1 tertile"] = table.groupby(["object_id", "engine"]).C1.transform(
        lambda v: pd.qcut(v.rank(method="first"), 3, labels=["low", "mid", "high"]))
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(f"{table.object_id.nunique()} {family} objects, {len(table) // 2} grips")
        print(table.groupby("engine")[COLUMNS].mean().round(2).to_string())
        print(table.groupby(["C1 tertile", "engine"], observed=True)[COLUMNS].mean().round(2)
              .to_string())


if __name__ == "__main__":
    main()
