"""Why an object's within-object retest is low: grips alike or trials noisy (run by hand;
issue 45).

    python -m tests.benchmarks.crosscheck_reliability \
        --parts /work/runs/crosscheck/standard40-drives.crosscheck

Reads a cross-check's kept outcomes (trials 0..2T-1 of every grip, both engines) and splits
each object's robustness, per engine, as grip + trial + residual (two-way analysis of variance
without replication; the trials' draws are common to the object's grips, so the trial term is
what every grip meets alike and does not reorder them): the spread of the grips' true means
(``sd_grip``), the residual noise that reorders them (``sd_noise``), and the reliability of a
T-trial mean that follows, ``sd_grip^2 / (sd_grip^2 + sd_noise^2 / T)`` (``icc``), beside the
measured retest (Spearman of trials 0..T-1 against T..2T-1) and the within-object Spearman
between engines. A low retest with a small ``sd_noise`` is grips alike, not an engine's noise.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
from pathlib import Path

import numpy as np

from grip_env.dataset.crosscheck import _means, _spearman
from grip_env.objects.family import object_family
from tests.benchmarks.crosscheck_contact_loads import kept_runs

ENGINES = ("pybullet", "mujoco")


def components(draws, retest) -> dict[str, float]:
    """One engine's grip and residual spreads (g), a T-trial mean's reliability, the retest."""
    frames = [f.sort_values(["grip", "trial"], kind="stable") for f in (draws, retest)]
    n = frames[0]["grip"].nunique()
    x = np.concatenate([f["robustness"].to_numpy(float).reshape(n, -1) for f in frames], axis=1)
    k, trials = x.shape[1], x.shape[1] // 2
    grip, trial = x.mean(1, keepdims=True), x.mean(0, keepdims=True)
    residual = x - grip - trial + x.mean()
    noise = (residual**2).sum() / max((n - 1) * (k - 1), 1)
    between = max((k * ((grip - x.mean()) ** 2).sum() / max(n - 1, 1) - noise) / k, 0.0)
    total = between + noise / trials
    return {"grips": n, "sd_grip": float(np.sqrt(between)), "sd_noise": float(np.sqrt(noise)),
            "icc": float(between / total) if total > 0 else float("nan"),
            "retest": _spearman(_means(draws), _means(retest))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rows = []
    for check, runs in kept_runs(args.parts, args.objects, args.seed):
        row = {"object": check.task.object_id, "family": object_family(check.task.obj),
               "within": _spearman(*(_means(runs.draws[e]) for e in ENGINES))}
        for engine in ENGINES:
            row[engine] = components(runs.draws[engine], runs.retest[engine])
        rows.append(row)
    print("| object | family | grips | PyBullet sd_grip, sd_noise (g) | icc | retest "
          "| MuJoCo sd_grip, sd_noise (g) | icc | retest | within-object Spearman |")
    print("| --- " * 10 + "|")
    for r in sorted(rows, key=lambda r: (r["family"], r["mujoco"]["grips"], r["object"])):
        p, m = r["pybullet"], r["mujoco"]
        print(f"| {r['object']} | {r['family']} | {p['grips']} | {p['sd_grip']:.1f}, "
              f"{p['sd_noise']:.1f} | {p['icc']:.2f} | {p['retest']:.2f} | {m['sd_grip']:.1f}, "
              f"{m['sd_noise']:.1f} | {m['icc']:.2f} | {m['retest']:.2f} | {r['within']:.2f} |")
    groups = {}
    for r in rows:
        few = "all 24 grips" if r["mujoco"]["grips"] == 24 else "fewer grips"
        for name in (r["family"], f"{r['family']}, {few}", "all", f"all, {few}"):
            groups.setdefault(name, []).append(r)
    print("\n| group | objects | PyBullet sd_grip, sd_noise | icc | retest | MuJoCo sd_grip, "
          "sd_noise | icc | retest | within |")
    print("| --- " * 9 + "|")
    for name, rs in sorted(groups.items()):
        def avg(engine: str, key: str, rs: list = rs) -> float:
            return float(np.nanmean([r[engine][key] for r in rs]))
        cells = [f"{avg(e, 'sd_grip'):.1f}, {avg(e, 'sd_noise'):.1f} | {avg(e, 'icc'):.2f} | "
                 f"{avg(e, 'retest'):.2f}" for e in ENGINES]
        within = float(np.nanmean([r["within"] for r in rs]))
        print(f"| {name} | {len(rs)} | {cells[0]} | {cells[1]} | {within:.2f} |")


if __name__ == "__main__":
    main()
