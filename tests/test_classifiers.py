"""Classifier registry, baselines, grouped evaluation, persistence and bad input."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from classifiers.evaluation.cross_validation import (
    cross_validate_models,
    evaluate_models,
    grouped_folds,
    top1,
)
from classifiers.evaluation.regression import evaluate_regressors, regression_fold_metrics, spearman
from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.learners.models import MODEL_NAMES, REGRESSOR_NAMES, make_model, make_regressor
from classifiers.learners.persistence import load_model, save_model
from classifiers.learners.torch_mlp import TorchMLPClassifier, TorchMLPRegressor
from grip_env.config import LearningConfig

FAST = {"mlp_torch": {"model__max_epochs": 30}, "mlp_sklearn": {"model__max_iter": 60}}


@pytest.fixture(scope="module")
def synthetic_grips_table() -> pd.DataFrame:
    """30 objects with 10–40 grips each; success logistic in C1, C4, S3, S2 plus noise."""
    return synthetic_grips(n_objects=30, seed=0)


def fast_model(name: str, seed: int = 0):
    return make_model(name, seed).set_params(**FAST.get(name, {}))


@pytest.mark.parametrize("estimator", [TorchMLPClassifier, TorchMLPRegressor])
@pytest.mark.parametrize(("name", "value"), [("max_epochs", 0), ("learning_rate", 0.0),
                                             ("dropout", 1.0), ("batch_size", 0),
                                             ("validation_fraction", 1.0), ("patience", 0),
                                             ("random_state", -1),
                                             ("hidden_layer_sizes", (8, 0))])  # fmt: skip
def test_torch_mlp_refuses_a_bad_parameter_in_fit(estimator, name, value):
    X = np.random.default_rng(0).random((20, 3))
    y = X[:, 0] > 0.5
    # constructing checks nothing (sklearn convention)
    model = estimator(**{"hidden_layer_sizes": (4,), name: value})
    with pytest.raises(ValueError, match=f"'{name}' parameter of {estimator.__name__}"):
        model.fit(X, y)


def test_torch_mlp_parameters_after_the_first_are_keyword_only():
    import inspect

    parameters = list(inspect.signature(TorchMLPClassifier).parameters.values())
    assert parameters[0].kind is inspect.Parameter.POSITIONAL_OR_KEYWORD
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in parameters[1:])
    assert {"hidden_layer_sizes", *TorchMLPClassifier._parameter_ranges} == {
        p.name for p in parameters}
    for attribute in ("classes_", "network_", "n_epochs_", "n_features_in_",
                      "best_validation_loss_"):
        assert f"{attribute} :" in TorchMLPClassifier.__doc__


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_every_model_fits_and_predicts(synthetic_grips_table, name):
    table = synthetic_grips_table
    model = fast_model(name).fit(table, table["success"])
    proba = model.predict_proba(table)
    assert proba.shape == (len(table), 2)
    assert np.allclose(proba.sum(axis=1), 1.0) and np.all((proba >= 0) & (proba <= 1))
    assert set(np.unique(model.predict(table))) <= {False, True}


def test_grouped_folds_never_share_an_object(synthetic_grips_table):
    table = synthetic_grips_table
    groups = table["object_id"].to_numpy()
    seen = []
    for train, test in grouped_folds(table, folds=4, seed=1):
        assert not set(groups[train]) & set(groups[test])
        seen.append(test)
    assert np.array_equal(np.sort(np.concatenate(seen)), np.arange(len(table)))


def test_a_fold_with_one_training_class_is_left_out_for_every_model():
    """Only one object fails: the fold that tests it trains on successes alone, and gives no
    row instead of a crash inside the solver."""
    table = synthetic_grips(n_objects=6, grips=(8, 12), seed=1)
    first = table["object_id"] == table["object_id"].iloc[0]
    table = table.assign(success=~first)
    config = LearningConfig(folds=3, repeats=2)
    per_fold = cross_validate_models(table, ["logreg", "random"], config=config)
    assert len(per_fold) == 2 * (3 - 1) * 2  # one fold a repeat left out, two models
    assert set(per_fold.groupby(["repeat", "fold"]).size()) == {2}


def test_cross_validation_gives_the_same_rows_on_any_number_of_workers(monkeypatch):
    import classifiers.learners.parallel as parallel

    table = synthetic_grips(n_objects=12, grips=(8, 12), seed=2)
    config = LearningConfig(folds=3, repeats=2, workers=1)
    alone = cross_validate_models(table, ["logreg", "hgb", "random"], config=config)
    monkeypatch.setattr(parallel, "PARALLEL_MIN_GRIPS", 0)  # spread even this small table
    spread = cross_validate_models(table, ["logreg", "hgb", "random"],
                                   config=config.model_copy(update={"workers": 2}))
    pd.testing.assert_frame_equal(alone, spread)
    assert len(alone) == 3 * 3 * 2


def test_rank_baselines_are_computed_from_the_columns(synthetic_grips_table):
    table = synthetic_grips_table
    for name, column in (("rank_qc", "Q_C"), ("rank_qg", "Q_G")):
        model = make_model(name).fit(table, table["success"])
        score = model.decision_function(table)
        np.testing.assert_allclose(score, -table[column].to_numpy())
        for _, grips in table.groupby("object_id"):
            assert np.argmax(model.decision_function(grips)) == np.argmin(grips[column].to_numpy())
        positive = model.predict_proba(table)[:, 1]
        order = np.argsort(table[column].to_numpy())
        assert np.all(np.diff(positive[order]) <= 1e-12)  # monotone: lower index, higher p


def test_random_baseline_is_seeded(synthetic_grips_table):
    table = synthetic_grips_table
    a = make_model("random", seed=3).fit(table, table["success"]).decision_function(table)
    b = make_model("random", seed=3).fit(table, table["success"]).decision_function(table)
    c = make_model("random", seed=4).fit(table, table["success"]).decision_function(table)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_top1_picks_the_highest_score_per_object():
    test = pd.DataFrame({"object_id": [0, 0, 1, 1], "success": [False, True, True, False],
                         "success_rate": [0.2, 0.8, 0.6, 0.0]})  # fmt: skip
    assert top1(test, np.array([0.1, 0.9, 0.7, 0.2])) == (1.0, pytest.approx(0.7))
    assert top1(test, np.array([0.9, 0.1, 0.2, 0.7])) == (0.0, pytest.approx(0.1))


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_saved_models_reload_and_predict_the_same(synthetic_grips_table, tmp_path, name):
    table = synthetic_grips_table
    model = fast_model(name).fit(table, table["success"])
    save_model(model, tmp_path, name, {"dataset_sha256": "abc"})
    loaded, info = load_model(tmp_path, name)
    np.testing.assert_array_equal(loaded.predict_proba(table), model.predict_proba(table))
    assert info["dataset_sha256"] == "abc" and info["name"] == name
    assert not list(tmp_path.glob("*.pkl"))


@pytest.mark.parametrize("name", ["rank_qc", "hgb"])
def test_a_model_saved_before_the_learners_moved_still_loads(synthetic_grips_table, tmp_path,
                                                            name):
    """Files written when the trusted types lived in classifiers.baselines / .threads."""
    import zipfile

    table = synthetic_grips_table
    model = fast_model(name).fit(table, table["success"])
    save_model(model, tmp_path, name)
    path = tmp_path / f"{name}.skops"
    with zipfile.ZipFile(path) as old:
        members = {item: old.read(item) for item in old.namelist()}
    schema = members["schema.json"].decode()
    assert "classifiers.learners." in schema
    members["schema.json"] = schema.replace("classifiers.learners.", "classifiers.").encode()
    with zipfile.ZipFile(path, "w") as rewritten:
        for item, data in members.items():
            rewritten.writestr(item, data)
    loaded, _ = load_model(tmp_path, name)
    np.testing.assert_array_equal(loaded.predict_proba(table), model.predict_proba(table))


def test_learned_models_beat_random_on_learnable_data(synthetic_grips_table):
    config = LearningConfig(folds=3, repeats=1, seed=0)
    models = {name: fast_model(name) for name in ("logreg", "mlp_torch", "random")}
    result = evaluate_models(synthetic_grips_table, models, config=config)
    auc = {name: result["models"][name]["roc_auc"]["mean"] for name in models}
    assert auc["random"] < 0.6
    assert auc["logreg"] > auc["random"] + 0.15 and auc["mlp_torch"] > auc["random"] + 0.15
    top = result["models"]["logreg"]["top1_success"]
    assert top["ci"][0] <= top["mean"] <= top["ci"][1]
    assert result["cv"]["folds"] == 3 and result["cv"]["seeds"] == [0]


def test_metrics_json_shape(synthetic_grips_table):
    config = LearningConfig(folds=2, repeats=2, seed=5)
    result = evaluate_models(synthetic_grips_table, ["rank_qc"], config=config)
    summary = result["models"]["rank_qc"]
    for metric in ("accuracy", "balanced_accuracy", "roc_auc", "f1", "brier", "top1_success"):
        assert set(summary[metric]) >= {"mean", "ci"} and len(summary[metric]["ci"]) == 2
        assert summary[metric]["n"] == 4
    assert result["cv"]["seeds"] == [5, 6] and result["cv"]["groups"] == "object_id"


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda t: t.drop(columns=["success", "successes", "success_rate"]), "lacks the columns"),
        (lambda t: t.assign(success=True), "one class"),
        (lambda t: t[t["object_id"] < 2], "fewer than"),
    ],
)
def test_bad_datasets_raise_value_error(synthetic_grips_table, mutate, message):
    with pytest.raises(ValueError, match=message):
        evaluate_models(mutate(synthetic_grips_table), ["rank_qc"], config=LearningConfig(folds=3))


def test_unknown_names_raise_value_error(synthetic_grips_table):
    with pytest.raises(ValueError, match="unknown model name 'forest'"):
        make_model("forest")
    with pytest.raises(ValueError, match="unknown feature names"):
        make_model("svm", features=("S1", "Z9"))
    with pytest.raises(ValueError, match="unknown feature names"):
        evaluate_models(synthetic_grips_table, ["svm"], features=["C7"])
    with pytest.raises(ValueError, match="DataFrame"):
        make_model("logreg").fit(np.zeros((4, 12)), [0, 1, 0, 1])


@pytest.mark.slow
def test_train_cli_writes_metrics_models_and_plots(synthetic_grips_table, tmp_path, monkeypatch):
    import json

    import yaml
    from typer.testing import CliRunner

    import grip_env.dataset
    from grip_env.cli import _register_commands, app

    monkeypatch.setattr(grip_env.dataset, "load", lambda path: synthetic_grips_table)
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump({"learning": {"folds": 2, "repeats": 1,
                                                   "regressors": ["ridge", "rank_qc"]}}))
    _register_commands()
    out = tmp_path / "out"
    args = ["train", "--data", str(tmp_path), "--out", str(out), "--config", str(config),
            "--models", "logreg,rank_qc,mlp_torch"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "metrics.json").read_text())
    assert set(metrics["models"]) == {"logreg", "rank_qc", "mlp_torch"}
    assert len(metrics["dataset"]["sha256"]) == 64
    assert (out / "roc.png").is_file() and (out / "calibration.png").is_file()
    assert {p.name for p in (out / "models").iterdir()} >= {"logreg.skops", "mlp_torch.pt"}
    loaded, info = load_model(out / "models", "mlp_torch")
    assert info["features"] == list(loaded[0].columns) and info["dataset_sha256"]
    regression = json.loads((out / "regression.json").read_text())
    assert set(regression["models"]) == {"ridge", "rank_qc"}
    assert set(regression["paired_difference"]["ridge"]) == {"vs_rank_qc"}
    assert (out / "models" / "regressor_ridge.skops").is_file()
    bad = CliRunner().invoke(app, [*args[:-1], "forest"])
    assert bad.exit_code == 2 and "unknown model" in bad.output and "forest" in bad.output


# ------------------------------------------------------------------------ regression task
FAST_REGRESSORS = {"mlp_torch": {"model__max_epochs": 30}}


def fast_regressor(name: str, seed: int = 0):
    return make_regressor(name, seed).set_params(**FAST_REGRESSORS.get(name, {}))


@pytest.mark.parametrize("name", REGRESSOR_NAMES)
def test_every_regressor_fits_predicts_and_reloads(synthetic_grips_table, tmp_path, name):
    table = synthetic_grips_table
    model = fast_regressor(name).fit(table, table["robustness_mean"])
    predicted = model.predict(table)
    assert predicted.shape == (len(table),) and np.isfinite(predicted).all()
    save_model(model, tmp_path, f"regressor_{name}")
    loaded, _ = load_model(tmp_path, f"regressor_{name}")
    np.testing.assert_allclose(loaded.predict(table), predicted, rtol=1e-6)


def test_rank_regressors_order_rows_exactly_as_their_column(synthetic_grips_table):
    table = synthetic_grips_table
    for name, column in (("rank_qc", "Q_C"), ("rank_qg", "Q_G")):
        predicted = make_regressor(name).fit(table, table["robustness_mean"]).predict(table)
        assert spearman(predicted, -table[column].to_numpy()) == pytest.approx(1.0)
    # even when the target rises with Q_C, the baseline keeps Q_C's order (it is not learned)
    flipped = make_regressor("rank_qc").fit(table, table["Q_C"]).predict(table)
    assert spearman(flipped, -table["Q_C"].to_numpy()) == pytest.approx(1.0)


def test_regression_metrics_on_a_known_fold():
    test = pd.DataFrame({"object_id": [0, 0, 0, 1, 1, 1], "robustness_mean": [1, 2, 3, 3, 2, 1.0],
                         "x": [1, 2, 3, 1, 2, 3.0]})  # fmt: skip

    class Column:
        def predict(self, frame):
            return frame["x"].to_numpy()

    metrics = regression_fold_metrics(Column(), test)
    assert metrics["spearman_object"] == pytest.approx(0.0)  # +1 on object 0, -1 on object 1
    assert metrics["spearman"] == pytest.approx(0.0)
    assert metrics["top1_robustness"] == pytest.approx((3 + 1) / 2)
    assert metrics["mae"] == pytest.approx(np.mean([0, 0, 0, 2, 0, 2]))


def test_learned_regressors_beat_random_and_the_rank_baselines_are_paired(synthetic_grips_table):
    config = LearningConfig(folds=3, repeats=1, seed=0)
    models = {name: fast_regressor(name) for name in ("svr", "mlp_torch", "rank_qc", "rank_qg",
                                                      "random")}  # fmt: skip
    result = evaluate_regressors(synthetic_grips_table, models, config=config)
    rho = {name: result["models"][name]["spearman"] for name in models}
    assert abs(rho["random"]["mean"]) < 0.1 and rho["random"]["ci"][0] < 0 < rho["random"]["ci"][1]
    assert rho["svr"]["mean"] > 0.5 and rho["mlp_torch"]["mean"] > 0.5
    assert result["models"]["svr"]["spearman_object"]["n"] == 3
    paired = result["paired_difference"]["svr"]
    assert set(paired) == {"vs_rank_qc", "vs_rank_qg"}
    direct = rho["svr"]["mean"] - rho["rank_qc"]["mean"]
    assert paired["vs_rank_qc"]["spearman"]["mean"] == pytest.approx(direct)
    assert set(result["paired_difference"]["rank_qc"]) == {"vs_rank_qg"}


def test_regression_needs_the_graded_outcome(synthetic_grips_table):
    with pytest.raises(ValueError, match="robustness_mean"):
        evaluate_regressors(synthetic_grips_table.drop(columns="robustness_mean"), ["ridge"],
                            config=LearningConfig(folds=3))  # fmt: skip
    with pytest.raises(ValueError, match="unknown regressor name 'forest'"):
        make_regressor("forest")


def test_study_stage_keys_follow_only_what_each_stage_depends_on():
    from classifiers.experiments.study import stage_key
    from grip_env.config import Config

    base = Config()
    reseeded = base.override(learning={"seed": 7})
    lighter = base.override(objects={"density_kg_m3": 250.0})
    for name in ("classifiers", "ablation", "selector"):
        assert stage_key(name, base, "d") != stage_key(name, reseeded, "d")
        assert stage_key(name, base, "d") != stage_key(name, base, "other dataset")
    assert stage_key("calibration", base, "d") == stage_key("calibration", reseeded, "d")
    assert stage_key("calibration", base, "d") != stage_key("calibration", lighter, "d")
    assert stage_key("classifiers", base, "d") == stage_key("classifiers", lighter, "d")
    more_steps = base.override(selector={"timesteps": 5})
    assert stage_key("selector", base, "d") != stage_key("selector", more_steps, "d")
    assert stage_key("ablation", base, "d") == stage_key("ablation", more_steps, "d")


def test_a_model_that_cannot_learn_from_a_tiny_fold_is_named_not_a_crash():
    from classifiers.evaluation.cross_validation import fit_fold
    from classifiers.learners.models import make_model
    from grip_env.columns import FEATURES

    rng = np.random.default_rng(0)
    fold = pd.DataFrame(rng.random((6, len(FEATURES))), columns=list(FEATURES)).assign(
        object_id=["a", "a", "b", "b", "c", "c"])
    labels = np.array([True, False, True, False, True, False])
    with pytest.raises(ValueError, match=r"model 'mlp_sklearn' cannot be fitted on a training "
                                         r"fold of 6 grips on 3 objects .*leave 'mlp_sklearn' out"):
        fit_fold("mlp_sklearn", make_model("mlp_sklearn"), fold, labels)
