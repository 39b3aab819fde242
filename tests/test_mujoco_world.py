"""MuJoCo's world is PyBullet's model: the same URDF gives the same masses, inertias, joint limits
and link frames; the same object the same mass, inertia and outline; a trial runs and repeats."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("mujoco")

from grip_env.config import Config
from grip_env.objects import load_object_set
from grip_env.sim.gantry import MOUNT_JOINTS
from grip_env.sim.hand import HAND_URDF, Hand
from grip_env.sim.mujoco_world import MujocoWorld
from grip_env.sim.world import World


@pytest.fixture(scope="module")
def robots():
    bullet, mujoco_world = World(), MujocoWorld()
    yield (bullet, bullet.load_robot(HAND_URDF)), (mujoco_world, mujoco_world.load_robot(HAND_URDF))
    bullet.close()
    mujoco_world.close()


def test_joint_order_and_limits_are_pybullets(robots):
    (bullet, b), (mj, m) = robots
    assert mj.link_count(m) == bullet.link_count(b)
    for joint in range(bullet.link_count(b)):
        name = bullet.client.getJointInfo(b, joint)[1].decode()
        assert mj._joints[m][joint] in (None, f"robot{m}/{name}")
        if mj._joints[m][joint] is not None and joint >= MOUNT_JOINTS:
            assert mj.joint_limits(m, joint) == pytest.approx(bullet.joint_limits(b, joint))


def test_masses_and_principal_inertias_are_pybullets(robots):
    (bullet, b), (mj, m) = robots
    model, _ = mj._compiled()
    for link in range(bullet.link_count(b)):  # the base is fixed to the world: no mass in Bullet
        mass, _, diagonal, *_ = bullet.client.getDynamicsInfo(b, link)
        index = mj._body_id(m, link)
        assert model.body_mass[index] == pytest.approx(mass, rel=1e-12)
        assert sorted(model.body_inertia[index]) == pytest.approx(sorted(diagonal), rel=1e-9)


def test_link_frames_match_in_a_posture(robots):
    """Dimensions: every link frame in the same place for the same joint values."""
    (bullet, b), (mj, m) = robots
    rng = np.random.default_rng(0)
    for joint in range(bullet.link_count(b)):
        if mj._joints[m][joint] is None:
            continue
        value = float(rng.uniform(0.1, 0.8))
        bullet.set_joint(b, joint, value)
        mj.set_joint(m, joint, value)
    for link in range(bullet.link_count(b)):
        position, orientation = bullet.link_pose_floats_mm(b, link)
        mj_position, mj_orientation = mj.link_pose_floats_mm(m, link)
        assert mj_position == pytest.approx(position, abs=1e-4)  # mm; Bullet rounds to float32
        turn = abs(float(np.dot(orientation, mj_orientation)))
        assert turn == pytest.approx(1.0, abs=1e-7)


def test_the_per_step_reads_are_plain_floats_equal_to_the_array_reads(robots):
    """``joint_positions``, ``joint_positions_velocities`` and the pose reads the controller and
    the ramp call every step give the values of the array reads, as Python floats."""
    for world, uid in robots:
        joints = [MOUNT_JOINTS + j for j in (4, 5, 1, 2, 6, 7)]
        for k, joint in enumerate(joints):
            world.set_joint(uid, joint, 0.1 + 0.05 * k)
        q, dq, _ = world.joint_states(uid, joints)
        positions, velocities = world.joint_positions_velocities(uid, joints)
        assert world.joint_positions(uid, joints) == positions == q.tolist()
        assert velocities == dq.tolist()
        position, orientation = world.link_pose_floats_mm(uid, joints[1])
        assert all(type(v) is float for v in (*position, *orientation))


def test_a_saved_state_survives_renewed_constants_and_replays_bit_for_bit():
    """The saved state and the constants' scratch share one spare ``MjData``: renewing the
    constants while a state is saved must not touch it, and a forgotten state's data serves
    again."""
    obj = next(o for o in load_object_set("default") if o.name == "rectangle")
    with MujocoWorld() as mj:
        mj.add_table()
        body = mj.add_object(obj, 30.0, 0.2, 0.5)
        mj.step(3)
        saved = mj.save()
        start = mj._compiled()[1].qpos.copy()
        mj.set_dynamics(body, 0.2, 0.5)  # the constants are renewed at the next step
        mj.step(5)
        after = mj._compiled()[1].qpos.copy()
        mj.restore(saved)
        assert mj._compiled()[1].qpos.tobytes() == start.tobytes()
        mj.step(5)
        assert mj._compiled()[1].qpos.tobytes() == after.tobytes()
        mj.forget(saved)
        again = mj.save()
        mj.step(2)
        mj.restore(again)
        assert mj._compiled()[1].qpos.tobytes() == after.tobytes()


def test_an_object_has_pybullets_mass_inertia_and_pose():
    obj = next(o for o in load_object_set("default") if o.name == "bean")
    with World() as bullet, MujocoWorld() as mj:
        ours, theirs = mj.add_object(obj, 30.0, 0.2, 0.5), bullet.add_object(obj, 30.0, 0.2, 0.5)
        assert ours.inertia_per_kg == theirs.inertia_per_kg
        model, _ = mj._compiled()
        base = mj._body_id(ours.uid, -1)
        assert model.body_mass[base] == pytest.approx(0.2)
        position, orientation = mj.pose_mm(ours.uid)
        expected, expected_orientation = bullet.pose_mm(theirs.uid)
        assert position == pytest.approx(expected, abs=1e-9)
        assert abs(np.dot(orientation, expected_orientation)) == pytest.approx(1.0, abs=1e-9)
        pieces = len(obj.simulated_shape(Config().objects.sim_tolerance_mm).pieces)
        assert model.npair == 0 or model.npair % pieces == 0
        assert (model.geom_bodyid == base).sum() == pieces


def test_friction_pairs_combine_as_bullet_does():
    """MuJoCo mixes geom frictions by their maximum; pairs carry Bullet's product instead."""
    obj = next(o for o in load_object_set("default") if o.name == "rectangle")
    with MujocoWorld() as mj:
        table = mj.add_table(friction=0.5)
        body = mj.add_object(obj, 30.0, 0.2, 0.3)
        hand = Hand(mj, Config().sim)
        model, _ = mj._compiled()
        table_geom = mj._link_geoms(table.uid, -1)[0]
        with_table = (model.pair_geom2 == table_geom) | (model.pair_geom1 == table_geom)
        assert model.pair_friction[with_table, 0] == pytest.approx(0.5 * 0.3)
        mj.set_dynamics(body, 0.2, 0.8)
        assert model.pair_friction[with_table, 0] == pytest.approx(0.5 * 0.8)
        pad = mj._link_geoms(hand.uid, hand.fingers[0].links[-1])
        with_pad = np.isin(model.pair_geom2, pad) | np.isin(model.pair_geom1, pad)
        assert model.pair_friction[with_pad, 0] == pytest.approx(0.8 * 1.0)
        torsion = Config().sim.pad_torsion_mm * 1e-3 * 0.8
        assert model.pair_friction[with_pad, 2] == pytest.approx(torsion)


