"""Where a MuJoCo trial's time goes (run by hand), and a bit-for-bit check of its outcomes.

    python -m tests.benchmarks.mujoco_cost --grips 12 --trials 2 --out before.json
    python -m tests.benchmarks.mujoco_cost --grips 12 --trials 2 --compare before.json
    python -m tests.benchmarks.mujoco_cost --grips 6 --profile      # cProfile on CPU time
    python -m tests.benchmarks.mujoco_cost --grips 12 --engine pybullet   # the same in PyBullet

Draws a seeded sample of the standard dataset's recorded grips (as ``tests.benchmarks.engines``
and ``grip-env validate --resimulate`` draw it), runs trials ``0 .. trials - 1`` of each in
MuJoCo (or ``--engine pybullet``) in this process, and prints the process's CPU time per trial
and per protocol step.
``--out`` writes every trial's outcome fields as exact hex floats; ``--compare`` runs the same
trials and names every field that differs from such a file (none: the outcomes are bit for bit
the same). ``--profile`` adds cProfile's top functions by own and cumulative CPU time.
``--timers`` adds MuJoCo's own timers (``mjData.timer``) summed over every physics step, read
through a clock compiled here with the system's C compiler (a Python clock would cost more than
the phases it times); its share of ``mj_step`` splits the physics into collision, constraint
solve and the rest.
``--against TREE --rounds N`` times this tree's ``MujocoWorld`` against another checkout's (its
``grip_env/sim/mujoco_world.py``, e.g. from ``git archive``) in one process, the two swapped in
turn for N rounds of the sample, and prints each round's ratio: on a machine whose speed drifts
between runs, interleaving in one process is what makes a few per cent measurable.

    python -m tests.benchmarks.mujoco_cost --grips 40 --trials 2 --against ../before --rounds 6

``--apart --rounds N`` times, the same way, this tree's world against itself with the ramp's
directions climbed one after another (``resumes_exactly`` off) instead of together.
"""

from __future__ import annotations

# grip_env before numpy: numpy held at portable kernels, as the dataset was made
import grip_env  # noqa: F401  # isort: skip

import argparse
import cProfile
import json
import os
import pstats
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

import pandas as pd

FIELDS = ("robustness", "success", "held", "friction", "mass_kg", "drift_mm", "rotation_deg",
          "steps")


def work(grips: int, seed: int, engine: str = "mujoco") -> list[tuple]:
    """(object, planned grips, config in ``engine``) of the seeded sample, as
    ``tests.benchmarks.engines``."""
    from grip_env.dataset.resimulation import _as_planned, _sample, kept_grips
    from grip_env.datasets import standard_path

    jobs = []
    for check in _sample(standard_path(), grips, seed):
        chosen = check.recorded.iloc[list(check.picked)]
        planned = _as_planned(chosen, kept_grips(check.task), check.task.object_id)
        jobs.append((check.task.obj, planned, check.task.config.override(
            sim={"engine": engine})))
    return jobs


def run(jobs: list[tuple], trials: int) -> pd.DataFrame:
    from grip_env.sim import run_trial_outcomes

    tables = []
    for obj, table, config in jobs:
        outcomes = run_trial_outcomes(obj, table, config, trials=trials, seed=config.dataset.seed)
        tables.append(outcomes.assign(grip_id=table.loc[outcomes["grip"], "grip_id"].to_numpy()))
    return pd.concat(tables, ignore_index=True)


def exact(table: pd.DataFrame) -> list[dict]:
    """Every trial's outcome fields, floats as hex (exact)."""
    return [{"grip_id": str(row["grip_id"]), "trial": int(row["trial"]),
             **{f: float(row[f]).hex() for f in FIELDS}} for _, row in table.iterrows()]


TIMER_SOURCE = """#include <time.h>
double grip_env_clock_us(void) {
    struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t);
    return 1e6 * (double)t.tv_sec + 1e-3 * (double)t.tv_nsec;
}
"""


def watch_timers() -> dict[str, float]:
    """Turn on MuJoCo's timers (a compiled clock) and sum each timer's microseconds over every
    ``MujocoWorld.step`` (a step's own delta: restoring a state copies the timers back)."""
    import ctypes
    import subprocess
    import tempfile

    import mujoco

    from grip_env.sim.mujoco_world import MujocoWorld

    folder = Path(tempfile.mkdtemp())
    (folder / "clock.c").write_text(TIMER_SOURCE)
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(folder / "clock.so"),
                    str(folder / "clock.c")], check=True)
    clock = ctypes.CDLL(str(folder / "clock.so")).grip_env_clock_us
    clock.restype = ctypes.c_double
    mujoco.set_mjcb_time(clock)
    names = [n.removeprefix("mjTIMER_") for n in mujoco.mjtTimer.__members__ if n != "mjNTIMER"]
    totals = dict.fromkeys(names + ["calls"], 0.0)
    step = MujocoWorld.step

    def timed_step(world: MujocoWorld, steps: int = 1) -> None:
        _, d = world._compiled()
        before = [(t.duration, t.number) for t in d.timer]
        step(world, steps)
        for name, (duration, _), timer in zip(names, before, d.timer, strict=False):
            totals[name] += timer.duration - duration
        totals["calls"] += d.timer[0].number - before[0][1]

    MujocoWorld.step = timed_step
    return totals


def print_timers(totals: dict[str, float]) -> None:
    total = totals["STEP"]
    print(f"\nMuJoCo's timers: {totals['calls']:.0f} physics steps, {total / 1e6:.2f} s in "
          f"mj_step, {total / max(totals['calls'], 1):.1f} us a physics step")
    print("| timer | s | share of mj_step |\n| --- | --- | --- |")
    for name, value in totals.items():
        if name not in ("calls", "INVERSE") and value:
            print(f"| {name} | {value / 1e6:.2f} | {value / total:.1%} |")


