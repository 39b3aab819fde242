"""Does cutting an object into more convex pieces move its labels? (run by hand)

    python -m tests.benchmarks.piece_cuts --cuts 6 --trials 5 --workers 2
    python -m tests.benchmarks.piece_cuts --split --objects proc_0_00319 urdf_972 --trials 5
    python -m tests.benchmarks.piece_cuts --control --trials 5    # the same pieces, reordered

Each engine simulates an object as a union of convex prisms, one per piece of its simulated shape
(PyBullet's eroded by its collision margin). A real body has no pieces: the same union cut
another way must hold the same. ``--cuts K`` takes the one-piece objects of the standard
dataset's 80-object cross-check sample (``--objects`` names others) and cuts each into K slices
across its x extent, seams meeting the faces where the fingers touch; ``--split`` halves every
piece of each object through its centroid across its longest extent; ``--control`` keeps the
pieces and only starts each one's vertex list one vertex later, the same body to the last bit of
geometry, to show how far a trial's chaos alone moves the figures. Every grip runs trials
0..T-1 (the recorded draws) whole and cut, in both engines, and the table gives per engine the
mean robustness whole and cut with the paired difference's 95 % bootstrap interval over trials,
successes, and the within-object Spearman of the grips' means whole against cut; then the
engines' within-object agreement whole and cut.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np
import pandas as pd
from scipy.stats import spearmanr
from shapely.geometry import LineString, Polygon
from shapely.ops import split

from grip_env.objects.decomposition import ccw
from grip_env.objects.simulated import SimulatedShape
from grip_env.sim.world import COLLISION_MARGIN_MM
from tests.benchmarks.engines import ENGINES

SAMPLE = 80  # the shipped cross-check's objects


def slices(piece: np.ndarray, cuts: int) -> tuple[np.ndarray, ...]:
    """A convex piece cut into ``cuts`` slices of equal width across its x extent."""
    polygon = Polygon(piece)
    x0, y0, x1, y1 = polygon.bounds
    parts = [polygon]
    for x in np.linspace(x0, x1, cuts + 1)[1:-1]:
        line = LineString([(x, y0 - 1.0), (x, y1 + 1.0)])
        parts = [g for p in parts for g in split(p, line).geoms]
    return tuple(ccw(np.asarray(g.exterior.coords)[:-1]) for g in parts)


def halves(piece: np.ndarray) -> tuple[np.ndarray, ...]:
    """A convex piece cut in two through its centroid, across its longest extent."""
    polygon = Polygon(piece)
    centre = np.asarray(polygon.centroid.coords[0])
    axis = np.linalg.svd(np.asarray(piece) - centre)[2][0]
    across = np.array([-axis[1], axis[0]])
    line = LineString([centre - 1e3 * across, centre + 1e3 * across])
    return tuple(ccw(np.asarray(g.exterior.coords)[:-1]) for g in split(polygon, line).geoms)


def recut(shape: SimulatedShape, cuts: int) -> SimulatedShape:
    """``shape`` with every piece (and every eroded piece PyBullet collides) cut again: into
    ``cuts`` slices, halved (0), or only its vertices rolled by one (-1, the control)."""
    def pieces_of(piece: np.ndarray) -> tuple[np.ndarray, ...]:
        if cuts < 0:
            return (np.roll(piece, 1, axis=0),)
        return slices(piece, cuts) if cuts else halves(piece)

    def cut(pieces: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
        return tuple(q for p in pieces for q in pieces_of(p))

    recut_shape = replace(shape, pieces=cut(shape.pieces))
    recut_shape._eroded[COLLISION_MARGIN_MM] = cut(shape.collision_pieces(COLLISION_MARGIN_MM))
    return recut_shape


def _checks(names: list[str] | None) -> list:
    from grip_env.dataset.resimulation import _retest_sample
    from grip_env.datasets import standard_path

    checks = _retest_sample(standard_path(), SAMPLE, 0)
    if names:
        return [c for c in checks if c.task.object_id in names]
    tolerance = checks[0].task.config.objects.sim_tolerance_mm
    return [c for c in checks if c.task.object_id.startswith("proc_")
            and len(c.task.obj.simulated_shape(tolerance).pieces) == 1]


def run_object(item: tuple[str, int, int]) -> pd.DataFrame:
    """Every grip of one sampled object, whole and cut, in both engines."""
    from grip_env.sim import run_trial_outcomes

    object_id, cuts, trials = item
    check = _checks([object_id])[0]
    config, obj = check.task.config, check.task.obj
    tolerance = float(config.objects.sim_tolerance_mm)
    grips = check.recorded.assign(object_id=object_id).reset_index(drop=True)
    whole = obj.simulated_shape(tolerance)
    frames = []
    for variant, shape in (("whole", whole), ("cut", recut(whole, cuts))):
        obj._simulated[tolerance] = shape  # the object's cached simulated shape, for this run
        for engine in ENGINES:
            started = time.process_time()
            table = run_trial_outcomes(obj, grips, config.override(sim={"engine": engine}),
                                       trials, config.dataset.seed)
            frames.append(table.assign(object_id=object_id, engine=engine, variant=variant,
                                       pieces=len(shape.pieces),
                                       cpu_s=time.process_time() - started))
    obj._simulated[tolerance] = whole
    return pd.concat(frames, ignore_index=True)


def _within(table: pd.DataFrame, a: tuple[str, str], b: tuple[str, str]) -> float:
    """Mean over objects of the Spearman of the grips' means in (engine, variant) a and b."""
    means = table.groupby(["object_id", "engine", "variant", "grip"]).robustness.mean()
    values = [spearmanr(means[o][a], means[o][b]).statistic
              for o in table.object_id.unique()]
    return float(np.nanmean(values))