def test_a_sphere_touches_through_pairs_of_bullets_friction_and_its_compliance():
    """A free sphere joins the pairs: with the table and with an object, each carrying Bullet's
    product of the two frictions, and a compliant sphere's pairs its spring (``pad_solref``)."""
    from grip_env.sim.mujoco_world import pad_solref

    obj = next(o for o in load_object_set("default") if o.name == "rectangle")
    with MujocoWorld() as mj:
        table = mj.add_table(friction=0.5)
        body = mj.add_object(obj, 30.0, 0.2, 0.3)
        sphere = mj.add_sphere(3.0, 0.05, 0.8, np.array([0.0, 0.0, 50.0]))
        mj.set_contact_compliance(sphere.uid, -1, 22_600.0, 8.5)
        model, _ = mj._compiled()
        ball = mj._link_geoms(sphere.uid, -1)
        assert model.geom_size[ball[0], 0] == pytest.approx(0.003)
        assert model.body_mass[mj._body_id(sphere.uid, -1)] == pytest.approx(0.05)
        mine = (model.pair_geom1 == ball[0]) | (model.pair_geom2 == ball[0])
        others = (set(model.pair_geom1[mine]) | set(model.pair_geom2[mine])) - {ball[0]}
        table_geom = mj._link_geoms(table.uid, -1)[0]
        assert others == {table_geom, *mj._link_geoms(body.uid, -1)}
        with_table = mine & ((model.pair_geom1 == table_geom) | (model.pair_geom2 == table_geom))
        assert model.pair_friction[with_table, 0] == pytest.approx(0.8 * 0.5)
        assert model.pair_friction[mine & ~with_table, 0] == pytest.approx(0.8 * 0.3)
        mj.step()
        invweight = model.body_invweight0[:, 0]
        k = np.flatnonzero(with_table)[0]
        assert model.pair_solref[k] == pytest.approx(pad_solref(
            22_600.0, 8.5, invweight[mj._body_id(sphere.uid, -1)]))


