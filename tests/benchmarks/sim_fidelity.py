"""Measurements behind BENCHMARKS.md's "Simulator" section (run by hand, they take minutes).

    python -m tests.benchmarks.sim_fidelity convergence
    python -m tests.benchmarks.sim_fidelity decomposition
    python -m tests.benchmarks.sim_fidelity slip
    python -m tests.benchmarks.sim_fidelity cost
    python -m tests.benchmarks.sim_fidelity curve --trials 3
    python -m tests.benchmarks.sim_fidelity ramp --steps 3 6 --trials 5 --cache runs/ramp
    python -m tests.benchmarks.sim_fidelity ramp --key ramp_max_steps_per_level --steps 60 120 \
        --trials 5 --cache runs/ramp
    python -m tests.benchmarks.sim_fidelity paired --b sim.solver_iterations=300 --trials 1200
    python -m tests.benchmarks.sim_fidelity chaos
    python -m tests.benchmarks.sim_fidelity directions --b sim.solver_iterations=300 --trials 2
    python -m tests.benchmarks.sim_fidelity paired --variant first-piece-friction
    python -m tests.benchmarks.sim_fidelity paired --variant proximal-clutch
    python -m tests.benchmarks.sim_fidelity paired --variant floor-erp
    python -m tests.benchmarks.sim_fidelity paired --variant rigid-pads
    python -m tests.benchmarks.sim_fidelity paired --variant restored-scene
    python -m tests.benchmarks.sim_fidelity paired --variant weak-stop      # HOLD_FACTOR 2.5
    python -m tests.benchmarks.sim_fidelity paired --variant strong-stop    # HOLD_FACTOR 10
    python -m tests.benchmarks.sim_fidelity paired --variant capped-stop    # HOLD_FACTOR 5

* ``convergence``: a symmetric grip closes on a pinned 90 x 55 mm box; for each solver
  iteration count, each finger's joint-2 motor torque against its command and its fingertip
  normal force against ``sim.finger_force_n``, all three closing together and each alone.
* ``decomposition``: the same close; each finger's torque balance about joint 2 (normal
  forces, friction, motor, and the floor's share), at 100, 200 and 300 iterations, with the
  worm gear's floors and without them.
* ``slip``: how far the loaded worm-gear stops let joints slip below their floors in the best
  grips' trials, and the share of closes that settle, at 100, 150, 200 and 300 iterations.
* ``curve``: success and robustness of the same (grip, trial) draws at 100, 200 and 400 solver
  iterations, each count paired with the first.
* ``ramp``: success and robustness of the same draws at each value of a ramp hold setting (the
  steps a level is held at least, or at most), each paired with the next: the ramp's
  convergence in time, N against 2N.
* ``cost``: time per physics step and per trial of the same grips at 100, 150 and 200 iterations.
* ``paired``: the same (grip, trial) pairs under config A (the default) and config B (dotted
  overrides); the paired difference in success and in robustness with 95 % intervals, and the
  share of trials whose success flips.
* ``chaos``: the same pairs with the palm moved by 1 nm: the flip rate a change must beat.
* ``directions``: ``paired`` with every planar direction ramped to its end, and the mean change of
  each direction's level in octaves: which disturbance a change moves.

Grips: every default object's candidates, a stratified sample of ``--per-object`` per object.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np
import pandas as pd

from grip_env.config import Config
from grip_env.objects import load_object_set, make_shape
from grip_env.planning.pipeline import candidates
from grip_env.sim import TrialResult, TrialScene, grip_plans
from grip_env.sim.execution import grip_keys
from grip_env.sim.uncertainty import (
    sample_noise,
    stable_key,
    trial_noises,
    trial_rng,
    zero_noise,
)


def convergence(iterations: tuple[int, ...] = (50, 100, 150, 200, 300)) -> list[dict]:
    """Motor torque / command and fingertip normal force per finger on a pinned box: all three
    closing together, and each closing alone (``alone_normal_force_n``, the others idle)."""
    rows = []
    for n in iterations:
        config = Config().override(sim={"solver_iterations": n})
        with _pinned_box(config) as scene:
            torques = scene.hand.motor_torques()[:, 0]
            commands = np.array([f.tau2 for f in scene.hand.fingers])
            normals = _finger_normal_forces(scene)
        rows.append({"iterations": n, "torque_ratio": (torques / commands).round(3).tolist(),
                     "normal_force_n": normals.round(2).tolist(),
                     "alone_normal_force_n": pinned_alone(config).round(2).tolist()})
    return rows


def pinned_alone(config: Config) -> np.ndarray:
    """Each finger's normal force on the pinned box when it closes alone (3,), N."""
    forces = np.zeros(3)
    for i in range(3):
        with _pinned_box(config, alone=i) as scene:
            forces[i] = _finger_normal_forces(scene)[i]
    return forces


