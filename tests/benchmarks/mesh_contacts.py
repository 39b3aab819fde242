"""How many contact points carry each finger on mesh objects, in both engines (run by hand;
issue 45).

    python -m tests.benchmarks.mesh_contacts \
        --parts /work/runs/crosscheck/standard40-drives.crosscheck --family mesh --trials 12

Draws (seeded) ``--trials`` (object, grip, trial) of a cross-check's kept outcomes in one family,
runs each again in both engines with its own grip and draw (as ``run_trial_outcomes`` does) up
to the end of the hold (the ramp is skipped), and after every step of the lift and the hold
counts, per hand link pressing the object with at least ``MIN_NORMAL_N`` in all: its contact
points with the object (PyBullet: ``getContactPoints`` of the link; MuJoCo: the active contacts
of the link's geoms), and in MuJoCo the object's convex pieces (geoms) it touches and whether
its box (the pad face) or its tip sphere carries the load. PyBullet reports no compound child,
so its pieces are not counted. Reads MuJoCo's model and data through the private
``_compiled()``, read-only (as ``crosscheck_contact_loads`` does).
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import contextlib
import json
import time
from collections import Counter
from pathlib import Path

import numpy as np

from grip_env.dataset.crosscheck import _from_json
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.objects.family import object_family
from grip_env.sim.execution import grip_keys, object_key
from grip_env.sim.trial import TrialScene, grip_plans
from grip_env.sim.uncertainty import trial_noises
from tests.benchmarks.crosscheck_contact_loads import _HoldEnded

ENGINES = ("pybullet", "mujoco")
MIN_NORMAL_N = 1.0  # a link pressing less than this in all is a graze, not a finger of the grip


def _tilt(normal) -> float:
    """The angle (deg) of a contact normal out of the horizontal plane (the grip's plane)."""
    n = np.asarray(normal, float)
    return float(np.degrees(np.arcsin(min(abs(n[2]) / np.linalg.norm(n), 1.0))))


def pybullet_links(scene: TrialScene) -> dict[int, list[tuple[float, str, int]]]:
    """Per hand link: (N, geom kind unknown, piece unknown, normal's tilt) of each contact."""
    client, hand, obj = scene.world.client, scene.hand.uid, scene.object.uid
    out: dict[int, list] = {}
    for p in client.getContactPoints(bodyA=hand, bodyB=obj):
        out.setdefault(int(p[3]), []).append((float(p[9]), "?", -1, _tilt(p[7])))
    return out


def mujoco_links(scene: TrialScene) -> dict[int, list[tuple[float, str, int]]]:
    """Per hand link: (N, 'box' or 'sphere', object geom, normal's tilt) of each active
    contact."""
    world, hand, obj = scene.world, scene.hand.uid, scene.object.uid
    m, d = world._compiled()
    uid, link = world._body_uid, world._body_link
    out: dict[int, list] = {}
    for c in d.contact[: d.ncon]:
        geoms = [c.geom1, c.geom2]
        owners = uid[m.geom_bodyid[geoms]].tolist()
        if set(owners) != {hand, obj} or c.efc_address < 0:
            continue
        pad, piece = geoms[owners.index(hand)], geoms[owners.index(obj)]
        kind = "sphere" if m.geom_type[pad] == 2 else "box"  # mjGEOM_SPHERE
        out.setdefault(int(link[m.geom_bodyid[pad]]), []).append(
            (float(d.efc_force[c.efc_address]), kind, int(piece), _tilt(c.frame[:3])))
    return out


def run_to_hold(check, grip: int, trial: int, engine: str) -> dict[str, object]:
    """One trial to the end of its hold in ``engine``: per step of the lift and hold, each
    pressing link's contact points (and, in MuJoCo, pieces and pad part)."""
    config = check.task.config.override(sim={"engine": engine})
    grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
    (plan,) = grip_plans(grips.iloc[[grip]])
    ((noise,),) = trial_noises(config, config.dataset.seed,
                               object_key(check.task.obj, grips.iloc[[grip]]),
                               grip_keys(grips.iloc[[grip]]), range(trial, trial + 1))
    read = mujoco_links if engine == "mujoco" else pybullet_links
    points: list[int] = []  # per (step, pressing link): contact points
    pieces: list[int] = []
    kinds: Counter[str] = Counter()
    found: dict[str, object] = {}
    with TrialScene(check.task.obj, config) as scene:
        def on_phase(name: str, s: TrialScene) -> None:
            if name == "closed":
                stepper = s.world.step

                def recording(n: int = 1) -> None:
                    stepper(n)
                    for rows in read(s).values():
                        if sum(r[0] for r in rows) < MIN_NORMAL_N:
                            continue
                        points.append(len(rows))
                        pieces.append(len({r[2] for r in rows}))
                        load = Counter()
                        for n_, kind, _, _ in rows:
                            load[kind] += n_
                        kinds[max(load, key=load.get)] += 1
                s.world.step = recording
            if name == "held":
                links = [rows for rows in read(s).values()
                         if sum(r[0] for r in rows) >= MIN_NORMAL_N]
                found["links_at_hold"] = len(links)
                found["tilts"] = [sum(r[0] * r[3] for r in rows) / sum(r[0] for r in rows)
                                  for rows in links]
                raise _HoldEnded
        with contextlib.suppress(_HoldEnded):
            scene.run(plan, noise, on_phase)
    found.setdefault("tilts", [])
    found.update(points=points, pieces=pieces, kinds=dict(kinds))
    return found


def sample(parts: Path, objects: int, seed: int, family: str, trials: int,
           only: list[str] | None = None):
    """Seeded (check, grip, trial) of the family's objects, held in both engines' first run or
    not (any trial)."""
    pool = []
    for check in _retest_sample(standard_path(), objects, seed):
        if object_family(check.task.obj) != family or (only and check.task.object_id not in only):
            continue
        file = parts / f"{check.task.index:05d}.json"
        if not file.is_file():
            continue
        runs = _from_json(json.loads(file.read_text(encoding="utf-8")))
        frame = runs.draws["mujoco"]
        pool += [(check, int(g), int(t)) for g, t in zip(frame["grip"], frame["trial"],
                                                          strict=True)]
    rng = np.random.default_rng(seed)
    return [pool[i] for i in sorted(rng.choice(len(pool), min(trials, len(pool)),
                                               replace=False))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--family", default="mesh")
    parser.add_argument("--trials", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", nargs="*", default=None, help="object ids (default: all)")
    args = parser.parse_args()
    picked = sample(args.parts, args.objects, args.seed, args.family, args.trials, args.only)
    started = time.process_time()
    totals = {e: {"points": [], "pieces": [], "kinds": Counter()} for e in ENGINES}
    print("| object | grip | trial | engine | pressing links at hold | points per pressing link "
          "(median, max) | share of link-steps on >1 point | pieces touched >1 | load on "
          "| contact normals' tilt at hold (deg, force-weighted per link) |")
    print("| --- " * 10 + "|")
    for check, grip, trial in picked:
        for engine in ENGINES:
            r = run_to_hold(check, grip, trial, engine)
            p, q = np.array(r["points"] or [0]), np.array(r["pieces"] or [0])
            t = totals[engine]
            t["points"] += list(r["points"])
            t["pieces"] += list(r["pieces"])
            t["kinds"].update(r["kinds"])
            piece = "n/a" if engine == "pybullet" else f"{np.mean(q > 1):.0%}"
            print(f"| {check.task.object_id} | {grip} | {trial} | {engine} | "
                  f"{r.get('links_at_hold', 'dropped')} | {np.median(p):.0f}, {p.max()} | "
                  f"{np.mean(p > 1):.0%} | {piece} | {r['kinds']} | "
                  f"{', '.join(f'{t:.0f}' for t in r['tilts'])} |", flush=True)
    print(f"CPU {time.process_time() - started:.1f} s (this process)")
    for engine, t in totals.items():
        p = np.array(t["points"])
        hist = {k: int((p == k).sum()) for k in range(1, int(p.max()) + 1)} if len(p) else {}
        line = (f"{engine}: {len(p)} pressing link-steps; points per link {hist}; mean "
                f"{p.mean():.2f}; load mostly on {dict(t['kinds'])}")
        if engine == "mujoco":
            line += f"; on more than one piece in {np.mean(np.array(t['pieces']) > 1):.0%}"
        print(line)


if __name__ == "__main__":
    main()