@pytest.mark.parametrize("multi", [True, False])
def test_a_flat_face_rests_on_several_points_with_multi_contact(monkeypatch, multi):
    """A prism on the table touches it at its face's four corners, each piece (MuJoCo's
    multiccd, as Bullet's manifold); without multi-contact at one point a piece."""
    import grip_env.sim.mujoco_world as mujoco_world

    monkeypatch.setattr(mujoco_world, "MULTI_CONTACT", multi)
    obj = next(o for o in load_object_set("default") if o.name == "rectangle")
    with MujocoWorld() as mj:
        mj.add_table(friction=0.5)
        body = mj.add_object(obj, 30.0, 0.2, 0.5)
        mj.step(24)  # a tenth of a second: settled on the table
        _, data = mj._compiled()
        pieces = mj._link_geoms(body.uid, -1)
        touching = sum(1 for c in data.contact[: data.ncon]
                       if c.geom1 in pieces or c.geom2 in pieces)
        assert touching == (4 * len(pieces) if multi else len(pieces))


@pytest.mark.slow
def test_a_mujoco_trial_runs_and_repeats_bit_for_bit():
    from grip_env.planning.pipeline import candidates
    from grip_env.sim import run_trial_outcomes

    obj = next(o for o in load_object_set("default") if o.name == "hexagon")
    grips = candidates(obj).sort_values("Q_C", kind="stable").head(1)
    config = Config().override(sim={"engine": "mujoco"})
    first = run_trial_outcomes(obj, grips, config, trials=1, seed=3)
    second = run_trial_outcomes(obj, grips, config, trials=1, seed=3)
    assert first.equals(second)
    assert int(first["steps"].iloc[0]) > 100


@pytest.mark.slow
def test_a_mujoco_outcome_does_not_depend_on_the_order_of_the_grips():
    from grip_env.planning.pipeline import candidates
    from grip_env.sim import run_trial_outcomes

    obj = next(o for o in load_object_set("default") if o.name == "pentagon")
    grips = candidates(obj).sort_values("Q_C", kind="stable").head(2)
    config = Config().override(sim={"engine": "mujoco"})
    forward = run_trial_outcomes(obj, grips, config, trials=1, seed=5)
    backward = run_trial_outcomes(obj, grips.iloc[::-1], config, trials=1, seed=5)
    pd.testing.assert_frame_equal(forward.set_index("grip").sort_index(),
                                  backward.set_index("grip").sort_index())


@pytest.fixture(scope="module")
def mesh_objects():
    return [o for o in load_object_set("household") if o.mesh is not None][:3]


