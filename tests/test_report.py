"""The paper's analyses and the report writer, on hand-built tables with known answers."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from classifiers.report import analysis
from classifiers.report.document import Report
from grip_env.config import Config


def _candidates() -> pd.DataFrame:
    # grasp 1 (best Q_G) yields configurations ranked 3 and 4; grasp 2 yields 1; grasp 3 yields 2, 5
    return pd.DataFrame(
        {
            "object_id": "box",
            "grasp_id": [1, 1, 2, 3, 3],
            "Q_G": [1.0, 1.0, 2.0, 3.0, 3.0],
            "Q_C": [3.0, 4.0, 1.0, 2.0, 5.0],
        }
    )


def test_compare_ranks_matches_hand_ranking():
    result = analysis.compare_ranks(_candidates())
    table = result.table.set_index("grasp_rank")
    assert table.loc[1, "config_ranks"] == (3, 4)
    assert table.loc[2, "config_ranks"] == (1,)
    assert table.loc[3, "config_ranks"] == (2, 5)
    assert result.best_config_grasp_rank == 2
    assert result.best_grasp_best_config_rank == 3
    # best ranks (3, 1, 2) against grasp ranks (1, 2, 3): Spearman = -0.5
    assert result.best_config_correlation == pytest.approx(-0.5)
    # mean ranks (3.5, 1, 3.5): ties -> Spearman of (1,2,3) with (2.5, 1, 2.5)
    assert result.mean_config_correlation == pytest.approx(0.0)


def test_compare_ranks_refuses_several_objects():
    two = pd.concat([_candidates(), _candidates().assign(object_id="disc")])
    with pytest.raises(ValueError, match="one object"):
        analysis.compare_ranks(two)


def test_rank_summary_flags():
    summary = analysis.rank_summary([analysis.compare_ranks(_candidates())])
    row = summary.iloc[0]
    assert row["grasps"] == 3 and row["configurations"] == 5
    assert bool(row["best_config_from_top3_grasp"]) and bool(row["best_grasp_config_in_top6"])


def test_success_by_decile_orders_bins_by_quality():
    table = pd.DataFrame({"Q_C": np.arange(100.0), "success_rate": np.linspace(1, 0, 100)})
    bins = analysis.success_by_decile(table)
    assert list(bins["grips"]) == [10] * 10
    assert bins["success_rate"].is_monotonic_decreasing
    assert bins.loc[1, "Q_C_max"] == 9


def test_feature_correlations_reads_the_columns():
    rng = np.random.default_rng(0)
    table = pd.DataFrame(rng.normal(size=(50, 11)), columns=analysis.CORRELATION_COLUMNS)
    table["Q_C"] = 2 * table["C1"]
    corr = analysis.feature_correlations(table)
    assert corr.loc["C1", "Q_C"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="S4"):
        analysis.feature_correlations(table.drop(columns="S4"))


def test_report_writes_markdown_and_html(tmp_path):
    report = Report("title <x>")
    report.heading("Section")
    report.text("a & b, best **rank_qc**")
    report.table(pd.DataFrame({"m": [0.12345], "eta": [101.5], "s": ["x|y"]},
                              index=pd.Index(["svm"], name="model")))  # fmt: skip
    report.figure("figures/a.png", "caption")
    report.code("grasp:\n  mu: 0.4\n", "yaml")
    md, page = report.write(tmp_path)
    text = md.read_text()
    assert "## Section" in text and "| model | m | eta | s |" in text
    assert "| svm | 0.1235 | 101.5 | x\\|y |" in text  # 4 significant digits, pipe escaped
    assert "![caption](figures/a.png)" in text and "```yaml\ngrasp:\n  mu: 0.4\n```" in text
    html = page.read_text()
    assert "<h1>title &lt;x&gt;</h1>" in html and "a &amp; b" in html
    assert "<strong>rank_qc</strong>" in html and "**" not in html
    assert "<table>" in html and "<td>x|y</td>" in html
    assert '<img src="figures/a.png" alt="caption"' in html
    assert '<code class="language-yaml">grasp:' in html


def _calibration_trials() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    rows = []

    def add(obj: str, part: str, end: str, grip: str, level: float, trials: int) -> None:
        for k in range(trials):
            value = max(level + rng.normal(0, 0.5), 0.0)
            rows.append({"object_id": obj, "grip": grip, "part": part, "end": end, "Q_C": 1.0,
                         "Q_G": 1.0, "trial": k, "robustness": value, "success": value >= 4,
                         "friction": 0.4, "mass_kg": 0.2})  # fmt: skip

    for box in ("box_90x55", "box_70x70", "box_120x40"):
        add(box, "design", "best", f"{box}/0", 8.0, 1)
    for obj in "abcdefghij":  # ten objects: fewer are too few for the cone check's verdict
        add(obj, "cone", "best", f"{obj}/best", 6.0, 4)
        add(obj, "cone", "outside", f"{obj}/out", 2.0, 4)
    for obj in ("a", "b", "c"):
        for i in range(8):
            add(obj, "retest", "best" if i < 4 else "worst", f"{obj}/{i}", float(i), 8)
    return pd.DataFrame(rows)


def test_calibration_report_states_every_check_with_its_figures(tmp_path):
    from dataclasses import asdict

    from classifiers.evaluation.synthetic import synthetic_grips
    from classifiers.report.calibration import write_calibration
    from grip_env.calibration import (
        CalibrationSettings,
        cone_check,
        dataset_checks,
        design_check,
        icc_check,
        retest_check,
    )

    trials = _calibration_trials()
    settings = CalibrationSettings(trials_per_set=4, bootstrap=100)
    checks = [design_check(trials, 4.0), cone_check(trials), retest_check(trials, settings),
              icc_check(trials), *dataset_checks(synthetic_grips(20, seed=1), settings)]
    result = {"reference_level_g": 4.0, "mu": 0.4, "settings": asdict(settings),
              "trials": len(trials), "checks": {c["name"]: c for c in checks}}  # fmt: skip
    assert [c["passed"] for c in checks[:4]] == [True, True, True, True]
    md = write_calibration(tmp_path, result, trials)
    text = md.read_text()
    table = text.split("*Checks against their targets.*")[1].split("###")[0]
    assert table.count("| pass |") == 5 and "| - |" in table  # Q_G: for comparison only
    for figure in ("design", "cone", "retest", "deciles"):
        assert f"figures/calibration_{figure}.png" in text
        assert (tmp_path / "figures" / f"calibration_{figure}.png").stat().st_size > 1000
    assert "ICC(1)" in text and "Spearman" in text
    failing = dict(result, checks={"retest": dict(result["checks"]["retest"], passed=False)})
    assert "FAIL" in write_calibration(tmp_path / "f", failing, trials).read_text()


def test_decile_intervals_resample_objects_and_bracket_the_means():
    rng = np.random.default_rng(1)
    table = pd.DataFrame({"object_id": np.repeat(np.arange(20), 10), "Q_C": rng.random(200)})
    table["success_rate"] = np.clip(1 - table["Q_C"] + rng.normal(0, 0.1, 200), 0, 1)
    bins = analysis.success_by_decile(table, resamples=300)
    assert (bins["ci_low"] <= bins["success_rate"]).all()
    assert (bins["success_rate"] <= bins["ci_high"]).all()
    # an object-level effect widens the intervals: grips of one object move together
    shifted = table.assign(success_rate=np.clip(
        table["success_rate"] + rng.normal(0, 0.3, 20)[table["object_id"]], 0, 1))  # fmt: skip
    wide = analysis.success_by_decile(shifted, resamples=300)
    assert (wide["ci_high"] - wide["ci_low"]).mean() > (bins["ci_high"] - bins["ci_low"]).mean()


def test_correlations_are_spearman_unless_asked():
    rng = np.random.default_rng(2)
    table = pd.DataFrame(rng.normal(size=(60, 11)), columns=analysis.CORRELATION_COLUMNS)
    table["Q_C"] = np.exp(3 * table["C1"])  # monotone, far from linear
    assert analysis.feature_correlations(table).loc["C1", "Q_C"] == pytest.approx(1.0)
    assert analysis.feature_correlations(table, "pearson").loc["C1", "Q_C"] < 0.9


def test_report_package_never_imports_the_study_that_drives_it():
    """classifiers.experiments.study calls the report; the report must not import
    classifiers.experiments.study back."""
    import ast
    from pathlib import Path

    import classifiers.report

    for path in Path(classifiers.report.__file__).parent.glob("*.py"):
        tree = ast.parse(path.read_text())
        imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
        imported |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        assert "classifiers.experiments.study" not in imported, path.name


def _stored_run(out):
    """A study folder's result files, as the stages write them (hand-picked numbers)."""
    import json

    def block(mean, low, high):
        return {"mean": mean, "ci": [low, high], "n": 5}

    (out / "classifiers").mkdir(parents=True)
    (out / "selector").mkdir()
    (out / "ablation").mkdir()
    metrics = {"cv": {"folds": 5, "repeats": 3},
               "models": {"svm": {"roc_auc": block(0.712, 0.566, 0.859),
                                  "top1_success": block(0.6, 0.45, 0.75)},
                          "random": {"roc_auc": block(0.5, 0.47, 0.54),
                                     "top1_success": block(0.53, 0.4, 0.66)}}}  # fmt: skip
    selector = {"split": {"test": ["a", "b", "c"]},
                "policies": {"rl": {"success_rate": block(0.607, 0.39, 0.79)},
                             "oracle": {"success_rate": block(0.79, 0.59, 0.96)}}}  # fmt: skip
    ablation = {"model": "svm", "feature_sets": {"without_hand": {"paired_difference": {
        "svm": {"roc_auc": block(0.004, -0.05, 0.06)}}}}}
    (out / "classifiers" / "metrics.json").write_text(json.dumps(metrics))
    (out / "selector" / "selector.json").write_text(json.dumps(selector))
    (out / "ablation" / "ablation.json").write_text(json.dumps(ablation))
    (out / "timings.json").write_text(json.dumps({"dataset": 300.0, "classifiers": 60.0}))
    rng = np.random.default_rng(0)
    return pd.DataFrame({"object_id": np.repeat(["a", "b", "c", "d"], 5), "trials": 4,
                         "success_rate": rng.random(20), "success": rng.random(20) > 0.5,
                         "Q_C": rng.random(20)})  # fmt: skip


