"""Cheaper MuJoCo physics a label, against a converged reference (run by hand; issue 45).

    python -m tests.benchmarks.mujoco_lean run NAME [NAME ...] --grips 150 --out DIR
    python -m tests.benchmarks.mujoco_lean judge NAME [NAME ...] --out DIR
    python -m tests.benchmarks.mujoco_lean checks NAME [NAME ...]

``run`` simulates trial 0 of a seeded sample of the standard dataset's grips (the draw of
``tests.benchmarks.engines --grips``) in MuJoCo with each named variant (``VARIANTS``: substeps,
the stop's and motors' time constant, the servos' references, NoSlip and Newton settings), and
writes its outcomes and CPU seconds to ``DIR/NAME.parquet``. ``judge`` prints each variant
against the reference of its own physical model (``reference_of``): success and held alike,
Spearman of robustness, the mean difference with its paired 95 % bootstrap interval against
±5 % of the reference's mean, and the cost. ``checks`` runs each variant's analytic cases,
faithfulness checks and pads on the held box (BENCHMARKS.md, "Cheaper MuJoCo physics per label").
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

import grip_env.sim.mujoco_world as mujoco_world
from grip_env.config import Config

#: The converged integration: 16 substeps, NoSlip 20, Newton 200 iterations at 1e-10.
FINE = {"substeps": 16, "noslip": 20, "iterations": 200, "tolerance": 1e-10}
#: Each variant of the current model (``mujoco-2026.12-lean``: 4 substeps, the stop's and
#: motors' time constant ``STIFF_TIME_CONSTANT_S``): its physical model (``stiff``, the stop's
#: and motors' time constant in s) and its integration. The ``-drives`` rows of BENCHMARKS.md
#: (the stop following the substep) and the servos' references as moving joints were measured
#: with switches for both at commit 09ab565.
VARIANTS: dict[str, dict] = {
    "lean": {"substeps": 4},
    "lean-s5": {"substeps": 5},
    "lean-s3": {"substeps": 3},
    "stop3-s4": {"substeps": 4, "stiff": 1 / 360},
    "stop3-s3": {"substeps": 3, "stiff": 1 / 360},
    "noslip3": {"substeps": 4, "noslip": 3},
    "noslip2": {"substeps": 4, "noslip": 2},
    "tol6": {"substeps": 4, "tolerance": 1e-6, "noslip_tolerance": 1e-4},
    "iter10": {"substeps": 4, "iterations": 10},
    "fine24": {**FINE, "substeps": 24},  # is the reference itself converged?
}
PHYSICAL = ("stiff",)


def reference_of(name: str) -> str:
    """The name of the reference variant of ``name``'s physical model."""
    spec = VARIANTS.get(name) or json.loads(name.removeprefix("ref:"))
    return "ref:" + json.dumps({k: spec[k] for k in PHYSICAL if k in spec}, sort_keys=True)


def settings(name: str) -> dict:
    if name.startswith("ref:"):
        return {**json.loads(name.removeprefix("ref:")), **FINE}
    return VARIANTS[name]


def apply(spec: dict) -> None:
    """Patch the MuJoCo world's module constants and options for ``spec``."""
    sim = Config().sim
    phase = math.sqrt(sim.pad_stiffness_n_per_m / mujoco_world.PAD_REFERENCE_MASS_KG) * (
        sim.timestep)
    mujoco_world.PAD_PHASE_PER_STEP = phase / spec["substeps"] * (1 + 1e-9)
    mujoco_world.STIFF_TIME_CONSTANT_S = spec.get("stiff", STIFF)
    mujoco_world.NOSLIP_ITERATIONS = spec.get("noslip", 5)
    compile_ = ORIGINAL_COMPILE

    def patched(self: mujoco_world.MujocoWorld) -> None:
        compile_(self)
        opt = self._model.opt
        if "iterations" in spec:
            opt.iterations = spec["iterations"]
        if "tolerance" in spec:
            opt.tolerance = spec["tolerance"]
        if "noslip_tolerance" in spec:
            opt.noslip_tolerance = spec["noslip_tolerance"]

    mujoco_world.MujocoWorld._compile = patched