#: The torque of an idle finger's motors (N·m): it stays open, touching with under 0.1 N.
IDLE_TORQUE = 1e-3


@contextlib.contextmanager
def _pinned_box(config: Config, floors: bool = True, alone: int | None = None,
                steps: int = 120) -> Iterator[TrialScene]:
    """The symmetric grip closed for ``steps`` steps on the 90 x 55 mm box pinned to the world;
    ``floors=False`` leaves the worm gear's floors at the URDF's limits (motors only); with
    ``alone`` only that finger closes.

    Why each finger alone: with all three on an immovable box the two fingers' 30 N against the
    thumb's 15 N leave 15 N that the hand's hold and the locked thumb share, in a proportion
    only their compliances set (rigid bodies leave it undetermined), so the thumb presses more
    than its motor whatever the finger model."""
    box = make_shape("rectangle")
    grip = pd.DataFrame([{"hand_x": 0.0, "hand_y": 0.0, "hand_yaw": np.pi / 2, "spread": 0.0,
                          "p1_x": 25.0, "p1_y": 27.5, "p2_x": -25.0, "p2_y": 27.5,
                          "p3_x": 0.0, "p3_y": -27.5}])
    plan = grip_plans(grip)[0]
    with TrialScene(box, config) as scene:
        if not floors:
            scene.hand._raise_floors = lambda which: None  # type: ignore[method-assign]
        c = scene.world.client
        noise = sample_noise(trial_rng(0, 0, 0), config)
        noise = replace(noise, offset_mm=(0.0, 0.0), yaw_error=0.0)
        palm, yaw, z = scene._place(plan, noise)
        if alone is not None:
            for i, finger in enumerate(scene.hand.fingers):
                if i != alone:
                    finger.tau2 = finger.tau3 = IDLE_TORQUE
            scene.hand._command_motors()
            scene.hand._raise_floors(range(6))
        c.createConstraint(scene.object.uid, -1, -1, -1, c.JOINT_FIXED, [0, 0, 0],
                           [0, 0, 0], [0, 0, 0.015])
        scene._approach(palm, yaw, z)
        for _ in range(steps):
            scene.hand.drive_fingers(scene.hand.touching(scene.object.uid))
            scene.world.step()
        yield scene


def decomposition(iterations: tuple[int, ...] = (100, 200, 300)) -> list[dict]:
    """Where each pad's normal force on the pinned box comes from: the torque balance of the
    finger (both links) about joint 2, with and without the worm gear's floors.

    The normal forces open the finger about joint 2 with ``normal_nm``; the motor (``motor_nm``)
    and the pads' friction (``friction_nm``, positive when it closes the finger) hold it; what
    balances the rest (``floor_nm``) can only come from the joint's lower limit (gravity on the
    links is below 0.01 N·m: it is the whole remainder with the floors off). PyBullet reports
    a contact's friction as the force on the body of the lower id, whichever body is asked
    first (measured: a box pushed by 3 N along x on a plane reads +3 N in either order), while
    the normal is turned towards ``bodyA``; the object (id 1) is loaded before the hand (id 2),
    so the friction on the hand is minus the reported one. ``normal_n`` is the pad force,
    ``lever_mm`` the normal torque over it.
    """
    rows = []
    for n in iterations:
        for floors in (True, False):
            config = Config().override(sim={"solver_iterations": n})
            with _pinned_box(config, floors) as scene:
                rows.append({"iterations": n, "floors": floors,
                             "fingers": _joint2_balance(scene)})
    return rows


