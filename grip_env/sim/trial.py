"""One grip execution in PyBullet: place, pre-shape, lower, close, lift, shake, judge.

A ``TrialScene`` owns one ``World`` with the table, the object and the hand, saved once; every
trial restores that state (cheaper than rebuilding, see the benchmark) and applies its noise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from grip_env import barrett
from grip_env.config import Config
from grip_env.objects import PlanarObject
from grip_env.sim.hand import Hand, closing_depth, closing_posture
from grip_env.sim.uncertainty import TrialNoise
from grip_env.sim.world import World

PLAN_COLUMNS = ("hand_x", "hand_y", "hand_yaw", "spread", "p1_x", "p1_y", "p2_x", "p2_y",
                "p3_x", "p3_y")
APPROACH_MM = 10.0  # the pre-shaped hand is lowered this far onto its grip height
APPROACH_STEPS = 8
SETTLE_STEPS = 8
HOLD_STEPS = 12
STALL_SPEED = 0.05  # rad/s: a finger whose joints move slower than this has stopped
SHAKE_DIRECTIONS = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


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
    """Outcome of one trial: held or not, object drift in the palm frame (mm), physics steps."""

    success: bool
    drift_mm: float
    lifted_mm: float
    steps: int
    close_steps: int


def finger_reaches(grips: pd.DataFrame) -> NDArray[np.float64]:
    """(n, 3) reach of each finger from its line origin to its contact, from the grip columns."""
    yaw, spread = grips["hand_yaw"].to_numpy(float), grips["spread"].to_numpy(float)
    palm = grips[["hand_x", "hand_y"]].to_numpy(float)
    forces = barrett.finger_forces(yaw, spread)
    origins = np.concatenate([barrett.spread_axes(palm, yaw), palm[:, None, :]], axis=1)
    contacts = grips[list(PLAN_COLUMNS[4:])].to_numpy(float).reshape(-1, 3, 2)
    return np.einsum("nij,nij->ni", origins - contacts, forces)


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
    """Table, object and hand in one headless world, reused across trials of one object."""

    def __init__(self, obj: PlanarObject, config: Config | None = None) -> None:
        self.obj = obj
        self.config = config if config is not None else Config()
        sim = self.config.sim
        self.thickness_mm = self.config.objects.thickness_mm
        self.world = World(timestep=sim.timestep, solver_iterations=sim.solver_iterations)
        self.world.add_table()
        mass = sim.mass_per_weight_kg * self.config.grasp.weight
        self.object = self.world.add_object(obj, self.thickness_mm, mass, self.config.grasp.mu)
        info = self.world.client.getDynamicsInfo(self.object.uid, -1)
        self._inertia_per_kg = np.asarray(info[2]) / info[0]
        self.hand = Hand(self.world, sim)
        self.hand.teleport(np.array([0.0, 0.0, 400.0]), 0.0)
        self.state = self.world.client.saveState()

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
        """Execute ``plan`` under ``noise``; ``on_phase(name, scene)`` is called at each phase."""
        self._reset(noise)
        counter = _StepCounter(self.world)
        notify = on_phase or (lambda name, scene: None)
        palm, yaw, grip_z = self._place(plan, noise)
        for z in np.linspace(grip_z + APPROACH_MM, grip_z, APPROACH_STEPS + 1)[1:]:
            self.hand.move(np.array([*palm, z]), yaw)
            counter.step(1, self.hand)
        notify("approach", self)
        close_steps = self._close(counter)
        counter.step(SETTLE_STEPS, self.hand)
        notify("closed", self)
        reference = self._object_in_palm()
        start_z = self._object_height()
        self._lift(palm, yaw, grip_z, counter)
        notify("lifted", self)
        self._shake(palm, yaw, grip_z + self.config.sim.lift_height_mm, counter)
        counter.step(HOLD_STEPS, self.hand)
        notify("shaken", self)
        drift = float(np.linalg.norm(self._object_in_palm() - reference))
        lifted = self._object_height() - start_z
        sim = self.config.sim
        held = drift < sim.hold_tolerance_mm and lifted > 0.5 * sim.lift_height_mm
        return TrialResult(bool(held), drift, float(lifted), counter.steps, close_steps)

    def _reset(self, noise: TrialNoise) -> None:
        c = self.world.client
        c.restoreState(self.state)
        c.changeDynamics(
            self.object.uid, -1, mass=noise.mass_kg, lateralFriction=noise.friction,
            localInertiaDiagonal=(self._inertia_per_kg * noise.mass_kg).tolist(),
        )

    def _place(self, plan: GripPlan, noise: TrialNoise) -> tuple[NDArray, float, float]:
        """Pre-shape the hand for the plan and put it (with error) just above its grip height."""
        sim = self.config.sim
        reach = np.asarray(plan.reach_mm)
        q2_grip, _ = closing_posture(reach)
        q2_open, _ = closing_posture(reach + sim.preshape_gap_mm)
        grip_z = float(closing_depth(q2_open, q2_grip).max() + sim.fingertip_clearance_mm)
        palm = np.asarray(plan.palm_mm) + np.asarray(noise.offset_mm)
        yaw = plan.yaw + noise.yaw_error
        self.hand.preshape(plan.spread, q2_open)
        self.hand.set_finger_torques(q2_grip)
        self.hand.teleport(np.array([*palm, grip_z + APPROACH_MM]), yaw)
        return palm, yaw, grip_z

    def _close(self, counter: _StepCounter) -> int:
        """Close all fingers until every one has stopped (or the step cap); returns steps used."""
        still = 0
        for step in range(1, self.config.sim.max_close_steps + 1):
            velocities = self.hand.drive_fingers(self.hand.touching(self.object.uid))
            counter.step()
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
            counter.step(1, self.hand)

    def _shake(self, palm: NDArray, yaw: float, z: float, counter: _StepCounter) -> None:
        """One sine period of ``shake_amplitude_mm`` along world x, then y, then z."""
        sim = self.config.sim
        if sim.shake_amplitude_mm == 0 or sim.shake_frequency_hz == 0:
            return
        steps = max(2, round(1.0 / (sim.shake_frequency_hz * sim.timestep)))
        phase = np.sin(2 * np.pi * np.arange(1, steps + 1) / steps)
        centre = np.array([*palm, z])
        for direction in SHAKE_DIRECTIONS:
            for s in phase:
                self.hand.move(centre + sim.shake_amplitude_mm * s * np.asarray(direction), yaw)
                counter.step(1, self.hand)
        self.hand.move(centre, yaw)

    def _object_in_palm(self) -> NDArray[np.float64]:
        palm_pos, palm_orn = self.hand.palm_pose_mm()
        obj_pos, _ = self.world.pose_mm(self.object.uid)
        return Rotation.from_quat(palm_orn).inv().apply(obj_pos - palm_pos)

    def _object_height(self) -> float:
        return float(self.world.pose_mm(self.object.uid)[0][2])


class _StepCounter:
    def __init__(self, world: World) -> None:
        self.world, self.steps = world, 0

    def step(self, n: int = 1, hand: Hand | None = None) -> None:
        """Step ``n`` times, updating the hand's motors before each step when given."""
        for _ in range(n):
            if hand is not None:
                hand.drive_fingers()
            self.world.step()
        self.steps += n