def world_of(tree: Path) -> type:
    """The ``MujocoWorld`` class of another checkout (its module loaded under its own name; what
    it imports from ``grip_env`` comes from this tree)."""
    import importlib.util

    path = tree / "grip_env" / "sim" / "mujoco_world.py"
    if not path.is_file():
        raise SystemExit(f"no {path}: --against takes a checkout of grip-env")
    spec = importlib.util.spec_from_file_location("mujoco_world_against", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    missing = [name for name in engine_members() if not hasattr(module.MujocoWorld, name)]
    if missing:
        raise SystemExit(f"{path}'s MujocoWorld lacks {', '.join(missing)}, which this tree's "
                         f"trial protocol calls: --against takes a checkout with its engine seam")
    return module.MujocoWorld


def engine_members() -> list[str]:
    """What the trial protocol asks of an engine's class (``Engine``'s methods and
    ``resumes_exactly``)."""
    from grip_env.sim.engine import Engine

    methods = [name for name, value in vars(Engine).items()
               if callable(value) and not name.startswith("_")]
    return [*methods, "resumes_exactly"]


def climbing_apart() -> type:
    """This tree's ``MujocoWorld`` with the ramp's directions climbed one after another."""
    from grip_env.sim.mujoco_world import MujocoWorld

    return type("MujocoWorldApart", (MujocoWorld,), {"resumes_exactly": False})


def interleave(jobs: list[tuple], trials: int, other: type, rounds: int) -> None:
    """CPU ms a trial of this tree's world and ``other``, swapped in turn (order alternating)."""
    import statistics

    from grip_env.sim import mujoco_world

    worlds = {"this": mujoco_world.MujocoWorld, "against": other}
    times: dict[str, list[float]] = {"this": [], "against": []}
    try:
        for k in range(rounds):
            for name in ("this", "against") if k % 2 else ("against", "this"):
                mujoco_world.MujocoWorld = worlds[name]
                started = time.process_time()
                table = run(jobs, trials)
                times[name].append(1e3 * (time.process_time() - started) / len(table))
    finally:
        mujoco_world.MujocoWorld = worlds["this"]
    ratios = [a / b for a, b in zip(times["this"], times["against"], strict=True)]
    for name, values in times.items():
        print(f"{name}: {', '.join(f'{v:.1f}' for v in values)} ms a trial; "
              f"median {statistics.median(values):.1f}")
    print(f"this / against, each round: {', '.join(f'{r:.3f}' for r in ratios)}; "
          f"median {statistics.median(ratios):.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grips", type=int, default=12)
    parser.add_argument("--trials", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--engine", choices=("mujoco", "pybullet"), default="mujoco")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--compare", type=Path)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--timers", action="store_true")
    parser.add_argument("--against", type=Path, help="another checkout, timed interleaved")
    parser.add_argument("--apart", action="store_true",
                        help="timed interleaved against the directions climbed one by one")
    parser.add_argument("--rounds", type=int, default=6)
    args = parser.parse_args()
    if (args.against or args.apart) and args.engine != "mujoco":
        parser.error("--against and --apart swap MuJoCo's world: they time --engine mujoco only")
    if args.against and args.apart:
        parser.error("--against and --apart each name the world to time against: give one")
    jobs = work(args.grips, args.seed, args.engine)
    if args.against or args.apart:
        other = world_of(args.against) if args.against else climbing_apart()
        run(jobs[:1], 1)  # warm
        interleave(jobs, args.trials, other, args.rounds)
        return
    timers = watch_timers() if args.timers else None
    run(jobs[:1], 1)  # warm: imports, caches of the first object
    if timers:
        timers.update(dict.fromkeys(timers, 0.0))
    profiler = cProfile.Profile(time.process_time) if args.profile else None
    started = time.process_time()
    if profiler:
        profiler.enable()
    table = run(jobs, args.trials)
    if profiler:
        profiler.disable()
    seconds = time.process_time() - started
    steps = int(table["steps"].sum())
    print(f"{len(table)} trials, {steps} protocol steps, {seconds:.2f} CPU s: "
          f"{1e3 * seconds / len(table):.1f} ms a trial, {1e6 * seconds / steps:.1f} us a step; "
          f"held {int(table['held'].sum())}, success {int(table['success'].sum())}")
    print(f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC, load {os.getloadavg()[0]:.2f}")
    if timers:
        print_timers(timers)
    if profiler:
        stats = pstats.Stats(profiler)
        stats.sort_stats("tottime").print_stats(25)
        stats.sort_stats("cumulative").print_stats(40)
    records = exact(table)
    if args.out:
        args.out.write_text(json.dumps(records, indent=0) + "\n")
    if args.compare:
        old = json.loads(args.compare.read_text())
        moved = [f"{a['grip_id']} trial {a['trial']}: {f} {float.fromhex(a[f])!r} -> "
                 f"{float.fromhex(b[f])!r}" for a, b in zip(old, records, strict=True)
                 for f in FIELDS if a[f] != b[f]]
        trials_moved = len({(a["grip_id"], a["trial"]) for a, b in zip(old, records, strict=True)
                            if a != b})
        print("\n".join(moved) or "every outcome bit for bit the recorded one")
        print(f"{trials_moved} of {len(records)} trials moved")
        sys.exit(1 if moved else 0)


if __name__ == "__main__":
    main()