def _joint2_balance(scene: TrialScene) -> list[dict]:
    c, hand, obj = scene.world.client, scene.hand, scene.object.uid
    sign = -1.0 if obj < hand.uid else 1.0  # friction reported on the lower id (docstring)
    points = c.getContactPoints(bodyA=hand.uid, bodyB=obj)
    out = []
    for finger, motor in zip(hand.fingers, hand.motor_torques()[:, 0], strict=True):
        joint = finger.joints[0]
        state = c.getLinkState(hand.uid, joint, computeForwardKinematics=1)
        axis = (np.asarray(c.getMatrixFromQuaternion(state[5])).reshape(3, 3)
                @ np.asarray(c.getJointInfo(hand.uid, joint)[13]))
        normal_nm = friction_nm = normal_n = 0.0
        for p in (p for p in points if p[3] in finger.links):
            arm = np.asarray(p[5]) - np.asarray(state[4])
            friction = sign * (p[10] * np.asarray(p[11]) + p[12] * np.asarray(p[13]))
            normal_nm -= float(np.cross(arm, p[9] * np.asarray(p[7])) @ axis)
            friction_nm += float(np.cross(arm, friction) @ axis)
            normal_n += p[9]
        out.append({"normal_n": round(normal_n, 2), "motor_nm": round(float(motor), 3),
                    "normal_nm": round(normal_nm, 3), "friction_nm": round(friction_nm, 3),
                    "floor_nm": round(normal_nm - friction_nm - float(motor), 3),
                    "lever_mm": round(1e3 * normal_nm / normal_n, 1) if normal_n else None})
    return out


def floor_slip(iterations: tuple[int, ...] = (100, 150, 200, 300)) -> list[dict]:
    """How far the loaded worm-gear stops let their joints slip below their floors in trials:
    the best 3 grips of every default object at zero noise, the largest slip of any flexion
    joint after the close and after the lift (mrad), and the share of closes that settle."""
    rows = []
    for n in iterations:
        config = Config().override(sim={"solver_iterations": n})
        slips: dict[str, list[float]] = {"closed": [], "held": []}
        settled = [r.close_steps < config.sim.max_close_steps
                   for r in best_grip_trials(config, _slip_recorder(slips))]
        row: dict = {"iterations": n, "closes": len(settled),
                     "settled": round(float(np.mean(settled)), 3)}
        for phase, values in slips.items():
            v = np.asarray(values)
            row[phase] = {"median_mrad": round(float(np.median(v)), 2),
                          "p90_mrad": round(float(np.percentile(v, 90)), 2),
                          "max_mrad": round(float(v.max()), 2),
                          "over_1_mrad": round(float((v > 1).mean()), 3)}
        rows.append(row)
    return rows


def best_grip_trials(config: Config,
                     on_phase: Callable[[str, TrialScene], None] | None = None,
                     per_object: int = 3) -> list[TrialResult]:
    """One zero-noise trial of each default object's best ``per_object`` grips by Q_C."""
    results = []
    for obj in load_object_set("default"):
        table = candidates(obj, config=config)
        if not len(table):
            continue
        with TrialScene(obj, config) as scene:
            for plan in grip_plans(table.head(per_object)):
                results.append(scene.run(plan, zero_noise(config), on_phase))
    return results


def _slip_recorder(slips: dict[str, list[float]]) -> Callable[[str, TrialScene], None]:
    """An ``on_phase`` callback appending, at each phase named in ``slips``, the largest slip
    of any flexion joint below its floor (mrad)."""
    def on_phase(name: str, scene: TrialScene) -> None:
        if name in slips:
            q, _ = scene.hand.joint_states()
            below = np.reshape(scene.hand.state().peak, (3, 2)) - q
            slips[name].append(1e3 * float(below.max()))
    return on_phase


