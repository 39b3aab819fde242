"""MuJoCo's pads and worm-gear stops, measured (run by hand; issue 45, label model
``mujoco-2026.12-pads``).

    python -m tests.benchmarks.mujoco_pads fidelity  # the faithfulness table, both engines
    python -m tests.benchmarks.mujoco_pads impedance 0.01 0.1 0.3 0.9  # the held box
    python -m tests.benchmarks.mujoco_pads substeps 2 3 4 5 8 12 --grips 60  # convergence

``fidelity`` runs one zero-noise trial of each default object's three best grips by Q_C (the
trials of ``tests/test_engine_fidelity.py``) and prints the closes settled, every finger touching,
the largest slip of a loaded flexion joint below its worm-gear floor after the hold, the median
sum of the pads' normal forces after the close, held and successes. ``impedance`` runs the held
box (``tests.benchmarks.engines.held_box_grip``) with each pad impedance (``PAD_IMPEDANCE``
patched) and prints each pad's force over depth after the hold, the object's speed then and the
outcome. ``substeps`` runs trial 0 of a seeded sample of the standard dataset's grips (as
``tests.benchmarks.engines --grips`` draws them) in MuJoCo with the physics step split into each
number of substeps (``PAD_PHASE_PER_STEP`` patched), and prints each count's outcomes against
the finest count's and its CPU cost a trial and a protocol step.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import math
import time

import mujoco
import numpy as np
import pandas as pd
from scipy import stats

import grip_env.sim.mujoco_world as mujoco_world
from grip_env.config import Config
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import TrialNoise
from tests.benchmarks.engines import held_box_grip


def fidelity(engine: str) -> str:
    """One markdown row of the faithfulness table for ``engine``."""
    from tests.benchmarks.sim_fidelity import best_grip_trials

    touching, slips, squeeze = [], [], []

    def on_phase(name: str, scene: TrialScene) -> None:
        if name == "closed":
            touching.append(bool(scene.hand.touching(scene.object.uid).any(axis=1).all()))
            squeeze.append(scene.world.contact_normal_force_n(scene.hand.uid, scene.object.uid))
        if name == "held":
            q, _ = scene.hand.joint_states()
            slips.append(1e3 * float((np.reshape(scene.hand.state().peak, (3, 2)) - q).max()))

    config = Config().override(sim={"engine": engine})
    results = best_grip_trials(config, on_phase)
    settled = sum(r.close_steps < config.sim.max_close_steps for r in results)
    return (f"| {engine} | {settled} of {len(results)} | {sum(touching)} of {len(touching)} | "
            f"{max(slips):.2f} mrad | {np.median(squeeze):.1f} N | "
            f"{sum(r.held for r in results)} / {sum(r.success for r in results)} |")


def impedance(values: list[float]) -> None:
    config = Config().override(sim={"engine": "mujoco"})
    box, grip = held_box_grip(config)
    for value in values:
        mujoco_world.PAD_IMPEDANCE = value
        found: list[str] = []

        def watch(name: str, scene: TrialScene, found: list[str] = found) -> None:
            if name != "held":
                return
            world = scene.world
            m, d, wrench = world._model, world._data, np.empty(6)
            for i, contact in enumerate(d.contact[: d.ncon]):
                owners = set(world._body_uid[m.geom_bodyid[[contact.geom1, contact.geom2]]]
                             .tolist())
                if owners == {scene.hand.uid, scene.object.uid}:
                    mujoco.mj_contactForce(m, d, i, wrench)
                    found.append(f"{wrench[0] / -contact.dist / 1e3:.1f} kN/m at "
                                 f"{-1e3 * contact.dist:.2f} mm")
            speed = np.linalg.norm(d.cvel[world._body_id(scene.object.uid, -1)][3:])
            found.append(f"object at {1e3 * speed:.1f} mm/s")

        with TrialScene(box, config) as scene:
            result = scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0),
                               on_phase=watch)
        print(f"| {value} | {'; '.join(found)} | {result.describe()} |")


def substeps(counts: list[int], grips: int, seed: int) -> None:
    from grip_env.dataset.resimulation import _as_planned, _sample, kept_grips
    from grip_env.datasets import standard_path
    from grip_env.sim import run_trial_outcomes

    work = []
    for check in _sample(standard_path(), grips, seed):
        chosen = check.recorded.iloc[list(check.picked)]
        work.append((check.task.obj, _as_planned(chosen, kept_grips(check.task),
                                                 check.task.object_id), check.task.config))
    sim = Config().sim
    phase = math.sqrt(sim.pad_stiffness_n_per_m / mujoco_world.PAD_REFERENCE_MASS_KG) * (
        sim.timestep)
    tables, costs = {}, {}
    for count in counts:
        mujoco_world.PAD_PHASE_PER_STEP = phase / count * (1 + 1e-9)
        started = time.process_time()
        rows = [run_trial_outcomes(obj, table, config.override(sim={"engine": "mujoco"}),
                                   trials=1, seed=config.dataset.seed)
                for obj, table, config in work]
        costs[count] = time.process_time() - started
        tables[count] = pd.concat(rows, ignore_index=True)
    finest = tables[max(counts)]
    print("| substeps | trials | held | success | mean robustness (g) | minus the finest's, 95 % "
          "interval | success alike with the finest | Spearman with the finest | ms / trial | "
          "µs / protocol step |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    rng = np.random.default_rng(seed)
    for count in counts:
        t = tables[count]
        rho = stats.spearmanr(t["robustness"], finest["robustness"]).statistic
        diff = (t["robustness"] - finest["robustness"]).to_numpy(float)
        boot = diff[rng.integers(0, len(diff), (2000, len(diff)))].mean(axis=1)
        low, high = np.quantile(boot, [0.025, 0.975])
        print(f"| {count} | {len(t)} | {int(t['held'].sum())} | {int(t['success'].sum())} | "
              f"{t['robustness'].mean():.1f} | {diff.mean():+.1f} [{low:+.1f}, {high:+.1f}] | "
              f"{int((t['success'] == finest['success']).sum())} | {rho:.2f} | "
              f"{1e3 * costs[count] / len(t):.0f} | "
              f"{1e6 * costs[count] / t['steps'].sum():.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("fidelity", "impedance", "substeps"))
    parser.add_argument("values", nargs="*", type=float, help="impedances or substep counts")
    parser.add_argument("--grips", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.what == "fidelity":
        print("| engine | closes settled | every finger touches | largest slip below the floor "
              "| median squeeze after the close | held / success |")
        print("| --- | --- | --- | --- | --- | --- |")
        for engine in ("pybullet", "mujoco"):
            print(fidelity(engine))
    elif args.what == "impedance":
        impedance(args.values or [0.01, 0.1, 0.3, 0.9])
    else:
        substeps([int(v) for v in args.values] or [2, 3, 4, 5, 8, 12], args.grips, args.seed)


if __name__ == "__main__":
    main()
