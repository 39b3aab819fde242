"""The RL selector trained with several seeds, each run kept, every candidate scored per seed.

:func:`run_selectors` trains ``selector.seeds`` selectors, seeds ``selector.seed + k``, in
``selector.workers`` processes (each run is seeded and single-threaded, so its result does not
depend on them), each with :func:`classifiers.experiments.selector.run_selector` into
``out/seed_<s>/``. The first seed's ``selector.json``, ``model.zip`` and
``learning_curve.png`` are copied to ``out/`` (what a single-seed run writes there), with
``"seeds"``: every run's seed, folder, training time and held-out first-pick success.
``out/held_out_curve.csv`` and ``.png`` are every run's held-out first-pick success after each
rollout (:mod:`classifiers.experiments.selector.curve`'s layout and figure).
``out/scores.parquet`` holds each run's action probabilities for every candidate of every
held-out object, in the layout of :mod:`classifiers.experiments.candidate_scores` (method ``"rl"``).
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd

from classifiers.experiments.selector.data import check_grip_table
from grip_env.config import Config

METHOD = "rl"
#: The method name of selectors trained for the retry task (``max_attempts`` > 1).
RETRY_METHOD = "rl_retry"
CURVE_TABLE, CURVE_FIGURE = "held_out_curve.csv", "held_out_curve.png"
_COPIED = ("model.zip", "model.json", "learning_curve.png")


def seed_dir(out: str | Path, seed: int) -> Path:
    """The folder of the run with ``seed``."""
    return Path(out) / f"seed_{seed}"


def policy_scores(model: Any, table: pd.DataFrame, config: Config, seed: int,
                  method: str = METHOD) -> pd.DataFrame:  # fmt: skip
    """``model``'s score rows (:data:`classifiers.experiments.candidate_scores.SCORE_COLUMNS`):
    its probability of picking each held-out candidate; for a retry policy (its observation has
    ``failed``), ``count - j`` for the j-th slot it picks, each earlier pick shown to it as
    failed, so that a static order of the scores is what the policy does after each failure."""
    from classifiers.experiments.candidate_scores import score_frame
    from classifiers.experiments.selector.evaluation import (
        action_probabilities,
        held_out_candidate_sets,
        order_scores,
        policy_orders,
    )

    sets = held_out_candidate_sets(table, config)
    if "failed" in getattr(model.observation_space, "spaces", {}):
        orders = policy_orders(model, sets, config.selector.max_candidates)
        scores = [order_scores(order, found.count)
                  for found, order in zip(sets, orders, strict=True)]
    else:
        scores = list(action_probabilities(model, sets)) if sets else []
    return pd.concat([score_frame(found.object_id, seed, method, found.rows, p[: found.count])
                      for found, p in zip(sets, scores, strict=True)],
                     ignore_index=True)  # fmt: skip


def run_selectors(
    table: pd.DataFrame, out_dir: str | Path, config: Config, policy: str = "set",
    progress: bool = True, method: str = METHOD,
) -> dict[str, Any]:
    """Train and evaluate one selector per seed, the runs shared among ``selector.workers``
    processes; returns the first seed's report (with ``"seeds"``), which is also written to
    ``out_dir/selector.json``. ``method`` names the runs in the score and curve tables."""
    from joblib import Parallel, delayed

    from classifiers.experiments.candidate_scores import SCORES_FILE, training_seeds, write_scores
    from classifiers.experiments.selector import REPORT_FILE

    table = check_grip_table(table)
    out = Path(out_dir)
    settings = config.selector
    seeds = training_seeds(settings.seed, settings.seeds)
    workers = min(settings.workers, len(seeds))
    finished = Parallel(n_jobs=workers)(
        delayed(_seed_run)(table, out, config, seed, policy, progress and workers == 1, method)
        for seed in seeds)
    reports, scores = zip(*finished, strict=True)
    runs = [{"seed": seed, "dir": seed_dir(out, seed).name,
             "held_out_success_rate": report["policies"]["rl"]["success_rate"]["mean"],
             "seconds": report["training"]["seconds"]}
            for seed, report in zip(seeds, reports, strict=True)]  # fmt: skip
    for name in _COPIED:
        if (seed_dir(out, settings.seed) / name).exists():  # a run from before model.json
            shutil.copyfile(seed_dir(out, settings.seed) / name, out / name)
    first = reports[0]
    training = {**first["training"], "tensorboard": f"{seed_dir(out, settings.seed).name}/tb"}
    first = {**first, "training": training, "seeds": runs, "scores": SCORES_FILE}
    (out / REPORT_FILE).write_text(json.dumps(first, indent=2))
    write_scores(list(scores), out / SCORES_FILE)
    write_held_out_curves(reports, seeds, out, method)
    return first


def write_held_out_curves(reports: Sequence[dict[str, Any]], seeds: Sequence[int],
                          out: Path, method: str = METHOD) -> Path:  # fmt: skip
    """Every seed's held-out curve (scored after each rollout) as ``held_out_curve.csv``
    (:data:`~classifiers.experiments.selector.curve.CURVE_COLUMNS`, variant ``method``) and its
    figure ``held_out_curve.png``, with best-Q_C's and the classifiers' first picks as lines."""
    from classifiers.experiments.selector.curve import CURVE_COLUMNS, plot_curves

    rows = [(method, seed, step, value, None, report["training"]["seconds"])
            for seed, report in zip(seeds, reports, strict=True)
            for step, value in report["training"].get("held_out_curve", [])]  # fmt: skip
    frame = pd.DataFrame(rows, columns=list(CURVE_COLUMNS))
    frame.to_csv(out / CURVE_TABLE, index=False)
    policies = reports[0]["policies"]
    lines = {name: policies[name]["success_rate"]["mean"] for name in policies
             if name == "best_qc" or name.startswith("classifier_")}  # fmt: skip
    if len(frame):
        plot_curves(frame, out / CURVE_FIGURE, lines)
    return out / CURVE_TABLE


def _seed_run(table: pd.DataFrame, out: Path, config: Config, seed: int, policy: str,
              progress: bool, method: str = METHOD) -> tuple[dict[str, Any], pd.DataFrame]:
    """One seed's run into ``out/seed_<seed>``: its report and its held-out scores."""
    from sb3_contrib import MaskablePPO

    from classifiers.experiments.selector import run_selector

    seeded = config.override(selector={"seed": seed})
    folder = seed_dir(out, seed)
    report = run_selector(table, folder, seeded, policy, progress=progress)
    model = MaskablePPO.load(folder / "model.zip", device="cpu")
    return report, policy_scores(model, table, seeded, seed, method)