def cost(iterations: tuple[int, ...] = (100, 150, 200), repeats: int = 3) -> list[dict]:
    """Time per step and per trial of the same 8 pentagon grips at each solver setting.

    The settings alternate within each repeat, so machine load hits them alike; the fastest
    repeat is kept.
    """
    obj = make_shape("pentagon")
    plans = grip_plans(candidates(obj).iloc[::20].head(8))
    scenes = {n: TrialScene(obj, Config().override(sim={"solver_iterations": n}))
              for n in iterations}
    best: dict[int, tuple[float, int]] = {}
    for rep in range(repeats):
        for n, scene in scenes.items():
            started, steps = time.perf_counter(), 0
            for k, plan in enumerate(plans):
                steps += scene.run(plan, sample_noise(trial_rng(0, k, rep), scene.config)).steps
            took = time.perf_counter() - started
            if n not in best or took < best[n][0]:
                best[n] = (took, steps)
    for scene in scenes.values():
        scene.close()
    return [{"iterations": n, "us_per_step": round(1e6 * took / steps, 1),
             "ms_per_trial": round(1e3 * took / len(plans), 1),
             "steps_per_trial": round(steps / len(plans))} for n, (took, steps) in best.items()]


def closing_energy_j(scene: TrialScene, finger: int) -> float:
    """The kinetic energy of ``finger`` closing freely at the config's speed: joint 2 at
    ``close_speed_rad_s``, joint 3 geared to a third of it, through the hand's joint-space mass
    matrix at its pose (the links and the motor's rotor, reflected through the worm gear)."""
    c, uid = scene.world.client, scene.hand.uid
    movable = [j for j in range(c.getNumJoints(uid))
               if c.getJointInfo(uid, j)[2] != c.JOINT_FIXED]
    mass = np.array(c.calculateMassMatrix(uid, [c.getJointState(uid, j)[0] for j in movable]))
    rate = np.zeros(len(movable))
    joint2, joint3 = scene.hand._flex[2 * finger:2 * finger + 2]
    speed = scene.hand.config.close_speed_rad_s
    rate[movable.index(joint2)], rate[movable.index(joint3)] = speed, speed / 3
    return float(0.5 * rate @ mass @ rate)


def _finger_normal_forces(scene: TrialScene) -> np.ndarray:
    c, hand = scene.world.client, scene.hand
    points = c.getContactPoints(bodyA=hand.uid, bodyB=scene.object.uid)
    forces = np.zeros(3)
    for i, finger in enumerate(hand.fingers):
        forces[i] = sum(p[9] for p in points if p[3] in finger.links)
    return forces


def sample_grips(per_object: int, config: Config) -> list[tuple[object, pd.DataFrame]]:
    """A stratified sample of each default object's candidates over its Q_C ranking."""
    out = []
    for obj in load_object_set("default"):
        table = candidates(obj, config=config)
        if len(table):
            picks = np.unique(np.linspace(0, len(table) - 1, per_object).round().astype(int))
            out.append((obj, table.iloc[picks]))
    return out


#: Fixes that can be undone one at a time, to measure what each changes (config B runs them).
VARIANTS = ("none", "first-piece-friction", "proximal-clutch", "floor-erp", "rigid-pads",
            "restored-scene", "weak-stop", "strong-stop", "capped-stop")
#: The worm gear stop's holding torque (``hand.HOLD_FACTOR`` times the motor's) of the stop
#: variants: the range measured around the label model 2026.12-hertz's 5 (BENCHMARKS,
#: "HOLD_FACTOR"), and that 5 itself (``capped-stop``, against a self-locking gear's unbounded
#: stop since 2026.12-worm).
STOP_FACTORS = {"weak-stop": 2.5, "strong-stop": 10.0, "capped-stop": 5.0}


#: Bullet's non-contact erp before the arm (measured then: a fifth of a joint's gap per step).
FLOOR_ERP_BEFORE = 0.2


