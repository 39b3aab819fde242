"""One grip execution in the simulator: place, pre-shape, lower, close, lift, hold, judge, disturb.

A ``TrialScene`` builds a fresh world of ``sim.engine`` (``grip_env.sim.engine``; PyBullet's
``World`` by default, its own client) with the table, the object
and the hand for every trial, so that no trial can reach the state another left: PyBullet's
``restoreState`` does not restore everything the solver carries from step to step, and restored
scenes made 23 % of trials depend on the trials run before them (BENCHMARKS.md, "A clean trial").
All three fingertip pads are planned to touch in one horizontal plane, as close above the
object's mid-thickness as the hand reaches (``sim.contact_plane_rise_mm``), so the planar model's
contacts are the simulated ones (no pitching couple between fingers). A trial is
held when, after the lift and a hold of ``sim.hold_time_s``, the object has moved at most
``sim.hold_tolerance_mm`` and turned at most ``sim.hold_rotation_deg`` in the palm frame; its
robustness is then the disturbance level it resists (``grip_env.sim.disturbance``), and it
succeeds when that level reaches ``sim.reference_level_g``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.config import Config, SimConfig
from grip_env.objects import PlanarObject
from grip_env.objects.meshes import (
    executes_on_mesh,
    execution_height_mm,
    pose_mass_properties,
)
from grip_env.planning.finger import (
    ContactPosture,
    finger_reaches,
    opening_posture,
    planar_contacts,
)
from grip_env.sim import pose
from grip_env.sim.disturbance import RampProbe, reaches, robustness
from grip_env.sim.engine import Engine, make_world
from grip_env.sim.hand import Hand, palm_to_world
from grip_env.sim.uncertainty import TrialNoise, object_mass_kg

PLAN_COLUMNS = ("hand_x", "hand_y", "hand_yaw", "spread", "p1_x", "p1_y", "p2_x", "p2_y",
                "p3_x", "p3_y")
APPROACH_MM = 10.0  # the pre-shaped hand is lowered this far onto its grip height
APPROACH_STEPS = 8
SETTLE_STEPS = 8
STALL_SPEED = 0.05  # rad/s: a finger whose joints move slower than this has stopped
#: The graded outcome's search, given the scene's probe, the object's mass (kg) and radius of
#: gyration (m): :func:`grip_env.sim.disturbance.robustness` unless a diagnostic swaps in another.
Ramp = Callable[[RampProbe, float, float, SimConfig], float]
#: The phases ``TrialScene.run`` reports to ``on_phase``, in order (the ramp only when held).
TRIAL_PHASES = ("approach", "closed", "held", "ramp")


@dataclass(frozen=True)
class GripPlan:
    """What the planner asks for: palm centre (mm), yaw and spread (rad), finger reaches (mm).

    ``reach_mm[i]`` is the distance from finger i's line origin (its spread axis; O for the thumb)
    back along F_i to its contact, in planar finger order.
    """

    palm_mm: tuple[float, float]
    yaw: float
    spread: float
    reach_mm: tuple[float, float, float]


@dataclass(frozen=True)
class TrialResult:
    """Outcome of one trial.

    ``held``: the object was lifted and stayed within the hold tolerance; ``robustness_g``: the
    disturbance level it then resisted (0 when not held); ``success``: robustness reached the
    reference level ``reference_g``. Drift (mm) and rotation (deg) are in the palm frame after
    the hold. ``failed_at`` names the phase the trial failed in: ``"lift"`` (the object did not
    rise with the hand), ``"hold"`` (it rose but moved in the hand past the hold tolerance),
    ``"ramp"`` (held, but below the reference disturbance), ``""`` when it succeeded.
    """

    success: bool
    robustness_g: float
    held: bool
    drift_mm: float
    rotation_deg: float
    lifted_mm: float
    steps: int
    close_steps: int
    reference_g: float
    failed_at: str

    def describe(self) -> str:
        """The outcome in words, from this trial's own fields."""
        if self.failed_at == "lift":
            return f"dropped at the lift (the object rose only {self.lifted_mm:.1f} mm)"
        if self.failed_at == "hold":
            return (f"slipped in the hand at the lift (drift {self.drift_mm:.1f} mm, "
                    f"turn {self.rotation_deg:.1f} deg after the hold)")
        reference = f"the reference of {grams(self.reference_g)}"
        if self.success:
            return f"held up to {grams(self.robustness_g)} against {reference}"
        if self.robustness_g <= 0:
            return f"held after the lift, then slipped at the ramp's first level ({reference})"
        return (f"held after the lift, then slipped at the ramp: held up to "
                f"{grams(self.robustness_g)}, short of {reference}")


