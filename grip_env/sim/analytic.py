"""Physics whose answer is written out, run in any engine: the judge where engines disagree.

Each case finds, by bisection, the load at which a body starts to slide, and compares it with
Coulomb's law:

* ``tilted_plane``: a block on a plane tilted by theta slides when tan theta > mu (gravity is
  tilted instead of the plane: the same statics);
* ``pushed_block``: a block pushed through its centre of mass slides at F = mu m g;
* ``two_pad_squeeze``: a block squeezed between two of the hand's rubber pads (compliant free
  blocks, each pressed on with F) slides out when the pull exceeds mu F per pad, 2 mu F in all
  (the pads are held against the pull by half of it each; all three stand on a frictionless
  table, which carries their weights and resists nothing sideways);
* ``held_box``: a box held by the hand (the real trial up to the hold of a grip the caller
  planned, e.g. the default rectangle's best by Q_C; paper's mu = 0.4) slides
  out along the fingers when the pull plus its weight exceeds mu times the sum of the pads'
  normal forces, as the engine itself reports them at the largest pull it held (``detail`` gives
  that sum and the one at the hold before any pull: how far the squeeze gave way).

A load "slides" the body when it moves more than ``SLIP_MM`` within ``SLIP_TIME_S``: at 1 % over
the critical load a block slides about 18 mm in that time, while the creep of a sticking contact
(MuJoCo's soft friction, mujoco #3328: at most 0.15 mm/s at impratio 10) stays far below it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.sim import pose
from grip_env.sim.engine import Engine, make_world

GRAVITY = 9.81
SLIP_MM = 2.0
SLIP_TIME_S = 1.0
SETTLE_S = 0.1
BISECTIONS = 12
#: The block of the table cases: 40 mm square, 20 mm thick, 200 g.
BLOCK = PlanarObject.from_polygon([[-20, -20], [20, -20], [20, 20], [-20, 20]], name="block")
BLOCK_THICKNESS_MM = 20.0
BLOCK_KG = 0.2


@dataclass(frozen=True)
class CaseResult:
    """One case in one engine: the critical load's ratio to Coulomb's (1 is exact)."""

    case: str
    engine: str
    analytic: float
    simulated: float
    quantity: str
    detail: str = ""

    @property
    def error(self) -> float:
        """Relative error of the simulated critical load."""
        return self.simulated / self.analytic - 1.0


def critical_load(slides: Callable[[float], bool], low: float, high: float,
                  bisections: int = BISECTIONS) -> float:
    """The load between ``low`` (held) and ``high`` (slides) where ``slides`` turns true.

    Raises:
        ValueError: ``low`` already slides or ``high`` does not (no threshold in between).
    """
    if slides(low) or not slides(high):
        raise ValueError(f"no slip threshold between loads {low:g} and {high:g}")
    for _ in range(bisections):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if slides(middle) else (middle, high)
    return 0.5 * (low + high)


def _block_world(config: Config, mu: float) -> tuple[Engine, int]:
    world = make_world(config.sim)
    world.add_table(friction=1.0)  # the pair's friction is the product: mu
    block = world.add_object(BLOCK, BLOCK_THICKNESS_MM, BLOCK_KG, friction=mu,
                             tolerance_mm=config.objects.sim_tolerance_mm)
    return world, block.uid


def _slides(world: Engine, uid: int, load: Callable[[], None], timestep: float) -> bool:
    """Whether the block moves more than ``SLIP_MM`` within ``SLIP_TIME_S`` under ``load``
    (applied before every step), after ``SETTLE_S`` under it."""
    for _ in range(round(SETTLE_S / timestep)):
        load()
        world.step()
    start = world.pose_floats_mm(uid)[0]
    for _ in range(round(SLIP_TIME_S / timestep)):
        load()
        world.step()
        if np.linalg.norm(np.subtract(world.pose_floats_mm(uid)[0], start)) > SLIP_MM:
            return True
    return False


def tilted_plane(config: Config, mu: float = 0.4) -> CaseResult:
    """The tangent of the steepest tilt a block rests at, against mu."""
    def slides(tangent: float) -> bool:
        world, uid = _block_world(config, mu)
        try:
            tilt = np.arctan(tangent)
            world.set_gravity((GRAVITY * np.sin(tilt), 0.0, -GRAVITY * np.cos(tilt)))
            return _slides(world, uid, lambda: None, config.sim.timestep)
        finally:
            world.close()

    found = critical_load(slides, 0.5 * mu, 1.5 * mu)
    return CaseResult("tilted plane", config.sim.engine, mu, found, "tan theta")


def pushed_block(config: Config, mu: float = 0.4) -> CaseResult:
    """The horizontal push (in body weights) a block resists, against mu."""
    def slides(weights: float) -> bool:
        world, uid = _block_world(config, mu)
        force = np.array([weights * BLOCK_KG * GRAVITY, 0.0, 0.0])
        try:
            return _slides(world, uid, lambda: world.push(uid, force), config.sim.timestep)
        finally:
            world.close()

    found = critical_load(slides, 0.5 * mu, 1.5 * mu)
    return CaseResult("pushed block", config.sim.engine, mu, found, "F / (m g)")


#: The two-pad case: pads 40 mm by 20 mm beside the 40 mm block, pressed on with ``SQUEEZE_N``.
SQUEEZE_N = 10.0
PAD_KG = 0.2
PAD_LEVER_M = 0.01  # from a pad's centre of mass to its face on the block


def _pad(y0_mm: float) -> PlanarObject:
    return PlanarObject.from_polygon([[-20, y0_mm], [20, y0_mm], [20, y0_mm + 20],
                                      [-20, y0_mm + 20]], name="pad")


def two_pad_squeeze(config: Config, mu: float = 0.4, compliant: bool = True) -> CaseResult:
    """The pull (in squeezes) a block between two pads resists, against 2 mu; the pads are the
    hand's rubber (``sim.pad_stiffness_n_per_m``, ``sim.pad_damping_n_s_per_m``) or rigid."""
    sim = config.sim
    squeeze = SQUEEZE_N

    def slides(pulls: float) -> bool:
        world = make_world(sim)
        try:
            world.add_table(friction=0.0)  # carries the weights, resists nothing sideways
            block = world.add_object(BLOCK, BLOCK_THICKNESS_MM, BLOCK_KG, friction=mu,
                                     tolerance_mm=config.objects.sim_tolerance_mm)
            pads = [world.add_object(_pad(y0), BLOCK_THICKNESS_MM, PAD_KG, friction=1.0,
                                     tolerance_mm=config.objects.sim_tolerance_mm)
                    for y0 in (20.0, -40.0)]
            for pad in pads if compliant else []:
                world.set_contact_compliance(pad.uid, -1, sim.pad_stiffness_n_per_m,
                                             sim.pad_damping_n_s_per_m)
            pull = pulls * squeeze

            def load(pulling: bool) -> None:
                """Each pad pressed on along its own face's normal (squeezes fixed in the world
                would turn the stack like a buckling column; two following the pads stay
                opposite and in line) and held at its face against the pull."""
                x = pull if pulling else 0.0
                world.push(block.uid, np.array([x, 0.0, 0.0]))
                for pad, side in zip(pads, (1.0, -1.0), strict=True):
                    qx, qy, qz, qw = world.pose_floats_mm(pad.uid)[1]
                    yaw = np.arctan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
                    inward = side * squeeze * np.array([np.sin(yaw), -np.cos(yaw), 0.0])
                    world.push(pad.uid, inward + np.array([-x / 2, 0.0, 0.0]))
                    world.twist(pad.uid, np.array([0.0, 0.0, -side * PAD_LEVER_M * x / 2]))

            def offset() -> float:
                pad_x = [world.pose_floats_mm(pad.uid)[0][0] for pad in pads]
                return world.pose_floats_mm(block.uid)[0][0] - float(np.mean(pad_x))

            for _ in range(round(SETTLE_S / sim.timestep)):
                load(False)
                world.step()
            start = offset()
            for _ in range(round(SLIP_TIME_S / sim.timestep)):
                load(True)
                world.step()
                if abs(offset() - start) > SLIP_MM:
                    return True
            return False
        finally:
            world.close()

    found = critical_load(slides, mu, 3.0 * mu)
    name = "two-pad squeeze" + ("" if compliant else " (rigid pads)")
    return CaseResult(name, sim.engine, 2.0 * mu, found, "pull / F")