def test_a_mesh_has_pybullets_pieces_mass_inertia_and_pose(mesh_objects):
    """``objects.execute_on: mesh``: the same convex pieces of the OBJ file, posed alike."""
    from grip_env.objects.meshes import pose_mass_properties, read_obj_pieces

    assert mesh_objects
    for obj in mesh_objects:
        mesh = obj.mesh
        _, inertia, axes = pose_mass_properties(mesh)
        args = (mesh.path(), mesh.scale, np.array(mesh.com_mm), np.array(mesh.position_mm),
                mesh.orientation, 0.15, 0.5, inertia, axes)
        with World() as bullet, MujocoWorld() as mj:
            ours, theirs = mj.add_mesh(*args), bullet.add_mesh(*args)
            assert ours.inertia_per_kg == theirs.inertia_per_kg == tuple(inertia)
            model, _ = mj._compiled()
            base = mj._body_id(ours.uid, -1)
            assert model.body_mass[base] == pytest.approx(0.15, rel=1e-12)
            assert model.body_inertia[base] == pytest.approx(np.array(inertia) * 0.15, rel=1e-12)
            assert (model.geom_bodyid == base).sum() == len(read_obj_pieces(mesh.path()))
            position, orientation = mj.pose_mm(ours.uid)
            expected, expected_orientation = bullet.pose_mm(theirs.uid)
            assert position == pytest.approx(expected, abs=1e-9)  # the centre of mass, mm
            assert abs(np.dot(orientation, expected_orientation)) == pytest.approx(1.0, abs=1e-9)
            assert 0.0 < ours.top_mm <= theirs.top_mm  # Bullet's: a turned box, and its margin


def test_a_mesh_at_pybullets_rest_settles_by_bullets_margin_in_mujoco(mesh_objects):
    """The rest pose was found in PyBullet, whose hulls are 1 mm larger (its collision margin):
    in MuJoCo the mesh falls that millimetre and stays near its pose (measured: 1.1 to 1.2 mm
    down, the duck rolls 3 degrees)."""
    from grip_env.objects.meshes import pose_mass_properties

    for obj in mesh_objects:
        mesh = obj.mesh
        _, inertia, axes = pose_mass_properties(mesh)
        with MujocoWorld() as mj:
            mj.add_table()
            body = mj.add_mesh(mesh.path(), mesh.scale, np.array(mesh.com_mm),
                               np.array(mesh.position_mm), mesh.orientation, 0.1, 0.5, inertia,
                               axes)
            start, turn0 = mj.pose_mm(body.uid)
            mj.step(240)
            end, turn1 = mj.pose_mm(body.uid)
        assert -2.0 < end[2] - start[2] < -0.5, obj.name
        assert np.linalg.norm(end - start) < 3.0, obj.name
        assert abs(np.dot(turn0, turn1)) > np.cos(np.radians(5.0) / 2), obj.name


@pytest.mark.slow
def test_a_mujoco_trial_runs_on_a_mesh(mesh_objects):
    from grip_env.planning.pipeline import candidates
    from grip_env.sim import run_trial_outcomes

    obj = mesh_objects[0]
    config = Config().override(sim={"engine": "mujoco"}, objects={"execute_on": "mesh"})
    grips = candidates(obj, config=config).sort_values("Q_C", kind="stable").head(1)
    first = run_trial_outcomes(obj, grips, config, trials=1, seed=3)
    assert int(first["steps"].iloc[0]) > 100
    assert first.equals(run_trial_outcomes(obj, grips, config, trials=1, seed=3))


def test_an_arm_at_rest_steps_its_substeps_in_one_call_bit_for_bit():
    """While the arm's targets are where it started, ``step`` runs a step's substeps in one
    call to MuJoCo: the state after moving, holding and being pushed is, bit for bit, that of
    the general loop (which ``watch_servos`` keeps)."""
    states = []
    for watched in (True, False):
        with MujocoWorld() as mj:
            mj.watch_servos = watched
            mj.add_table()
            block = mj.add_object(next(o for o in load_object_set("default")
                                       if o.name == "rectangle"), 30.0, 0.2, 0.5)
            uid = mj.load_robot(HAND_URDF)
            mj.set_contact_compliance(uid, 5, 3.0e4, 5.0)  # pads: several substeps
            z = 2  # the gantry's vertical axis
            mj.set_joint(uid, z, 0.3)
            mj.position_motors(uid, [z], [0.3], [400.0], 1.0)
            mj.step(5)  # at rest
            for k in range(1, 4):  # moving
                mj.position_motors(uid, [z], [0.3 + 6e-4 * k], [400.0], 1.0)
                mj.step()
            mj.step(5)  # at rest again
            mj.push(block.uid, np.array([3.0, -2.0, 1.0]))
            mj.step(2)
            _, d = mj._compiled()
            assert mj.substeps > 1
            states.append((d.qpos.tobytes(), d.qvel.tobytes(), d.qacc.tobytes()))
    assert states[0] == states[1]


