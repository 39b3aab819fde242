"""Throughput at 1 and 2 local workers, process pool against Ray, and Ray's cost per object.

Run ``python -m tests.benchmarks.bench_cluster`` (sizes: ``GRIP_BENCH_OBJECTS`` (default 8),
``GRIP_BENCH_GRIPS`` (4), ``GRIP_BENCH_TRIALS`` (2), ``GRIP_BENCH_EMPTY_JOBS`` (200)). It prints:

- objects/s, grips/s and trials/s of one ``generate`` run (the real job: candidates and PyBullet
  trials, shards written) per backend and worker count, on the same fixed procedural objects;
  ``ray.init`` is timed apart and not counted;
- the cost of an object *without* its work: ``run_jobs`` of a job that returns a stored
  30-row result, through each backend (Ray: its first ``2 x workers`` jobs, which start its
  worker processes, apart from the rest), and the driver writing one shard. Against the work per
  object (the 1-worker run's seconds per object) this is what the projection of
  ``docs/cluster.md`` uses.

It also times a pure CPU-bound loop on 1 and 2 processes before and after (the speed-up the
machine offers at that moment: on a shared machine 2 workers cannot beat it). Nothing is
asserted; report the machine and its load with the figures.
"""

from __future__ import annotations

import functools
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import pandas as pd

from grip_env.config import Config
from grip_env.dataset import generate, load
from grip_env.dataset.backends import run_jobs
from grip_env.dataset.jobs import ObjectTask
from grip_env.dataset.shards import write_shard
from grip_env.objects import procedural_objects

OBJECTS = int(os.environ.get("GRIP_BENCH_OBJECTS", "8"))
GRIPS = int(os.environ.get("GRIP_BENCH_GRIPS", "4"))
TRIALS = int(os.environ.get("GRIP_BENCH_TRIALS", "2"))
EMPTY_JOBS = int(os.environ.get("GRIP_BENCH_EMPTY_JOBS", "200"))
CONFIG = Config().override(dataset={"max_grips_per_object": GRIPS, "trials": TRIALS, "seed": 1})
_RAY_OPTIONS = {"include_dashboard": False, "log_to_driver": False}


def real_run(workers: int, backend: str) -> dict[str, float]:
    """One end-to-end ``generate`` of ``OBJECTS`` procedural objects into a fresh directory."""
    with tempfile.TemporaryDirectory() as scratch:
        started = time.perf_counter()
        path = generate(CONFIG, Path(scratch) / "d", objects=OBJECTS, workers=workers,
                        backend=backend, progress=False)
        seconds = time.perf_counter() - started
        rows = load(path, verify=False)
    return {"seconds": seconds, "objects": OBJECTS, "grips": len(rows),
            "trials": int(rows["trials"].sum())}


def stored_result(rows: pd.DataFrame, task: ObjectTask) -> pd.DataFrame:
    """A job with no work: the same stored rows for every object."""
    return rows


def empty_jobs(rows: pd.DataFrame, workers: int, backend: str, count: int = EMPTY_JOBS) -> float:
    """Seconds per object of ``run_jobs`` with a job that does no work (``count`` objects)."""
    import importlib

    shapes = procedural_objects(count, 3)
    tasks = [ObjectTask(i, o.name, o, CONFIG, i) for i, o in enumerate(shapes)]
    # by its module's name, not __main__'s, so that pool workers can import it
    module = importlib.import_module("tests.benchmarks.bench_cluster")
    job = functools.partial(module.stored_result, rows)
    started = time.perf_counter()
    for _ in run_jobs(job, tasks, workers, backend):
        pass
    return (time.perf_counter() - started) / len(tasks)


def shard_write_seconds(rows: pd.DataFrame, repeats: int = 50) -> float:
    """Seconds the driver spends writing one object's shard (what it does per finished object)."""
    with tempfile.TemporaryDirectory() as scratch:
        started = time.perf_counter()
        for i in range(repeats):
            write_shard(Path(scratch) / f"part-{i}.parquet", rows, {"object_id": "o"})
        return (time.perf_counter() - started) / repeats


