"""What MuJoCo does during the lift (run by hand; issue 45): one trial, every physics substep.

    python -m tests.benchmarks.mujoco_lift --steps 8            # the held box's lift
    python -m tests.benchmarks.mujoco_lift --phase approach     # the same hand, in free air
    python -m tests.benchmarks.mujoco_lift --grips 20                # 20 grips' cost table
    python -m tests.benchmarks.mujoco_lift --pads                    # the pads' stiffness

Runs the held box's trial (``tests.benchmarks.engines.held_box_grip``: the default rectangle's
best grip by Q_C, no execution error) in MuJoCo and, from the named phase on, prints for each
physics substep the object's height and vertical velocity, the palm's height and the force of the
arm's vertical (gantry z) drive, the vertical force the contacts put on the object (world frame:
every contact's force turned out of its own frame) beside the object's weight, each contact's
penetration, and the finger joints.

``--finger-caps`` (a diagnostic finger drive: a constant torque under a moving joint limit) is
gone: label model ``mujoco-2026.12-drives`` solves the hand's motors with the contacts itself
(``grip_env.sim.mujoco_world``). ``--renew-constants``, the diagnostic that found the stale
constants, is gone too: label model ``mujoco-2026.12-pads`` renews them itself.
``--grips N`` runs ``tests.benchmarks.engines --grips N`` (both engines) instead of the trace.
The arm's drives that this trace showed chattering (``--arm-stiffness``, ``--arm-constraint``
before label model ``mujoco-2026.12-servo``) are now servo constraints
(``grip_env.sim.mujoco_world``).
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse

import mujoco
import numpy as np

from grip_env.config import Config
from grip_env.sim.hand import ARM
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import TrialNoise
from tests.benchmarks.engines import cost, held_box_grip


def pad_stiffness_at_hold(config: Config) -> list[tuple[float, float]]:
    """Each hand contact's penetration (mm) and normal force (N) on the held box after the
    hold: their ratio is the pad's stiffness as MuJoCo simulates it."""
    box, grip = held_box_grip(config)
    found: list[tuple[float, float]] = []

    def watch(name: str, scene: TrialScene) -> None:
        if name != "held":
            return
        world = scene.world
        m, d, wrench = world._model, world._data, np.empty(6)
        for i, contact in enumerate(d.contact[: d.ncon]):
            owners = set(world._body_uid[m.geom_bodyid[[contact.geom1, contact.geom2]]].tolist())
            if owners == {scene.hand.uid, scene.object.uid}:
                mujoco.mj_contactForce(m, d, i, wrench)
                found.append((-1e3 * float(contact.dist), float(wrench[0])))

    with TrialScene(box, config) as scene:
        scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0), on_phase=watch)
    return found


def vertical_contact_force_n(world, uid: int) -> tuple[float, list[float]]:
    """The vertical force (N) of all contacts on body ``uid`` and their penetrations (mm)."""
    m, d = world._model, world._data
    total, depths, wrench = 0.0, [], np.empty(6)
    for i, contact in enumerate(d.contact[: d.ncon]):
        owners = world._body_uid[m.geom_bodyid[[contact.geom1, contact.geom2]]]
        if uid not in owners or owners[0] == owners[1]:
            continue
        mujoco.mj_contactForce(m, d, i, wrench)
        on_object = 1.0 if owners[1] == uid else -1.0  # the force acts on geom2
        total += on_object * float((contact.frame.reshape(3, 3).T @ wrench[:3])[2])
        depths.append(round(-1e3 * float(contact.dist), 3))
    return total, depths


def trace(phase: str, steps: int) -> None:
    config = Config().override(sim={"engine": "mujoco"})
    box, grip = held_box_grip(config)
    physics_step_of_module = mujoco.mj_step

    def watch(name: str, scene: TrialScene) -> None:
        if name != phase:
            return
        world, hand, uid = scene.world, scene.hand, scene.object.uid
        m, d = world._model, world._data
        body = world._body_id(uid, -1)
        dof = m.jnt_dofadr[m.body_jntadr[body]] + 2
        weight = float(m.body_mass[body] * -m.opt.gravity[2])
        print(f"object {m.body_mass[body]:.5f} kg (weight {weight:.3f} N), "
              f"{world.substeps} substeps of {1e3 * m.opt.timestep:.4f} ms")
        print("step sub | object z mm, vz m/s | palm z mm, lift drive N | vertical contact force "
              "N | penetrations mm | finger joints rad")

        physics_step = mujoco.mj_step
        substep = [0]

        def traced(model: mujoco.MjModel, data: mujoco.MjData) -> None:
            physics_step(model, data)
            row, sub = divmod(substep[0], world.substeps)
            substep[0] += 1
            if row < steps:
                world._stale = True
                force, depths = vertical_contact_force_n(world, uid)
                joints, _ = world.joint_positions_velocities(hand.uid, hand._flex)
                lift_drive = world.joint_states(hand.uid, [ARM[2]])[2][0]
                print(f"{row:4d} {sub} | {1e3 * d.xpos[body][2]:8.3f} {d.qvel[dof]:+.4f} | "
                      f"{hand.palm_pose_floats()[0][2]:8.3f} {lift_drive:+7.1f} | {force:+7.2f} | "
                      f"{depths} | "
                      f"{np.round(joints, 4).tolist()}")

        mujoco.mj_step = traced  # the world's own stepping, substep by substep

    with TrialScene(box, config) as scene:
        result = scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0),
                           on_phase=watch)
    mujoco.mj_step = physics_step_of_module
    print(result.describe())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--phase", default="closed", choices=("approach", "closed"),
                        help="trace from the end of this phase (closed: the lift follows)")
    parser.add_argument("--steps", type=int, default=8, help="protocol steps to print")
    parser.add_argument("--pads", action="store_true",
                        help="print each pad contact's depth, force and stiffness at the hold")
    parser.add_argument("--grips", type=int, default=0,
                        help="run tests.benchmarks.engines --grips N --seed 0 instead")
    args = parser.parse_args()
    if args.pads:
        for depth, force in pad_stiffness_at_hold(Config().override(sim={"engine": "mujoco"})):
            print(f"depth {depth:.4f} mm, normal force {force:.2f} N: {force / depth:.1f} kN/m")
    elif args.grips:
        cost(args.grips, 0)
    else:
        trace(args.phase, args.steps)


if __name__ == "__main__":
    main()
