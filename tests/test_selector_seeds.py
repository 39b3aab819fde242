"""The RL selector trained with several seeds: one folder per seed, per-seed candidate scores."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.candidate_scores import SCORE_COLUMNS
from classifiers.experiments.selector.seeds import run_selectors
from grip_env.config import load_config


@pytest.mark.slow
def test_selector_seeds_differ_and_repeat(tmp_path):
    grips = synthetic_grips(n_objects=16, grips=(4, 10), seed=2)
    config = load_config().override(
        selector={"max_candidates": 12, "timesteps": 256, "seeds": 2, "seed": 3},
        learning={"models": ("logreg",)},
    )
    report = run_selectors(grips, tmp_path / "a", config, progress=False)
    assert [run["seed"] for run in report["seeds"]] == [3, 4]
    for seed in (3, 4):
        folder = tmp_path / "a" / f"seed_{seed}"
        assert (folder / "model.zip").stat().st_size > 0
        assert json.loads((folder / "selector.json").read_text())["policies"]["rl"]
    top = json.loads((tmp_path / "a" / "selector.json").read_text())
    assert top == report and top["training"]["tensorboard"] == "seed_3/tb"
    scores = pd.read_parquet(tmp_path / "a" / "scores.parquet")
    assert list(scores.columns) == list(SCORE_COLUMNS)
    assert set(scores["method"]) == {"rl"} and set(scores["seed"]) == {3, 4}
    sums = scores.groupby(["seed", "object_id"])["score"].sum()
    assert np.allclose(sums, 1.0)  # probabilities over each object's candidates
    by_seed = [group["score"].to_numpy() for _, group in scores.groupby("seed")]
    assert not np.allclose(*by_seed)  # another seed, another policy
    curves = pd.read_csv(tmp_path / "a" / "held_out_curve.csv")
    assert set(curves["seed"]) == {3, 4} and set(curves["variant"]) == {"rl"}
    for seed in (3, 4):  # one row a rollout, as the seed's own report records it
        own = json.loads((tmp_path / "a" / f"seed_{seed}" / "selector.json").read_text())
        rows = curves[curves["seed"] == seed][["timesteps", "held_out_success"]]
        assert rows.to_numpy().tolist() == own["training"]["held_out_curve"]
    assert (tmp_path / "a" / "held_out_curve.png").stat().st_size > 10_000
    run_selectors(grips, tmp_path / "b", config.override(selector={"seeds": 1}), progress=False)
    again = pd.read_parquet(tmp_path / "b" / "scores.parquet")
    first = scores[scores["seed"] == 3].reset_index(drop=True)
    # the same seed, the same policy: trained in a second process above, in this one here
    pd.testing.assert_frame_equal(first, again)