STRIP_PHASES = ("approach", "closed", "lifted", "shaken")


def render_trial_strip(
    obj: PlanarObject, grip: pd.Series | dict, config: Config | None = None, seed: int = 0,
    path: str | Path = "trial.png", width: int = 320, height: int = 240,
) -> TrialResult:
    """Run one trial of ``grip`` (a candidate row) and write a PNG strip of its phases.

    Frames: approach, closed, lifted, shaken, seen obliquely from the side; the trial's noise is
    drawn from ``seed`` (trial 0 of a grip keyed 0). Returns the trial's result.
    """
    from PIL import Image

    from grip_env.sim.uncertainty import sample_noise, trial_rng

    row = pd.DataFrame([dict(grip)])
    plan = grip_plans(row)[0]
    frames: list[NDArray[np.uint8]] = []

    def capture(name: str, scene: TrialScene) -> None:
        palm, _ = scene.hand.palm_pose_mm()
        target = np.array([*plan.palm_mm, 0.5 * palm[2]])
        eye = target + np.array([260.0, -260.0, 160.0])
        frames.append(scene.world.render(eye, target, width, height))

    with TrialScene(obj, config) as scene:
        noise = sample_noise(trial_rng(seed, 0, 0), scene.config)
        result = scene.run(plan, noise, on_phase=capture)
    Image.fromarray(np.concatenate(frames, axis=1)).save(Path(path))
    return result
