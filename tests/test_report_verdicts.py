"""The report declares nothing its numbers cannot carry (issue 35 item 11), and its figures stay
readable (item 12), on small hand-made result dicts."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from classifiers.report.document import Report
from classifiers.report.judge import difference_verdict, unjudgeable


def block(mean, low, high):
    return {"mean": mean, "ci": [low, high]}


def _write(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data))


# ------------------------------------------------------------------------------ intervals
def test_an_interval_carries_a_verdict_only_with_width_range_and_objects():
    assert unjudgeable(block(0.8, 0.7, 0.9), objects=40, span=(0, 1)) is None
    assert "zero width" in unjudgeable(block(0.5, 0.5, 0.5), objects=40)
    assert "every possible value" in unjudgeable(block(0.8, 0.0, 1.0), objects=40, span=(0, 1))
    assert "7 objects" in unjudgeable(block(0.8, 0.7, 0.9), objects=7)
    assert unjudgeable(block(None, None, None)) == "there is no interval"
    assert difference_verdict(block(0.0, 0.0, 0.0), 40).startswith("no verdict")
    assert difference_verdict(block(0.1, 0.05, 0.15), 40) == "the interval excludes zero"
    assert "includes zero" in difference_verdict(block(0.0, -0.05, 0.05), 40)


# ------------------------------------------------------------------------------ power
def test_a_zero_width_half_width_is_not_called_met(tmp_path):
    from classifiers.report.power import power_section, target_met

    _write(tmp_path / "classifiers" / "metrics.json",
           {"models": {"knn": {"roc_auc": block(0.813, 0.0, 1.0)}}, "cv": {"n_objects": 40}})
    _write(tmp_path / "ablation" / "ablation.json",  # the model scored 0.500 on every set
           {"model": "hgb", "cv": {"n_objects": 40}, "feature_sets": {"without_hand": {
               "paired_difference": {"hgb": {"roc_auc": block(0.0, 0.0, 0.0)}}}}})
    _write(tmp_path / "selector" / "selector.json",
           {"policies": {"rl": {"per_object": [0.0] * 10}, "best_qc": {"per_object": [0.0] * 10}},
            "split": {"train": ["x"] * 30, "test": ["y"] * 10, "seed": 0}})
    report = Report("t")
    power_section(report, tmp_path)
    text = report.to_markdown()
    assert "| hand features (paired ΔAUC) | 0.000 | 0.000 | 40 | 0.030 | not judged | – |" in text
    assert "| RL − best Q_C (held out) | 0.000 | 0.000 | 40 | 0.060 | not judged | – |" in text
    assert "| yes |" not in text and "zero width" in text
    assert target_met(0.01, 0.02, 40) == ("yes", None)
    assert target_met(0.01, 0.02, 7)[0] == "not judged"  # within target, but on 7 objects
    assert target_met(0.5, 0.05, 7) == ("no", None)


# ------------------------------------------------------------------------------ study report
def test_a_quick_study_says_so_at_the_top(tmp_path):
    from classifiers.report.study_report import _size_banner, ran_quick
    from grip_env.config import Config

    assert not ran_quick(tmp_path)
    _write(tmp_path / "calibration" / "stage.json", {"inputs": {"quick": True}})
    assert ran_quick(tmp_path)
    table = pd.DataFrame({"object_id": list("abcdefg")})
    report = Report("t")
    _size_banner(report, Config(), table, quick=True)
    top = report.to_markdown().split("\n")[2]
    assert top.startswith("**Toy profile (`grip-env study --quick`)")
    small = Report("t")
    _size_banner(small, Config(), table, quick=False)
    assert "Small study: 7 objects" in small.to_markdown()
    full = Report("t")
    _size_banner(full, Config(), pd.DataFrame({"object_id": range(40)}), quick=False)
    assert full.blocks == []


def _metrics(interval, objects):
    models = {"knn": {"roc_auc": block(0.813, *interval), "top1_success": block(0.6, *interval)},
              "random": {"roc_auc": block(0.5, 0.4, 0.6), "top1_success": block(0.5, 0.4, 0.6)}}
    return {"models": models, "cv": {"n_objects": objects}}


@pytest.mark.parametrize("interval, objects, bold", [
    ((0.0, 1.0), 40, False),  # spans everything
    ((0.75, 0.87), 2, False),  # too few objects
    ((0.813, 0.813), 40, False),  # zero width
    ((0.75, 0.87), 40, True),
])
def test_no_bold_winner_on_an_interval_that_cannot_carry_it(tmp_path, interval, objects, bold):
    from classifiers.report.study_report import _classifier_section

    _write(tmp_path / "classifiers" / "metrics.json", _metrics(interval, objects))
    report = Report("t")
    _classifier_section(report, tmp_path)
    text = report.to_markdown()
    assert ("Best ROC-AUC: **knn**" in text) is bold
    assert ("**" in text) is bold
    if not bold:
        assert "Highest mean ROC-AUC: knn (0.813" in text and "not declared best" in text


def test_constant_ablation_scores_give_no_verdict(tmp_path):
    from classifiers.report.study_report import _ablation_section

    flat = {"roc_auc": block(0.5, 0.5, 0.5), "top1_success": block(0.583, 0.0, 1.0)}
    zero = {"roc_auc": block(0.0, 0.0, 0.0)}
    _write(tmp_path / "ablation" / "ablation.json", {
        "model": "hgb", "reference": "all_twelve", "cv": {"n_objects": 40},
        "feature_sets": {"all_twelve": {"models": {"hgb": flat}, "paired_difference": {}},
                         "without_hand": {"models": {"hgb": flat},
                                          "paired_difference": {"hgb": zero}}}})
    report = Report("t")
    _ablation_section(report, tmp_path)
    text = report.to_markdown()
    assert ("0.000 [0.000, 0.000] against all twelve; no verdict: its interval has zero width"
            in text)
    assert "no significant effect" not in text
    assert "scores ROC-AUC 0.500 on every feature set and fold, with no spread (chance" in text


def _board(objects: int) -> dict:
    from classifiers.experiments.benchmark.leaderboard import build_leaderboard

    plain = dict.fromkeys(("success", "robustness", "regret", "robustness_regret", "ndcg5",
                           "attempts", *(f"success_at_{k}" for k in range(1, 6))), 0.5)
    rows = [{"method": m, "seed": 0, "object_id": f"o{i}", "normalised": v + 0.01 * i + 0.02 * j,
             **plain} for i in range(objects) for j, (m, v) in enumerate(
                 (("best_qc", 0.1), ("good", 0.9)))]  # fmt: skip
    return build_leaderboard(pd.DataFrame(rows), {"name": "t", "version": 0}, reps=200)


def test_no_method_beats_best_qc_on_two_held_out_objects(tmp_path):
    from classifiers.experiments.benchmark.leaderboard import write_leaderboard
    from classifiers.report.readme import _leaderboard_lines
    from classifiers.report.study_report import _benchmark_section

    board = _board(2)
    assert board["methods"]["good"]["verdict"] == "beats best_qc"  # what the stage computes
    write_leaderboard(board, tmp_path / "benchmark")
    report = Report("r")
    _benchmark_section(report, tmp_path)
    text = report.to_markdown()
    assert "beats best_qc" not in text and "Beat the best-Q_C pick" not in text
    assert "only 2 held-out object(s)" in text and "| not judged |" in text
    readme = "\n".join(_leaderboard_lines(tmp_path))
    assert "Beat the best-Q_C pick" not in readme and "only 2 held-out" in readme


def test_an_undefined_held_out_score_is_a_dash_with_its_reason():
    from classifiers.report.study_report import _held_out_table

    report = Report("t")
    _held_out_table(report, {"split": {"train": ["a"] * 5, "test": ["b", "c"],
                                       "test_fraction": 0.25, "seed": 0},
                             "models": {"knn": {"roc_auc": float("nan"), "brier": 0.718,
                                                "balanced_accuracy": float("nan"),
                                                "top1_success": 0.0}}})
    text = report.to_markdown()
    assert "nan" not in text and "| knn | — | — | 0.718 | 0 |" in text
    assert "grips that held and grips that slipped" in text and "2 held-out objects" in text


def test_readme_names_no_best_classifier_on_an_interval_spanning_everything():
    from classifiers.report.readme import _meaning

    assert "no classifier is declared best" in _meaning(_metrics((0.0, 1.0), 40), {})
    assert "the best classifier by ROC-AUC is knn" in _meaning(_metrics((0.75, 0.87), 40), {})


def test_stage_figures_are_the_listed_ones_not_whatever_png_lies_there(tmp_path):
    from classifiers.report.study_report import STAGE_FIGURES, _stage_figures

    folder = tmp_path / "classifiers"
    folder.mkdir()
    for name in ("calibration.png", "roc.png", "stray.png"):
        (folder / name).write_bytes(b"png")
    report = Report("t")
    _stage_figures(report, tmp_path, "classifiers")
    shown = [b.content for b in report.blocks]
    assert shown == ["classifiers/roc.png", "classifiers/calibration.png"]
    assert set(STAGE_FIGURES) == {"classifiers", "ablation", "selector", "benchmark"}
    source = Path("classifiers/report/study_report.py").read_text()
    assert "glob(" not in source


# ------------------------------------------------------------------------------ calibration
def test_calibration_states_the_sample_and_when_it_is_too_small():
    from classifiers.report.calibration import summary_table

    one_object = {"name": "cone", "measured": 44.3, "ci": [44.3, 44.3], "passed": False,
                  "target": "below 0", "per_object": [{"object_id": "t"}]}
    few_grips = {"name": "retest", "measured": -0.775, "ci": [-1.0, -0.447], "passed": False,
                 "target": "Spearman >= 0.8", "grips": 8, "objects": 2, "trials_per_set": 2}
    enough = {"name": "retest", "measured": 0.9, "ci": [0.85, 0.95], "passed": True,
              "target": "Spearman >= 0.8", "grips": 96, "objects": 6, "trials_per_set": 8}
    table = summary_table({"cone": one_object, "retest": few_grips, "ok": enough},
                          {"cone_trials": 2})
    assert table.loc["cone", "sample"] == "1 object(s) × 2 trial(s) a grip"
    assert table.loc["cone", "verdict"] == "too small to judge; measured FAIL"
    assert table.loc["retest", "sample"] == "8 grips on 2 object(s), 2 × 2 trials"
    assert table.loc["retest", "verdict"].startswith("too small to judge")
    assert table.loc["ok", "verdict"] == "pass"


def _overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_the_design_legend_leaves_the_reference_line_visible():
    from classifiers.report.calibration import design_figure

    rows = pd.DataFrame({"object_id": ["box_120x40", "box_70x70", "box_90x55"],
                         "robustness": [38.1, 38.1, 38.1],
                         "friction_ceiling_g": [25.5, 24.9, 24.7]})
    fig = design_figure(rows, 64.0)
    FigureCanvasAgg(fig).draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent(renderer)
    reference = next(line for line in ax.lines if line.get_linestyle() == "--")
    assert not _overlap(legend, reference.get_window_extent(renderer).expanded(1.0, 1.0)
                        .padded(2.0))
    assert fig.bbox.contains(legend.x1 - 1, legend.y0 + 1)  # the legend is not cut off


# ------------------------------------------------------------------------------ figures
def _grips(constant: str = "C6") -> pd.DataFrame:
    from classifiers.report.analysis import CORRELATION_COLUMNS
    from grip_env.columns import FEATURES

    rng = np.random.default_rng(0)
    names = sorted({*CORRELATION_COLUMNS, *FEATURES, "Q_G"})
    table = pd.DataFrame(rng.random((40, len(names))), columns=names)
    table[constant] = 0.0
    table["object_id"] = np.repeat(np.arange(8), 5)
    table["success_rate"] = rng.random(40)
    table["success"] = table["success_rate"] > 0.5
    return table


def test_a_constant_feature_shows_as_constant_not_nan(tmp_path):
    from classifiers.report import analysis
    from classifiers.report.figures import correlation_figure
    from classifiers.report.study_report import _feature_section

    table = _grips()
    assert analysis.constant_columns(table, analysis.CORRELATION_COLUMNS) == {"C6": 0.0}
    report = Report("t")
    _feature_section(report, table, tmp_path / "figures")
    text = report.to_markdown()
    assert "nan" not in text.lower()
    row = next(line for line in text.splitlines() if line.startswith("| C6 |"))
    assert set(row.strip("| ").split(" | ")[1:]) == {"—"}
    assert "C6 (every grip 0) is constant on this dataset" in text
    cells = [t.get_text() for t in correlation_figure(
        analysis.feature_correlations(table)).axes[0].texts]
    assert "nan" not in cells and cells.count("—") == 2 * len(analysis.CORRELATION_COLUMNS) - 1


def test_a_constant_feature_histogram_has_a_readable_axis():
    from classifiers.report.figures import distribution_figure

    fig = distribution_figure(_grips())
    by_title = {ax.get_title(): ax for ax in fig.axes}
    axis = by_title["C6 (constant 0)"]
    low, high = axis.get_xlim()
    assert low <= 0.0 <= high and high - low >= 1.0  # not -5e-8 .. 1e-6
    assert "C1" in by_title


# ------------------------------------------------------------------------------ line styles
def test_every_line_has_a_look_of_its_own():
    from classifiers.experiments.plots import line_styles

    names = [f"m{k}" for k in range(20)] + ["random", "oracle", "best_qc"]
    styles = line_styles(names, ("random", "oracle", "best_qc"))
    looks = {(s["color"], s["linestyle"], s["marker"]) for s in styles.values()}
    assert len(looks) == len(names)
    few = line_styles(["rl", "ranker_lambdarank", "knn", "epsilon", "random"], ("random",))
    assert len({s["color"] for s in few.values()}) == 5
    # one hue each (tab10), not tab20's light and dark pairs of one hue
    tab10 = {f"tab:{c}" for c in ("blue", "orange", "green", "red", "purple", "brown", "pink",
                                  "olive", "cyan")}
    assert {few[n]["color"] for n in ("rl", "ranker_lambdarank", "knn", "epsilon")} <= tab10
    widths = [styles[n]["linewidth"] for n in names]
    assert widths == sorted(widths, reverse=True) and widths[0] > widths[-1]


def test_the_performance_profile_draws_each_method_distinctly(tmp_path, monkeypatch):
    from classifiers.experiments.benchmark import plots

    board = _board(10)
    names = ["rl", "ranker_lambdarank", "knn", "epsilon", "classifier_svm", "random", "oracle"]
    board["methods"] = {n: board["methods"]["good"] for n in names} | {
        "best_qc": board["methods"]["best_qc"]}  # identical profiles: lines on top of each other
    drawn = {}
    real_close = plots._pyplot().close
    monkeypatch.setattr(plots._pyplot(), "close",
                        lambda fig: drawn.setdefault("fig", fig) and real_close(fig))
    plots.plot_profiles(board, tmp_path / "profile.png")
    lines = drawn["fig"].axes[0].lines
    labels = [line.get_label() for line in lines]
    assert [label.split(" ")[0] for label in labels] == list(board["methods"])
    assert len({str(line.get_color()) for line in lines}) == len(lines)
    assert len({line.get_linewidth() for line in lines}) == len(lines)
    first = labels[0]  # the methods' profiles coincide: every later one says under which it lies
    assert all(label.endswith(f"(= {first})") for label in labels[1:] if "random" not in label
               and "oracle" not in label and "best_qc" not in label)  # fmt: skip


def test_a_line_identical_to_one_drawn_before_says_so():
    import matplotlib.pyplot as plt

    from classifiers.experiments.plots import draw_lines

    fig, ax = plt.subplots()
    lines = draw_lines(ax, {"rl": ([0, 1], [0.5, 0.2]), "best_qc": ([0, 1], [0.5, 0.2]),
                            "knn": ([0, 1], [0.4, 0.2])}, references=("best_qc",))
    plt.close(fig)
    assert [line.get_label() for line in lines] == ["rl", "best_qc (= rl)", "knn"]
    assert lines[0].get_linewidth() > lines[1].get_linewidth() > lines[2].get_linewidth()
