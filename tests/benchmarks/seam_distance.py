"""Do the engines part more where a grip's contacts lie near a seam? (run by hand)

    python -m tests.benchmarks.seam_distance --parts R.crosscheck

Reads a cross-check's kept outcomes (``grip-env validate standard --crosscheck N --report R.json``
keeps them in ``R.crosscheck/``). For every grip of an object simulated as several convex
pieces, the distance from its three planned contact points to the nearest point where a seam
between two pieces meets the outline at a vertex that is not a concave corner (within 5 degrees
of straight, or convex: where a seam is a ridge on a face; MuJoCo's pieces or PyBullet's eroded
ones, whichever is nearer), and the grip's mean robustness in each engine; then, by distance,
the grips, the engines' means and PyBullet's excess. Then every object of the sample (one piece
or several) by family and piece count: the within-object Spearman between the engines' grip
means and PyBullet's mean robustness over MuJoCo's.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import itertools
from pathlib import Path

import numpy as np
import pandas as pd
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from grip_env.sim.analytic import seam_ends
from grip_env.sim.world import COLLISION_MARGIN_MM
from tests.benchmarks.crosscheck_contact_loads import kept_runs

SAMPLE = 80
#: A vertex that turns inwards by more than this (sine of 5 degrees) is a concave corner.
CONCAVE_SINE = np.sin(np.radians(5.0))
BINS_MM = (0.0, 2.0, 4.0, 8.0, 16.0, np.inf)


def face_seam_ends(pieces: tuple[np.ndarray, ...]) -> np.ndarray:
    """Points (mm) where a seam between pieces (``analytic.seam_ends``) meets the union's outline
    away from a concave corner."""
    outline = unary_union([Polygon(p) for p in pieces]).exterior
    ring = np.asarray(outline.coords)[:-1]
    turn = 1.0 if outline.is_ccw else -1.0
    before, after = ring - np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0) - ring
    cross = before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0]
    sine = turn * cross / (np.linalg.norm(before, axis=1) * np.linalg.norm(after, axis=1))
    concave = ring[sine < -CONCAVE_SINE].reshape(-1, 2)
    ends = seam_ends(pieces)
    on_outline = np.array([outline.distance(Point(e)) < 1e-6 for e in ends], dtype=bool)
    at_concave = (np.linalg.norm(ends[:, None] - concave[None], axis=2) < 1e-6).any(axis=1)
    return ends[on_outline & ~at_concave]


def grip_rows(parts: Path) -> pd.DataFrame:
    """One row per grip of every multi-piece object with kept outcomes."""
    rows = []
    for check, runs in kept_runs(parts, SAMPLE, 0):
        shape = check.task.obj.simulated_shape(check.task.config.objects.sim_tolerance_mm)
        if len(shape.pieces) == 1:
            continue
        ends = np.vstack([face_seam_ends(shape.pieces),
                          face_seam_ends(shape.collision_pieces(COLLISION_MARGIN_MM))])
        grips = check.recorded.reset_index(drop=True)
        contacts = np.stack([grips[[f"p{i}_x", f"p{i}_y"]].to_numpy() for i in (1, 2, 3)], 1)
        means = {e: f.groupby("grip").robustness.mean() for e, f in runs.draws.items()}
        for k in range(len(grips)):
            distance = (np.min(np.linalg.norm(contacts[k][:, None] - ends[None], axis=2))
                        if len(ends) else np.inf)
            rows.append({"object_id": check.task.object_id, "pieces": len(shape.pieces),
                         "grip": k, "distance_mm": distance,
                         **{e: float(m[k]) for e, m in means.items()}})
    return pd.DataFrame(rows)


def object_rows(parts: Path) -> pd.DataFrame:
    """One row per object with kept outcomes: family, pieces, the engines' agreement."""
    from grip_env.dataset.crosscheck import _means, _spearman
    from grip_env.objects.family import object_family

    rows = []
    for check, runs in kept_runs(parts, SAMPLE, 0):
        draws = runs.draws
        shape = check.task.obj.simulated_shape(check.task.config.objects.sim_tolerance_mm)
        rows.append({"family": object_family(check.task.obj), "pieces": len(shape.pieces),
                     "within": _spearman(_means(draws["pybullet"]), _means(draws["mujoco"])),
                     "pybullet": draws["pybullet"].robustness.mean(),
                     "mujoco": draws["mujoco"].robustness.mean()})
    return pd.DataFrame(rows)


def print_by_family(table: pd.DataFrame) -> None:
    """Objects by family and piece count (1, 2-5, 6 or more)."""
    table = table.assign(group=pd.cut(table.pieces, [0, 1, 5, np.inf], labels=["1", "2–5", "6+"]))
    print("| family | pieces | objects | within-object Spearman between engines | PyBullet / "
          "MuJoCo mean robustness (g) |")
    print("| --- | --- | --- | --- | --- |")
    for (family, group), rows in table.groupby(["family", "group"], observed=True):
        print(f"| {family} | {group} | {len(rows)} | {rows.within.mean():.2f} | "
              f"{rows.pybullet.mean():.1f} / {rows.mujoco.mean():.1f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--parts", type=Path, required=True)
    args = parser.parse_args()
    table = grip_rows(args.parts)
    print(f"{len(table)} grips of {table.object_id.nunique()} objects of several pieces")
    print("| nearest seam end (mm) | grips | objects | PyBullet mean (g) | MuJoCo | PyBullet minus "
          "MuJoCo |")
    print("| --- | --- | --- | --- | --- | --- |")
    for low, high in itertools.pairwise(BINS_MM):
        rows = table[(table.distance_mm >= low) & (table.distance_mm < high)]
        if len(rows):
            print(f"| {low:g}–{high:g} | {len(rows)} | {rows.object_id.nunique()} | "
                  f"{rows.pybullet.mean():.1f} | {rows.mujoco.mean():.1f} | "
                  f"{(rows.pybullet - rows.mujoco).mean():+.1f} |")
    none = table[~np.isfinite(table.distance_mm)]
    if len(none):
        print(f"| no such seam end | {len(none)} | {none.object_id.nunique()} | "
              f"{none.pybullet.mean():.1f} | {none.mujoco.mean():.1f} | "
              f"{(none.pybullet - none.mujoco).mean():+.1f} |")
    print()
    print_by_family(object_rows(args.parts))


if __name__ == "__main__":
    main()