def test_readme_results_block_is_the_stored_runs_numbers(tmp_path):
    from classifiers.report.readme import BEGIN, END, readme_block, results_block, update_readme

    table = _stored_run(tmp_path / "run")
    block = results_block(tmp_path / "run", table, "abc1234", "0.1.0")
    assert "| svm | 0.71 [0.57, 0.86] | 0.60 [0.45, 0.75] |" in block
    assert "| rl | 0.61 [0.39, 0.79] |" in block and "first pick on 3 held-out objects" in block
    assert "changes ROC-AUC by 0.00 [-0.05, 0.06]" in block
    assert "commit abc1234 (grip-env 0.1.0)" in block and "6.0 min of stage time" in block
    assert "80 simulated trials" in block and "4 objects" in block
    assert "What it does not mean" in block
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n{BEGIN}\nstale\n{END}\noutro\n")
    update_readme(readme, block)
    once = readme.read_text()
    update_readme(readme, block)
    assert readme.read_text() == once  # rewriting is idempotent
    assert once.startswith("intro\n") and once.endswith(f"{END}\noutro\n")
    assert readme_block(readme) == block.strip()


def test_perception_section_states_each_paired_difference_and_the_cost(tmp_path):
    import json

    from classifiers.report.document import Report
    from classifiers.report.study_report import _perception_section

    (tmp_path / "perception").mkdir()
    differences = {"S1": {"true": 0.2, "render": 0.25, "mean": 0.05, "ci": [-0.01, 0.11]},
                   "Q_C": {"true": 3.0, "render": 3.3, "mean": 0.3, "ci": [0.1, 0.5]}}
    (tmp_path / "perception" / "perception.json").write_text(json.dumps({
        "planned_on": "render", "objects": 7, "differences": differences,
        "timing_s": {"plan_true_s": 4.5, "simulate_true_best_s": 21.0}}))
    table = pd.DataFrame({"object_id": ["a"]})
    table.attrs["manifest"] = {"perception_seconds": 12.25}
    report = Report("t")
    _perception_section(report, tmp_path, table)
    md, _ = report.write(tmp_path)
    text = md.read_text()
    assert "over the 7 objects" in text
    assert "| Q_C | 3 | 3.3 | 0.300 [0.100, 0.500] |" in text
    assert "12.2 s" in text and "4.5 s" in text and "21.0 s" in text
    (tmp_path / "perception" / "perception.json").write_text(json.dumps(
        {"planned_on": "polygon", "objects": 0}))
    report = Report("t")
    _perception_section(report, tmp_path, table)
    assert "no rendered plan" in report.write(tmp_path / "p")[0].read_text()


