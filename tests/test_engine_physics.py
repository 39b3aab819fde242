"""Both engines against Coulomb's law (``grip_env.sim.analytic``): where the engines disagree on
a grip, these cases say which one is right."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.sim import analytic
from grip_env.sim.uncertainty import TrialNoise

#: A trial without execution error or draws, at the paper's mu.
NO_ERROR = TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0)
ENGINES = ["pybullet", pytest.param("mujoco", marks=pytest.mark.skipif(
    __import__("importlib").util.find_spec("mujoco") is None, reason="mujoco not installed"))]


def _config(engine: str) -> Config:
    return Config().override(sim={"engine": engine})


def _mujoco(*marks: pytest.MarkDecorator) -> object:
    return pytest.param("mujoco", marks=[*marks, *ENGINES[1].marks])


def _failing_in_both(pybullet: str, mujoco: str) -> list[object]:
    """Both engines, each a strict expected failure for its own reason."""
    return [pytest.param("pybullet", marks=pytest.mark.xfail(strict=True, reason=pybullet)),
            _mujoco(pytest.mark.xfail(strict=True, reason=mujoco))]


def _held_box(engine: str) -> analytic.CaseResult:
    from tests.benchmarks.engines import held_box_grip

    return analytic.held_box(_config(engine), *held_box_grip(Config()))


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("case", [analytic.tilted_plane, analytic.pushed_block])
def test_a_block_slides_at_coulombs_load(engine, case):
    result = case(_config(engine), mu=0.4)
    assert result.engine == engine
    assert abs(result.error) < 0.01, result


@pytest.mark.parametrize("engine", ENGINES)
def test_a_rougher_block_needs_more_push(engine):
    rough = analytic.pushed_block(_config(engine), mu=0.8)
    assert abs(rough.error) < 0.01, rough


def test_a_load_with_no_threshold_is_refused():
    with pytest.raises(ValueError, match="no slip threshold"):
        analytic.critical_load(lambda load: True, 0.0, 1.0)
    assert analytic.critical_load(lambda load: load > 0.3, 0.0, 1.0) == pytest.approx(0.3, 1e-3)


def _rest_sphere(engine: str, compliant: bool) -> tuple[float, float, object]:
    """A 3 mm sphere of 0.5 kg put down touching the table, settled for 2 s (the rubber rings
    down as exp(-c t / 2 m)): its height (mm), its normal force on the table (N) and its body."""
    from grip_env.sim.engine import make_world

    with make_world(_config(engine).sim) as world:
        table = world.add_table(friction=1.0)
        sphere = world.add_sphere(3.0, 0.5, 0.4, np.array([10.0, -5.0, 3.0]))
        if compliant:
            world.set_contact_compliance(sphere.uid, -1, 22_600.0, 8.5)
        world.step(480)
        return (world.pose_floats_mm(sphere.uid)[0][2],
                world.contact_normal_force_n(sphere.uid, table.uid), sphere)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_sphere_rests_on_the_table_at_its_radius(engine):
    """Rigid, it rests at its radius (MuJoCo's default soft contact sinks it g (1 - d) / (d k) =
    0.37 mm at solref 0.02 s, whatever its mass); the pad's rubber sinks it by m g / k (0.22 mm;
    Bullet's contact rests 0.01 mm deeper, rigid or not)."""
    height, normal, sphere = _rest_sphere(engine, compliant=False)
    assert sphere.top_mm == 6.0
    assert sphere.inertia_per_kg == pytest.approx((0.4 * 0.003 ** 2,) * 3)
    assert height == pytest.approx(3.0, abs=0.4)
    assert normal == pytest.approx(0.5 * 9.81, rel=1e-3)
    height, normal, _ = _rest_sphere(engine, compliant=True)
    assert 3.0 - height == pytest.approx(0.5 * 9.81 / 22_600.0 * 1e3, abs=0.015)
    assert normal == pytest.approx(0.5 * 9.81, rel=1e-3)
    from grip_env.sim.engine import make_world

    with make_world(_config(engine).sim) as world, pytest.raises(ValueError, match="inertia"):
        world.add_sphere(3.0, 0.5, 0.4, np.zeros(3), inertia_kg_m2=0.0)


