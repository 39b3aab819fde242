"""What MuJoCo does during the lift (run by hand; issue 45): one trial, every physics substep.

    python -m tests.benchmarks.mujoco_lift --steps 8            # the held box's lift
    python -m tests.benchmarks.mujoco_lift --phase approach     # the same hand, in free air
    python -m tests.benchmarks.mujoco_lift --arm-stiffness 0.3  # a diagnostic arm drive
    python -m tests.benchmarks.mujoco_lift --arm-stiffness 0.3 --grips 20  # ... on 20 grips
    python -m tests.benchmarks.mujoco_lift --arm-constraint 0.02 --grips 20  # arm as constraints

Runs the held box's trial (``tests.benchmarks.engines.held_box_grip``: the default rectangle's
best grip by Q_C, no execution error) in MuJoCo and, from the named phase on, prints for each
physics substep the object's height and vertical velocity, the palm's height and the force of the
arm's vertical (gantry z) drive, the vertical force the contacts put on the object (world frame:
every contact's force turned out of its own frame) beside the object's weight, each contact's
penetration, and the finger joints.

``--arm-stiffness S`` is a diagnostic, not a model: it gives the arm's (gantry's) prismatic drives
a velocity gain of S joint inertias per physics substep instead of ``MOTOR_STIFFNESS`` (h kv / I
= S), the fingers' drives unchanged. ``--arm-constraint T`` is another: the arm's four joints (the
gantry's three and the wrist) are held at their targets by joint equality constraints of time
constant T s (damping ratio 1), which MuJoCo solves together with the contacts, instead of by
drives (no force limit). ``--grips N`` then runs ``tests.benchmarks.engines --grips N`` under
either instead of the trace.
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


def set_arm_stiffness(stiffness: float) -> None:
    """Give the prismatic (arm) drives of every ``MujocoWorld`` ``stiffness`` joint inertias per
    substep of velocity gain (a diagnostic patch of ``MujocoWorld._motor``)."""
    import grip_env.sim.mujoco_world as mujoco_world

    def motor(world, body: int, joint: int) -> tuple[int, float]:
        index = world._joint_id(body, joint)
        slide = world._model.jnt_type[index] == mujoco.mjtJoint.mjJNT_SLIDE
        per_substep = stiffness if slide else mujoco_world.MOTOR_STIFFNESS
        gain = per_substep * world._inertia[index] / world._model.opt.timestep
        return world._actuator[index], float(gain)

    mujoco_world.MujocoWorld._motor = motor


def set_arm_constraint(time_constant_s: float) -> None:
    """Hold the arm's joints of every ``MujocoWorld`` at their position targets by joint equality
    constraints of ``time_constant_s`` instead of by drives (a diagnostic patch)."""
    import grip_env.sim.mujoco_world as mujoco_world
    from grip_env.sim.gantry import ARM_JOINTS

    world_class = mujoco_world.MujocoWorld
    compile_model, drive = world_class._compile, world_class.position_motors

    def compile_with_constraints(world) -> None:
        for joint in world._spec.joints:
            if joint.name.split("/")[-1] in ARM_JOINTS:
                equality = world._spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1=joint.name)
                equality.solref = [time_constant_s, 1.0]
        compile_model(world)
        world._arm_equality = {int(j): k for k, j in enumerate(world._model.eq_obj1id)}

    def position_motors(world, body, joints, targets, torques, gain=None) -> None:
        m, _ = world._compiled()
        driven = [k for k, j in enumerate(joints)
                  if world._joint_id(body, j) not in world._arm_equality]
        for joint, target in zip(joints, targets, strict=True):
            index = world._joint_id(body, joint)
            if index in world._arm_equality:
                m.eq_data[world._arm_equality[index], 0] = target
                act = world._actuator[index]
                m.actuator_gainprm[act, 0], m.actuator_biasprm[act, :3] = 0.0, 0.0
        if driven:
            drive(world, body, [joints[k] for k in driven], [targets[k] for k in driven],
                  [torques[k] for k in driven], gain)

    world_class._compile = compile_with_constraints
    world_class.position_motors = position_motors


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
    parser.add_argument("--arm-stiffness", type=float, default=None,
                        help="diagnostic: the arm drives' h kv / I (the model's: MOTOR_STIFFNESS)")
    parser.add_argument("--arm-constraint", type=float, default=None,
                        help="diagnostic: hold the arm's joints by equality constraints of this "
                        "time constant (s)")
    parser.add_argument("--grips", type=int, default=0,
                        help="run tests.benchmarks.engines --grips N --seed 0 instead")
    args = parser.parse_args()
    if args.arm_stiffness is not None:
        set_arm_stiffness(args.arm_stiffness)
    if args.arm_constraint is not None:
        set_arm_constraint(args.arm_constraint)
    if args.grips:
        cost(args.grips, 0)
    else:
        trace(args.phase, args.steps)


if __name__ == "__main__":
    main()