def grams(level_g: float) -> str:
    """A disturbance level for people: ``64 g``, ``45.3 g``."""
    return f"{level_g:.1f}".removesuffix(".0") + " g"


def grip_plans(grips: pd.DataFrame) -> list[GripPlan]:
    """One ``GripPlan`` per row of a candidate table."""
    missing = [c for c in PLAN_COLUMNS if c not in grips.columns]
    if missing:
        raise ValueError(f"grips lack columns {missing}")
    values = grips[list(PLAN_COLUMNS)].to_numpy(float)
    if not np.isfinite(values).all():
        raise ValueError("grips hold NaN or infinite hand/contact values")
    reaches = finger_reaches(grips)
    return [GripPlan((float(v[0]), float(v[1])), float(v[2]), float(v[3]), tuple(map(float, r)))
            for v, r in zip(values, reaches, strict=True)]


class TrialScene:
    """Table, object and hand in one headless world, reused across trials of one object.

    ``ramp`` is the graded outcome's search (None: :func:`grip_env.sim.disturbance.robustness`,
    the labels'); a diagnostic may pass another, e.g. one that records every direction's limit.
    """

    def __init__(self, obj: PlanarObject, config: Config | None = None,
                 ramp: Ramp | None = None) -> None:
        self.obj = obj
        self.config = config if config is not None else Config()
        self.ramp = ramp
        self.thickness_mm = execution_height_mm(obj, self.config.objects)
        self.mass_kg = object_mass_kg(obj, self.config)
        self._postures: dict[GripPlan, ContactPosture] = {}
        self._build()

    def _build(self) -> None:
        """A new world holding the table, the object at rest and the hand high above it."""
        sim, objects = self.config.sim, self.config.objects
        self.world = make_world(sim)
        self.world.add_table()
        if executes_on_mesh(self.obj, objects):  # the mesh itself, at rest
            mesh = self.obj.mesh
            _, inertia, axes = pose_mass_properties(mesh)
            self.object = self.world.add_mesh(mesh.path(), mesh.scale, np.array(mesh.com_mm),
                                              np.array(mesh.position_mm), mesh.orientation,
                                              self.mass_kg, self.config.grasp.mu, inertia, axes)
        else:
            self.object = self.world.add_object(self.obj, self.thickness_mm, self.mass_kg,
                                                self.config.grasp.mu,
                                                tolerance_mm=objects.sim_tolerance_mm)
        self.gyration_m = float(np.sqrt(self.object.inertia_per_kg[2]))
        self.hand = Hand(self.world, sim)
        self.hand.teleport(np.array([0.0, 0.0, 400.0]), 0.0)

    def fresh(self) -> None:
        """Replace the world by a new one, as built: whatever touched the old one (an earlier
        trial, or a caller stepping ``world`` itself) cannot reach the next trial."""
        self.world.close()
        self._build()

    def close(self) -> None:
        """Release the PyBullet client."""
        self.world.close()

    def __enter__(self) -> TrialScene:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ one trial
    def run(
        self, plan: GripPlan, noise: TrialNoise,
        on_phase: Callable[[str, TrialScene], None] | None = None,
    ) -> TrialResult:
        """Execute ``plan`` under ``noise``; ``on_phase(name, scene)`` is called at each phase
        (``TRIAL_PHASES``: after the approach, the close, the lift and hold, and, when the
        object was held, the disturbance ramp, the world as its last disturbance left it).

        Raises:
            ValueError: the plan is out of the hand's reach (no posture puts its pads there).
        """
        sim = self.config.sim
        self.fresh()
        palm, yaw, grip_z = self._place(plan, noise)
        counter = _StepCounter(self.world, self.hand)
        notify = on_phase or (lambda name, scene: None)  # phases: TRIAL_PHASES
        self._approach(palm, yaw, grip_z, counter)
        notify("approach", self)
        close_steps = self._close(counter)
        counter.step(SETTLE_STEPS)
        notify("closed", self)
        reference = self._object_in_palm()
        start_z = self._object_height()
        self._lift(palm, yaw, grip_z, counter)
        counter.step(max(0, round(sim.hold_time_s / sim.timestep)))
        notify("held", self)
        drift, turn = self._moved_from(reference)
        lifted = self._object_height() - start_z
        held = (drift <= sim.hold_tolerance_mm and turn <= sim.hold_rotation_deg
                and lifted > 0.5 * sim.lift_height_mm)
        level = 0.0
        if held:
            level = self._robustness(yaw, noise, counter)
            notify("ramp", self)
        success = held and reaches(level, sim.reference_level_g)
        failed_at = ("" if success else "ramp" if held
                     else "lift" if lifted <= 0.5 * sim.lift_height_mm else "hold")
        return TrialResult(bool(success), level, bool(held), drift, turn, float(lifted),
                           counter.steps, close_steps, float(sim.reference_level_g), failed_at)

    def posture(self, plan: GripPlan) -> ContactPosture:
        """The plan's contact posture (cached: it does not depend on a trial's noise)."""
        if plan not in self._postures:
            sim = self.config.sim
            posture, found = planar_contacts(
                np.asarray(plan.reach_mm), self.thickness_mm, sim.contact_plane_rise_mm,
                sim.fingertip_clearance_mm, sim.palm_clearance_mm, sim.preshape_gap_mm,
            )
            if not found[0]:
                raise ValueError(f"no posture puts every pad of reaches "
                                 f"{np.round(plan.reach_mm, 2).tolist()} mm in one plane of the "
                                 f"object: the plan is out of the hand's reach")
            self._postures[plan] = ContactPosture(posture.q2[0], posture.q3[0],
                                                  posture.height_mm[0], posture.plane_z_mm[0])
        return self._postures[plan]

    def _place(self, plan: GripPlan, noise: TrialNoise) -> tuple[NDArray, float, float]:
        """The hand pre-shaped for the plan and put (with the trial's error, in the palm frame)
        just above its height, in the current world."""
        sim = self.config.sim
        self.world.set_dynamics(self.object, self.mass_kg * noise.mass_scale, noise.friction)
        posture = self.posture(plan)
        q2_open, q3_open = opening_posture(posture.q2, posture.q3, sim.preshape_gap_mm)
        grip_z = float(posture.plane_z_mm + posture.height_mm)
        error = palm_to_world(plan.yaw, np.array([*noise.offset_mm, 0.0]))[:2]  # palm frame
        palm = np.asarray(plan.palm_mm) + error
        yaw = plan.yaw + noise.yaw_error
        self.hand.teleport(np.array([*palm, grip_z + APPROACH_MM]), yaw)
        self.hand.preshape(plan.spread, q2_open, q3_open)
        self.hand.set_finger_torques(posture.q2, posture.q3)
        return palm, yaw, grip_z

    def _approach(self, palm: NDArray, yaw: float, grip_z: float,
                  counter: _StepCounter | None = None) -> None:
        """Lower the pre-shaped hand onto its grip height (the arm stops it there)."""
        step = counter.step if counter is not None else self.world.step
        for z in np.linspace(grip_z + APPROACH_MM, grip_z, APPROACH_STEPS + 1)[1:]:
            self.hand.move(np.array([*palm, z]), yaw)
            step()

    def _close(self, counter: _StepCounter) -> int:
        """Close all fingers until every one has stopped (or the step cap); returns steps used."""
        still = 0
        for step in range(1, self.config.sim.max_close_steps + 1):
            velocities = self.hand.drive_fingers(self.hand.touching(self.object.uid))
            self.world.step()
            counter.steps += 1
            moving = np.abs(velocities[:, 0]).max()
            broken = [i for i, f in enumerate(self.hand.fingers) if f.broken_away]
            if broken:
                moving = max(moving, np.abs(velocities[broken, 1]).max())
            still = still + 1 if moving < STALL_SPEED else 0
            if step > 4 and still >= 3:
                return step
        return self.config.sim.max_close_steps

    def _lift(self, palm: NDArray, yaw: float, grip_z: float, counter: _StepCounter) -> None:
        sim = self.config.sim
        steps = max(1, round(sim.lift_time_s / sim.timestep))
        for t in np.arange(1, steps + 1) / steps:
            z = grip_z + sim.lift_height_mm * (1 - np.cos(np.pi * t)) / 2
            self.hand.move(np.array([*palm, z]), yaw)
            counter.step()

    def _robustness(self, yaw: float, noise: TrialNoise, counter: _StepCounter) -> float:
        """The disturbance ramp from this moment (``grip_env.sim.disturbance``)."""
        moment = _HeldMoment(self, yaw, counter)
        try:
            search = self.ramp or robustness
            return search(moment.probe(), self.mass_kg * noise.mass_scale, self.gyration_m,
                          self.config.sim)
        finally:
            moment.close()

    def _object_in_palm(self) -> tuple[pose.Vector, pose.Quaternion]:
        """The object's pose (mm, quaternion) in the palm frame."""
        palm, palm_orn = self.hand.palm_pose_floats()
        return pose.in_frame(palm, palm_orn, *self.world.pose_floats_mm(self.object.uid))

    def _moved_from(self, reference: tuple[pose.Vector, pose.Quaternion]) -> tuple[float, float]:
        """Drift (mm) and rotation (deg) of the object in the palm frame since ``reference``."""
        return pose.moved_from(reference, self._object_in_palm())

    def _object_height(self) -> float:
        return float(self.world.pose_mm(self.object.uid)[0][2])