class _Restored(Exception):
    """Raised from the held phase once the restores are measured."""


def _disc_grips(count: int) -> tuple[Config, PlanarObject, pd.DataFrame]:
    """The paper's mu, the default disc (its simulated outline has many facets) and its ``count``
    best grips by Q_C."""
    from grip_env.objects import load_object_set
    from grip_env.planning.pipeline import candidates

    config = Config().override(grasp={"mu": 0.4})
    disc = next(o for o in load_object_set("default") if o.name == "disc")
    return config, disc, candidates(disc, config=config).sort_values("Q_C", kind="stable").head(
        count)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_trial_s_robustness_is_its_weakest_direction_s_own_limit(engine):
    """Every direction of the ramp climbs from the same restored moment, so the label (the ramp
    stops each direction at the weakest level so far) is the least of the limits each direction
    reaches alone. With Bullet's stacked contact points each climb began where the one before
    left the contacts, and the two differed."""
    from grip_env.sim import disturbance
    from grip_env.sim.trial import TrialScene, grip_plans

    config, disc, grips = _disc_grips(3)
    limits: list[float] = []

    def every_direction(probe, mass_kg, gyration_m, sim) -> float:
        limits.append(float(disturbance.direction_limits(probe, mass_kg, gyration_m, sim).min()))
        return limits[-1]

    config = config.override(sim={"engine": engine})
    for plan in grip_plans(grips):
        with TrialScene(disc, config) as scene:
            label = scene.run(plan, NO_ERROR).robustness_g
        with TrialScene(disc, config, ramp=every_direction) as scene:
            scene.run(plan, NO_ERROR)
        assert label == limits[-1]


def test_mujocos_directions_climb_together_to_the_same_outcome_in_fewer_steps(monkeypatch):
    """MuJoCo resumes a paused climb bit for bit, so the ramp's directions climb together, one
    level each in turn: every outcome of the disc's grips is the one of the directions climbed
    one after another (``resumes_exactly`` off), in fewer steps."""
    pytest.importorskip("mujoco")
    from dataclasses import asdict

    from grip_env.sim.mujoco_world import MujocoWorld
    from grip_env.sim.trial import TrialScene, grip_plans

    config, disc, grips = _disc_grips(3)
    config = config.override(sim={"engine": "mujoco"})
    results = {}
    for together in (True, False):
        monkeypatch.setattr(MujocoWorld, "resumes_exactly", together)
        with TrialScene(disc, config) as scene:
            results[together] = [asdict(scene.run(plan, NO_ERROR)) for plan in grip_plans(grips)]
    steps = {k: sum(r.pop("steps") for r in rows) for k, rows in results.items()}
    assert results[True] == results[False]
    assert any(r["held"] and r["robustness_g"] < 128.0 for r in results[True])
    assert steps[True] < steps[False]


@pytest.mark.parametrize("engine", ENGINES)
def test_a_restore_returns_the_held_grip_whatever_ran_since(engine):
    """The hand holds the disc (its best grip by Q_C); the world is saved, the disc pushed one
    way or another, and restored: it moves on bit for bit alike, touched by the three fingers.
    Bullet's ``restoreState`` kept the contact points of the moment beside the saved ones: the
    pads pressed through stacked springs, differently after every restore."""
    from grip_env.sim.trial import TrialScene, grip_plans

    config, disc, grip = _disc_grips(1)
    held_links: list[int] = []
    found: list[tuple[int, list[float]]] = []

    def measure(phase: str, scene: TrialScene) -> None:
        if phase != "held":
            return
        world, hand, uid = scene.world, scene.hand, scene.object.uid
        saved, state = world.save(), hand.state()
        world.step()
        held_links.append(len(world.touching_links(hand.uid, uid)))
        for push in ([3.0, 0.0, 0.0], [0.0, -4.0, 1.0]):
            for _ in range(20):
                world.push(uid, np.array(push))
                world.step()
            world.restore(saved)
            hand.restore(state)
            world.step()
            touching = len(world.touching_links(hand.uid, uid))
            world.step(30)
            found.append((touching, [*world.pose_floats_mm(uid)[0]]))
        raise _Restored

    with TrialScene(disc, config.override(sim={"engine": engine})) as scene, \
            pytest.raises(_Restored):
        scene.run(grip_plans(grip)[0], NO_ERROR, on_phase=measure)
    first, second = found
    assert first == second
    assert first[0] == held_links[0] == 3


