"""The stronger learners (HistGradientBoosting, lambdarank), their seeds and the per-seed scores."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from classifiers.evaluation.cross_validation import cross_validate_models, grouped_folds
from classifiers.evaluation.ranking import (
    cross_validate_rankers,
)
from classifiers.evaluation.regression import cross_validate_regressors
from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.candidate_scores import (
    SCORE_COLUMNS,
    held_out_candidates,
    learner_scores,
    score_frame,
    training_seeds,
)
from classifiers.experiments.training import train_rankers
from classifiers.learners.models import make_model, make_regressor
from classifiers.learners.persistence import load_model, save_model, saved_models
from classifiers.learners.ranking import GroupedRanker, make_ranker, relevance
from grip_env.columns import FEATURES
from grip_env.config import Config, LearningConfig, SimConfig

CV = LearningConfig(folds=3, repeats=1)


@pytest.fixture(scope="module")
def grips() -> pd.DataFrame:
    return synthetic_grips(n_objects=30, grips=(10, 20), seed=3)


def test_hgb_classifier_beats_random_and_is_seeded(grips):
    per_fold = cross_validate_models(grips, ["hgb", "random"], config=CV)
    auc = per_fold.groupby("model")["roc_auc"].mean()
    assert auc["hgb"] > 0.7 and auc["hgb"] > auc["random"] + 0.15
    first, again, other = (make_model("hgb", seed).fit(grips, grips["success"])
                           for seed in (0, 0, 1))  # fmt: skip
    assert np.array_equal(first.predict_proba(grips), again.predict_proba(grips))
    assert not np.array_equal(first.predict_proba(grips), other.predict_proba(grips))


def test_hgb_regressor_ranks_robustness_better_than_random(grips):
    per_fold = cross_validate_regressors(grips, ["hgb", "random"], config=CV)
    spearman = per_fold.groupby("model")["spearman"].mean()
    assert spearman["hgb"] > 0.4 and spearman["random"] < 0.2


def test_hgb_saves_and_loads_as_a_trusted_skops_file(grips, tmp_path):
    model = make_regressor("hgb", 0).fit(grips, grips["robustness_mean"])
    save_model(model, tmp_path, "regressor_hgb")
    loaded, _ = load_model(tmp_path, "regressor_hgb")
    assert np.allclose(loaded.predict(grips), model.predict(grips))


def test_relevance_counts_the_ramp_levels_reached():
    sim = SimConfig()
    low, ratio = sim.ramp_levels_g[0], sim.ramp_ratio
    table = pd.DataFrame({"robustness_mean": [0.0, low * 0.99, low, low * ratio * 1.001,
                                              low * ratio**4 * 1.001, 128.0]})
    assert relevance(table, sim).tolist() == [0, 0, 1, 2, 5, 25]
    assert relevance(pd.DataFrame({"successes": [0, 3]})).tolist() == [0, 3]


def test_ranker_groups_are_whole_objects_whatever_the_row_order(grips):
    grades = relevance(grips)
    shuffled = np.random.default_rng(0).permutation(len(grips))
    ranker = GroupedRanker(random_state=0).fit(grips, grades)
    mixed = GroupedRanker(random_state=0).fit(grips.iloc[shuffled], grades[shuffled])
    assert ranker.n_groups_ == grips["object_id"].nunique() == mixed.n_groups_
    assert np.allclose(ranker.predict(grips), mixed.predict(grips))
    for train, test in grouped_folds(grips, 3, 0):  # the CV never splits an object's group
        assert not set(grips["object_id"].iloc[train]) & set(grips["object_id"].iloc[test])


def test_ranker_orders_each_objects_grips_better_than_random(grips):
    per_fold = cross_validate_rankers(grips, ["lambdarank", "random"], config=CV)
    within = per_fold.groupby("model")["spearman_object"].mean()
    assert within["lambdarank"] > 0.3 and abs(within["random"]) < 0.15
    assert per_fold.groupby("model")["roc_auc_object"].mean()["lambdarank"] > 0.65


def test_ranker_refuses_bad_grades(grips):
    with pytest.raises(ValueError, match="integers"):
        GroupedRanker().fit(grips, grips["robustness_mean"].to_numpy())
    with pytest.raises(ValueError, match=">= 0"):
        GroupedRanker().fit(grips, -np.ones(len(grips), dtype=int))
    with pytest.raises(ValueError, match="unknown ranker"):
        make_ranker("xgboost")


def test_ranker_seeds_differ_and_repeat(grips):
    grades = relevance(grips)
    scores = [make_ranker("lambdarank", seed).fit(grips, grades).predict(grips)
              for seed in (0, 0, 1)]  # fmt: skip
    assert np.array_equal(scores[0], scores[1]) and not np.array_equal(scores[0], scores[2])


def test_rankers_saved_by_training_load_and_score_as_fitted(grips, tmp_path):
    config = Config().override(learning={"rankers": ("lambdarank", "rank_qc"), "folds": 3,
                                         "repeats": 1})
    train_rankers(grips, tmp_path, config, "sha")
    assert saved_models(tmp_path / "models") == ["ranker_lambdarank", "ranker_rank_qc"]
    assert saved_models(tmp_path) == []  # ranking.json beside them is no model
    fitted = make_ranker("lambdarank", config.learning.seed).fit(grips,
                                                                 relevance(grips, config.sim))
    loaded, info = load_model(tmp_path / "models", "ranker_lambdarank")
    assert info["format"] == "lightgbm_text" and info["columns"] == list(FEATURES)
    np.testing.assert_allclose(loaded.predict(grips), fitted.predict(grips))
    (tmp_path / "models" / "ranker_lambdarank.txt").write_text("not a model")
    with pytest.raises(ValueError, match="not a LightGBM model"):
        load_model(tmp_path / "models", "ranker_lambdarank")


def test_training_seeds():
    assert training_seeds(3, 2) == (3, 4)
    with pytest.raises(ValueError, match="seeds"):
        training_seeds(0, 0)


def test_learner_scores_cover_every_held_out_candidate_and_seed(grips):
    config = Config().override(
        learning={"models": ("hgb", "logreg"), "regressors": ("hgb",),
                  "rankers": ("lambdarank",), "seeds": 2, "seed": 4},
        selector={"max_candidates": 12},
    )  # fmt: skip
    scores = learner_scores(grips, config)
    assert list(scores.columns) == list(SCORE_COLUMNS)
    candidates = held_out_candidates(grips, config)
    assert set(scores["object_id"]) == set(candidates)
    assert set(scores["seed"]) == {4, 5}
    methods = {"classifier_hgb", "classifier_logreg", "regressor_hgb", "ranker_lambdarank"}
    assert set(scores["method"]) == methods
    per = scores.groupby(["method", "seed", "object_id"])["candidate"]
    assert (per.count() == per.max() + 1).all()
    sizes = {oid: len(rows) for oid, rows in candidates.items()}
    assert per.count().groupby("object_id").max().to_dict() == sizes
    wide = scores.pivot_table(index=["object_id", "candidate"], columns=["method", "seed"],
                              values="score")  # fmt: skip
    for method in ("classifier_hgb", "ranker_lambdarank"):  # stochastic: seeds differ
        assert not np.allclose(wide[(method, 4)], wide[(method, 5)])
    assert np.array_equal(wide[("classifier_logreg", 4)], wide[("classifier_logreg", 5)])
    pd.testing.assert_frame_equal(scores, learner_scores(grips, config))  # reproducible


def test_learner_scores_are_the_same_in_two_processes(grips, monkeypatch):
    """The fits spread over two processes (the threshold lowered for this small table) give the
    same table, row for row, as one process; seed-free learners are fitted once."""
    import classifiers.experiments.candidate_scores as module
    import classifiers.learners.parallel as parallel

    config = Config().override(
        learning={"models": ("hgb", "knn", "random"), "regressors": ("ridge",),
                  "rankers": ("rank_qc",), "seeds": 3, "workers": 1},
        selector={"max_candidates": 12},
    )  # fmt: skip
    alone = learner_scores(grips, config)
    monkeypatch.setattr(parallel, "PARALLEL_MIN_GRIPS", 0)
    together = learner_scores(grips, config.override(learning={"workers": 2}))
    pd.testing.assert_frame_equal(alone, together)
    seed_free = {name: module.seed_free(module._maker(make_model, name))
                 for name in ("hgb", "knn", "random", "svm", "logreg")}  # fmt: skip
    assert seed_free == {"hgb": False, "knn": True, "random": False, "svm": False,
                         "logreg": True}
    assert module.seed_free(module._maker(make_regressor, "ridge"))
    assert not module.seed_free(module._maker(make_ranker, "lambdarank"))


def test_score_frame_refuses_nan_or_wrong_length():
    rows = pd.DataFrame({"grip_id": [1, 2]})
    with pytest.raises(ValueError, match="2 candidates"):
        score_frame("a", 0, "m", rows, np.array([0.1, np.nan]))
    with pytest.raises(ValueError, match="2 candidates"):
        score_frame("a", 0, "m", rows, np.array([0.1]))


def test_held_out_family_and_importance_fits_are_the_same_in_two_processes(grips, monkeypatch):
    """The stage's independent fits (held-out split, each family held out, permutation
    importance per fold) give the same numbers spread over two processes as in one."""
    import classifiers.learners.parallel as parallel
    from classifiers.evaluation.cross_validation import family_holdout_metrics, held_out_metrics
    from classifiers.experiments.ablation import importance

    models = {name: make_model(name, 0) for name in ("hgb", "logreg")}
    ids = sorted(grips["object_id"].astype(str).unique())
    families = {oid: "named" if k % 3 else "mesh" for k, oid in enumerate(ids)}

    def run(learning: LearningConfig) -> tuple:
        return (held_out_metrics(grips, learning, models),
                family_holdout_metrics(grips, families, models, learning.workers),
                importance(grips, "hgb", learning, n_repeats=2))  # fmt: skip

    learning = LearningConfig(folds=3, repeats=2, workers=1)
    alone = run(learning)
    monkeypatch.setattr(parallel, "PARALLEL_MIN_GRIPS", 0)
    assert run(learning.model_copy(update={"workers": 2})) == alone
    held_out, by_family, _ = alone
    assert set(held_out["models"]) == {"hgb", "logreg"}
    assert set(by_family["families"]) == {"mesh", "named"}
    assert all(set(f["models"]) == {"hgb", "logreg"} for f in by_family["families"].values())
