"""Each finger contact's load against the box and the ellipse at the lift, on trials the engines
judge differently (run by hand; issue 45).

    python -m tests.benchmarks.crosscheck_contact_loads \
        --parts /work/runs/crosscheck/standard40.crosscheck --drops 12 --controls 12

Draws (seeded) ``--drops`` trials of a cross-check's kept outcomes where PyBullet holds after the
lift and MuJoCo does not (robustness > 0 against 0), and ``--controls`` where both hold, runs each
again in both engines with its own grip and draw (as ``run_trial_outcomes`` does) up to the end of
the hold (the ramp is skipped), and after every step of the lift and the hold reads each
hand-object contact's normal force N, sideways force |f_t| and twist |tau| about its normal. Its
load against MuJoCo's elliptic cone is sqrt((f_t/mu)^2 + (tau/(mu s))^2) / N and against
Bullet's box max(f_t/(mu N), tau/(mu s N)); mu and mu s are the contact pair's own coefficients.

What each engine exposes: PyBullet's ``getContactPoints`` reports N and both sideways friction
forces but not the spinning-friction torque, so PyBullet's twist (and so its ellipse load) is not
read; its sideways load is. MuJoCo's elliptic contacts keep (N, f1, f2, tau) in ``efc_force``; the
world exposes no contact-wrench query, so this reads its model and data through the private
``_compiled()`` (as ``tests/test_mujoco_world.py`` does), read-only.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import contextlib
import json
import time
from pathlib import Path

import numpy as np

from grip_env.dataset.crosscheck import _from_json
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.sim import pose
from grip_env.sim.execution import grip_keys, object_key
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import trial_noises

ENGINES = ("pybullet", "mujoco")


class _HoldEnded(Exception):
    """Raised at the end of the hold: the ramp is not needed here."""


def pybullet_contacts(scene: TrialScene) -> list[tuple[int, float, float, float, float, float]]:
    """(hand link, N, |f_t|, tau (NaN: not reported), mu, mu s) of each hand-object contact."""
    world, hand, obj = scene.world, scene.hand.uid, scene.object.uid
    client = world.client
    rows = []
    for p in client.getContactPoints(bodyA=hand, bodyB=obj):
        pad, other = client.getDynamicsInfo(hand, p[3]), client.getDynamicsInfo(obj, p[4])
        mu = pad[1] * other[1]
        spin = pad[7] * other[1] + other[7] * pad[1]
        rows.append((int(p[3]), float(p[9]), float(np.hypot(p[10], p[12])), float("nan"),
                     mu, spin))
    return rows


def mujoco_hand_contacts(scene: TrialScene):
    """Each hand-object contact of MuJoCo's last step as (contact, hand link, its wrench in
    ``efc_force``: normal, two sideways, and twist with condim 4)."""
    world, hand, obj = scene.world, scene.hand.uid, scene.object.uid
    m, d = world._compiled()
    uid, link = world._body_uid, world._body_link
    for c in d.contact[: d.ncon]:
        bodies = m.geom_bodyid[[c.geom1, c.geom2]]
        owners = uid[bodies].tolist()
        if set(owners) == {hand, obj} and c.efc_address >= 0:
            yield (c, int(link[bodies[owners.index(hand)]]),
                   d.efc_force[c.efc_address: c.efc_address + c.dim])


def mujoco_contacts(scene: TrialScene) -> list[tuple[int, float, float, float, float, float]]:
    """(hand link, N, |f_t|, |tau|, mu, mu s) of each hand-object contact (elliptic cones)."""
    rows = []
    for c, hand_link, wrench in mujoco_hand_contacts(scene):
        tau = abs(float(wrench[3])) if c.dim >= 4 else 0.0
        rows.append((hand_link, float(wrench[0]), float(np.hypot(wrench[1], wrench[2])), tau,
                     float(c.friction[0]), float(c.friction[2]) if c.dim >= 4 else float("nan")))
    return rows


STILL_DEG = 1.0  # steps before the object has turned this far in the palm: before it pivots
MIN_NORMAL_N = 1.0  # lighter touches (grazes) are left out: their ratios say nothing of the grip


def loads(rows: list[tuple]) -> np.ndarray:
    """Per contact pressed with at least ``MIN_NORMAL_N``: (link, N, sideways f_t/(mu N), twist
    tau/(mu s N), ellipse, box)."""
    out = []
    for link, n, ft, tau, mu, spin in rows:
        if n < MIN_NORMAL_N:
            continue
        side, twist = ft / (mu * n), tau / (spin * n)
        out.append((link, n, side, twist, float(np.hypot(side, twist)), max(side, twist)))
    return np.array(out).reshape(-1, 6)


def run_to_hold(check, grip: int, trial: int, engine: str) -> dict[str, float]:
    """Run one trial to the end of its hold in ``engine``, recording loads after each step."""
    config, plan, noise, read = trial_setup(check, grip, trial, engine)
    steps: list[np.ndarray] = []
    turns: list[float] = []
    found: dict[str, float] = {}
    with TrialScene(check.task.obj, config) as scene:
        def on_phase(name: str, s: TrialScene) -> None:
            if name == "closed":
                found["z0"] = float(s.world.pose_mm(s.object.uid)[0][2])
                found["start"] = in_palm(s)
                stepper = s.world.step

                start = found["start"]

                def recording(n: int = 1) -> None:
                    stepper(n)
                    steps.append(loads(read(s)))
                    turns.append(pose.moved_from(start, in_palm(s))[1])
                s.world.step = recording
            if name == "held":
                found["lifted_mm"] = float(s.world.pose_mm(s.object.uid)[0][2]) - found["z0"]
                found["drift_mm"], found["turn_deg"] = pose.moved_from(found.pop("start"),
                                                                       in_palm(s))
                raise _HoldEnded
        with contextlib.suppress(_HoldEnded):
            scene.run(plan, noise, on_phase)
        sim = config.sim
        found["held"] = float(found["drift_mm"] <= sim.hold_tolerance_mm
                              and found["turn_deg"] <= sim.hold_rotation_deg
                              and found["lifted_mm"] > 0.5 * sim.lift_height_mm)
    still = [k for k, turn in enumerate(turns) if turn <= STILL_DEG]
    early = peak([steps[k] for k in still])
    before = {"still": len(still)} | {"still_" + k: v for k, v in early.items()}
    return {**found, **peak(steps), **onset(steps), **before}


def in_palm(scene: TrialScene):
    palm, orientation = scene.hand.palm_pose_floats()
    return pose.in_frame(palm, orientation, *scene.world.pose_floats_mm(scene.object.uid))


def peak(steps: list[np.ndarray]) -> dict[str, float]:
    """Over the lift and hold: the highest ellipse load of any contact (with that contact's box,
    sideways and twist loads), the highest box load and sideways load, and the share of steps
    with some contact whose ellipse reaches 0.98 while its box stays below 0.9."""
    table = np.concatenate([s for s in steps if len(s)]) if any(len(s) for s in steps) else (
        np.empty((0, 6)))
    if not len(table):
        return {"ellipse": np.nan, "box": np.nan, "side": np.nan, "twist": np.nan,
                "box_max": np.nan, "side_max": np.nan, "gap_steps": 0.0}
    finite = np.where(np.isfinite(table[:, 4]), table[:, 4], -1.0)
    top = table[int(np.argmax(finite))]
    gap = [bool(((s[:, 4] >= 0.98) & (s[:, 5] < 0.9)).any()) if len(s) else False for s in steps]
    return {"ellipse": float(top[4]) if finite.max() >= 0 else np.nan, "box": float(top[5]),
            "side": float(top[2]), "twist": float(top[3]),
            "box_max": float(np.nanmax(table[:, 5])), "side_max": float(table[:, 2].max()),
            "gap_steps": float(np.mean(gap))}


def onset(steps: list[np.ndarray], at: float = 0.98) -> dict[str, float]:
    """The first step of the lift or hold (1-based) at which some contact's ellipse load (or, in
    PyBullet, its sideways load: its twist is not reported) reaches ``at``, and that contact's
    link, sideways, twist and box loads (the contact with the highest ellipse load then)."""
    for k, s in enumerate(steps, start=1):
        if not len(s):
            continue
        level = np.where(np.isfinite(s[:, 4]), s[:, 4], s[:, 2])
        if level.max() >= at:
            c = s[int(np.argmax(level))]
            return {"onset": float(k), "onset_link": float(c[0]), "onset_side": float(c[2]),
                    "onset_twist": float(c[3]), "onset_box": float(c[5])}
    return {"onset": np.nan, "onset_link": np.nan, "onset_side": np.nan,
            "onset_twist": np.nan, "onset_box": np.nan}


def kept_runs(parts: Path, objects: int, seed: int):
    """(check, runs) of every object of the seeded cross-check sample whose outcomes ``parts``
    keeps (a ``validate --crosscheck`` run's parts folder)."""
    for check in _retest_sample(standard_path(), objects, seed):
        file = parts / f"{check.task.index:05d}.json"
        if file.is_file():
            yield check, _from_json(json.loads(file.read_text(encoding="utf-8")))


def trial_setup(check, grip: int, trial: int, engine: str):
    """(config, plan, noise, contact reader) of trial ``trial`` of grip ``grip`` in ``engine``:
    the recorded grip and its recorded draw."""
    config = check.task.config.override(sim={"engine": engine})
    grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
    rows = grips.iloc[[grip]]
    (plan,) = grip_plans(rows)
    ((noise,),) = trial_noises(config, config.dataset.seed, object_key(check.task.obj, rows),
                               grip_keys(rows), range(trial, trial + 1))
    return config, plan, noise, (mujoco_contacts if engine == "mujoco" else pybullet_contacts)


def sample(parts: Path, objects: int, seed: int, drops: int, controls: int):
    """Seeded draws of (check, grip, trial, kind) from the kept outcomes."""
    found = {"drop": [], "control": []}
    for check, runs in kept_runs(parts, objects, seed):
        a, b = (runs.draws[e] for e in ENGINES)
        ra, rb = a["robustness"].to_numpy(float), b["robustness"].to_numpy(float)
        for kind, mask in (("drop", (ra > 0) & (rb == 0)), ("control", (ra > 0) & (rb > 0))):
            found[kind] += [(check, int(g), int(t)) for g, t in
                            zip(a["grip"][mask], a["trial"][mask], strict=True)]
    rng = np.random.default_rng(seed)
    picked = []
    for kind, count in (("drop", drops), ("control", controls)):
        pool = found[kind]
        chosen = sorted(rng.choice(len(pool), min(count, len(pool)), replace=False))
        picked += [(*pool[i], kind) for i in chosen]
    return picked, {k: len(v) for k, v in found.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--drops", type=int, default=12)
    parser.add_argument("--controls", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    picked, pools = sample(args.parts, args.objects, args.seed, args.drops, args.controls)
    print(f"pools: {pools}; sampled {len(picked)}")
    print("| kind | object | grip | trial | engine | held | lifted mm | turn deg | peak ellipse "
          "| its box | its side | its twist | max box | max side | steps ellipse>=0.98 & box<0.9 "
          "| onset step (link) | onset side | onset twist | onset box | steps turned <= 1 deg "
          "| of them ellipse>=0.98 & box<0.9 |")
    print("| --- " * 21 + "|")
    started, results = time.process_time(), []
    for check, grip, trial, kind in picked:
        for engine in ENGINES:
            r = run_to_hold(check, grip, trial, engine)
            results.append((kind, engine, r))
            gap = (f"{r['gap_steps']:.0%}", f"{r['still_gap_steps']:.0%}") if engine == "mujoco" \
                else ("not read", "not read")
            print(f"| {kind} | {check.task.object_id} | {grip} | {trial} | {engine} | "
                  f"{'yes' if r['held'] else 'no'} | "
                  f"{r['lifted_mm']:.1f} | {r['turn_deg']:.1f} | {r['ellipse']:.2f} | "
                  f"{r['box']:.2f} | {r['side']:.2f} | {r['twist']:.2f} | {r['box_max']:.2f} | "
                  f"{r['side_max']:.2f} | {gap[0]} | {r['onset']:.0f} "
                  f"({r['onset_link']:.0f}) | {r['onset_side']:.2f} | {r['onset_twist']:.2f} | "
                  f"{r['onset_box']:.2f} | {r['still']} | {gap[1]} |",
                  flush=True)
    print(f"CPU {time.process_time() - started:.1f} s (this process)")
    print(summary(results))


def summary(results: list[tuple[str, str, dict[str, float]]]) -> str:
    """Per kind and engine: trials held, with a contact whose ellipse reaches 0.98 while its box
    stays below 0.9, and whose first saturated contact is still below the box's 0.9."""
    lines = []
    for kind in ("drop", "control"):
        for engine in ENGINES:
            got = [r for k, e, r in results if k == kind and e == engine]
            if not got:
                continue
            gap = sum(r["gap_steps"] > 0 for r in got)
            held = sum(r["held"] > 0 for r in got)
            combined = sum(r["onset_box"] < 0.9 for r in got)
            saturated = sum(np.isfinite(r["onset"]) for r in got)
            early = sum(r["still_gap_steps"] > 0 for r in got)
            side = sum(r["side_max"] >= 0.98 for r in got)
            if engine == "mujoco":
                lines.append(f"{kind} {engine}: held {held} of {len(got)}; a contact's sideways "
                             f"load >= 0.98 in {side}; a contact with ellipse >= 0.98 and box "
                             f"< 0.9 at some step in {gap}, at a step before the object turned "
                             f"{STILL_DEG} deg in {early}; first saturated contact (in "
                             f"{saturated}) below the box's 0.9 in {combined}")
            else:
                lines.append(f"{kind} {engine}: held {held} of {len(got)}; a contact's sideways "
                             f"load >= 0.98 in {side} (twist not reported by PyBullet)")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