def _sphere_slides(engine: str, pushes: float, torsion: bool) -> float:
    """How far (mm) a sphere of the pad's rubber that cannot roll slides on the table in 1 s,
    pushed with ``pushes`` times mu m g (mu = 0.4 x 1, Bullet's product in both engines)."""
    from grip_env.sim.engine import make_world

    with make_world(_config(engine).sim) as world:
        world.add_table(friction=1.0)
        sphere = world.add_sphere(3.0, 0.5, 0.4, np.array([0.0, 0.0, 3.0]), 1e3)
        if torsion:
            world.set_pad_friction(sphere.uid, -1, 0.4, 2.0)
        world.set_contact_compliance(sphere.uid, -1, 22_600.0, 8.5)
        world.step(48)
        start = np.array(world.pose_floats_mm(sphere.uid)[0])
        for _ in range(240):
            world.push(sphere.uid, np.array([pushes * 0.4 * 0.5 * 9.81, 0.0, 0.0]))
            world.step()
        return float(np.linalg.norm(world.pose_floats_mm(sphere.uid)[0] - start))


@pytest.mark.parametrize(("engine", "torsion"), [
    ("pybullet", False), ("pybullet", True),
    pytest.param("mujoco", True, marks=ENGINES[1].marks),
    pytest.param("mujoco", False, marks=[*ENGINES[1].marks, pytest.mark.xfail(
        strict=True, reason="MuJoCo's point contact whose torsional friction is mjMINMU (condim "
        "4, as every pair) lets a compliant sphere pushed at 0.5 mu m g slide 11 mm in 1 s, at "
        "0.9 20 mm; with the pad's torsion (2 mm arm) 0.02 and 0.2 mm")])])
def test_a_sphere_that_cannot_roll_slides_at_mu_times_its_weight(engine, torsion):
    assert _sphere_slides(engine, 0.9, torsion) < 0.5
    assert _sphere_slides(engine, 0.5, torsion) < 0.5
    assert _sphere_slides(engine, 1.1, torsion) > 100.0


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_a_held_box_slips_at_coulombs_load_on_its_own_normal_forces(engine):
    """Both engines since the 2 mm arm: at 3 mm PyBullet's pads pressed 106 N at the largest
    pull held against 72 N at the hold and the box resisted 68 % of mu times that (BENCHMARKS.md,
    "The next label model of both engines")."""
    result = _held_box(engine)
    assert abs(result.error) < 0.02, result


LIFT_ENGINES = ENGINES


def _lift_of_held_box(engine: str) -> tuple[object, list[float]]:
    """The held box's trial (no execution error) and the lift drive's force at every protocol
    step from the end of the close to the end of the hold."""
    from grip_env.sim.hand import ARM
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import TrialNoise
    from tests.benchmarks.engines import held_box_grip

    box, grip = held_box_grip(Config())
    forces: list[float] = []

    def watch(phase: str, scene: TrialScene) -> None:
        if phase != "closed":
            return
        world, step = scene.world, scene.world.step

        def recorded(n: int = 1) -> None:
            step(n)
            forces.append(float(world.joint_states(scene.hand.uid, [ARM[2]])[2][0]))

        world.step = recorded

    with TrialScene(box, _config(engine)) as scene:
        result = scene.run(grip_plans(grip)[0], TrialNoise((0.0, 0.0), 0.0, 0.4, 1.0),
                           on_phase=watch)
        forces = forces[: round(scene.config.sim.lift_time_s / scene.config.sim.timestep)]
    return result, forces