class _HeldMoment:
    """The held grip's moment, saved for the ramp: its probe restores it, pushes the object,
    steps, watches the object in the palm frame and (where the engine resumes exactly) pauses a
    climb in progress."""

    def __init__(self, scene: TrialScene, yaw: float, counter: _StepCounter) -> None:
        self.scene, self.world, self.counter = scene, scene.world, counter
        self.saved, self.hand_state = self.world.pause(), scene.hand.state()
        self.reference = self.seen = scene._object_in_palm()
        self.paused: set[int] = set()
        self.palm_axes = np.stack([palm_to_world(yaw, np.eye(3)[k]) for k in range(3)])

    def probe(self) -> RampProbe:
        return RampProbe(self.restore, self.push, self.counter.step, self.moved, self.where,
                         self.palm_axes, self.pause if self.world.resumes_exactly else None)

    def restore(self) -> None:
        self.world.restore(self.saved)
        self.scene.hand.restore(self.hand_state)
        self.seen = self.reference

    def push(self, kind: str, vector: NDArray) -> None:
        if kind == "torque":
            self.world.twist(self.scene.object.uid, vector)
        else:
            self.world.push(self.scene.object.uid, vector)

    def moved(self) -> bool:
        sim = self.scene.config.sim
        self.seen = self.scene._object_in_palm()
        drift, turn = pose.moved_from(self.reference, self.seen)
        return drift > sim.hold_tolerance_mm or turn > sim.hold_rotation_deg

    def where(self) -> tuple[pose.Vector, pose.Quaternion]:
        return self.seen

    def pause(self) -> Callable[[], None]:
        """Save this moment of a climb; the callable returned resumes it (once)."""
        key, hand_state, seen = self.world.pause(), self.scene.hand.state(), self.seen
        self.paused.add(key)

        def resume() -> None:
            self.world.resume(key)
            self.scene.hand.resume(hand_state)
            self.seen = seen
            self.world.forget(key)
            self.paused.discard(key)
        return resume

    def close(self) -> None:
        """Free every state saved for the ramp."""
        for key in (self.saved, *self.paused):
            self.world.forget(key)


class _StepCounter:
    """Steps the world with the hand's controller updated before each step, and counts."""

    def __init__(self, world: Engine, hand: Hand) -> None:
        self.world, self.hand, self.steps = world, hand, 0

    def step(self, n: int = 1) -> None:
        hold, step = self.hand.hold_fingers, self.world.step
        for _ in range(n):
            hold()
            step()
        self.steps += n