def planning_seconds(objects: int = 20) -> float:
    """Seconds per object of planning alone (candidates on the true contour), one core."""
    from grip_env.planning.pipeline import candidates

    shapes = procedural_objects(objects, 1)
    started = time.perf_counter()
    for obj in shapes:
        candidates(obj, CONFIG.grasp, CONFIG)
    return (time.perf_counter() - started) / objects


def measure() -> dict[str, Any]:
    """Every figure: real runs, ray.init, the empty-job costs and the shard write."""
    import importlib

    import ray

    # Ray workers do not have the tests on their path: ship this module's functions by value
    ray.cloudpickle.register_pickle_by_value(importlib.import_module("tests.benchmarks"))
    from tests.benchmarks.test_bench_generate import hardware_speedup

    figures: dict[str, Any] = {"real": {}, "empty": {}, "ray_init_s": {},
                               "cpu_speedup_before": hardware_speedup()}  # fmt: skip
    for workers in (1, 2):
        figures["real"][f"process x{workers}"] = real_run(workers, "process")
    for workers in (1, 2):
        started = time.perf_counter()
        ray.init(num_cpus=workers, **_RAY_OPTIONS)
        figures["ray_init_s"][workers] = time.perf_counter() - started
        try:
            figures["real"][f"ray x{workers}"] = real_run(workers, "ray")
        finally:
            ray.shutdown()
    with tempfile.TemporaryDirectory() as scratch:
        rows = load(generate(CONFIG.override(dataset={"max_grips_per_object": 30, "trials": 1}),
                             Path(scratch) / "d", objects=1, progress=False), verify=False)
    figures["stored_rows"] = len(rows)
    figures["planning_s"] = planning_seconds()
    figures["shard_write_s"] = shard_write_seconds(rows)
    for workers in (1, 2):
        figures["empty"][f"process x{workers}"] = empty_jobs(rows, workers, "process")
        ray.init(num_cpus=workers, **_RAY_OPTIONS)
        try:  # the first jobs start Ray's worker processes (cold); then they are reused (warm)
            figures["empty"][f"ray x{workers} cold"] = empty_jobs(rows, workers, "ray", 2 * workers)
            figures["empty"][f"ray x{workers} warm"] = empty_jobs(rows, workers, "ray")
        finally:
            ray.shutdown()
    figures["cpu_speedup_after"] = hardware_speedup()
    return figures


def main() -> None:
    """Print the table of :func:`measure`."""
    figures = measure()
    print(f"{OBJECTS} procedural objects (seed 1), <= {GRIPS} grips each, {TRIALS} trials a grip")
    print(f"{'run':11s} {'s':>7s} {'objects/s':>10s} {'grips/s':>8s} {'trials/s':>9s}")
    for name, run in figures["real"].items():
        s = run["seconds"]
        print(f"{name:11s} {s:7.1f} {run['objects'] / s:10.3f} {run['grips'] / s:8.2f} "
              f"{run['trials'] / s:9.2f}   ({run['grips']} grips, {run['trials']} trials)")
    print(f"CPU-bound control, 2 processes / 1 (what the machine offers now): "
          f"{figures['cpu_speedup_before']:.2f}x before, {figures['cpu_speedup_after']:.2f}x after")
    print(f"ray.init: {', '.join(f'x{w} {s:.1f} s' for w, s in figures['ray_init_s'].items())}")
    print(f"no-work job ({figures['stored_rows']} rows returned), {EMPTY_JOBS} objects, "
          "ms per object:")
    for name, seconds in figures["empty"].items():
        print(f"  {name:16s} {1000 * seconds:8.2f}")
    print(f"driver writes one {figures['stored_rows']}-row shard: "
          f"{1000 * figures['shard_write_s']:.2f} ms")
    print(f"planning alone (candidates), one core: {1000 * figures['planning_s']:.1f} ms/object")
    one = figures["real"]["process x1"]
    per_trial = (one["seconds"] - one["objects"] * figures["planning_s"]) / one["trials"]
    print(f"work per trial, 1 worker, planning removed: {1000 * per_trial:.1f} ms")


if __name__ == "__main__":
    main()
