"""Feature-ablation study: feature sets, paired differences, JSON shape, CLI-free entry point."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.ablation import REFERENCE, ablation_study, feature_sets, run_ablation
from grip_env.columns import FEATURES
from grip_env.config import Config
from grip_env.dataset import held_out_objects

CONFIG = Config().override(learning={"folds": 3, "repeats": 1})


@pytest.fixture(scope="module")
def grips() -> pd.DataFrame:
    return synthetic_grips(n_objects=24, grips=(10, 25), seed=2)


def test_feature_sets_cover_the_study():
    sets = feature_sets()
    assert sets[REFERENCE] == FEATURES
    assert set(sets["without_hand"]) == {"S1", "S2", "S3", "S4", "G1", "G2"}
    assert set(sets["hand_only"]) == {"C1", "C2", "C3", "C4", "C5", "C6"}
    assert sets["eps_only"] == ("eps",) and sets["twelve_and_eps"][-1] == "eps"
    lofo = [name for name in sets if name.startswith("without_") and name != "without_hand"]
    assert len(lofo) == 12 and all(len(sets[name]) == 11 for name in lofo)


def test_ablation_json_shape_and_paired_differences(grips, tmp_path):
    sets = {REFERENCE: FEATURES, "without_hand": FEATURES[:6], "eps_only": ("eps",)}
    result = ablation_study(grips, CONFIG, model="logreg", sets=sets, importance_repeats=2)
    assert set(result["feature_sets"]) == set(sets)
    reference = result["feature_sets"][REFERENCE]
    assert reference["paired_difference"]["logreg"]["roc_auc"]["mean"] == 0.0
    no_hand = result["feature_sets"]["without_hand"]
    diff = no_hand["paired_difference"]["logreg"]["roc_auc"]["mean"]
    expected = (no_hand["models"]["logreg"]["roc_auc"]["mean"]
                - reference["models"]["logreg"]["roc_auc"]["mean"])  # fmt: skip
    assert diff == pytest.approx(expected)
    assert diff < 0.0  # the synthetic success depends on C1 and C4: dropping hand features hurts
    importance = result["permutation_importance"]
    assert set(importance) == set(FEATURES)
    assert importance["C1"]["mean"] > importance["G2"]["mean"]
    held_out = result["held_out"]
    assert tuple(held_out["split"]["test"]) == held_out_objects(grips["object_id"],
                                                                CONFIG.learning)[1]
    assert set(held_out["models"]) == set(sets)
    assert 0.0 <= held_out["models"][REFERENCE]["roc_auc"] <= 1.0
    json.dumps(result)  # JSON-able


def test_ablation_reports_the_regression_task_on_the_same_sets(grips):
    sets = {REFERENCE: FEATURES, "without_hand": FEATURES[:6], "hand_only": FEATURES[6:]}
    result = ablation_study(grips, CONFIG, model="logreg", sets=sets, importance_repeats=1,
                            regressor="ridge")  # fmt: skip
    regression = result["regression"]
    assert regression["model"] == "ridge" and set(regression["feature_sets"]) == set(sets)
    reference = regression["feature_sets"][REFERENCE]["models"]["ridge"]["spearman"]["mean"]
    no_hand = regression["feature_sets"]["without_hand"]
    diff = no_hand["paired_difference"]["ridge"]["spearman"]
    assert diff["mean"] == pytest.approx(no_hand["models"]["ridge"]["spearman"]["mean"] - reference)
    # the synthetic robustness follows C1 and C4: without the hand features the ranking is worse
    assert diff["mean"] < 0 and diff["ci"][1] < 0
    assert "regression" not in ablation_study(
        grips.drop(columns="robustness_mean"), CONFIG, model="logreg",
        sets={REFERENCE: FEATURES}, importance_repeats=1,
    )  # fmt: skip


def test_ablation_runs_the_other_learners_on_the_named_sets(grips):
    sets = {REFERENCE: FEATURES, "without_hand": FEATURES[:6], "without_C1": FEATURES[1:]}
    learners = ablation_study(grips, CONFIG, model="logreg", sets=sets, importance_repeats=1,
                              regressor="ridge")["learners"]  # fmt: skip
    assert set(learners) == {"classifier_hgb", "classifier_svm", "regressor_hgb",
                             "ranker_lambdarank"}
    for key, metric in (("classifier_hgb", "roc_auc"), ("classifier_svm", "roc_auc"),
                        ("regressor_hgb", "spearman_object"),
                        ("ranker_lambdarank", "spearman_object")):
        name = key.split("_", 1)[1]
        found = learners[key]["feature_sets"]
        assert set(found) == {REFERENCE, "without_hand"}  # leave-one-feature-out sets skipped
        assert found[REFERENCE]["paired_difference"][name][metric]["mean"] == 0.0
        # the synthetic outcome follows C1 and C4: every strong learner loses without the hand
        assert found["without_hand"]["paired_difference"][name][metric]["mean"] < 0


def test_ablation_runs_the_configured_model_and_not_twice(grips):
    """The default model is ``learning.ablation_model``; it is not repeated among the learners."""
    sets = {REFERENCE: FEATURES, "without_hand": FEATURES[:6]}
    config = CONFIG.override(learning={"ablation_model": "svm"})
    result = ablation_study(grips, config, sets=sets, importance_repeats=1, regressor="ridge")
    assert result["model"] == "svm"
    assert set(result["feature_sets"][REFERENCE]["models"]) == {"svm"}
    assert set(result["learners"]) == {"classifier_hgb", "regressor_hgb", "ranker_lambdarank"}


@pytest.mark.slow
def test_run_ablation_writes_json_and_chart(grips, tmp_path):
    result = run_ablation(grips, tmp_path, CONFIG.override(learning={"folds": 2}), model="logreg")
    saved = json.loads((tmp_path / "ablation.json").read_text())
    assert saved["reference"] == REFERENCE and len(saved["feature_sets"]) == 18
    assert saved["feature_sets"].keys() == result["feature_sets"].keys()
    assert (tmp_path / "ablation.png").stat().st_size > 1000
    assert len(saved["regression"]["feature_sets"]) == 18
    assert (tmp_path / "ablation_regression.png").stat().st_size > 1000


def test_ablation_rejects_bad_input(grips):
    with pytest.raises(ValueError, match="reference"):
        ablation_study(grips, CONFIG, sets={"x": FEATURES})
    with pytest.raises(ValueError, match="unknown model name"):
        ablation_study(grips, CONFIG, model="forest", sets={REFERENCE: FEATURES})
    with pytest.raises(ValueError, match="one class"):
        ablation_study(grips.assign(success=False), CONFIG)