@pytest.mark.parametrize("keep", ["save", "pause"])
def test_resume_continues_a_saved_moment_bit_for_bit_whatever_was_commanded_since(keep):
    """``resume`` brings back every command with the state (the arm's targets, the motors'
    targets, torques and modes, the joints' stops), so the world goes on exactly as it would
    have, from a moment kept whole (``save``) or as its integration state (``pause``);
    ``restore`` brings back the state only and leaves the commands for the caller."""
    with MujocoWorld() as mj:
        mj.add_table()
        mj.add_object(next(o for o in load_object_set("default") if o.name == "rectangle"),
                      30.0, 0.2, 0.5)
        uid = mj.load_robot(HAND_URDF)
        z, flex = 2, MOUNT_JOINTS + 1  # the gantry's vertical axis; a finger's first joint
        mj.position_motors(uid, [z], [0.3], [400.0], 1.0)
        mj.velocity_motors(uid, [flex], [0.5], [0.3])
        mj.step(3)
        saved = getattr(mj, keep)()
        mj.step(6)
        _, d = mj._compiled()
        ahead = (d.qpos.tobytes(), d.qvel.tobytes(), d.qacc_warmstart.tobytes())
        # commanded otherwise since the moment was saved
        mj.position_motors(uid, [z], [0.31], [100.0], 1.0)
        mj.position_motors(uid, [flex], [0.2], [0.1], 0.5)
        mj.joint_floors(uid, [flex], [0.05], [1.0], [1.0])
        mj.step(2)
        mj.restore(saved)
        mj.step(6)
        assert d.qpos.tobytes() != ahead[0]  # the new commands acted
        mj.resume(saved)
        mj.step(6)
        assert (d.qpos.tobytes(), d.qvel.tobytes(), d.qacc_warmstart.tobytes()) == ahead
        assert mj.resumes_exactly and not World.resumes_exactly


def _servo_world_in_a_trial(obj_name: str = "rectangle") -> MujocoWorld:
    """The MuJoCo world of one whole trial (approach to ramp) of ``obj_name``'s best grip, its
    servos watched."""
    from grip_env.planning.pipeline import candidates
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import TrialNoise

    obj = next(o for o in load_object_set("default") if o.name == obj_name)
    grip = candidates(obj).sort_values("Q_C", kind="stable").head(1)
    worlds: list[MujocoWorld] = []
    with TrialScene(obj, Config().override(sim={"engine": "mujoco"})) as scene:
        scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.5, 1.0),
                  on_phase=lambda phase, s: worlds.append(s.world))
        return worlds[-1]


def test_the_arms_servos_follow_their_targets_at_the_steps_speed():
    """A servo driven 6 mm in 10 protocol steps is there at the end of the last (a critically
    damped servo without the reference's lead would trail by twice its time constant times the
    speed, 2.4 mm here), settles there, and holds the hand's weight at rest."""
    with MujocoWorld() as mj:
        uid = mj.load_robot(HAND_URDF)
        z = 2  # the gantry's vertical axis
        mj.set_joint(uid, z, 0.3)
        mj.position_motors(uid, [z], [0.3], [400.0], 1.0)
        mj.step(30)
        weight = mj.joint_states(uid, [z])[2][0]
        model, _ = mj._compiled()
        carried = model.body_subtreemass[mj._body_id(uid, z)] * 9.81
        assert weight == pytest.approx(carried, rel=0.02)
        for k in range(1, 11):  # 10 steps of 0.6 mm: 0.144 m/s
            mj.position_motors(uid, [z], [0.3 + 6e-4 * k], [400.0], 1.0)
            mj.step()
        assert mj.joint_states(uid, [z])[0][0] == pytest.approx(0.306, abs=1e-4)
        mj.step(30)  # the soft constraint (impedance 0.95) sags about (1 - d) g T^2 (34 um)
        sag = 0.306 - mj.joint_states(uid, [z])[0][0]
        assert 20e-6 < sag < 50e-6