def _apply(variant: str) -> None:
    """Undo one fix in this (worker) process."""
    if variant == "first-piece-friction":
        from grip_env.sim import world

        def base_only(self, body, mass_kg, friction, spinning_friction=1.0):
            inertia = [i * mass_kg for i in body.inertia_per_kg]
            self.client.changeDynamics(body.uid, -1, mass=mass_kg, localInertiaDiagonal=inertia,
                                       lateralFriction=friction,
                                       spinningFriction=spinning_friction)

        world.World.set_dynamics = base_only
    elif variant == "floor-erp":  # 4518833's: joint limits corrected towards their floors
        from grip_env.sim import world

        reset = world.World.reset

        def with_erp(self):
            reset(self)
            self.client.setPhysicsEngineParameter(erp=FLOOR_ERP_BEFORE)

        world.World.reset = with_erp
    elif variant in STOP_FACTORS:
        from grip_env.sim import hand

        hand.HOLD_FACTOR = STOP_FACTORS[variant]
    elif variant == "restored-scene":  # cb01661's: one world per scene, restored every trial
        from grip_env.sim import trial

        build = trial.TrialScene._build

        def build_and_save(self):
            build(self)
            self._saved = self.world.save()

        def restore(self):
            self.world.restore(self._saved)

        trial.TrialScene._build = build_and_save
        trial.TrialScene.fresh = restore
    elif variant == "rigid-pads":  # ba7f89a's pad sphere with a rigid contact, as before it
        from grip_env.sim import world

        world.World.set_contact_compliance = lambda self, *args: None
    elif variant == "proximal-clutch":
        from grip_env.sim import hand

        def drive_fingers(self, touching=None):  # 6e85518's: only the proximal link breaks away
            q, dq = self.world.joint_positions_velocities(self.uid, self._flex)
            advanced = self._follow(q)
            if touching is not None:
                for i, finger in enumerate(self.fingers):
                    if touching[i, 0] and dq[2 * i] < 0.1 * self.config.close_speed_rad_s:
                        finger.broken_away = True
            if advanced or touching is not None:
                self._command_motors()
            return np.array(dq).reshape(3, 2)

        hand.Hand.drive_fingers = drive_fingers


def _every_direction(probe, mass_kg: float, gyration_m: float, config) -> float:
    """``disturbance.robustness`` with every direction ramped to its end (not stopped at the
    weakest so far); the levels are kept in ``_DIRECTION_LEVELS``."""
    from grip_env.sim import disturbance

    levels = disturbance.ramp_levels(config)
    held = []
    for kind, axis, sign in disturbance.disturbances(config):
        probe.restore()
        scale = mass_kg * disturbance.GRAVITY * (gyration_m if kind == "torque" else 1.0)
        failed = disturbance._first_failure(probe, kind, sign * probe.palm_axes[axis] * scale,
                                            levels, config)
        held.append(float(levels[failed - 1]) if failed else 0.0)
    _DIRECTION_LEVELS[:] = held
    return min(held)


_DIRECTION_LEVELS: list[float] = []
#: The planar disturbances' names, in ``disturbance.PLANAR_DISTURBANCES`` order.
DIRECTIONS = ("+x", "-x", "+y", "-y", "+twist", "-twist")


def _run(args: tuple) -> list[tuple]:
    obj, grips, config, trials, shift_mm, variant, directions, first = args
    _apply(variant)
    if directions:
        from grip_env.sim import trial

        trial.robustness = _every_direction  # this worker process only
    rows = []
    keys = grip_keys(grips)
    draws = trial_noises(config, 0, stable_key(obj.name), keys, range(first, first + trials))
    with TrialScene(obj, config) as scene:
        for plan, key, noises in zip(grip_plans(grips), keys, draws, strict=True):
            for k, noise in enumerate(noises, start=first):
                if shift_mm:
                    noise = replace(noise, offset_mm=(noise.offset_mm[0] + shift_mm,
                                                      noise.offset_mm[1]))
                _DIRECTION_LEVELS[:] = [0.0] * len(DIRECTIONS)  # a trial not held ramps none
                r = scene.run(plan, noise)
                row = (obj.name, key, k, r.success, r.robustness_g, r.held, r.steps)
                rows.append(row + (tuple(_DIRECTION_LEVELS) if directions else ()))
    return rows


