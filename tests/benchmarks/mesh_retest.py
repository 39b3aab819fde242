"""MuJoCo's within-object retest and agreement on a cross-check's objects under a model setting
(run by hand; issue 45).

    python -m tests.benchmarks.mesh_retest \
        --parts /work/runs/crosscheck/standard40-drives.crosscheck --family mesh \
        --set MULTI_CONTACT=0
    python -m tests.benchmarks.mesh_retest --parts ... --family procedural \
        --sim ramp_ratio=1.4142135623730951

Sets each ``--set NAME=VALUE`` constant of ``grip_env.sim.mujoco_world`` (a float; 0/1 for a
flag), runs every recorded grip of the family's objects of the cross-check's sample in MuJoCo,
trials 0..T-1 and T..2T-1 as the cross-check does (``crosscheck._simulate``), and prints per
object and on average: MuJoCo's own within-object retest, the within-object Spearman against
PyBullet's kept outcomes (trials 0..T-1), per-trial success agreement, whether MuJoCo's outcomes
are the kept ones (same model: bit for bit), and the CPU seconds a trial. Without ``--set`` it
re-runs the committed model (a check that the kept outcomes are reproduced). ``--sim
NAME=VALUE`` overrides a ``sim`` setting of the dataset's config instead (a float).
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import json
import time
from pathlib import Path

import numpy as np

import grip_env.sim.mujoco_world as mujoco_world
from grip_env.dataset.crosscheck import _from_json, _means, _spearman
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.objects.family import object_family
from grip_env.sim import run_trial_outcomes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--family", default="mesh")
    parser.add_argument("--only", nargs="*", default=None, help="object ids (default: all)")
    parser.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE")
    parser.add_argument("--sim", nargs="*", default=[], metavar="NAME=VALUE")
    args = parser.parse_args()
    sim = {name: float(value) for name, value in (item.split("=") for item in args.sim)}
    for item in args.set:
        name, value = item.split("=")
        if not hasattr(mujoco_world, name):
            raise SystemExit(f"error: mujoco_world has no constant {name}")
        old = getattr(mujoco_world, name)
        setattr(mujoco_world, name, type(old)(float(value)) if not isinstance(old, bool)
                else bool(float(value)))
    print(f"settings: {args.set + args.sim or 'committed'}")
    print("| object | grips | retest MuJoCo | kept retest | within vs PyBullet | kept within "
          "| success agree | kept agree | same as kept | ms a trial |")
    print("| --- " * 10 + "|")
    sums: dict[str, list[float]] = {}
    for check in _retest_sample(standard_path(), args.objects, args.seed):
        if object_family(check.task.obj) != args.family or (
                args.only and check.task.object_id not in args.only):
            continue
        kept = _from_json(json.loads((args.parts / f"{check.task.index:05d}.json").read_text(
            encoding="utf-8")))
        config = check.task.config.override(sim={"engine": "mujoco", **sim})
        grips = check.recorded.assign(object_id=check.task.object_id).reset_index(drop=True)
        trials, seed = config.dataset.trials, config.dataset.seed
        started = time.process_time()
        draws = run_trial_outcomes(check.task.obj, grips, config, trials, seed)
        again = run_trial_outcomes(check.task.obj, grips, config, trials, seed,
                                   trial_offset=trials)
        ms = 1000 * (time.process_time() - started) / (len(draws) + len(again))
        pybullet = kept.draws["pybullet"]
        row = {
            "retest": _spearman(_means(draws), _means(again)),
            "kept_retest": _spearman(_means(kept.draws["mujoco"]), _means(kept.retest["mujoco"])),
            "within": _spearman(_means(pybullet), _means(draws)),
            "kept_within": _spearman(_means(pybullet), _means(kept.draws["mujoco"])),
            "agree": float(np.mean(pybullet["success"].to_numpy() == draws["success"].to_numpy())),
            "kept_agree": float(np.mean(pybullet["success"].to_numpy()
                                        == kept.draws["mujoco"]["success"].to_numpy())),
            "same": float(np.array_equal(draws["robustness"].to_numpy(),
                                         kept.draws["mujoco"]["robustness"].to_numpy())
                          and np.array_equal(again["robustness"].to_numpy(),
                                             kept.retest["mujoco"]["robustness"].to_numpy())),
            "ms": ms,
        }
        for k, v in row.items():
            sums.setdefault(k, []).append(v)
        print(f"| {check.task.object_id} | {len(grips)} | " + " | ".join(
            f"{v:.2f}" if k not in ("ms",) else f"{v:.0f}" for k, v in row.items()) + " |",
            flush=True)
    print(f"| mean of {len(sums.get('ms', []))} | | " + " | ".join(
        f"{np.nanmean(v):.2f}" if k != "ms" else f"{np.mean(v):.0f}" for k, v in sums.items())
        + " |")


if __name__ == "__main__":
    main()
