"""The study's answers: paired differences reproduced from the leaderboard's own bootstrap,
worded by the leaderboard's verdict rule, drawn in figures, and published beside the README with
a stamp of their run."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from PIL import Image

from classifiers.evaluation.verdicts import relation
from classifiers.experiments.answers import pick_differences, study_answers
from classifiers.experiments.benchmark.leaderboard import build_leaderboard
from classifiers.report.answers import answer_sentences


def _board(seed: int = 3, extra: dict | None = None) -> dict:
    """A leaderboard of 30 held-out objects (4 degenerate): lambdarank picks about 0.1 better than
    best-Q_C on every object, best-Q_G 0.05 better with noise, the RL selector as best-Q_C with
    noise, random 0.15 worse."""
    rng = np.random.default_rng(seed)
    base = rng.uniform(0.2, 0.6, 30)
    plain = dict.fromkeys(("robustness", "regret", "robustness_regret", "ndcg5", "attempts",
                           *(f"success_at_{k}" for k in range(1, 6))), 0.5)  # fmt: skip
    shifts = {"best_qc": (0.0, 0.0, 1), "best_qg": (0.05, 0.05, 1), "random": (-0.15, 0.0, 1),
              "oracle": (0.3, 0.0, 1), "ranker_lambdarank": (0.1, 0.05, 2),
              "classifier_knn": (0.0, 0.1, 2), "rl": (0.0, 0.1, 2), **(extra or {})}
    rows = []
    for method, (shift, noise, runs) in shifts.items():
        for run in range(runs):
            for i in range(30):
                success = base[i] + shift + noise * rng.normal()
                rows.append({"method": method, "seed": run, "object_id": f"o{i:02d}",
                             "normalised": np.nan if i < 4 else success - base[i], **plain,
                             "success": success})  # fmt: skip
    metrics = pd.DataFrame(rows)
    board = build_leaderboard(metrics, {"name": "t", "version": 0}, reps=400, seed=seed)
    board["per_object"] = metrics.round(6).to_dict(orient="records")
    return board


def test_the_verdict_rule_is_one_function_the_leaderboard_uses():
    assert relation((0.001, 0.07)) == "beats"
    assert relation((-0.07, -0.01)) == "is worse than"
    assert relation((-0.01, 0.07)) == relation((0.0, 0.07)) == "is not distinguishable from"
    board = _board()
    for name, row in board["methods"].items():
        if name != "best_qc":
            found = relation(row["difference_vs_reference"]["ci"]).removeprefix("is ")
            assert row["verdict"] == f"{found} best_qc"


def test_pick_differences_are_the_leaderboards_own_resamples():
    """Against best-Q_C the answers equal the board's success difference (same objects, same
    resamples); between two other methods the difference is paired too."""
    board = _board()
    found = pick_differences(board, [("rl", "best_qc"), ("best_qg", "best_qc"),
                                     ("ranker_lambdarank", "best_qg")], seed=3, reps=400)
    for name in ("rl", "best_qg"):
        expected = board["methods"][name]["success_difference_vs_reference"]
        assert found[f"{name} - best_qc"]["estimate"] == pytest.approx(expected["estimate"],
                                                                       abs=1e-6)
        assert found[f"{name} - best_qc"]["ci"] == pytest.approx(expected["ci"], abs=1e-6)
    between = found["ranker_lambdarank - best_qg"]
    assert between["estimate"] == pytest.approx(0.05, abs=0.03) and between["objects"] == 30
    with pytest.raises(ValueError, match="no method 'svm'"):
        pick_differences(board, [("svm", "best_qc")], seed=3)


def test_the_answers_are_worded_from_their_intervals(tmp_path):
    board = _board()
    (tmp_path / "benchmark").mkdir()
    (tmp_path / "benchmark" / "leaderboard.json").write_text(json.dumps(board))
    (tmp_path / "ablation").mkdir()
    (tmp_path / "ablation" / "ablation.json").write_text(json.dumps({
        "model": "hgb", "cv": {"n_objects": 40}, "feature_sets": {"without_hand": {
            "paired_difference": {"hgb": {"roc_auc": {"mean": -0.09, "ci": [-0.12, -0.07]}}}}}}))
    answers = study_answers(tmp_path, seed=3)
    assert answers["best_supervised"] == "ranker_lambdarank"
    learned, hand, rl, image = answer_sentences(answers)
    assert image.endswith("Not answered: the image stage did not run.")
    picks = answers["picks"]
    lambdarank = picks["ranker_lambdarank - best_qc"]
    assert lambdarank["ci"][0] > 0  # 0.1 better on every object, give or take 0.05
    assert (f"**beats** best-Q_C (+{lambdarank['estimate']:.3f} [+{lambdarank['ci'][0]:.3f}, "
            in learned)
    assert "without them **is worse than** itself with all twelve measures (ROC-AUC -0.090 " \
           "[-0.120, -0.070])" in hand
    worse = picks["rl - ranker_lambdarank"]
    assert worse["ci"][1] < 0 and "**is worse than** `ranker_lambdarank`" in rl
    assert f"best-Q_C ({picks['rl - best_qc']['estimate']:+.3f}" in rl
    assert relation(picks["rl - best_qc"]["ci"]) in rl

    few = {**answers, "ranked_objects": 6}
    assert "no verdict (only 6 held-out object(s) could be ranked" in answer_sentences(few)[0]
    no_rl = {**answers, "picks": {k: v for k, v in picks.items() if not k.startswith("rl")}}
    assert answer_sentences(no_rl)[2].endswith("Not answered: no RL selector was scored.")
    flat = {**answers, "hand_measures": {"model": "hgb", "mean": 0.0, "ci": [0.0, 0.0],
                                         "objects": 40}}
    assert "changes ROC-AUC by +0.000 [+0.000, +0.000], no verdict (its interval has zero " \
           "width" in answer_sentences(flat)[1]


def test_the_image_answer_is_worded_from_the_image_stage(tmp_path):
    """cnn_measures picks 0.2 better than best-Q_C on every object (lambdarank 0.1), and its
    ROC-AUC interval lies above the measures' learner's: the measures miss something."""
    board = _board(extra={"classifier_cnn_measures": (0.2, 0.05, 2),
                          "classifier_cnn": (0.1, 0.1, 2)})
    (tmp_path / "benchmark").mkdir()
    (tmp_path / "benchmark" / "leaderboard.json").write_text(json.dumps(board))
    (tmp_path / "images").mkdir()
    families = {f"o{i:02d}": "mesh" if i < 12 else "procedural" for i in range(30)}
    (tmp_path / "images" / "images.json").write_text(json.dumps({
        "models": ["cnn", "cnn_measures"], "families": families,
        "cv": {"reference": "hgb", "n_objects": 40, "paired_difference": {
            "cnn": {"roc_auc": {"mean": -0.01, "ci": [-0.04, 0.02]}},
            "cnn_measures": {"roc_auc": {"mean": 0.05, "ci": [0.03, 0.07]}}}}}))
    answers = study_answers(tmp_path, seed=3)
    image = answers["image"]
    assert set(image["picks"]) == {f"classifier_{m} - {v}" for m in ("cnn", "cnn_measures")
                                   for v in ("ranker_lambdarank", "best_qc")}
    versus = image["picks"]["classifier_cnn_measures - ranker_lambdarank"]
    assert versus["estimate"] == pytest.approx(0.1, abs=0.03) and versus["objects"] == 30
    assert {f: rows["classifier_cnn_measures - best_qc"]["objects"]
            for f, rows in image["families"].items()} == {"mesh": 12, "procedural": 18}
    sentence = answer_sentences(answers)[3]
    assert "No: they miss something worth +0.050 ROC-AUC: the image with the measures " \
           "(`cnn_measures`) **beats** `hgb` on the twelve measures (+0.050 [+0.030, +0.070])" \
           in sentence
    assert "the image alone (`cnn`) **is not distinguishable from** it (-0.010 [-0.040, " \
           "+0.020])" in sentence
    # no picks of hgb on this board: the carry-over is judged against lambdarank's
    assert "; and the gain carries over to picking: `cnn_measures` **beats** `lambdarank`" \
        in sentence
    wide = {**image, "auc": {**image["auc"], "cnn_measures": {"mean": 0.08, "ci": [-0.19, 0.36],
                                                                "objects": 40}}}
    assert "Not answered: the image with the measures (`cnn_measures`) against `hgb` on the " \
           "twelve measures changes ROC-AUC by +0.080 [-0.190, +0.360], an interval that " \
           "allows the image a gain of up to +0.360" in answer_sentences({**answers,
                                                                          "image": wide})[3]
    same = {**image, "auc": {**image["auc"], "cnn_measures": {"mean": 0.0, "ci": [-0.02, 0.02],
                                                                "objects": 40}}}
    assert "Yes, as far as this network can tell: the image with the measures (`cnn_measures`) " \
           "**is not distinguishable from** `hgb`" in answer_sentences({**answers,
                                                                          "image": same})[3]


def _image_study(tmp_path, extra: dict) -> dict:
    board = _board(extra=extra)
    (tmp_path / "benchmark").mkdir()
    (tmp_path / "benchmark" / "leaderboard.json").write_text(json.dumps(board))
    (tmp_path / "images").mkdir()
    (tmp_path / "images" / "images.json").write_text(json.dumps({
        "models": ["cnn_measures"], "families": {},
        "cv": {"reference": "hgb", "n_objects": 40, "paired_difference": {
            "cnn_measures": {"roc_auc": {"mean": 0.05, "ci": [0.03, 0.07]}}}}}))
    return study_answers(tmp_path, seed=3)


def test_the_image_answer_says_in_one_sentence_when_the_auc_gain_does_not_carry_to_picking(
        tmp_path):  # fmt: skip
    """cnn_measures gains ROC-AUC over hgb but picks 0.1 worse than hgb's picks on every object:
    the one sentence says the gain does not carry over, with the picking figures it rests on."""
    from classifiers.report.answers import signed

    answers = _image_study(tmp_path, {"classifier_hgb": (0.1, 0.02, 2),
                                      "classifier_cnn_measures": (0.0, 0.02, 2)})
    picks = answers["image"]["picks"]
    versus_hgb = picks["classifier_cnn_measures - classifier_hgb"]
    assert versus_hgb["estimate"] == pytest.approx(-0.1, abs=0.02) and versus_hgb["ci"][1] < 0
    sentence = answer_sentences(answers)[3]
    assert sentence.count(". ") == 0 and sentence.endswith(").")  # one sentence
    assert ("**beats** `hgb` on the twelve measures (+0.050 [+0.030, +0.070]); but the gain "
            "does not carry over to picking: `cnn_measures` **is worse than** `hgb` "
            f"({signed(versus_hgb)}), ") in sentence
    lambdarank = picks["classifier_cnn_measures - ranker_lambdarank"]
    assert f"`lambdarank` ({signed(lambdarank)}) and " in sentence
    # without a ROC-AUC gain there is nothing to carry over: the picks alone
    flat = {**answers["image"], "auc": {"cnn_measures": {"mean": 0.0, "ci": [-0.02, 0.02],
                                                         "objects": 40}}}
    worded = answer_sentences({**answers, "image": flat})[3]
    assert "carry" not in worded
    assert "; at picking, `cnn_measures` **is worse than** `hgb`" in worded
    # a picking interval without a verdict (too few ranked objects) claims neither way
    few = answer_sentences({**answers, "ranked_objects": 3})[3]
    assert "carry" not in few and "no verdict (only 3 held-out object(s)" in few


def test_every_answer_figure_is_drawn_from_the_results(tmp_path):
    from classifiers.report.answer_figures import ALT_TEXT, draw_answer_figures

    board = _board()
    (tmp_path / "benchmark").mkdir()
    (tmp_path / "benchmark" / "leaderboard.json").write_text(json.dumps(board))
    (tmp_path / "ablation").mkdir()
    sets = {name: {"paired_difference": {"hgb": {"roc_auc": {"mean": m, "ci": [m - 0.02,
                                                                                m + 0.02]}}}}
            for name, m in (("all_twelve", 0.0), ("without_hand", -0.09), ("hand_only", 0.01))}
    (tmp_path / "ablation" / "ablation.json").write_text(json.dumps(
        {"model": "hgb", "reference": "all_twelve", "feature_sets": sets}))
    (tmp_path / "calibration").mkdir()
    per_object = [{"object_id": f"o{i}", "spearman": s} for i, s in enumerate((0.5, None, 0.9))]
    (tmp_path / "calibration" / "calibration.json").write_text(json.dumps({"checks": {
        "within_object": {"measured": 0.7, "ci": [0.5, 0.9], "trials_per_set": 5,
                          "per_object": per_object}}}))
    drawn = draw_answer_figures(tmp_path, ["ranker_lambdarank", "rl"], tmp_path / "figures")
    assert list(drawn) == list(ALT_TEXT)
    for path in drawn.values():
        with Image.open(path) as image:
            assert image.size[0] >= 1000  # readable at the docs' width
    assert draw_answer_figures(tmp_path / "nothing", [], tmp_path / "none") == {}


def test_the_forest_plot_sorts_its_rows_and_marks_each_by_its_verdict():
    from classifiers.report.answer_figures import VERDICT_STYLE, _interval_rows

    rows = {"a": {"estimate": 0.05, "ci": [0.01, 0.09]}, "b": {"estimate": -0.05,
                                                             "ci": [-0.09, -0.01]},
            "c": {"mean": 0.0, "ci": [-0.02, 0.03]}}  # fmt: skip
    _, ax = _interval_rows(rows, "x")
    assert [t.get_text() for t in ax.get_yticklabels()] == ["b", "c", "a"]  # largest on top
    markers = [line for line in ax.get_lines() if line.get_linestyle() == "None"]
    assert [(m.get_color(), m.get_marker()) for m in markers] == [
        VERDICT_STYLE["is worse than"], VERDICT_STYLE["is not distinguishable from"],
        VERDICT_STYLE["beats"]]
    assert len({colour for colour, _ in VERDICT_STYLE.values()}) == 3
    assert len({marker for _, marker in VERDICT_STYLE.values()}) == 3


def test_the_gallery_shows_meshes_beside_drawn_shapes():
    from classifiers.report.figures import gallery_choice

    objects = pd.DataFrame({
        "object_index": range(8), "object_id": [f"x{i}" for i in range(8)],
        "family": ["mesh", "named", "procedural", "named", "mesh", "mesh", "procedural",
                   "named"]})  # fmt: skip
    grips = pd.DataFrame({"object_id": ["x0", "x1", "x2", "x3", "x4", "x6", "x7"]})  # no x5
    chosen = gallery_choice(objects, grips, per_kind=3)
    assert list(chosen["object_id"]) == ["x1", "x3", "x7", "x0", "x4"]
    assert list(chosen["kind"]) == ["drawn"] * 3 + ["mesh"] * 2


def _retry_board(rl_shift: float, seed: int = 3) -> dict:
    """A retry board of 30 objects, within 1-3 attempts on shared draws: lambdarank's order 0.05
    above best-Q_C's, the oracle's 0.2, the RL retry selector ``rl_shift`` (two runs, noisy)."""
    from classifiers.experiments.benchmark.retry import retry_leaderboard

    rng = np.random.default_rng(seed)
    base = rng.uniform(0.3, 0.6, 30)
    shifts = {
        "best_qc": (0.0, 0.0, 1),
        "ranker_lambdarank": (0.05, 0.0, 1),
        "oracle": (0.2, 0.0, 1),
        "rl_retry": (rl_shift, 0.02, 2),
    }
    rows = []
    for method, (shift, noise, runs) in shifts.items():
        for run in range(runs):
            for i in range(30):
                held = np.clip(base[i] + shift + noise * rng.normal() + [0.0, 0.05, 0.08], 0, 1)
                rows.append({"method": method, "seed": run, "object_id": f"o{i:02d}",
                             **{f"shared_at_{m}": held[m - 1] for m in (1, 2, 3)},
                             **{f"overstatement_at_{m}": 0.0 for m in (1, 2, 3)},
                             "ceiling": 1.0})  # fmt: skip
    metrics = pd.DataFrame(rows)
    retry = retry_leaderboard(metrics, reps=400, seed=seed)
    return {"retry": {**retry, "per_object": metrics.to_dict(orient="records")}}


def test_the_retry_answer_is_the_retry_boards_paired_difference() -> None:
    from classifiers.experiments.answers import retry_answers

    board = _retry_board(rl_shift=0.1)
    found = retry_answers(board, seed=3, reps=400)
    versus_qc = found["picks"]["rl_retry - best_qc"]
    assert versus_qc["estimate"] == pytest.approx(
        board["retry"]["methods"]["rl_retry"]["shared_at_3_minus_best_qc"]["estimate"]
    )
    assert (
        versus_qc["ci"] == board["retry"]["methods"]["rl_retry"]["shared_at_3_minus_best_qc"]["ci"]
    )
    assert found["picks"]["rl_retry - ranker_lambdarank"]["estimate"] == pytest.approx(
        0.05, abs=0.01
    )
    sentence = answer_sentences({"picks": {}, "retry": found})[-1]
    assert sentence.startswith("**Does a retry policy use what a failure tells?** Within 3 ")
    assert "**beats** best-Q_C" in sentence and "**beats** `ranker_lambdarank`'s order" in sentence
    worse = retry_answers(_retry_board(rl_shift=-0.1), seed=3, reps=400)
    assert "**is worse than** best-Q_C" in answer_sentences({"picks": {}, "retry": worse})[-1]


def test_without_a_retry_selector_there_is_no_retry_answer() -> None:
    from classifiers.experiments.answers import retry_answers

    board = _retry_board(rl_shift=0.0)
    del board["retry"]["methods"]["rl_retry"]
    assert retry_answers(board, seed=3) is None
    assert retry_answers({}, seed=3) is None
    assert len(answer_sentences({"picks": {}, "retry": None})) == 4