def outcomes(config: Config, per_object: int, trials: int, shift_mm: float = 0.0,
             workers: int = 2, variant: str = "none", directions: bool = False,
             first_trial: int = 0) -> pd.DataFrame:
    """One row per (object, grip, trial) under ``config`` (with one fix undone: ``variant``);
    with ``directions`` also the level held in each planar direction, every ramp run to its
    end."""
    if directions and config.sim.ramp_directions != "planar":
        raise ValueError("directions ramps the planar disturbances only")
    jobs = [(obj, g, config, trials, shift_mm, variant, directions, first_trial)
            for obj, g in sample_grips(per_object, Config())]
    with ProcessPoolExecutor(workers) as pool:
        rows = [row for part in pool.map(_run, jobs) for row in part]
    return pd.DataFrame(rows, columns=["object", "grip", "trial", "success", "robustness",
                                       "held", "steps", *(DIRECTIONS if directions else ())])


def paired_directions(a: pd.DataFrame, b: pd.DataFrame) -> dict:
    """``paired_difference`` plus, per direction, the mean change of the level held in
    octaves (log2 of B over A, levels below 1 g counted as 1 g)."""
    m = a.merge(b, on=["object", "grip", "trial"], suffixes=("_a", "_b"))
    octaves = {d: round(float(np.mean(np.log2(np.maximum(m[f"{d}_b"], 1.0))
                                      - np.log2(np.maximum(m[f"{d}_a"], 1.0)))), 3)
               for d in DIRECTIONS}
    return {**paired_difference(a, b), "octaves": octaves}


def label_curve(iterations: tuple[int, ...] = (100, 200, 400), per_object: int = 20,
                trials: int = 3, workers: int = 2) -> list[dict]:
    """Success and robustness of the same draws at each solver iteration count; every count
    after the first is also paired with the first (``paired_difference``)."""
    rows, first = [], None
    for n in iterations:
        out = outcomes(Config().override(sim={"solver_iterations": n}), per_object, trials,
                       workers=workers)
        row: dict = {"iterations": n, "success": round(float(out.success.mean()), 4),
                     "robustness_g": round(float(out.robustness.mean()), 2)}
        if first is None:
            first = out
        else:
            row["against_first"] = paired_difference(first, out)
        rows.append(row)
    return rows


def ramp_convergence(steps: tuple[int, ...] = (3, 6, 12), per_object: int = 20, trials: int = 3,
                     workers: int = 2, cache: str | None = None,
                     key: str = "ramp_steps_per_level") -> list[dict]:
    """Labels of the same draws at each value of the ramp setting ``key`` (``sim.<key>``: the
    steps a level is held at least, or at most), each value paired with the next (N against 2N
    when the values double); ``cache`` keeps each value's trials."""
    from pathlib import Path

    rows, previous = [], None
    for n in steps:
        path = Path(cache) / f"{key}_{n}.parquet" if cache else None
        kept = pd.read_parquet(path) if path is not None and path.exists() else None
        done = 0 if kept is None else int(kept["trial"].max()) + 1
        out = kept
        if done < trials:  # only the trial numbers the cache lacks
            more = outcomes(Config().override(sim={key: n}), per_object,
                            trials - done, workers=workers, first_trial=done)
            out = more if kept is None else pd.concat([kept, more], ignore_index=True)
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                out.to_parquet(path)
        out = out[out["trial"] < trials]
        row: dict = {key: n, "success": round(float(out.success.mean()), 4),
                     "robustness_g": round(float(out.robustness.mean()), 2),
                     "steps": round(float(out.steps.mean()), 1)}
        if previous is not None:
            row["against_previous"] = paired_difference(previous, out)
        rows.append(row)
        previous = out
    return rows


