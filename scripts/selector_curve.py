"""Learning curves of the RL selector on the standard dataset (issue 47).

One run per (variant, seed), appended to the CSV as each checkpoint is reached; a variant is a
name with ``selector`` overrides (JSON), e.g.::

    nice -n 10 python scripts/selector_curve.py --out docs/_static/selector/curves.csv \\
        --variant success '{}' --seeds 0 1 --timesteps 1000000

``--plot PNG`` draws the file with lambdarank's and best-Q_C's held-out top-1 success (from a
study's ``benchmark/leaderboard.json``, ``--board``) as horizontal lines.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from classifiers.experiments.selector.curve import plot_curves, read_curves, run_curve
from grip_env.config import load_config
from grip_env.datasets import load_standard


def references(board_path: str) -> dict[str, float]:
    """Held-out top-1 success of lambdarank and best-Q_C on the study's leaderboard."""
    methods = json.loads(Path(board_path).read_text())["methods"]
    return {f"{name} ({methods[name]['runs']} seeds)" if methods[name]["runs"] > 1 else name:
            methods[name]["success"] for name in ("ranker_lambdarank", "best_qc")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--variant", nargs=2, metavar=("NAME", "OVERRIDES"))
    parser.add_argument("--policy", default="set")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--timesteps", type=int, default=1_000_000)
    parser.add_argument("--config", default="configs/default.yaml")
    parser.add_argument("--plot")
    parser.add_argument("--board", default="runs/default/benchmark/leaderboard.json")
    args = parser.parse_args()
    if args.variant:
        name, overrides = args.variant
        config = load_config(args.config).override(selector=json.loads(overrides))
        table = load_standard()
        for seed in args.seeds:
            run_curve(table, args.out, config, name, seed, args.timesteps, args.policy)
    if args.plot:
        plot_curves(read_curves(args.out), args.plot, references(args.board))


if __name__ == "__main__":
    main()
