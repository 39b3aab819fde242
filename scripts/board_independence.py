"""Does a method's leaderboard interval depend on the board's other methods? A study's board
built twice from its score files, with and without one of them (default: the image models'),
and every method on both compared bit for bit.

    PYTHONPATH=$PWD .venv/bin/python scripts/board_independence.py runs/default /tmp/boards

Writes the two boards under OUT (``with/``, ``without/``) and prints, for each method on both,
whether its row is identical, with its top-1 success difference from best-Q_C, and the pick
differences the study's answers name (lambdarank - best-Q_G, rl - best-Q_C).
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

from classifiers.experiments.answers import pick_differences
from classifiers.experiments.benchmark import study_benchmark
from classifiers.experiments.benchmark.methods import SCORE_FILES
from classifiers.report.answers import signed
from grip_env.config import load_config
from grip_env.dataset.loading import load
from grip_env.datasets import resolve_data

PAIRS = [("ranker_lambdarank", "best_qg"), ("rl", "best_qc")]


def board(study: Path, out: Path, files: list[str], config_file: str | None) -> dict:
    """The study's board from ``files`` (its score files) alone, written under ``out``."""
    for name in files:
        (out / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(study / name, out / name)
    config = load_config(config_file)
    return study_benchmark(load(resolve_data("standard")), out, config)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--drop", default="images/scores.parquet")
    parser.add_argument("--config", default="configs/default.yaml")
    args = parser.parse_args()
    files = [f for f in SCORE_FILES if (args.study / f).is_file()]
    full = board(args.study, args.out / "with", files, args.config)
    fewer = board(args.study, args.out / "without", [f for f in files if f != args.drop],
                  args.config)  # fmt: skip
    seed = load_config(args.config).learning.seed
    for name, row in fewer["methods"].items():
        same = row == full["methods"][name]
        print(f"{name:>24}: {'identical' if same else 'MOVED':>9}; success - best_qc without "
              f"{signed(row['success_difference_vs_reference'], 4)}, with "
              f"{signed(full['methods'][name]['success_difference_vs_reference'], 4)}")
    for label, found in (("without", fewer), ("with", full)):
        for key, value in pick_differences(found, PAIRS, seed).items():
            print(f"{label:>8} {args.drop}: {key} {signed(value, 4)}")


if __name__ == "__main__":
    main()
