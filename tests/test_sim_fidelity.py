"""The executed grip is the planned grip: friction, inertia, worm gear, palm, contacts, order."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pybullet
import pytest

from grip_env.config import Config
from grip_env.objects import make_shape
from grip_env.planning.finger import pad_contact_in_plane, planar_contacts
from grip_env.planning.pipeline import candidates
from grip_env.sim import (
    TrialNoise,
    TrialScene,
    grip_plans,
    object_mass_kg,
    run_trial_outcomes,
    zero_noise,
)
from grip_env.sim.disturbance import ramp_levels, reaches
from grip_env.sim.hand import FINGER_LINKS, palm_quaternion, palm_to_world
from grip_env.sim.world import MM, World, prism_inertia

BOX = make_shape("rectangle")  # 90 x 55 mm
OPPOSED = {"grip_id": "opposed", "hand_x": 0.0, "hand_y": 0.0, "hand_yaw": np.pi / 2,
           "spread": 0.0, "p1_x": 25.0, "p1_y": 27.5, "p2_x": -25.0, "p2_y": 27.5,
           "p3_x": 0.0, "p3_y": -27.5}


def test_every_piece_of_a_compound_object_gets_the_trial_friction():
    star = make_shape("star")
    with World() as world:
        body = world.add_object(star, 30.0, 0.2, 0.5)
        assert len(body.links) == len(star.convex_pieces()) > 1
        world.set_dynamics(body, 0.3, 0.77)
        for link in body.links:
            info = world.client.getDynamicsInfo(body.uid, link)
            assert info[1] == pytest.approx(0.77)
            # the pair's torsional friction is then mu * the pad's arm (Bullet: s0 mu1 + s1 mu0)
            assert info[7] == 0.0


def test_inertia_is_the_whole_prism_not_its_first_piece():
    shape = make_shape("l_shape")
    with World() as world:
        body = world.add_object(shape, 30.0, 0.5, 0.5)
        diagonal = np.asarray(world.client.getDynamicsInfo(body.uid, -1)[2])
    expected, _ = prism_inertia(shape, 30.0)
    np.testing.assert_allclose(diagonal, 0.5 * np.asarray(expected), rtol=1e-6)
    # A uniform 90 x 55 x 30 mm box, by hand: Izz = m (a^2 + b^2) / 12.
    inertia, _ = prism_inertia(BOX, 30.0)
    assert inertia[2] == pytest.approx((0.090**2 + 0.055**2) / 12, rel=1e-9)


def test_mass_comes_from_area_thickness_density_and_weight_class():
    config = Config().override(grasp={"weight": 2.0}, objects={"density_kg_m3": 800.0})
    assert object_mass_kg(BOX, config) == pytest.approx(0.090 * 0.055 * 0.030 * 800 * 2)


@pytest.mark.parametrize("push_n", [40.0, 400.0])
def test_worm_gear_holds_a_finger_pushed_back_harder_than_its_motor(push_n):
    """The self-locking worm: 40 N on the thumb's tip is about 3 times its motor's torque, 400 N
    about 30 times (a stop of 5 times the motor, label model 2026.12-hertz's, gave way)."""
    with TrialScene(BOX, Config()) as scene:
        hand, c = scene.hand, scene.world.client
        hand.teleport(np.array([0.0, 0.0, 300.0]), 0.0)
        hand.preshape(0.0, np.array([0.8, 0.8, 0.8]))
        hand.set_finger_torques(np.array([0.8, 0.8, 0.8]))
        start, _ = hand.joint_states()
        tip = FINGER_LINKS[2][-1]
        back = []
        for _ in range(120):  # on the thumb's distal link
            position = c.getLinkState(hand.uid, tip)[0]
            outward = palm_to_world(0.0, np.array([0.0, -1.0, 0.0]))
            c.applyExternalForce(hand.uid, tip, (push_n * outward).tolist(), position,
                                 pybullet.WORLD_FRAME)
            hand.drive_fingers()
            scene.world.step()
            back.append(start[2] - hand.joint_states()[0][2])
    # At no step does either joint move back by more than 1 mrad (0.1 mm at the tip),
    assert np.max(back) <= 1e-3
    # nor does the stop push the finger forward against the load (no ratchet).
    assert np.min(back) >= -1e-3


@pytest.mark.parametrize("hold", [10.0, float("inf")], ids=["10Nm", "unbounded"])
def test_a_stop_never_pushes_a_joint_forward_to_its_floor(hold):
    """No position correction on the worm gear's stops (the world's erp is 0), bounded or not: a
    joint left below its floor, with its motor off, stays where it is; it is only kept from
    going back."""
    with TrialScene(BOX, Config()) as scene:
        hand, world = scene.hand, scene.world
        world.client.setGravity(0, 0, 0)
        hand.teleport(np.array([0.0, 0.0, 300.0]), 0.0)
        hand.preshape(0.0, np.array([0.8, 0.8, 0.8]))
        joint = FINGER_LINKS[2][-2]  # the thumb's joint 2 (a link's index is its joint's)
        world.velocity_motors(hand.uid, [joint], [0.0], [0.0])
        world.joint_floors(hand.uid, [joint], [0.81], [2.44], [hold])  # 10 mrad above it
        start = world.joint_states(hand.uid, [joint])[0][0]
        for _ in range(60):
            world.step()
        moved = world.joint_states(hand.uid, [joint])[0][0] - start
    assert start == pytest.approx(0.8)
    assert abs(moved) < 1e-4  # not pushed up towards 0.81


def test_each_flexion_joint_carries_its_motors_reflected_rotor_inertia():
    """Each flexion link's inertia about its joint's axis (local y) against the bare URDF's: the
    distal link gains joint 3's reflected rotor inertia, 1.41e-7 kg m^2 x 93.75^2 = 1.24e-3, the
    proximal link the rest of joint 2's, x 125^2 = 2.20e-3 (the distal link turns with joint 2
    too); no other axis or link changes. (``calculateMassMatrix`` keeps the inertia loaded from
    the URDF, so the links are read back.)"""
    from grip_env.sim import HAND_URDF
    from grip_env.sim.gantry import MOUNT_JOINTS

    with TrialScene(BOX, Config()) as scene:
        c, hand = scene.world.client, scene.hand.uid
        bare = c.loadURDF(str(HAND_URDF), basePosition=[1, 1, 1], useFixedBase=True,
                          flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        added = {link: np.subtract(c.getDynamicsInfo(hand, link)[2],
                                   c.getDynamicsInfo(bare, link - MOUNT_JOINTS)[2])
                 for link in range(MOUNT_JOINTS, c.getNumJoints(hand))}
    joint2, joint3 = 1.41e-7 * 125**2, 1.41e-7 * 93.75**2
    for links in FINGER_LINKS:
        np.testing.assert_allclose(added.pop(links[-2]), [0, joint2 - joint3, 0], atol=1e-12)
        np.testing.assert_allclose(added.pop(links[-1]), [0, joint3, 0], atol=1e-12)
    assert all(np.abs(v).max() < 1e-12 for v in added.values())  # the spread links


def test_the_hand_rides_an_arm_of_four_joints_before_its_own():
    """The mounted URDF: the arm's x, y, z and yaw joints, the fixed palm mount, then the
    bare URDF's joints in their order; the palm frame is where the arm's joints put it."""
    from grip_env.sim import HAND_URDF
    from grip_env.sim.gantry import ARM_JOINTS, MOUNT_JOINTS, PALM_LINK

    with World() as world:
        bare = world.client.loadURDF(str(HAND_URDF), useFixedBase=True)
        bare_names = [world.client.getJointInfo(bare, j)[1].decode()
                      for j in range(world.client.getNumJoints(bare))]
        hand = world.load_robot(HAND_URDF)
        names = [world.client.getJointInfo(hand, j)[1].decode()
                 for j in range(world.client.getNumJoints(hand))]
        for joint, value in zip(range(4), (0.01, -0.02, 0.3, 0.4), strict=True):
            world.set_joint(hand, joint, value)
        position, orientation = world.link_pose_floats_mm(hand, PALM_LINK)
    assert names[:MOUNT_JOINTS] == [*ARM_JOINTS, "palm_mount"]
    assert names[MOUNT_JOINTS:] == bare_names
    np.testing.assert_allclose(position, [10.0, -20.0, 300.0], atol=1e-6)
    np.testing.assert_allclose(np.abs(np.dot(orientation, palm_quaternion(0.4))), 1.0, atol=1e-6)


def test_joint3_follows_a_third_of_joint2_until_the_object_stops_the_finger():
    """The Barrett clutch: closing in free air joint 3 turns a third of joint 2 and no finger
    breaks away; on the pinned box every finger, stopped at its distal pad, breaks away."""
    from tests.benchmarks.sim_fidelity import _pinned_box

    with TrialScene(BOX, Config()) as scene:
        hand = scene.hand
        hand.teleport(np.array([0.0, 0.0, 300.0]), 0.0)
        hand.preshape(0.0, np.array([0.3, 0.3, 0.3]))
        hand.set_finger_torques(np.array([1.0, 1.0, 1.0]))
        start, _ = hand.joint_states()
        for _ in range(40):
            hand.drive_fingers(np.zeros((3, 2), bool))
            scene.world.step()
        q, _ = hand.joint_states()
        assert not any(f.broken_away for f in hand.fingers)
    closed = q - start
    assert (closed[:, 0] > 0.15).all()  # 40 steps at 1 rad/s: 0.167 rad
    np.testing.assert_allclose(closed[:, 1], closed[:, 0] / 3, atol=0.006)  # servo lag 4 mrad
    with _pinned_box(Config()) as scene:
        assert all(f.broken_away for f in scene.hand.fingers)
        assert not scene.hand.touching(scene.object.uid)[:, 0].any()  # by the distal pads


def test_teleport_puts_the_palm_base_where_asked_and_the_palm_tracks_its_target():
    with TrialScene(BOX, Config()) as scene:
        hand = scene.hand
        hand.teleport(np.array([10.0, -5.0, 250.0]), 0.3)
        scene.world.step()
        position, _ = hand.palm_pose_mm()
        np.testing.assert_allclose(position, [10.0, -5.0, 250.0], atol=0.2)
        errors = []
        for t in np.linspace(0, 1, 60):  # the lift's profile: 60 mm in 0.25 s
            target = np.array([10.0, -5.0, 250.0 + 60.0 * (1 - np.cos(np.pi * t)) / 2])
            hand.move(target, 0.3)
            scene.world.step()
            errors.append(np.linalg.norm(hand.palm_pose_mm()[0] - target))
    assert max(errors) <= 1.0


def test_the_palm_stays_at_its_grip_height_while_the_fingers_close():
    """The approach stops where the plan puts the palm and the arm holds it there while the
    fingers close (a palm carried on by 5 mm, as the old constraint's lead did, closes the pads
    below their planned plane)."""
    with TrialScene(BOX, Config()) as scene:
        hand = scene.hand
        plan = grip_plans(pd.DataFrame([OPPOSED]))[0]
        palm, yaw, grip_z = scene._place(plan, zero_noise())
        scene._approach(palm, yaw, grip_z)
        errors = []
        for _ in range(90):
            hand.drive_fingers(hand.touching(scene.object.uid))
            scene.world.step()
            errors.append(np.abs(hand.palm_pose_mm()[0] - [*palm, grip_z]).max())
    assert max(errors) <= 0.2


def test_executor_refuses_an_unreachable_plan_instead_of_clipping():
    far = {**OPPOSED, "p1_y": 400.0, "p2_y": 400.0}
    with TrialScene(BOX, Config()) as scene, pytest.raises(ValueError, match="reach"):
        scene.run(grip_plans(pd.DataFrame([far]))[0], zero_noise())


def test_planned_contacts_are_where_the_urdf_puts_its_pads():
    """Forward kinematics of the URDF: every pad corner lands on its planned contact (1 mm)."""
    config = Config()
    grips = candidates(BOX, config=config).head(6)
    assert len(grips)
    with TrialScene(BOX, config) as scene:
        c, hand = scene.world.client, scene.hand
        for plan in grip_plans(grips):
            posture = scene.posture(plan)
            z = float(posture.plane_z_mm + posture.height_mm)
            hand.teleport(np.array([*plan.palm_mm, z]), plan.yaw)
            hand.preshape(plan.spread, posture.q2, posture.q3)
            reach, height = pad_contact_in_plane(posture.q2, posture.q3)
            assert np.allclose(reach, plan.reach_mm, atol=1e-6)
            assert np.allclose(z - height, posture.plane_z_mm, atol=1e-6)
            contacts = grips.loc[grips.index[0]]  # placeholder row replaced below
            for links in FINGER_LINKS:
                pad = _pad_corner(c, hand.uid, links[-1])
                assert abs(pad[2] - posture.plane_z_mm) <= 1.0
            del contacts


def _pad_corner(client, uid: int, link: int) -> np.ndarray:
    """The distal link's inner tip corner in the world (mm), from its URDF box (50 x 25 x 16)."""
    position, orientation = client.getLinkState(uid, link)[4:6]
    rotation = np.asarray(client.getMatrixFromQuaternion(orientation)).reshape(3, 3)
    corner = np.array([0.050, 0.0, 0.008])  # link frame at joint 3: tip along x, pad face +z
    return (np.asarray(position) + rotation @ corner) / MM


def test_contacts_lie_in_one_plane_within_the_allowed_rise():
    config = Config()
    grips = candidates(BOX, config=config)
    from grip_env.planning.finger import finger_reaches

    sim = config.sim
    posture, found = planar_contacts(finger_reaches(grips), 30.0, sim.contact_plane_rise_mm,
                                     sim.fingertip_clearance_mm, sim.palm_clearance_mm,
                                     sim.preshape_gap_mm)
    assert found.all()
    assert ((posture.plane_z_mm >= 15.0) & (posture.plane_z_mm <= 15.0 + 8.0)).all()


def test_outcomes_do_not_depend_on_trial_order():
    grips = candidates(BOX).head(3)
    forward = run_trial_outcomes(BOX, grips, trials=2, seed=5)
    backward = run_trial_outcomes(BOX, grips.iloc[::-1], trials=2, seed=5)
    merged = forward.merge(backward, on=["grip", "trial"], suffixes=("", "_b"))
    assert len(merged) == 6
    np.testing.assert_array_equal(merged["robustness"], merged["robustness_b"])
    np.testing.assert_allclose(merged["drift_mm"], merged["drift_mm_b"], atol=1e-9)


def test_a_centred_grip_resists_more_than_a_heavier_copy_of_it():
    light = Config()
    heavy = Config().override(objects={"density_kg_m3": 4000.0})
    plan = grip_plans(pd.DataFrame([OPPOSED]))[0]
    noise = TrialNoise((0.0, 0.0), 0.0, 0.5, 1.0)
    with TrialScene(BOX, light) as scene:
        a = scene.run(plan, noise)
    with TrialScene(BOX, heavy) as scene:
        b = scene.run(plan, noise)
    assert a.held and a.robustness_g >= 4.0
    assert b.robustness_g < a.robustness_g


def test_ramp_levels_double_then_rise_geometrically_within_the_configured_range():
    sim = Config().sim
    levels = ramp_levels(sim)
    fine = int(np.flatnonzero(np.isclose(levels, sim.ramp_fine_from_g))[0])
    np.testing.assert_allclose(levels[:fine + 1], 2.0 * 2.0 ** np.arange(fine + 1))
    np.testing.assert_allclose(levels[fine + 1:] / levels[fine:-1], sim.ramp_ratio)
    assert levels[0] == sim.ramp_levels_g[0] and levels[-1] == pytest.approx(sim.ramp_levels_g[1])
    assert len(levels) == 16  # 2, 4, 8, then 16 * 2^(k/4) for k = 0..12


def test_a_ramp_fine_from_its_first_level_is_geometric_throughout():
    levels = ramp_levels(Config().sim.model_copy(update={"ramp_fine_from_g": 2.0}))
    assert len(levels) == 25
    np.testing.assert_allclose(levels[1:] / levels[:-1], 2.0**0.25)


def test_a_reference_on_a_ramp_level_is_reached_by_that_level():
    levels = ramp_levels(Config().sim)
    assert levels[11] != 64.0  # 16 * ratio**8 in floating point
    assert reaches(levels[11], 64.0) and reaches(levels[9], 45.0)
    assert not reaches(levels[10], 64.0)


def test_each_motor_delivers_its_command_on_a_pinned_box():
    """Converged contact forces: every joint-2 motor applies its commanded torque (5 %)."""
    from tests.benchmarks.sim_fidelity import _pinned_box

    with _pinned_box(Config()) as scene:
        torques = scene.hand.motor_torques()[:, 0]
        commands = np.array([f.tau2 for f in scene.hand.fingers])
    np.testing.assert_allclose(torques / commands, 1.0, atol=0.05)


def test_each_pad_touches_at_one_point_that_yields_like_rubber():
    """On the pinned box every fingertip touches through its pad sphere alone (one contact point,
    so a compliant contact is not counted twice), and the point presses with the pad's stiffness
    times its depth (at rest, damping aside): the contact is the rubber's, not a rigid one."""
    from tests.benchmarks.sim_fidelity import _pinned_box

    config = Config()
    with _pinned_box(config) as scene:
        points = scene.world.client.getContactPoints(bodyA=scene.hand.uid,
                                                     bodyB=scene.object.uid)
        for finger in scene.hand.fingers:
            (point,) = [p for p in points if p[3] in finger.links]
            assert point[3] == finger.links[-1]
            depth_m = -point[8]
            assert point[9] == pytest.approx(config.sim.pad_stiffness_n_per_m * depth_m, rel=0.05)
            assert 0.3e-3 < depth_m < 1.5e-3


@pytest.mark.parametrize("speed", [0.25, 1.0], ids=["slow", "default"])
@pytest.mark.parametrize("iterations", [1, 2], ids=["N", "2N"])
@pytest.mark.parametrize("finger", [0, 1, 2])
def test_each_finger_presses_its_commanded_force_on_a_pinned_box(finger, iterations, speed):
    """Every pad, closing alone on the pinned box, presses at least ``finger_force_n`` (5 %), and
    at most that plus the squeeze the impact can lock in: the worm gear keeps the finger where
    the impact carried it, and a velocity-driven finger reaches the motor's force with at most
    its free closing energy E, which a pad of stiffness k turns into at most sqrt(2 k E) more
    force. At the default solver iterations N and at 2N (converged), at the default speed and at
    a quarter of it (a sixteenth of the energy: the motor's force within 16 %)."""
    from tests.benchmarks.sim_fidelity import _finger_normal_forces, _pinned_box, closing_energy_j

    config = Config()
    config = config.override(sim={"solver_iterations": iterations * config.sim.solver_iterations,
                                  "close_speed_rad_s": speed})
    with _pinned_box(config, alone=finger, steps=int(120 / speed)) as scene:
        force = _finger_normal_forces(scene)[finger]
        energy = closing_energy_j(scene, finger)
    impact_n = np.sqrt(2 * config.sim.pad_stiffness_n_per_m * energy)
    assert 0.95 * config.sim.finger_force_n <= force <= config.sim.finger_force_n + impact_n


def test_the_closing_energy_is_the_rotors_and_the_links():
    """The free closing energy the bound above uses is the rotors' (as PyBullet carries them:
    joint 3's on the distal link, which turns at 4/3 of joint 2's speed when geared) and the
    links' own, under a third more."""
    from grip_env.sim.hand import MOTION_RATIOS, ROTOR_INERTIA_KG_M2
    from tests.benchmarks.sim_fidelity import _pinned_box, closing_energy_j

    joint2, joint3 = (ROTOR_INERTIA_KG_M2 * r**2 for r in MOTION_RATIOS)
    rotors_j = 0.5 * (joint2 - joint3 + joint3 * (4 / 3) ** 2)  # at 1 rad/s
    with _pinned_box(Config(), alone=2, steps=1) as scene:
        energy = closing_energy_j(scene, 2)
    assert rotors_j < energy < 4 / 3 * rotors_j


@pytest.mark.slow
def test_loaded_fingers_hold_where_they_closed_in_the_best_grips():
    """The worm gear in contact: after the lift no flexion joint of the best grips' zero-noise
    trials sits more than 1 mrad below where it closed."""
    from tests.benchmarks.sim_fidelity import _slip_recorder, best_grip_trials

    slips: dict[str, list[float]] = {"held": []}
    best_grip_trials(Config(), _slip_recorder(slips))
    assert len(slips["held"]) >= 40 and max(slips["held"]) <= 1.0


@pytest.mark.slow
def test_the_close_settles_before_the_cap_on_the_best_grips():
    """No chatter: the worm gear's floor holds every joint where it closed, so the closes of the
    best grips settle (>= 95 % of zero-noise trials of every default object's best three)."""
    from tests.benchmarks.sim_fidelity import best_grip_trials

    config = Config()
    settled = [r.close_steps < config.sim.max_close_steps for r in best_grip_trials(config)]
    assert len(settled) >= 40 and np.mean(settled) >= 0.95


def test_a_fine_start_outside_the_levels_is_held_within_them():
    """Above the last level the ramp doubles throughout; below the first it is fine throughout."""
    sim = Config().sim
    doubling = ramp_levels(sim.model_copy(update={"ramp_fine_from_g": 500.0}))
    np.testing.assert_allclose(doubling, [2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0])
    fine = ramp_levels(sim.model_copy(update={"ramp_fine_from_g": 0.5}))
    assert len(fine) == 25 and fine[0] == 2.0
