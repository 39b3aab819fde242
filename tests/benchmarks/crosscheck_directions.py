"""Where the engines part: each disturbance direction's level on trials they judge differently
(run by hand; issue 45).

    python -m tests.benchmarks.crosscheck_directions \
        --parts /work/runs/crosscheck/standard40.crosscheck --trials 40

Reads the outcomes a cross-check keeps (``grip-env validate standard --crosscheck 40 --report
R.json`` keeps them in ``R.crosscheck/``), draws ``--trials`` of the trials whose success the
two engines judge differently (seeded), runs each again in both engines with every one of the
ramp's directions raised to the ceiling (not only to the weakest so far, as the label does) and
prints, for each way the engines part, how often each direction is an engine's weakest: along
the palm frame's x and y (force) or about its normal (twist).
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
from collections import Counter
from pathlib import Path

import numpy as np

import grip_env.sim.disturbance as disturbance
import grip_env.sim.trial as trial_module
from grip_env.sim import run_trial_outcomes
from tests.benchmarks.crosscheck_contact_loads import kept_runs

ENGINES = ("pybullet", "mujoco")


def every_direction(found: list[dict[str, float]]):
    """A ``robustness`` that ramps every direction to the ceiling and appends its levels."""
    def robustness(probe, mass_kg: float, gyration_m: float, config) -> float:
        levels = disturbance.ramp_levels(config)
        held = {}
        for kind, axis, sign in disturbance.disturbances(config):
            probe.restore()
            unit = sign * probe.palm_axes[axis]
            scale = mass_kg * disturbance.GRAVITY * (gyration_m if kind == "torque" else 1.0)
            failed = disturbance._first_failure(probe, kind, unit * scale, levels, config)
            name = f"{'force' if kind == 'force' else 'twist'} {'xyz'[axis]}{'+-'[sign < 0]}"
            held[name] = float(levels[failed - 1]) if failed > 0 else 0.0
        found.append(held)
        return min(held.values())
    return robustness


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--trials", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    parted = []
    for check, runs in kept_runs(args.parts, args.objects, args.seed):
        a, b = (runs.draws[e] for e in ENGINES)
        apart = a["success"].to_numpy() != b["success"].to_numpy()
        parted += [(check, int(g), int(t)) for g, t in zip(a["grip"][apart], a["trial"][apart],
                                                           strict=True)]
    rng = np.random.default_rng(args.seed)
    picked = sorted(rng.choice(len(parted), min(args.trials, len(parted)), replace=False))
    found: list[dict[str, float]] = []
    trial_module.robustness = every_direction(found)
    weakest: dict[str, dict[str, Counter]] = {}
    for i in picked:
        check, grip, trial = parted[i]
        grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        config = check.task.config
        outcomes = {}
        for engine in ENGINES:
            found.clear()
            row = run_trial_outcomes(check.task.obj, grips.iloc[[grip]],
                                     config.override(sim={"engine": engine}), 1,
                                     config.dataset.seed, trial_offset=trial)
            held = found[0] if found else {}
            low = min(held.values()) if held else 0.0
            outcomes[engine] = (bool(row["success"].iloc[0]),
                                [k for k, v in held.items() if v == low] or ["not held"])
        way = f"{'mujoco' if outcomes['mujoco'][0] else 'pybullet'} succeeds alone"
        for engine, (_, directions) in outcomes.items():
            weakest.setdefault(way, {}).setdefault(engine, Counter()).update(directions)
    print(f"{len(picked)} of {len(parted)} trials the engines judge differently")
    for way, engines in sorted(weakest.items()):
        for engine, counts in engines.items():
            print(f"{way}: {engine}'s weakest directions (ties all counted): "
                  f"{dict(counts.most_common())}")


if __name__ == "__main__":
    main()
