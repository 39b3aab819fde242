"""MuJoCo's hand motors, measured (run by hand; issue 45, label model ``mujoco-2026.12-drives``).

    python -m tests.benchmarks.mujoco_drives squeeze  # the held box: squeeze, torques, caps
    python -m tests.benchmarks.mujoco_drives drops \
        --parts /work/runs/crosscheck/standard40.crosscheck --drops 75 --controls 75

``squeeze`` runs the held box's trial (``tests.benchmarks.engines.held_box_grip``) in MuJoCo and
prints, after the close and after the hold, each pad's normal force and the sum, each flexion
motor's torque beside its cap, and over every protocol step of the trial the largest ratio of a
motor's torque to its cap (a joint 3 geared to joint 2 has ``GEAR_FACTOR`` times its cap).

``drops`` draws (seeded, ``crosscheck_contact_loads.sample``) trials of a cross-check's kept
outcomes where PyBullet holds after the lift and MuJoCo does not (robustness > 0 against 0) and
trials both hold, runs each whole in MuJoCo with the code on ``PYTHONPATH`` and prints how many
are held after the lift, their robustness and success. Run it with another checkout on
``PYTHONPATH`` to compare label models on the same trials.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import time
from pathlib import Path

import numpy as np

from grip_env.config import Config
from grip_env.sim.execution import grip_keys, object_key
from grip_env.sim.hand import GEAR_FACTOR
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import TrialNoise, trial_noises
from tests.benchmarks.engines import held_box_grip


def caps(scene: TrialScene) -> np.ndarray:
    """(3, 2): each flexion motor's torque cap now (joint 3 geared: ``GEAR_FACTOR`` tau3)."""
    return np.array([[f.tau2, f.tau3 if f.broken_away else GEAR_FACTOR * f.tau3]
                     for f in scene.hand.fingers])


def watch_torque_ratio(scene: TrialScene, worst: list[float]) -> None:
    """From now on, after every protocol step keep in ``worst[0]`` the largest ratio of a
    flexion motor's torque to its cap so far."""
    step = scene.world.step

    def watched(n: int = 1) -> None:
        step(n)
        ratio = np.abs(scene.hand.motor_torques()) / caps(scene)
        worst[0] = max(worst[0], float(ratio.max()))
    scene.world.step = watched


def squeeze() -> None:
    config = Config().override(sim={"engine": "mujoco"})
    box, grip = held_box_grip(config)
    worst = [0.0]

    def on_phase(name: str, scene: TrialScene) -> None:
        if name == "approach":
            watch_torque_ratio(scene, worst)
        if name in ("closed", "held"):
            forces = pad_forces(scene)
            print(f"{name}: pads {np.round(forces, 2).tolist()} N, sum {sum(forces):.2f} N; "
                  f"motor torques {np.round(scene.hand.motor_torques(), 3).tolist()} N m, caps "
                  f"{np.round(caps(scene), 3).tolist()}")

    with TrialScene(box, config) as scene:
        result = scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0), on_phase)
    print(f"largest |torque| / cap of a flexion motor over the trial: {worst[0]:.6f}")
    print(result.describe())


def pad_forces(scene: TrialScene) -> list[float]:
    """Each hand-object contact's normal force (N) in the last step."""
    import mujoco

    world = scene.world
    m, d = world._compiled()
    found, wrench = [], np.empty(6)
    for i, contact in enumerate(d.contact[: d.ncon]):
        owners = set(world._body_uid[m.geom_bodyid[[contact.geom1, contact.geom2]]].tolist())
        if owners == {scene.hand.uid, scene.object.uid}:
            mujoco.mj_contactForce(m, d, i, wrench)
            found.append(float(wrench[0]))
    return found


def drops(parts: Path, drops: int, controls: int, seed: int) -> None:
    from tests.benchmarks.crosscheck_contact_loads import sample

    picked, pools = sample(parts, 40, seed, drops, controls)
    print(f"pools {pools}; sampled {len(picked)}")
    started = time.process_time()
    found: dict[str, list[tuple[bool, float, bool]]] = {"drop": [], "control": []}
    for check, grip, trial, kind in picked:
        config = check.task.config.override(sim={"engine": "mujoco"})
        rows = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        rows = rows.iloc[[grip]]
        (plan,) = grip_plans(rows)
        ((noise,),) = trial_noises(config, config.dataset.seed, object_key(check.task.obj, rows),
                                   grip_keys(rows), range(trial, trial + 1))
        with TrialScene(check.task.obj, config) as scene:
            r = scene.run(plan, noise)
        found[kind].append((r.held, r.robustness_g, r.success))
        print(f"{kind} {check.task.object_id} grip {grip} trial {trial}: {r.describe()}",
              flush=True)
    for kind, rows in found.items():
        held = sum(h for h, _, _ in rows)
        print(f"{kind}: held after the lift {held} of {len(rows)}, robustness > 0 in "
              f"{sum(g > 0 for _, g, _ in rows)}, success {sum(s for _, _, s in rows)}, mean "
              f"robustness {np.mean([g for _, g, _ in rows]):.1f} g")
    print(f"CPU {time.process_time() - started:.1f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("squeeze", "drops"))
    parser.add_argument("--parts", type=Path)
    parser.add_argument("--drops", type=int, default=20)
    parser.add_argument("--controls", type=int, default=20)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.what == "squeeze":
        squeeze()
    else:
        drops(args.parts, args.drops, args.controls, args.seed)


if __name__ == "__main__":
    main()
