"""The simulation loop's speed against a previous commit's, in one process (run by hand).

    python -m tests.benchmarks.sim_speed --baseline 271fc90 --trials 24 --rounds 3

The baseline commit's ``grip_env`` is extracted (``git archive``) into a temporary directory and
imported under its own module objects next to this tree's, so both loops run in the same process
on the same machine load. The same trials (stratified grips of a few default objects, noise drawn
as ``run_trial_outcomes`` draws it) run under each loop in alternating rounds; the fastest round
of each is kept. Times are the process's CPU time (the machine is shared: wall time measures the
neighbours too); the wall-time ratio is given beside. Reports both, their ratio (this tree over
the baseline) and how many outcomes (success, robustness, steps, drift) are identical: an exact
lever must keep them all.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Iterator
from io import BytesIO
from pathlib import Path
from types import ModuleType

import numpy as np

OBJECTS = ("pentagon", "rectangle", "l_shape", "star")


def _own_modules() -> dict[str, ModuleType]:
    return {k: v for k, v in sys.modules.items() if k == "grip_env" or k.startswith("grip_env.")}


@contextlib.contextmanager
def tree_of(commit: str) -> Iterator[ModuleType]:
    """``grip_env.sim`` (with ``config`` and ``objects``) of ``commit``, imported beside ours.

    Inside the block the baseline's modules are the imported ones; ours come back after it.
    Objects built inside keep referring to their own modules afterwards.
    """
    repo = Path(__file__).resolve().parents[2]
    archive = subprocess.run(["git", "-C", str(repo), "archive", commit, "grip_env"],
                             check=True, capture_output=True).stdout
    with tempfile.TemporaryDirectory() as tmp:
        with tarfile.open(fileobj=BytesIO(archive)) as tar:
            tar.extractall(tmp, filter="data")
        ours = _own_modules()
        for name in ours:
            del sys.modules[name]
        sys.path.insert(0, tmp)
        try:
            import grip_env.sim  # noqa: F401  (the baseline's)

            yield sys.modules["grip_env"]
        finally:
            sys.path.remove(tmp)
            for name in _own_modules():
                del sys.modules[name]
            sys.modules.update(ours)


class Loop:
    """One implementation's scenes and the trials to run in them."""

    def __init__(self, package: ModuleType, trials: int) -> None:
        from importlib import import_module

        def mod(name: str) -> ModuleType:
            return import_module(f"{package.__name__}.{name}")

        config = mod("config").Config()
        sim, objects, pipeline = mod("sim"), mod("objects"), mod("pipeline")
        uncertainty, execution = mod("sim.uncertainty"), mod("sim.execution")
        self.jobs = []
        for name in OBJECTS:
            obj = objects.make_shape(name)
            table = pipeline.candidates(obj, config=config)
            picks = np.unique(np.linspace(0, len(table) - 1, trials).round().astype(int))
            grips = table.iloc[picks]
            scene = sim.TrialScene(obj, config)
            for plan, key in zip(sim.grip_plans(grips), execution.grip_keys(grips), strict=True):
                noise = uncertainty.sample_noise(uncertainty.trial_rng(0, key, 0), config)
                self.jobs.append((scene, plan, noise))

    def run(self) -> tuple[float, float, list[tuple]]:
        """CPU seconds, wall seconds and the outcomes of every trial."""
        cpu, wall = time.process_time(), time.perf_counter()
        results = [scene.run(plan, noise) for scene, plan, noise in self.jobs]
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        return cpu, wall, [(r.success, r.robustness_g, r.steps, r.drift_mm) for r in results]

    def close(self) -> None:
        for scene in {id(s): s for s, _, _ in self.jobs}.values():
            scene.close()


def compare(baseline: str, trials: int, rounds: int) -> dict:
    """Fastest-round times of the baseline's loop and ours on the same trials, alternating."""
    with tree_of(baseline) as old_package:
        old = Loop(old_package, trials)
    import grip_env

    new = Loop(grip_env, trials)
    best = {"baseline": np.inf, "ours": np.inf}
    wall = {"baseline": np.inf, "ours": np.inf}
    outcomes: dict[str, list[tuple]] = {}
    for _ in range(rounds):
        for name, loop in (("baseline", old), ("ours", new)):
            cpu, took, outcomes[name] = loop.run()
            best[name] = min(best[name], cpu)
            wall[name] = min(wall[name], took)
    old.close()
    new.close()
    a, b = outcomes["baseline"], outcomes["ours"]
    steps_a, steps_b = sum(r[2] for r in a), sum(r[2] for r in b)
    return {
        "trials": len(a), "baseline": baseline,
        "baseline_cpu_s": round(best["baseline"], 2), "ours_cpu_s": round(best["ours"], 2),
        "time_ratio": round(best["ours"] / best["baseline"], 3),
        "wall_ratio": round(wall["ours"] / wall["baseline"], 3),
        "us_per_step_baseline": round(1e6 * best["baseline"] / steps_a, 1),
        "us_per_step_ours": round(1e6 * best["ours"] / steps_b, 1),
        "identical_success_robustness": sum(x[:2] == y[:2] for x, y in zip(a, b, strict=True)),
        "identical_steps": sum(x[2] == y[2] for x, y in zip(a, b, strict=True)),
        "max_drift_difference_mm": max(abs(x[3] - y[3]) for x, y in zip(a, b, strict=True)),
        "success_baseline": float(np.mean([x[0] for x in a])),
        "success_ours": float(np.mean([y[0] for y in b])),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="commit of the previous loop")
    parser.add_argument("--trials", type=int, default=12, help="grips per object")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print(json.dumps(compare(args.baseline, args.trials, args.rounds), indent=1))


if __name__ == "__main__":
    main()