@pytest.mark.slow
def test_the_arms_servos_never_need_more_than_the_arms_force_in_a_trial(monkeypatch):
    """The arm's force limit (``Hand.max_palm_force_n``, its wrist's at ``ARM_LEVER_M``) is not
    imposed on MuJoCo's servo constraints; a whole trial shows it never binds."""
    from grip_env.sim.hand import ARM_LEVER_M

    monkeypatch.setattr(MujocoWorld, "watch_servos", True)
    world = _servo_world_in_a_trial()
    limit = Hand.max_palm_force_n
    assert world.servos_within_limits()
    assert (world.servo_peak_n < [limit, limit, limit, limit * ARM_LEVER_M]).all()
    assert world.servo_peak_n[2] > 25.0  # the z axis carried the hand's weight (about 29 N)


@pytest.mark.slow
def test_each_pad_yields_like_rubber_on_the_held_box():
    """As PyBullet's pads do (``tests/test_sim_fidelity.py``): force = stiffness x depth (5 %),
    measured on each pad's contact after the hold (label model ``mujoco-2026.12-servo`` gave
    106-122 kN/m for the rubber's 22.6)."""
    from tests.benchmarks.mujoco_lift import pad_stiffness_at_hold

    contacts = pad_stiffness_at_hold(Config().override(sim={"engine": "mujoco"}))
    assert len(contacts) == 3
    stiffness = Config().sim.pad_stiffness_n_per_m
    for depth_mm, force in contacts:
        assert force == pytest.approx(stiffness * depth_mm * 1e-3, rel=0.05)


def test_a_pad_pressed_on_a_free_block_yields_like_rubber():
    """A block of 0.5 kg lying on a rigid pad (a compliant box on the table) settles at the depth
    the rubber gives its weight: force over depth is the stiffness, at rest, whatever the
    block's mass (two masses) and after the mass is changed in the compiled model."""
    from grip_env.objects import PlanarObject
    from grip_env.sim.mujoco_world import PAD_IMPEDANCE, pad_solref

    block = PlanarObject.from_polygon([[-10, -10], [10, -10], [10, 10], [-10, 10]], name="block")
    stiffness, damping = 22_600.0, 8.5
    for mass in (0.05, 0.5):
        with MujocoWorld() as mj:
            table = mj.add_table()
            body = mj.add_object(block, 20.0, 1.0, 0.5)
            mj.set_contact_compliance(table.uid, -1, stiffness, damping)
            mj.set_dynamics(body, mass, 0.5)
            mj.step(480)
            model, data = mj._compiled()
            depths = [-c.dist for c in data.contact[: data.ncon]]
            assert len(depths) == 4  # a face on a face: four points, each a spring
            assert model.body_mass[mj._body_id(body.uid, -1)] == mass
            total = mass * 9.81
            assert np.mean(depths) == pytest.approx(total / (4 * stiffness), rel=0.02)
            assert mj.contact_normal_force_n(body.uid, table.uid) == pytest.approx(total, rel=1e-3)
    assert pad_solref(1.0, 2.0, 3.0) == pytest.approx((-3.0 * (1 - PAD_IMPEDANCE),
                                                       -6.0 * (1 - PAD_IMPEDANCE)))


