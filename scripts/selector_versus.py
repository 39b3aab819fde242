"""The study's selector stage with a given ``selector`` configuration, judged as the study judges
it (issue 47): the leaderboard of ``study_benchmark`` on a folder holding these selector runs
beside a finished study's learner scores, and the paired top-1 differences of the answers.

    nice -n 10 python scripts/selector_versus.py --out runs/rl47/pool \\
        --overrides '{"context": "pool"}' --study runs/default

Writes ``OUT/selector/`` (the stage's files), ``OUT/benchmark/`` and ``OUT/versus.json``:
the stage's seconds, the RL row of the leaderboard and ``rl - ranker_lambdarank``,
``rl - best_qc`` with their 95 % intervals. ``--skip-training`` re-judges existing runs.
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

from classifiers.experiments.answers import pick_differences
from classifiers.experiments.benchmark import study_benchmark
from classifiers.experiments.selector.seeds import run_selectors
from grip_env.config import load_config
from grip_env.datasets import load_standard

PAIRS = [("rl", "ranker_lambdarank"), ("rl", "best_qc"), ("ranker_lambdarank", "best_qc")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--overrides", default="{}")
    parser.add_argument("--study", default="runs/default")
    parser.add_argument("--config", default="configs/default.yaml")
    parser.add_argument("--skip-training", action="store_true")
    args = parser.parse_args()
    out, study = Path(args.out), Path(args.study)
    config = load_config(args.config).override(selector=json.loads(args.overrides))
    table = load_standard()
    seconds = None
    if not args.skip_training:
        start = time.perf_counter()
        run_selectors(table, out / "selector", config, progress=False)
        seconds = round(time.perf_counter() - start, 1)
    (out / "classifiers").mkdir(parents=True, exist_ok=True)
    scores = Path("classifiers") / "scores.parquet"
    shutil.copyfile(study / scores, out / scores)
    board = study_benchmark(table, out, config)
    picks = pick_differences(board, PAIRS, config.learning.seed)
    row = board["methods"]["rl"]
    found = {"overrides": json.loads(args.overrides), "selector_stage_seconds": seconds,
             "selector": config.selector.model_dump(), "rl_success": row["success"],
             "rl_success_ci": row["success_ci"], "picks": picks}
    (out / "versus.json").write_text(json.dumps(found, indent=2))
    print(json.dumps({k: found[k] for k in ("overrides", "selector_stage_seconds", "rl_success")}))
    for name, pick in picks.items():
        print(f"{name}: {pick['estimate']:+.3f} [{pick['ci'][0]:+.3f}, {pick['ci'][1]:+.3f}]")


if __name__ == "__main__":
    main()
