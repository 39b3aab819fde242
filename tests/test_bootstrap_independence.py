"""A method's bootstrap intervals depend on its own scores, the reference's, the held-out objects
and the seed: never on which other methods are on the board, nor on their order."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from classifiers.experiments.answers import pick_differences
from classifiers.experiments.benchmark.aggregate import mean, paired_bootstraps
from classifiers.experiments.benchmark.leaderboard import build_leaderboard
from classifiers.experiments.benchmark.retry import retry_leaderboard

OBJECTS = [f"o{i:02d}" for i in range(25)]
PLAIN = ("robustness", "regret", "robustness_regret", "ndcg5", "attempts",
         *(f"success_at_{k}" for k in range(1, 6)))
#: method: runs. ``a_cnn`` sorts first and has several runs: under one generator consumed method
#: after method it shifted every later method's run draws.
METHODS = {"a_cnn": 4, "best_qc": 1, "best_qg": 1, "ranker_lambdarank": 4, "rl": 3, "oracle": 1}


def _metrics(methods: dict[str, int], seed: int = 0) -> pd.DataFrame:
    """Per (method, run, object) metrics; each method's values from its own generator, so a
    method's rows are the same whatever the other methods."""
    rows = []
    for method, runs in methods.items():
        rng = np.random.default_rng([seed, sum(map(ord, method))])
        for run in range(runs):
            for i, obj in enumerate(OBJECTS):
                success = float(rng.uniform(0.0, 1.0))
                rows.append({"method": method, "seed": run, "object_id": obj,
                             "normalised": np.nan if i < 3 else success - 0.4,
                             "success": success, **dict.fromkeys(PLAIN, 0.5)})  # fmt: skip
    return pd.DataFrame(rows)


def _board(metrics: pd.DataFrame) -> dict:
    board = build_leaderboard(metrics, {"name": "t", "version": 0}, reps=300, seed=2)
    board["per_object"] = metrics.to_dict(orient="records")
    return board


def test_a_methods_resamples_do_not_depend_on_the_others() -> None:
    rng = np.random.default_rng(5)
    matrices = {"rl": rng.random((3, 10)), "best_qc": rng.random((1, 10)),
                "a_cnn": rng.random((4, 10))}  # fmt: skip
    every = paired_bootstraps(matrices, reps=200, seed=1, objects=OBJECTS[:10])
    alone = paired_bootstraps({"rl": matrices["rl"]}, reps=200, seed=1, objects=OBJECTS[:10])
    reordered = paired_bootstraps(dict(reversed(matrices.items())), reps=200, seed=1,
                                  objects=OBJECTS[:10])  # fmt: skip
    assert np.array_equal(every["rl"], alone["rl"])
    for name in matrices:
        assert np.array_equal(every[name], reordered[name])
    # the resampled objects are shared: one object's column always comes from that object
    marker = {"x": np.arange(10.0)[None], "y": np.arange(10.0)[None] + 100}
    paired = paired_bootstraps(marker, reps=50, seed=1, objects=OBJECTS[:10])
    assert np.array_equal(paired["y"], paired["x"] + 100)


def test_adding_removing_or_reordering_methods_leaves_every_other_row_bit_identical() -> None:
    full = _board(_metrics(METHODS))
    fewer = _board(_metrics({k: v for k, v in METHODS.items() if k != "a_cnn"}))
    shuffled = _metrics(METHODS).sample(frac=1.0, random_state=3).reset_index(drop=True)
    reordered = _board(shuffled)
    for name, row in fewer["methods"].items():
        assert row == full["methods"][name], name
    for name, row in reordered["methods"].items():
        assert row == full["methods"][name], name
    pairs = [("ranker_lambdarank", "best_qg"), ("rl", "best_qc")]
    assert pick_differences(full, pairs, seed=2, reps=300) == pick_differences(fewer, pairs,
                                                                               seed=2, reps=300)


def test_the_paired_difference_still_cancels_what_objects_share() -> None:
    """A method ``shift`` above the reference on every object, in every run: a zero-width
    interval, however the objects and runs are resampled."""
    reference = np.random.default_rng(0).random((1, 25))
    boot = paired_bootstraps({"best_qc": reference, "up": np.repeat(reference + 0.1, 3, axis=0)},
                             reps=200, seed=0, objects=OBJECTS)  # fmt: skip
    assert np.allclose(mean(boot["up"]) - mean(boot["best_qc"]), 0.1)


def _retry_metrics(methods: dict[str, int]) -> pd.DataFrame:
    rows = []
    for method, runs in methods.items():
        rng = np.random.default_rng(sum(map(ord, method)))
        for run in range(runs):
            for obj in OBJECTS:
                shared = np.sort(rng.uniform(0.0, 1.0, 3))
                rows.append({"method": method, "seed": run, "object_id": obj, "ceiling": 0.9,
                             **{f"shared_at_{m}": shared[m - 1] for m in (1, 2, 3)},
                             **{f"overstatement_at_{m}": 0.01 * m for m in (1, 2, 3)}})
    return pd.DataFrame(rows)


def test_the_retry_board_does_not_depend_on_the_others() -> None:
    full = retry_leaderboard(_retry_metrics(METHODS), reps=300, seed=0)
    fewer = retry_leaderboard(_retry_metrics({k: v for k, v in METHODS.items() if k != "a_cnn"}),
                              reps=300, seed=0)  # fmt: skip
    for name, row in fewer["methods"].items():
        assert row == full["methods"][name], name


def test_object_ids_must_match_the_matrices() -> None:
    with pytest.raises(ValueError, match="3 object ids for matrices of 10 objects"):
        paired_bootstraps({"x": np.zeros((1, 10))}, objects=OBJECTS[:3])
