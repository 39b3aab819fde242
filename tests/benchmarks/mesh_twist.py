"""Each finger contact's load under a held twist about the palm normal, both engines (run by
hand; issue 45).

    python -m tests.benchmarks.mesh_twist urdf_930 --grip 0 --trial 0 --levels 45 64 90

Runs one grip and trial of a cross-check object in both engines to the end of its hold, then,
from that moment, applies a constant twist about the palm normal (one level at a time, ``m a g
k`` as the ramp does, both signs, from the held state each time) for
``ramp_max_steps_per_level`` steps (``--steps``) and prints: where the object went (drift mm,
turn deg in the palm frame, the ramp failing at 5 mm or 10 deg; the turn's axis in the palm
frame: z a twist, x a pivot about the squeeze axis), the spread joints' angles from their
target, how far each finger's contact point moved on the object and on the finger (sliding
moves it on the object only, rolling on both), and each contact's normal force, sideways load
``|f_t| / (mu N)`` and (MuJoCo) twist load ``tau / (mu s N)`` at the last step (1: on the
bound). Reads MuJoCo's contacts as ``crosscheck_contact_loads`` does.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse

import numpy as np

import grip_env.sim.trial as trial_module
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.sim import pose
from grip_env.sim.disturbance import GRAVITY
from grip_env.sim.hand import SPREAD_JOINTS
from grip_env.sim.trial import TrialScene
from tests.benchmarks.crosscheck_contact_loads import trial_setup

ENGINES = ("pybullet", "mujoco")


def contact_points(scene: TrialScene, engine: str) -> dict[int, tuple]:
    """Per finger link pressing the object (>= 1 N): its force-weighted contact point (mm) in
    the object's frame and in the link's frame."""
    world, hand, obj = scene.world, scene.hand.uid, scene.object.uid
    found: dict[int, list] = {}
    if engine == "mujoco":
        m, d = world._compiled()
        uid, link_of = world._body_uid, world._body_link
        for c in d.contact[: d.ncon]:
            bodies = m.geom_bodyid[[c.geom1, c.geom2]]
            owners = uid[bodies].tolist()
            if set(owners) == {hand, obj} and c.efc_address >= 0:
                link = int(link_of[bodies[owners.index(hand)]])
                found.setdefault(link, []).append((float(d.efc_force[c.efc_address]),
                                                   np.asarray(c.pos) * 1000.0))
    else:
        for p in world.client.getContactPoints(bodyA=hand, bodyB=obj):
            found.setdefault(int(p[3]), []).append((float(p[9]), np.asarray(p[5]) * 1000.0))
    out = {}
    body = world.pose_floats_mm(obj)
    for link, rows in found.items():
        total = sum(n for n, _ in rows)
        if total < 1.0:
            continue
        point = sum(n * x for n, x in rows) / total
        frame = world.link_pose_floats_mm(hand, link)
        out[link] = (np.asarray(pose.in_frame(*body, point, (0, 0, 0, 1))[0]),
                     np.asarray(pose.in_frame(*frame, point, (0, 0, 0, 1))[0]))
    return out


def turn_axis(reference, current) -> str:
    """The unit axis (palm frame) of the turn from ``reference`` to ``current``."""
    x, y, z, _ = pose.multiply(current[1], pose.conjugate(reference[1]))
    norm = (x * x + y * y + z * z) ** 0.5
    if norm < 1e-12:
        return "none"
    return f"({x / norm:+.2f}, {y / norm:+.2f}, {z / norm:+.2f})"


def twisted(check, grip: int, trial: int, engine: str, levels: list[float],
            steps: int | None = None) -> list[str]:
    """Lines of the table for one engine: per level and sign, the motion and contact loads."""
    config, plan, noise, read = trial_setup(check, grip, trial, engine)
    lines: list[str] = []
    scenes: list[TrialScene] = []

    def robustness(probe, mass_kg: float, gyration_m: float, sim) -> float:
        scene = scenes[0]
        for level in levels:
            for sign in (1.0, -1.0):
                probe.restore()
                start = probe.where()
                before = contact_points(scene, engine)
                torque = sign * probe.palm_axes[2] * mass_kg * GRAVITY * gyration_m * level
                worst = (0.0, 0.0)
                for _ in range(steps or sim.ramp_max_steps_per_level):
                    probe.push("torque", torque)
                    probe.step()
                    drift, turn = pose.moved_from(start, scene._object_in_palm())
                    worst = (max(worst[0], drift), max(worst[1], turn))
                axis = turn_axis(start, scene._object_in_palm())
                after = contact_points(scene, engine)
                shifts = ", ".join(
                    f"{link}: {np.linalg.norm(after[link][0] - before[link][0]):.2f} / "
                    f"{np.linalg.norm(after[link][1] - before[link][1]):.2f}"
                    for link in sorted(set(before) & set(after)))
                angles = scene.world.joint_states(scene.hand.uid, list(SPREAD_JOINTS))[0]
                spread = ", ".join(f"{np.degrees(a - scene.hand.spread):+.2f}" for a in angles)
                contacts = "; ".join(
                    f"link {link}: N {n:.1f}, side {ft / (mu * n):.2f}"
                    + ("" if tau != tau else f", twist {tau / (spin * n):.2f}")
                    for link, n, ft, tau, mu, spin in sorted(read(scene)) if n >= 0.5)
                lines.append(f"| {engine} | {level:g} | {sign:+.0f} | {worst[0]:.2f} | "
                             f"{worst[1]:.2f} | {axis} | "
                             f"{spread} | {shifts} | {contacts} |")
        return 0.0

    original = trial_module.robustness
    trial_module.robustness = robustness
    try:
        with TrialScene(check.task.obj, config) as scene:
            scenes.append(scene)
            scene.run(plan, noise)
    finally:
        trial_module.robustness = original
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("object_id")
    parser.add_argument("--grip", type=int, default=0)
    parser.add_argument("--trial", type=int, default=0)
    parser.add_argument("--levels", type=float, nargs="+", default=[45.0, 64.0, 90.0])
    parser.add_argument("--steps", type=int, default=None,
                        help="steps each level is held (default: ramp_max_steps_per_level)")
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    check = next(c for c in _retest_sample(standard_path(), args.objects, args.seed)
                 if c.task.object_id == args.object_id)
    print(f"{args.object_id} grip {args.grip} trial {args.trial}")
    print("| engine | level (g) | sign | drift mm (max) | turn deg (max) | turn axis (palm) "
          "| spread joints from their target (deg) "
          "| contact point moved, link: on object / on finger (mm) "
          "| contacts at the last step (side: |f_t| / (mu N); twist: tau / (mu s N)) |")
    print("| --- " * 9 + "|")
    for engine in ENGINES:
        print("\n".join(twisted(check, args.grip, args.trial, engine, args.levels,
                                   args.steps)), flush=True)


if __name__ == "__main__":
    main()
