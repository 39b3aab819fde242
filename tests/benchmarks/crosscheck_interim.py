"""The figures of an unfinished cross-check, from the objects it has finished (run by hand).

    python -m tests.benchmarks.crosscheck_interim --objects 40 \
        --parts /work/runs/crosscheck/standard40.crosscheck

``grip-env validate DIR --crosscheck N --report R.json`` keeps each finished object's outcomes in
``R.crosscheck/`` and resumes from them; this simulates nothing: it reads the parts made under
this code's label models and prints ``grip_env.dataset.crosscheck``'s own figures (agreement,
kappa, Spearman, retests, top-1, by family, cost) over the objects finished so far, as the card
shows them. An interim figure: the objects finished first are not a random subset of the sample.
"""

from __future__ import annotations

import grip_env  # noqa: F401  # isort: skip

import argparse
import json
from pathlib import Path

from grip_env.dataset.card import crosscheck_markdown
from grip_env.dataset.crosscheck import _figures, _from_json, _run_key
from grip_env.dataset.manifest import read_manifest
from grip_env.dataset.resimulation import _retest_sample
from grip_env.datasets import standard_path
from grip_env.label_model import engine_of


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--parts", type=Path, required=True)
    parser.add_argument("--data", type=Path, default=None, help="the dataset (standard's)")
    args = parser.parse_args()
    directory = args.data or standard_path()
    manifest = read_manifest(directory)
    key = _run_key(manifest, ceilings=True)
    checks, runs = [], []
    for check in _retest_sample(directory, args.objects, args.seed):
        file = args.parts / f"{check.task.index:05d}.json"
        if not file.is_file():
            continue
        stored = json.loads(file.read_text(encoding="utf-8"))
        if stored.get("key") == {**key, "object_id": check.task.object_id}:
            checks.append(check)
            runs.append(_from_json(stored))
    found = _figures(checks, runs, engine_of(manifest), args.seed)
    print(f"{len(checks)} of {args.objects} objects finished\n")
    print(crosscheck_markdown({"objects": len(checks), **found.as_dict()}))
    print(disagreements(runs, found.engine, found.other))


def disagreements(runs: list, engine: str, other: str) -> str:
    """Where the engines judge a trial differently, and which way robustness leans."""
    import numpy as np
    import pandas as pd

    own = pd.concat([r.draws[engine] for r in runs], ignore_index=True)
    theirs = pd.concat([r.draws[other] for r in runs], ignore_index=True)
    a, b = own["success"].to_numpy(bool), theirs["success"].to_numpy(bool)
    ra, rb = own["robustness"].to_numpy(float), theirs["robustness"].to_numpy(float)
    ratio = np.median(rb[ra > 0] / ra[ra > 0]) if (ra > 0).any() else float("nan")
    return (f"\ntrials judged differently: {int((a != b).sum())} of {len(a)}; {other} succeeds "
            f"where {engine} fails in {int((b & ~a).sum())}, the reverse in {int((a & ~b).sum())}; "
            f"robustness higher in {other} in {int((rb > ra).sum())}, lower in "
            f"{int((rb < ra).sum())}, equal in {int((rb == ra).sum())}; median ratio {other} / "
            f"{engine} {ratio:.2f}; success {b.mean():.1%} in {other}, {a.mean():.1%} in {engine}; "
            f"not held (robustness 0) in {int((rb == 0).sum())} in {other}, "
            f"{int((ra == 0).sum())} in {engine}, both {int(((ra == 0) & (rb == 0)).sum())}")


if __name__ == "__main__":
    main()
