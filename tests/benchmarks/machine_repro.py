"""Do a config's objects, contours and candidates come out the same on another x86-64 machine?
(BENCHMARKS.md, "The same dataset on any machine"). Run by hand; no trial is simulated.

    python -m tests.benchmarks.machine_repro --config configs/standard.yaml --out a.json
    NPY_DISABLE_CPU_FEATURES=X86_V3 OPENBLAS_CORETYPE=Nehalem \\
        python -m tests.benchmarks.machine_repro --config configs/standard.yaml --out b.json
    python -m tests.benchmarks.machine_repro --compare a.json b.json

The second run stands in for an older CPU: numpy without its AVX2/FMA kernels and OpenBLAS on
its SSE one. For each object (the dataset's own tasks, seeds and sampling) it hashes the true
outline, the perceived contour, the candidate table and the kept grips; ``--compare`` lists every
object whose stage differs, by the first stage that does.
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

import numpy as np
import pandas as pd

from grip_env.config import load_config
from grip_env.dataset.catalog import resolve_objects
from grip_env.dataset.jobs import ObjectTask, object_seeds, planning_contour
from grip_env.dataset.sampling import keep_grips
from grip_env.objects.meshes import execution_height_mm
from grip_env.planning.pipeline import candidates

STAGES = ("outline", "perceived", "candidates", "kept")


def digest(values: np.ndarray | pd.DataFrame) -> str:
    """Hash of the exact bits of an array or of a table's numeric columns."""
    if isinstance(values, pd.DataFrame):
        values = values.select_dtypes("number").to_numpy(float)
    return hashlib.sha256(np.ascontiguousarray(values, dtype=float).tobytes()).hexdigest()[:16]


def object_digests(config_path: str | None, limit: int | None) -> dict[str, dict[str, str]]:
    """Per object id: the hash of each stage of ``STAGES``."""
    config = load_config(config_path)
    seed = config.dataset.seed
    objects = resolve_objects(config, None, seed)[:limit]
    seeds = object_seeds(seed, len(objects))
    result = {}
    for item, object_seed in zip(objects, seeds, strict=True):
        task = ObjectTask(item.index, item.object_id, item.obj, config, object_seed)
        planned = planning_contour(task)
        height = execution_height_mm(task.obj, config.objects)
        table = candidates(planned, config.grasp, config, height_mm=height)
        kept = keep_grips(table, config.dataset, task.sampling_seed())
        result[item.object_id] = {"outline": digest(item.obj.contour),
                                  "perceived": digest(planned.contour),
                                  "candidates": digest(table), "kept": digest(kept)}
    return result


def compare(a: dict[str, dict[str, str]], b: dict[str, dict[str, str]]) -> list[str]:
    """One line per object whose stages differ, naming the first stage that does."""
    lines = []
    for object_id in sorted(set(a) | set(b)):
        if object_id not in a or object_id not in b:
            lines.append(f"{object_id}: only in one run")
            continue
        first = next((s for s in STAGES if a[object_id][s] != b[object_id][s]), None)
        if first is not None:
            lines.append(f"{object_id}: differs from {first}")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config")
    parser.add_argument("--limit", type=int)
    parser.add_argument("--out", type=Path)
    parser.add_argument("--compare", nargs=2, type=Path)
    args = parser.parse_args()
    if args.compare:
        a, b = (json.loads(p.read_text()) for p in args.compare)
        lines = compare(a, b)
        print("\n".join(lines) or "identical")
        print(f"{len(lines)} of {len(set(a) | set(b))} objects differ")
        return
    digests = object_digests(args.config, args.limit)
    text = json.dumps(digests, indent=1)
    if args.out:
        args.out.write_text(text)
    else:
        print(text)


if __name__ == "__main__":
    main()