ORIGINAL_COMPILE = mujoco_world.MujocoWorld._compile
STIFF = mujoco_world.STIFF_TIME_CONSTANT_S


def run(names: list[str], grips: int, seed: int, out: Path) -> None:
    from grip_env.sim import run_trial_outcomes
    from tests.benchmarks.mujoco_cost import work

    jobs = work(grips, seed)
    out.mkdir(parents=True, exist_ok=True)
    for name in names:
        apply(settings(name))
        started = time.process_time()
        rows = [run_trial_outcomes(obj, table, config, trials=1, seed=config.dataset.seed)
                for obj, table, config in jobs]
        cpu = time.process_time() - started
        table = pd.concat(rows, ignore_index=True)
        table.attrs = {}
        table["cpu_s"] = cpu / len(table)
        table.to_parquet(out / f"{_file(name)}.parquet")
        print(f"{name}: {len(table)} trials, {1e3 * cpu / len(table):.1f} ms a trial, "
              f"{1e6 * cpu / table['steps'].sum():.0f} µs a protocol step", flush=True)


def _file(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name)


def judge(names: list[str], out: Path, seed: int) -> None:
    print("| variant | held | success | mean robustness (g) | minus reference's, 95 % interval "
          "| ±5 % | success alike | held alike | Spearman | passes 1 | ms / trial | "
          "µs / protocol step |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in names:
        t = pd.read_parquet(out / f"{_file(name)}.parquet")
        ref = pd.read_parquet(out / f"{_file(reference_of(name))}.parquet")
        diff = (t["robustness"] - ref["robustness"]).to_numpy(float)
        rng = np.random.default_rng(seed)
        boot = diff[rng.integers(0, len(diff), (2000, len(diff)))].mean(axis=1)
        low, high = np.quantile(boot, [0.025, 0.975])
        band = 0.05 * ref["robustness"].mean()
        rho = stats.spearmanr(t["robustness"], ref["robustness"]).statistic
        success = (t["success"] == ref["success"]).mean()
        held = (t["held"] == ref["held"]).mean()
        ok = success >= 0.97 and held >= 0.97 and rho >= 0.97 and -band <= low and high <= band
        cpu = t["cpu_s"].iloc[0]
        print(f"| {name} | {int(t['held'].sum())} | {int(t['success'].sum())} | "
              f"{t['robustness'].mean():.1f} | {diff.mean():+.2f} [{low:+.2f}, {high:+.2f}] | "
              f"±{band:.2f} | {100 * success:.1f} % | {100 * held:.1f} % | {rho:.3f} | "
              f"{'yes' if ok else 'no'} | {1e3 * cpu:.0f} | "
              f"{1e6 * cpu * len(t) / t['steps'].sum():.0f} |")


def checks(names: list[str]) -> None:
    """Each variant's analytic cases (MuJoCo's rows), faithfulness row and pads on the held box."""
    from grip_env.sim.analytic import run_cases
    from tests.benchmarks.engines import held_box_grip
    from tests.benchmarks.mujoco_pads import fidelity, impedance

    for name in names:
        apply(settings(name))
        print(f"## {name}")
        box, grip = held_box_grip(Config())
        for r in run_cases(Config(), box, grip, ("mujoco",)):
            print(f"| {r.case} ({r.quantity}) | {name} | {r.analytic:.4g} | {r.simulated:.4g} "
                  f"| {r.error:+.2%} | {r.detail} |", flush=True)
        print(fidelity("mujoco").replace("| mujoco |", f"| {name} |"), flush=True)
        impedance([mujoco_world.PAD_IMPEDANCE])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("run", "judge", "checks"))
    parser.add_argument("names", nargs="+")
    parser.add_argument("--grips", type=int, default=150)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("/tmp/lean"))
    args = parser.parse_args()
    names = args.names  # "ref-NAME": the reference of NAME's physical model
    if args.what == "run":
        run([reference_of(n[len("ref-"):]) if n.startswith("ref-") else n for n in names],
            args.grips, args.seed, args.out)
    elif args.what == "checks":
        checks(names)
    else:
        judge(names, args.out, args.seed)


if __name__ == "__main__":
    main()