class _Held(Exception):
    """Raised from the trial's ``held`` phase to stop it once the case is measured."""

    def __init__(self, result: CaseResult) -> None:
        super().__init__()
        self.result = result


def held_box(config: Config, box: PlanarObject, grip: pd.DataFrame,
             mu: float = 0.4) -> CaseResult:
    """The pull along the fingers (plus the weight) a box held by the hand resists, against mu
    times the sum of the pads' normal forces (at the largest pull held); ``grip`` is one
    candidate row of ``box``, executed without execution error at friction ``mu``.

    Raises:
        ValueError: the hand did not hold the box after the lift.
    """
    from grip_env.sim.trial import TrialScene, grip_plans
    from grip_env.sim.uncertainty import TrialNoise

    config = config.override(grasp={"mu": mu})
    noise = TrialNoise((0.0, 0.0), 0.0, mu, 1.0)

    def measure(phase: str, scene: TrialScene) -> None:
        if phase != "held":
            return
        world, uid, hand = scene.world, scene.object.uid, scene.hand
        at_hold = world.contact_normal_force_n(hand.uid, uid)
        weight = scene.mass_kg * GRAVITY
        normal_when_held: dict[float, float] = {}
        saved, state = world.save(), hand.state()
        start = scene._object_in_palm()

        def slides(pull_n: float) -> bool:
            world.restore(saved)
            hand.restore(state)
            force = np.array([0.0, 0.0, -pull_n])
            for _ in range(round(SLIP_TIME_S / config.sim.timestep)):
                world.push(uid, force)
                scene_step()
                if pose.moved_from(start, scene._object_in_palm())[0] > SLIP_MM:
                    return True
            normal_when_held[pull_n] = world.contact_normal_force_n(hand.uid, uid)
            return False

        def scene_step() -> None:
            hand.hold_fingers()
            world.step()

        pull = critical_load(slides, 0.0, 2.0 * mu * at_hold)
        normal = normal_when_held[max(normal_when_held)]
        detail = (f"sum of normal forces {at_hold:.1f} N at the hold, {normal:.1f} N at the "
                  f"largest pull held ({max(normal_when_held):.2f} N)")
        raise _Held(CaseResult("held box", config.sim.engine, mu * normal, pull + weight,
                               "pull + m g (N)", detail))

    with TrialScene(box, config) as scene:
        try:
            result = scene.run(grip_plans(grip)[0], noise, on_phase=measure)
        except _Held as held:
            return held.result
    raise ValueError(f"the hand did not hold the box in {config.sim.engine}: "
                     f"{result.describe()}")


def run_cases(config: Config, box: PlanarObject, grip: pd.DataFrame,
              engines: tuple[str, ...] = ("pybullet", "mujoco")) -> list[CaseResult]:
    """Every case in every engine (the config's other settings), in order; the held box is
    ``box`` held by ``grip`` (see :func:`held_box`)."""
    cases: list[Callable[[Config], CaseResult]] = [
        tilted_plane, pushed_block, lambda c: two_pad_squeeze(c, compliant=False),
        two_pad_squeeze, lambda c: held_box(c, box, grip)]
    names = ("tilted plane", "pushed block", "two-pad squeeze (rigid pads)", "two-pad squeeze",
             "held box")
    results = []
    for engine in engines:
        engine_config = config.override(sim={"engine": engine})
        for name, case in zip(names, cases, strict=True):
            try:
                results.append(case(engine_config))
            except ValueError as failed:
                results.append(CaseResult(f"{name}: {failed}", engine, 1.0, float("nan"), ""))
    return results
