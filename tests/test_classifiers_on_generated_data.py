"""Every model on a dataset generated for real: fits, predicts, ranks and reloads."""

from __future__ import annotations

import numpy as np
import pytest

from classifiers.learners.models import MODEL_NAMES, make_model
from classifiers.learners.persistence import load_model, save_model
from grip_env.envs import split_objects


@pytest.fixture(scope="module")
def split(generated_grips):
    train_ids, test_ids = split_objects(generated_grips["object_id"].unique(), 0.25, seed=0)
    train = generated_grips[generated_grips["object_id"].isin(train_ids)]
    test = generated_grips[generated_grips["object_id"].isin(test_ids)]
    return train, test


def test_generated_dataset_has_both_outcomes(generated_grips):
    assert generated_grips["object_id"].nunique() >= 6
    assert 0 < generated_grips["success"].mean() < 1
    assert set(split_objects(generated_grips["object_id"].unique(), 0.25, 0)[1])


@pytest.mark.slow
@pytest.mark.parametrize("name", MODEL_NAMES)
def test_every_model_fits_predicts_and_reloads(split, tmp_path, name):
    train, test = split
    assert not set(train["object_id"]) & set(test["object_id"])
    model = make_model(name, seed=0).fit(train, train["success"])
    proba = model.predict_proba(test)
    assert proba.shape == (len(test), 2)
    assert np.all((proba >= 0) & (proba <= 1))
    np.testing.assert_allclose(proba.sum(axis=1), 1.0)
    save_model(model, tmp_path, name, {"dataset_sha256": "x"})
    loaded, _ = load_model(tmp_path, name)
    np.testing.assert_array_equal(loaded.predict_proba(test), proba)


def test_rank_baseline_orders_by_q_c_on_real_rows(split):
    train, test = split
    model = make_model("rank_qc").fit(train, train["success"])
    score = model.predict_proba(test)[:, 1]
    lowest = test["Q_C"].to_numpy().argmin()
    assert score[lowest] == score.max()


@pytest.mark.slow
def test_ablate_cli_on_a_generated_dataset(generated_dataset_dir, tmp_path):
    import json

    from typer.testing import CliRunner

    from grip_env.cli import _register_commands, app

    _register_commands()
    config = tmp_path / "c.yaml"
    config.write_text("learning:\n  folds: 2\n  repeats: 1\n")
    out = tmp_path / "ablation"
    args = ["ablate", "--data", str(generated_dataset_dir), "--out", str(out),
            "--config", str(config), "--model", "logreg"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    ablation = json.loads((out / "ablation.json").read_text())
    assert {"all_twelve", "without_hand", "hand_only"} <= set(ablation["feature_sets"])
    assert (out / "ablation.png").exists()
    bad = CliRunner().invoke(app, [*args[:-1], "nosuch"])
    assert bad.exit_code == 2 and "nosuch" in bad.output