@pytest.mark.parametrize("engine", LIFT_ENGINES)
def test_the_held_box_stays_in_place_through_the_lift(engine):
    result, _ = _lift_of_held_box(engine)
    assert result.held, result.describe()


@pytest.mark.parametrize("engine", LIFT_ENGINES)
def test_the_lift_drive_stays_inside_its_force_limit(engine):
    """The lift (60 mm in 0.25 s) asks the arm for the hand's weight and a few newtons more; a drive
    at its limit is fighting something else (MuJoCo's drives outside the contact solve chattered
    at +-400 N: BENCHMARKS.md, 'Why MuJoCo drops grips at the lift')."""
    from grip_env.sim.hand import Hand

    _, forces = _lift_of_held_box(engine)
    assert max(map(abs, forces)) < 0.5 * Hand.max_palm_force_n, forces




@pytest.mark.slow
@pytest.mark.parametrize("engine", [
    pytest.param("pybullet", marks=pytest.mark.xfail(
        strict=True, reason="PyBullet's squeezed block slides at about 85 % of 2 mu F with rigid "
        "pads (BENCHMARKS.md, 'PyBullet beside MuJoCo')")),
    _mujoco()])
def test_a_block_between_two_rigid_pads_slides_at_twice_mu_times_the_squeeze(engine):
    result = analytic.two_pad_squeeze(_config(engine), mu=0.4, compliant=False)
    assert result.analytic == pytest.approx(0.8)
    assert abs(result.error) < 0.05, result


@pytest.mark.slow
@pytest.mark.parametrize("engine", [
    pytest.param("pybullet", marks=pytest.mark.xfail(
        strict=True, reason="PyBullet's squeezed block slides at about 82 % of 2 mu F between the "
        "hand's compliant pads (BENCHMARKS.md, 'PyBullet beside MuJoCo')")),
    _mujoco()])  # label model mujoco-2026.12-servo's pads rang (5x stiff) and never settled
def test_a_block_between_the_hands_pads_slides_at_twice_mu_times_the_squeeze(engine):
    result = analytic.two_pad_squeeze(_config(engine), mu=0.4)
    assert abs(result.error) < 0.05, result


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_a_body_held_at_two_points_turns_at_twice_mu_times_squeeze_times_arm(engine):
    """Torsional friction alone: both engines' models say mu F s per contact."""
    result = analytic.twisted_squeeze(_config(engine), mu=0.4)
    assert result.analytic == pytest.approx(0.8)
    assert abs(result.error) < 0.01, result
    doubled = analytic.twisted_squeeze(_config(engine), mu=0.4, torsion_mm=6.0)
    assert abs(doubled.error) < 0.01, doubled


def test_a_disc_contacts_limit_surface_is_inside_the_ellipse():
    """Alone it carries its whole moment; carrying all of mu N sideways, none; in between, less
    than the elliptic cone's sqrt(1 - f^2) (Goyal, Ruina & Papadopoulos 1991)."""
    assert analytic.disc_moment_fraction(0.0) == pytest.approx(1.0, abs=1e-6)
    assert analytic.disc_moment_fraction(0.999) < 0.05
    for f in (0.25, 0.5, 0.75):
        assert 0.8 * (1 - f) < analytic.disc_moment_fraction(f) < (1 - f * f) ** 0.5
        assert analytic.disc_moment_fraction(f, hertz=True) < (1 - f * f) ** 0.5


@pytest.mark.slow
@pytest.mark.parametrize(("engine", "own_model"), [
    ("pybullet", 1.0),  # a box: torsion and sideways friction each bounded alone
    pytest.param("mujoco", (1 - (0.4 * 9.81 / 2 / 4.0) ** 2) ** 0.5,  # the elliptic cone
                 marks=ENGINES[1].marks)])
def test_a_body_held_at_two_points_pivots_where_its_engines_friction_model_says(engine,
                                                                                own_model):
    result = analytic.pivoting_body(_config(engine), mu=0.4)
    assert result.simulated == pytest.approx(own_model, rel=0.02), result