def test_a_hand_motor_holds_its_speed_and_presses_exactly_its_torque_when_stalled():
    """Bullet's motor, solved with the contacts: free, a finger joint closes at its target speed
    (within 0.5 %) with less than its torque; stopped by its upper limit, it presses exactly its
    torque, never more; a position motor covers ``gain`` of the way to its target in a step."""
    from grip_env.sim.hand import FLEX_JOINTS

    joint2, joint3 = FLEX_JOINTS[0]
    with MujocoWorld() as mj:
        uid = mj.load_robot(HAND_URDF)
        mj.set_contact_compliance(uid, joint3, 22_600.0, 8.5)  # a trial's 4 substeps
        mj.velocity_motors(uid, [joint2], [0.5], [1.2])
        mj.position_motors(uid, [joint3], [0.2], [1.0], 0.5)
        mj.step()
        q, speed, torque = mj.joint_states(uid, [joint2, joint3])
        assert 0.085 < q[1] < 0.1  # about half of the way to 0.2 in one step (from rest)
        mj.step(9)
        assert mj.joint_states(uid, [joint3])[0][0] == pytest.approx(0.2, abs=2e-3)
        _, speed, torque = mj.joint_states(uid, [joint2])
        assert speed[0] == pytest.approx(0.5, rel=5e-3) and abs(torque[0]) < 1.2
        stop = float(mj.joint_states(uid, [joint2])[0][0]) + 0.01
        mj.joint_floors(uid, [joint2], [0.0], [stop], [6.0])
        torques = []
        for _ in range(20):
            mj.step()
            torques.append(mj.joint_states(uid, [joint2])[2][0])
        assert max(np.abs(torques)) <= 1.2
        assert torques[-1] == pytest.approx(1.2, rel=1e-9)  # stalled: exactly its torque
        assert mj.joint_states(uid, [joint2])[1][0] == pytest.approx(0.0, abs=1e-3)


def test_the_stop_and_the_motors_keep_their_time_constant_in_seconds_whatever_the_substeps():
    """With the pads' substeps (4 at 240 Hz) the worm gear's stop and the motors' rows have the
    time constant 1/600 s, below MuJoCo's two-step floor (``refsafe`` off for it); without pads
    (one 4.17 ms step, which cannot resolve it) they fall back to two physics steps."""
    import mujoco

    from grip_env.sim.hand import FLEX_JOINTS
    from grip_env.sim.mujoco_world import STIFF_TIME_CONSTANT_S

    joint2, joint3 = FLEX_JOINTS[0]
    for pads, substeps, expected in ((True, 4, STIFF_TIME_CONSTANT_S), (False, 1, 2.0 / 240.0)):
        with MujocoWorld() as mj:
            uid = mj.load_robot(HAND_URDF)
            if pads:
                mj.set_contact_compliance(uid, joint3, 22_600.0, 8.5)
            mj.joint_floors(uid, [joint2], [0.0], [1.0], [6.0])
            m, _ = mj._compiled()
            assert mj.substeps == substeps
            stop = m.jnt_solref[mj._joint_id(uid, joint2)]
            assert stop[0] == pytest.approx(expected, rel=1e-12) and stop[1] == 1.0
            assert m.tendon_solref_fri[:, 0] == pytest.approx(expected, rel=1e-12)
            refsafe_off = bool(m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_REFSAFE)
            assert refsafe_off == pads  # 1/600 s is 1.6 physics steps of 4 substeps


@pytest.mark.slow
def test_the_fingers_press_their_torques_on_the_held_box_and_never_more():
    """On the held box every flexion motor's torque stays within its cap in every step, and
    after the close each presses exactly its cap (``mujoco-2026.12-pads``' drives pressed 0.513
    N m at joint 3 for a cap of 0.53-0.56)."""
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import TrialNoise
    from tests.benchmarks.engines import held_box_grip
    from tests.benchmarks.mujoco_drives import caps, watch_torque_ratio

    config = Config().override(sim={"engine": "mujoco"})
    box, grip = held_box_grip(config)
    over, held = [0.0], []

    def on_phase(name: str, scene: TrialScene) -> None:
        if name == "approach":
            watch_torque_ratio(scene, over)
        if name == "held":
            held.append((scene.hand.motor_torques(), caps(scene)))

    with TrialScene(box, config) as scene:
        result = scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0), on_phase)
    assert result.held
    assert over[0] <= 1.0 + 1e-12
    torques, limits = held[0]
    np.testing.assert_allclose(torques, limits, rtol=1e-9)