def test_a_calibration_recorded_with_the_dataset_stands_for_the_study_only_when_it_matches(
        tmp_path):
    """The study's calibration stage reuses a dataset's recorded calibration only when it is
    this label model's, on the same config fields, at full size; the copy says it was recorded."""
    from dataclasses import asdict

    from classifiers.experiments.study import copy_calibration, recorded_calibration
    from classifiers.report.calibration import write_calibration
    from grip_env.calibration import CalibrationSettings, cone_check, design_check
    from grip_env.label_model import LABEL_MODEL

    trials = _calibration_trials()
    config = Config()
    result = {"label_model": LABEL_MODEL, "reference_level_g": 4.0, "mu": 0.4,
              "settings": asdict(CalibrationSettings(workers=1)), "trials": len(trials),
              "checks": {c["name"]: c for c in (design_check(trials, 4.0), cone_check(trials))},
              "config": config.model_dump(mode="json")}  # fmt: skip
    dataset = tmp_path / "data"
    write_calibration(dataset / "calibration", result, trials)
    recorded = dataset / "calibration" / "calibration.json"
    assert recorded_calibration(dataset, config) == recorded
    assert recorded_calibration(dataset, config.override(learning={"seeds": 2})) == recorded
    assert recorded_calibration(dataset, config.override(sim={"finger_force_n": 12.0})) is None
    assert recorded_calibration(tmp_path / "elsewhere", config) is None
    for key, value in (("label_model", "2020.01-old"), ("settings", asdict(
            CalibrationSettings.quick()))):  # fmt: skip
        write_calibration(dataset / "calibration", {**result, key: value}, trials)
        assert recorded_calibration(dataset, config) is None, key
    write_calibration(dataset / "calibration", result, trials)
    text = copy_calibration(recorded, tmp_path / "study" / "calibration").read_text()
    assert f"Recorded with the dataset `{dataset}` (label model `{LABEL_MODEL}`)" in text
    copied = json.loads((tmp_path / "study" / "calibration" / "calibration.json").read_text())
    assert copied["checks"] == json.loads(recorded.read_text())["checks"]
