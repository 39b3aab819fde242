"""Dataset generation throughput: grips per second end to end, 1 vs 2 workers, process pool vs Ray.

Run ``python -m pytest tests/benchmarks/test_bench_generate.py --benchmark-enable -s`` (or
``python -m tests.benchmarks.test_bench_generate`` for a plain table). Every case runs the same
real job (procedural objects, real candidates and PyBullet trials) into a fresh directory.
Goals: 2 workers >= 1.7x one; Ray (instance already started) within 15% of the process pool.
Sizes: ``GRIP_BENCH_OBJECTS`` (default 4), ``GRIP_BENCH_GRIPS`` (2), ``GRIP_BENCH_TRIALS`` (2);
the defaults keep the suite quick, measure with larger ones. The plain table also times a pure
CPU-bound control on 1 and 2 processes: the speed-up the machine offers at that moment.
Nothing about time is asserted.
"""

from __future__ import annotations

import os
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

from grip_env.config import Config
from grip_env.dataset import generate, load

OBJECTS = int(os.environ.get("GRIP_BENCH_OBJECTS", "4"))
GRIPS = int(os.environ.get("GRIP_BENCH_GRIPS", "2"))
TRIALS = int(os.environ.get("GRIP_BENCH_TRIALS", "2"))
CONFIG = Config().override(dataset={"max_grips_per_object": GRIPS, "trials": TRIALS, "seed": 1})


def timed_run(workers: int, backend: str = "process") -> tuple[float, int]:
    """(seconds, grips) of one end-to-end generate run into a fresh directory."""
    with tempfile.TemporaryDirectory() as scratch:
        started = time.perf_counter()
        path = generate(CONFIG, Path(scratch) / "d", objects=OBJECTS, workers=workers,
                        backend=backend, progress=False)
        seconds = time.perf_counter() - started
        return seconds, len(load(path, verify=False))


def _bench(benchmark, workers: int, backend: str) -> float:  # type: ignore[no-untyped-def]
    benchmark.group = "generate"
    outcome: dict[str, float] = {}

    def once() -> None:
        outcome["seconds"], outcome["grips"] = timed_run(workers, backend)

    benchmark.pedantic(once, rounds=1, iterations=1)
    rate = outcome["grips"] / outcome["seconds"]
    benchmark.extra_info |= {"grips": outcome["grips"], "grips_per_s": round(rate, 2)}
    print(f"\n{backend} x{workers}: {outcome['grips']} grips in {outcome['seconds']:.1f} s "
          f"= {rate:.2f} grips/s")
    return rate


@pytest.mark.slow
def test_bench_one_worker(benchmark) -> None:  # type: ignore[no-untyped-def]
    _bench(benchmark, 1, "process")


@pytest.mark.slow
def test_bench_two_workers(benchmark) -> None:  # type: ignore[no-untyped-def]
    _bench(benchmark, 2, "process")


@pytest.mark.slow
def test_bench_ray_two_workers(benchmark) -> None:  # type: ignore[no-untyped-def]
    ray = pytest.importorskip("ray")
    started = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    print(f"\nray.init: {time.perf_counter() - started:.1f} s (not counted below)")
    try:
        _bench(benchmark, 2, "ray")
    finally:
        ray.shutdown()


def _burn(steps: int) -> int:
    total = 0
    for i in range(steps):
        total += i * i
    return total


def hardware_speedup(steps: int = 10_000_000) -> float:
    """Speed-up of two processes over one on a pure CPU-bound loop, right now on this machine."""
    started = time.perf_counter()
    _burn(steps), _burn(steps)
    one = time.perf_counter() - started
    with ProcessPoolExecutor(2) as pool:
        pool.submit(_burn, 1).result()
        started = time.perf_counter()
        list(pool.map(_burn, [steps, steps]))
        two = time.perf_counter() - started
    return one / two


def main() -> None:
    """Print the three figures, the two ratios and the CPU-bound control."""
    import ray

    control = hardware_speedup()
    one = timed_run(1)
    two = timed_run(2)
    started = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    init_seconds = time.perf_counter() - started
    try:
        on_ray = timed_run(2, "ray")
    finally:
        ray.shutdown()
    for label, (seconds, grips) in (("process x1", one), ("process x2", two), ("ray x2", on_ray)):
        print(f"{label:11s} {grips:5d} grips {seconds:7.1f} s {grips / seconds:8.2f} grips/s")
    print(f"speed-up 2 workers / 1: {one[0] / two[0]:.2f}x (goal >= 1.7x); "
          f"CPU-bound control: {control:.2f}x, after: {hardware_speedup():.2f}x")
    print(f"ray / process pool time: {on_ray[0] / two[0]:.2f} (goal <= 1.15); "
          f"ray.init {init_seconds:.1f} s excluded")


if __name__ == "__main__":
    main()