@pytest.mark.slow
@pytest.mark.parametrize("engine", _failing_in_both(
    "PyBullet's body pivots at 122 % of a disc contact's limit: Bullet bounds torsional and "
    "sideways friction each alone, so the weight a contact carries sideways takes nothing from "
    "its twist (BENCHMARKS.md, 'Twist and pivot')",
    "MuJoCo's body pivots at 106 % of a disc contact's limit: its elliptic cone lies outside "
    "the disc's limit surface (BENCHMARKS.md, 'Twist and pivot')"))
def test_a_body_held_at_two_points_pivots_under_its_weight_at_a_disc_contacts_limit(engine):
    result = analytic.pivoting_body(_config(engine), mu=0.4)
    assert result.analytic == pytest.approx(0.817, abs=0.002)
    assert abs(result.error) < 0.05, result


def test_seam_ends_are_the_vertices_two_pieces_share():
    # two unit squares side by side share the edge x = 1: its ends (1, 0) and (1, 1)
    left = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    ends = analytic.seam_ends((left, left + [1.0, 0.0]))
    assert sorted(map(tuple, ends)) == [(1.0, 0.0), (1.0, 1.0)]
    assert len(analytic.seam_ends((left,))) == 0
    assert analytic.seam_end_distance((left,), (0.5, 0.5)) == np.inf


def test_the_seam_blocks_pieces_are_cut_across_the_touched_face_where_intended():
    """Both engines' pieces (MuJoCo's exact, PyBullet's eroded by its margin) of the cut block
    end a seam within 0.01 mm of the point the tip crosses; the uncut block's none within 10 mm.
    A collinear vertex instead of the dent cuts nowhere near it (merged over, then eroded)."""
    from grip_env.objects import PlanarObject
    from grip_env.sim.world import COLLISION_MARGIN_MM

    analytic.check_seam(analytic.seam_block(cut=True), cut=True)
    analytic.check_seam(analytic.seam_block(cut=False), cut=False)
    shape = analytic.seam_block(cut=True).simulated_shape(0.0)
    assert len(shape.pieces) == len(shape.collision_pieces(COLLISION_MARGIN_MM)) == 2
    assert analytic.seam_end_distance(shape.pieces, (0.0, 20.0)) == pytest.approx(1e-3)
    collinear = PlanarObject.from_polygon(np.insert(analytic.seam_block(cut=False).contour, 6,
                                                    [0.0, 20.0], axis=0))
    assert len(collinear.contour) == 8
    with pytest.raises(ValueError, match="nearest seam ends"):
        analytic.check_seam(collinear, cut=True)
    with pytest.raises(ValueError, match="nearest seam ends"):
        analytic.check_seam(analytic.seam_block(cut=True), cut=False)


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_a_fingertip_slides_along_an_uncut_face_at_mu_times_its_squeeze(engine):
    result = analytic.tip_across_seam(_config(engine), mu=0.4, offset_mm=1.5, cut=False)
    assert abs(result.error) < 0.01, result


@pytest.mark.slow
@pytest.mark.parametrize("offset_mm", analytic.SEAM_OFFSETS_MM)
@pytest.mark.parametrize("engine", _failing_in_both(
    "PyBullet's fingertip slides across a seam 0.5 / 1.5 mm ahead at 1.196 / 1.262 mu F: the "
    "next piece's corner, rounded by Bullet's 1 mm margin, reaches 1 mm past the seam under the "
    "pressed rubber and carries 1.8-4.8 N at a 8-23 degree tilt",
    "MuJoCo's fingertip slides across a seam 0.5 / 1.5 mm ahead at 1.311 / 1.281 mu F: it "
    "creeps to the next piece's sharp edge and lodges against it (2.6-3.6 N at a 19-24 degree "
    "tilt)"))
def test_a_fingertip_slides_across_a_seam_of_the_simulated_pieces_at_mu_times_its_squeeze(
        engine, offset_mm):
    """A real body has no seams: the pull is mu F wherever the seam ends."""
    result = analytic.tip_across_seam(_config(engine), mu=0.4, offset_mm=offset_mm)
    assert abs(result.error) < 0.05, result
