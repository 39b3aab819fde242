"""Which of the standard dataset's objects would a planner change make other candidates for?

Usage: python scripts/replan_standard.py SECTION.FIELD=VALUE ... [--sample N] [--seed S]

Re-plans, on the contours recorded in objects.parquet (no render), every object the dataset kept
no grip of and a seeded sample of N (default 60) of the others: with the recorded config (which
must give the recorded grips bit for bit) and with the overrides (e.g.
``synthesis.frictional_closure=true``). Prints one line per object, then a summary per group.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict

import yaml

# grip_env before numpy: it holds numpy's kernels at x86-64-v3, as the dataset was made
from grip_env.config import Config
from grip_env.dataset.catalog import load_objects, load_perceived_objects
from grip_env.dataset.jobs import ObjectTask, kept_grips
from grip_env.dataset.loading import load
from grip_env.dataset.resimulation import same_candidates
from grip_env.datasets import standard_path
from grip_env.objects.meshes import execution_height_mm
from grip_env.planning.pipeline import candidates


def overridden(config: Config, assignments: list[str]) -> Config:
    """``config`` with each ``section.field=value`` (value read as YAML) set."""
    sections: dict[str, dict] = defaultdict(dict)
    for assignment in assignments:
        key, _, value = assignment.partition("=")
        section, _, field = key.partition(".")
        if not (section and field and value):
            raise SystemExit(f"error: {assignment!r} is not SECTION.FIELD=VALUE")
        sections[section][field] = yaml.safe_load(value)
    return config.override(**sections)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("overrides", nargs="+", metavar="SECTION.FIELD=VALUE")
    parser.add_argument("--sample", type=int, default=60, help="objects with grips to re-plan")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sample")
    args = parser.parse_args()
    import numpy as np  # after grip_env (see the imports)

    directory = standard_path()
    manifest = json.loads((directory / "manifest.json").read_text(encoding="utf-8"))
    recorded = Config.model_validate(manifest["config"])
    changed = overridden(recorded, args.overrides)
    table = load(directory)
    objects, perceived = load_objects(directory), load_perceived_objects(directory)
    with_grips = set(table["object_id"])
    entries = manifest["objects"]
    without = [e for e in entries if e["object_id"] not in with_grips]
    order = np.random.default_rng(args.seed).permutation(len(entries))
    sample = [entries[i] for i in order if entries[i]["object_id"] in with_grips][:args.sample]
    summary: dict[str, list[tuple[bool, bool, bool]]] = {"without grips": [], "with grips": []}
    for entry in without + sample:
        i, object_id = entry["index"], entry["object_id"]
        rows = table[table["object_id"] == object_id].reset_index(drop=True)
        tasks = [ObjectTask(i, object_id, objects[i], config, entry["seed"], perceived[i])
                 for config in (recorded, changed)]
        reproduces = same_candidates(kept_grips(tasks[0]), rows)
        contour = perceived[i] if perceived[i] is not None else objects[i]
        height = execution_height_mm(objects[i], recorded.objects)
        before, after = (candidates(contour, config.grasp, config, height_mm=height)
                         for config in (recorded, changed))
        same = before.equals(after)
        print(f"{object_id}: recorded {len(rows)} grips, reproduced {reproduces}; candidates "
              f"{len(before)} -> {len(after)}{'' if same else ' (differ)'}", flush=True)
        group = "with grips" if len(rows) else "without grips"
        summary[group].append((reproduces, same, len(before) == 0 and len(after) > 0))
    for group, found in summary.items():
        reproduced, same, gained = (sum(column) for column in zip(*found, strict=True))
        print(f"{group}: {len(found)} objects; recorded config reproduces {reproduced}; "
              f"candidates unchanged {same}, changed {len(found) - same}; gain grips {gained}")


if __name__ == "__main__":
    main()
