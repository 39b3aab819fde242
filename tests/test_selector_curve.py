"""The selector's learning curve: log-spaced checkpoints, rows written as they come, seeded
runs that repeat, and the figure."""

from __future__ import annotations

import pandas as pd
import pytest

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.selector.curve import (
    CURVE_COLUMNS,
    checkpoints,
    curve_summary,
    plot_curves,
    read_curves,
    run_curve,
)
from grip_env.config import load_config


def test_checkpoints_by_hand():
    assert checkpoints(1_000_000, first=1000, per_decade=1) == (1000, 10_000, 100_000, 1_000_000)
    assert checkpoints(100_000, first=1000, per_decade=2) == (1000, 3162, 10_000, 31_623,
                                                                 100_000)  # fmt: skip
    assert checkpoints(500, first=1000) == (500,)
    with pytest.raises(ValueError, match="checkpoints"):
        checkpoints(0)


@pytest.fixture(scope="module")
def grips() -> pd.DataFrame:
    return synthetic_grips(n_objects=16, grips=(4, 10), seed=2)


@pytest.fixture(scope="module")
def config():
    return load_config().override(selector={"max_candidates": 12, "n_envs": 2,
                                            "rollout_steps": 64, "batch_size": 32})  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("context", ["none", "attention"])
def test_seeded_curves_repeat_and_differ_between_seeds(grips, config, tmp_path, context):
    chosen = config.override(selector={"context": context, "reward": "expected_success"})
    for run, seed in (("a", 0), ("b", 0), ("c", 1)):
        run_curve(grips, tmp_path / f"{run}.csv", chosen, "v", seed, 512, first=64, per_decade=2)
    a, b, c = (read_curves(tmp_path / f"{run}.csv") for run in "abc")
    assert tuple(a.columns) == CURVE_COLUMNS
    # checkpoints 64, 181, 512 (geometric), each written at the first step count past it: the
    # two environments step together, so 181 is written at 182
    assert a["timesteps"].tolist() == [64, 182, 512]
    assert a["held_out_success"].between(0, 1).all()
    same = ["timesteps", "held_out_success", "train_reward"]
    pd.testing.assert_frame_equal(a[same], b[same])
    assert not a["train_reward"].equals(c["train_reward"])


def test_plot_and_summary_of_a_curve_file(tmp_path):
    rows = [("x", seed, t, 0.4 + 0.1 * seed + t / 1e4, 0.5, 1.0)
            for seed in (0, 1) for t in (100, 1000)] + [("y", 0, 100, 0.3, 0.3, 1.0)]
    frame = pd.DataFrame(rows, columns=CURVE_COLUMNS)
    frame.to_csv(tmp_path / "c.csv", index=False)
    summary = curve_summary(read_curves(tmp_path / "c.csv"))
    assert summary["x"] == {"seeds": 2, "timesteps": 1000, "mean": pytest.approx(0.55),
                            "min": pytest.approx(0.5), "max": pytest.approx(0.6)}  # fmt: skip
    assert summary["y"]["seeds"] == 1
    path = plot_curves(tmp_path / "c.csv", tmp_path / "c.png", {"lambdarank": 0.59})
    assert path.stat().st_size > 10_000
    with pytest.raises(ValueError, match="learning-curve"):
        frame.drop(columns="seed").to_csv(tmp_path / "bad.csv", index=False)
        read_curves(tmp_path / "bad.csv")


def test_full_information_curve_learns_the_training_objects(grips, config):
    from classifiers.experiments.selector.curve import full_information_curve

    found = full_information_curve(grips, config, iterations=200, every=100)
    again = full_information_curve(grips, config, iterations=200, every=100)
    assert [row[0] for row in found] == [100, 200] and found == again  # seeded
    train = grips[~grips["object_id"].astype(str).isin(_held_out(grips, config))]
    best = train.groupby("object_id")["success_rate"].max().mean()
    first = train.sort_values("Q_C").groupby("object_id").first()["success_rate"].mean()
    assert first < found[-1][1] <= best + 1e-6  # beats best-Q_C on what it was fitted to


def _held_out(grips, config):
    from grip_env.dataset.split import held_out_objects

    return held_out_objects(grips["object_id"].astype(str), config.learning)[1]