def report(table: pd.DataFrame, seed: int = 0) -> None:
    """Print the per-engine table and the engines' agreement whole and cut."""
    rng = np.random.default_rng(seed)
    print("| engine | whole: mean robustness (g) | cut | cut minus whole, 95 % | successes "
          "whole / cut | within-object Spearman whole ~ cut |")
    print("| --- | --- | --- | --- | --- | --- |")
    for engine in ENGINES:
        rows = table[table.engine == engine]
        whole = rows[rows.variant == "whole"].reset_index(drop=True)
        cut = rows[rows.variant == "cut"].reset_index(drop=True)
        difference = (cut.robustness - whole.robustness).to_numpy()
        boot = difference[rng.integers(0, len(difference), (2000, len(difference)))].mean(1)
        low, high = np.quantile(boot, [0.025, 0.975])
        print(f"| {engine} | {whole.robustness.mean():.2f} | {cut.robustness.mean():.2f} | "
              f"{difference.mean():+.2f} [{low:+.2f}, {high:+.2f}] "
              f"({difference.mean() / whole.robustness.mean():+.1%}) | "
              f"{whole.success.sum()} / {cut.success.sum()} | "
              f"{_within(table, (engine, 'whole'), (engine, 'cut')):.3f} |")
    for variant in ("whole", "cut"):
        agreement = _within(table, ("pybullet", variant), ("mujoco", variant))
        print(f"engines' within-object Spearman, {variant}: {agreement:.3f}")
    seconds = table.groupby(["object_id", "engine", "variant"]).cpu_s.first().sum()
    print(f"objects {table.object_id.nunique()}, trials a run {len(table) // (2 * len(ENGINES))}, "
          f"CPU s {seconds:.0f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cuts", type=int, default=6, help="slices a one-piece object is cut to")
    parser.add_argument("--split", action="store_true", help="halve every piece instead")
    parser.add_argument("--control", action="store_true", help="only roll each piece's vertices")
    parser.add_argument("--objects", nargs="*", help="object ids of the cross-check sample")
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", help="a Parquet file for every trial's outcome")
    args = parser.parse_args()
    cuts = -1 if args.control else 0 if args.split else args.cuts
    names = [c.task.object_id for c in _checks(args.objects)]
    with ProcessPoolExecutor(args.workers) as pool:
        tables = list(pool.map(run_object, [(n, cuts, args.trials) for n in names]))
    table = pd.concat(tables, ignore_index=True)
    if args.out:
        table.to_parquet(args.out)
    report(table)


if __name__ == "__main__":
    main()