def paired_difference(a: pd.DataFrame, b: pd.DataFrame) -> dict:
    """B minus A over the same trials: success (pp) and robustness (g) with 95 % intervals."""
    m = a.merge(b, on=["object", "grip", "trial"], suffixes=("_a", "_b"))
    ds = m["success_b"].astype(float) - m["success_a"].astype(float)
    dr = m["robustness_b"] - m["robustness_a"]

    def interval(d: pd.Series, scale: float) -> list[float]:
        half = 1.96 * d.std(ddof=1) / np.sqrt(len(d))
        return [round(scale * (d.mean() - half), 2), round(scale * (d.mean() + half), 2)]

    return {"trials": len(m), "success_a": round(m["success_a"].mean(), 4),
            "success_b": round(m["success_b"].mean(), 4),
            "success_diff_pp": round(100 * ds.mean(), 2), "success_ci_pp": interval(ds, 100),
            "robustness_diff_g": round(dr.mean(), 3), "robustness_ci_g": interval(dr, 1),
            "flip_rate": round(float((m["success_a"] != m["success_b"]).mean()), 4),
            "steps_a": round(m["steps_a"].mean(), 1), "steps_b": round(m["steps_b"].mean(), 1)}


def _overrides(items: list[str]) -> Config:
    sections: dict[str, dict] = {}
    for item in items:
        key, value = item.split("=", 1)
        section, name = key.split(".", 1)
        sections.setdefault(section, {})[name] = json.loads(value)
    return Config().override(**sections) if sections else Config()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("convergence", "decomposition", "slip", "cost",
                                           "curve", "ramp", "paired", "chaos", "directions"))
    parser.add_argument("--steps", type=int, nargs="*", default=[3, 6, 12],
                        help="ramp: steps per level to compare, each with the next")
    parser.add_argument("--cache", default=None, help="ramp: folder keeping each count's trials")
    parser.add_argument("--a-from", default=None,
                        help="paired, chaos: config A's trials from this file (a ramp cache of "
                             "the same --per-object) instead of running them")
    parser.add_argument("--key", default="ramp_steps_per_level",
                        choices=("ramp_steps_per_level", "ramp_max_steps_per_level"),
                        help="ramp: the setting --steps gives values of")
    parser.add_argument("--a", nargs="*", default=[], help="overrides of config A")
    parser.add_argument("--b", nargs="*", default=[], help="overrides of config B")
    parser.add_argument("--per-object", type=int, default=20)
    parser.add_argument("--trials", type=int, default=4, help="trials per grip")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--variant", choices=VARIANTS, default="none",
                        help="config B runs with this fix undone")
    args = parser.parse_args()
    started = time.perf_counter()
    if args.what == "convergence":
        result: object = convergence()
    elif args.what == "decomposition":
        result = decomposition()
    elif args.what == "slip":
        result = floor_slip()
    elif args.what == "cost":
        result = cost()
    elif args.what == "curve":
        result = label_curve(per_object=args.per_object, trials=args.trials,
                             workers=args.workers)
    elif args.what == "ramp":
        result = ramp_convergence(tuple(args.steps), args.per_object, args.trials,
                                  args.workers, args.cache, args.key)
    elif args.what == "directions":
        a, b = (outcomes(_overrides(side), args.per_object, args.trials,
                         workers=args.workers, directions=True) for side in (args.a, args.b))
        result = paired_directions(a, b)
    else:
        a = (pd.read_parquet(args.a_from).query(f"trial < {args.trials}") if args.a_from else
             outcomes(_overrides(args.a), args.per_object, args.trials, workers=args.workers))
        b = outcomes(_overrides(args.b if args.what == "paired" else args.a), args.per_object,
                     args.trials, shift_mm=1e-6 if args.what == "chaos" else 0.0,
                     workers=args.workers, variant=args.variant)
        result = paired_difference(a, b)
    print(json.dumps({"what": args.what, "a": args.a, "b": args.b, "variant": args.variant,
                      "result": result,
                      "seconds": round(time.perf_counter() - started, 1)}, indent=1))


if __name__ == "__main__":
    main()
