"""The power curve: seeded subsampling, the half-width law, the report section, the CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from cli_runs import assert_refused, cli

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments import power
from classifiers.report.document import Report
from classifiers.report.power import plot_power, power_section


@pytest.fixture(scope="module")
def grips() -> pd.DataFrame:
    table = synthetic_grips(n_objects=30, grips=(4, 12), trials=8, seed=3)
    table["object_id"] = "obj_" + table["object_id"].astype(str)
    return table


# ------------------------------------------------------------------------------- subsample
def test_subsample_keeps_whole_objects_and_exact_counts(grips):
    part = power.subsample(grips, objects=12, seed=5)
    sizes, original = part.groupby("object_id").size(), grips.groupby("object_id").size()
    assert part["object_id"].nunique() == 12
    assert (sizes == original[sizes.index]).all()  # every kept object with all its grips
    assert part.equals(grips.loc[part.index])  # rows untouched when trials are all kept


def test_subsample_is_seeded_and_reproducible(grips):
    first = power.subsample(grips, objects=10, trials=3, grips=5, seed=1)
    assert first.equals(power.subsample(grips, objects=10, trials=3, grips=5, seed=1))
    other = power.subsample(grips, objects=10, trials=3, grips=5, seed=2)
    assert set(other["object_id"]) != set(first["object_id"])
    again = power.subsample(grips, objects=10, trials=3, grips=5, seed=1, replicate=1)
    assert not again.equals(first)


def test_subsample_caps_grips_per_object(grips):
    part = power.subsample(grips, grips=5, seed=0)
    sizes = part.groupby("object_id").size()
    expected = grips.groupby("object_id").size().clip(upper=5)
    assert (sizes == expected[sizes.index]).all() and part["object_id"].nunique() == 30


def test_subsampled_trials_recompute_the_outcome_within_the_hypergeometric_support(grips):
    part = power.subsample(grips, trials=3, seed=4)
    kept, recorded = part["successes"], grips.loc[part.index, "successes"]
    failures = grips.loc[part.index, "trials"] - recorded
    assert (part["trials"] == 3).all()
    assert ((kept <= np.minimum(recorded, 3)) & (kept >= np.maximum(0, 3 - failures))).all()
    assert np.allclose(part["success_rate"], kept / 3)
    assert (part["success"] == (part["success_rate"] >= 0.5)).all()
    assert "robustness_mean" not in part.columns  # cannot be recomputed from counts


def test_subsampled_successes_have_the_hypergeometric_mean():
    table = pd.DataFrame({"object_id": ["a"] * 20000, "trials": 8, "successes": 3})
    part = power.subsample(table, trials=4, seed=0)
    assert part["successes"].mean() == pytest.approx(4 * 3 / 8, abs=0.03)
    assert part["successes"].var() == pytest.approx(4 * 3 / 8 * 5 / 8 * 4 / 7, rel=0.05)


@pytest.mark.parametrize("kwargs, fragment", [
    ({"objects": 31}, "holds 30 objects"), ({"trials": 9}, "only 8 trials"),
    ({"objects": 0}, "objects must be"), ({"grips": 2.5}, "grips must be"),
])
def test_subsample_refuses_impossible_sizes(grips, kwargs, fragment):
    with pytest.raises(ValueError, match=fragment):
        power.subsample(grips, **kwargs)


def test_pool_cuts_trials_and_keeps_an_object_once(grips):
    other = synthetic_grips(n_objects=5, grips=(3, 3), trials=4, seed=9)
    other["object_id"] = "obj_" + other["object_id"].astype(str)  # obj_0..4 again
    other.loc[other["object_id"] == "obj_4", "object_id"] = "new"
    pooled = power.pool([grips, other], seed=0)
    assert (pooled["trials"] == 4).all() and pooled["object_id"].nunique() == 31
    assert len(pooled[pooled["object_id"] == "obj_0"]) == (grips["object_id"] == "obj_0").sum()


# ------------------------------------------------------------------------------------- law
def test_fit_law_recovers_a_known_law_exactly():
    n = np.array([10, 20, 40, 80, 40, 40, 40])
    t = np.array([4, 4, 4, 4, 1, 2, 8])
    half = np.sqrt((0.03 + 0.08 / t) / n)
    law = power.fit_law(n, t, half)
    assert law.a == pytest.approx(0.03, rel=1e-6) and law.b == pytest.approx(0.08, rel=1e-6)
    assert law.half_width(40, 4) == pytest.approx(half[2])
    needed = power.objects_needed(law, 0.02, 4)
    assert law.half_width(needed, 4) <= 0.02 < law.half_width(needed - 1, 4)
    assert power.objects_needed(law, 0.02) == math.ceil(0.03 / 0.02**2)


def test_fit_law_on_noisy_half_widths_and_one_trial_count():
    rng = np.random.default_rng(0)
    n = np.repeat([15, 30, 60, 120], 5)
    half = 0.4 / np.sqrt(n) * np.exp(rng.normal(0, 0.05, n.size))
    law = power.fit_law(n, np.full(n.size, 4), half)
    assert law.b == 0 and math.sqrt(law.a) == pytest.approx(0.4, rel=0.05)
    assert power.exponent(n, half) == pytest.approx(-0.5, abs=0.05)


def test_paired_bootstrap_half_width_is_the_normal_one():
    rng = np.random.default_rng(1)
    a, b = rng.normal(0.5, 0.3, 400), rng.normal(0.5, 0.3, 400)
    mean, half = power.paired_bootstrap(a, b, seed=0)
    assert mean == pytest.approx((a - b).mean())
    assert half == pytest.approx(1.96 * (a - b).std() / 20, rel=0.08)


def test_fit_law_refuses_nothing_to_fit():
    with pytest.raises(ValueError, match="finite positive"):
        power.fit_law([10], [4], [float("nan")])


# ------------------------------------------------------------------------ curve and report
def _curve() -> pd.DataFrame:
    rows = []
    for quantity, (a, b) in {"roc_auc": (0.01, 0.04), "hand_difference": (0.1, 0.2),
                             "rl_minus_best_qc": (0.3, 0.0)}.items():  # fmt: skip
        for axis, n, t in [("objects", 10, 8), ("objects", 20, 8), ("objects", 40, 8),
                           ("trials", 40, 1), ("trials", 40, 2), ("trials", 40, 4)]:
            rows.append({"quantity": quantity, "axis": axis, "objects": n, "trials": t,
                         "replicate": 0, "estimate": 0.1,
                         "half_width": math.sqrt((a + b / t) / n)})  # fmt: skip
    return pd.DataFrame(rows)


def test_power_curve_measures_both_axes_on_real_subsamples(grips):
    from grip_env.config import Config

    config = Config().override(learning={"folds": 3, "repeats": 1})
    fewer = power.subsample(grips, objects=20, seed=1)
    curve = power.power_curve(grips, config, objects=(10, 30), trials=(2, 8), replicates=2,
                              model="logreg", trials_table=fewer)
    assert set(curve["quantity"]) == {"roc_auc", "hand_difference"}
    counts = curve.groupby(["axis", "objects", "trials"]).size().to_dict()
    # 2 replicates per size (a whole table too: other folds), 2 quantities each
    assert set(counts.values()) == {4}
    assert set(counts) == {("objects", 10, 8), ("objects", 30, 8), ("trials", 20, 2),
                           ("trials", 20, 8)}
    assert (curve["half_width"] > 0).all() and (curve["seconds"] > 0).all()
    whole = curve[(curve["axis"] == "objects") & (curve["objects"] == 30)
                  & (curve["quantity"] == "roc_auc")]
    assert whole["half_width"].nunique() == 2  # the replicates' folds differ


def test_report_section_renders_the_curve_and_the_projection(tmp_path):
    summary = power.summarise_curve(_curve())
    assert summary["projection"]["rl_minus_best_qc"]["inf"] == math.ceil(0.3 / 0.06**2)
    (tmp_path / "power").mkdir()
    (tmp_path / "power" / "power.json").write_text(json.dumps(summary))
    plot_power(summary, tmp_path / "power" / "power.png")
    assert (tmp_path / "power" / "power.png").stat().st_size > 5000
    _study_results(tmp_path)
    report = Report("t")
    power_section(report, tmp_path)
    text = report.to_markdown()
    assert "Statistical power" in text and "![" in text and "power/power.png" in text
    assert "best model's ROC-AUC" in text and "objects needed" in text
    mean, half = power.paired_bootstrap(np.array(RL), np.array(BEST_QC), seed=0)
    needed = math.ceil(40 * (half / 0.06) ** 2)
    verdict = "yes" if half <= 0.06 else "no"
    row = f"| {mean:.3f} | {half:.3f} | 40 | 0.060 | {verdict} | {needed} |"
    assert f"| RL − best Q_C (held out) {row}" in text


def test_report_section_without_a_curve_says_how_to_get_one(tmp_path):
    _study_results(tmp_path)
    report = Report("t")
    power_section(report, tmp_path)
    text = report.to_markdown()
    assert "grip-env power --data" in text and "power/power.png" not in text
    assert "| best model's ROC-AUC | 0.700 | 0.060 | 40 | 0.030 | no | 160 |" in text


RL = [0.0, 1.0, 0.5, 1.0, 0.2, 0.9, 1.0, 0.0, 0.7, 1.0]
BEST_QC = [0.1] * 10


def _study_results(out):
    (out / "classifiers").mkdir()
    (out / "selector").mkdir()
    auc = {"mean": 0.7, "ci": [0.64, 0.76]}
    (out / "classifiers" / "metrics.json").write_text(json.dumps(
        {"models": {"svm": {"roc_auc": auc}, "random": {"roc_auc": {"mean": 0.5, "ci": [0, 1]}}},
         "cv": {"n_objects": 40}}))
    selector = {"policies": {"rl": {"per_object": RL}, "best_qc": {"per_object": BEST_QC}},
                "split": {"train": ["x"] * 30, "test": ["y"] * 10, "seed": 0}}
    (out / "selector" / "selector.json").write_text(json.dumps(selector))


# ------------------------------------------------------------------------------------- CLI
@pytest.mark.parametrize("args, fragment", [
    (["--objects", "10,a"], "'a' is not a positive integer"),
    (["--trials", "0"], "--trials"),
    (["--model", "tree"], "unknown model"),
])
def test_power_cli_refuses_bad_sizes_before_reading_data(tmp_path, args, fragment):
    assert_refused(*cli("power", "--data", tmp_path / "none", "--out", tmp_path / "o", *args),
                   fragment)


def test_power_cli_refuses_a_missing_dataset_and_too_many_objects(tmp_path, generated_dataset_dir):
    assert_refused(*cli("power", "--data", tmp_path / "none", "--out", tmp_path / "o"), "none")
    assert_refused(*cli("power", "--data", generated_dataset_dir, "--out", tmp_path / "o",
                        "--objects", "999"), "999")


def test_power_cli_writes_the_curve(tmp_path, generated_dataset_dir):
    code, output = cli("power", "--data", generated_dataset_dir, "--out", tmp_path / "p",
                       "--model", "logreg", "--objects", "6", "--trials", "1",
                       "--replicates", "1", "--seed", "3")
    assert code == 0, output
    summary = json.loads((tmp_path / "p" / "power.json").read_text())
    assert set(summary["laws"]) == {"roc_auc", "hand_difference"}
    assert (tmp_path / "p" / "power.png").exists() and "wrote" in output


def test_a_quantity_no_subsample_can_measure_is_named_not_fitted(tmp_path):
    curve = _curve()
    curve.loc[curve["quantity"] == "rl_minus_best_qc", "half_width"] = 0.0  # too few objects
    summary = power.summarise_curve(curve)
    assert summary["unmeasured"] == ["rl_minus_best_qc"]
    assert set(summary["laws"]) == {"roc_auc", "hand_difference"}
    assert "rl_minus_best_qc" not in summary["projection"]
    plot_power(summary, tmp_path / "power.png")
    curve["half_width"] = float("nan")
    with pytest.raises(ValueError, match=r"no subsample of this dataset \(40 objects at most\)"):
        power.summarise_curve(curve)


def test_report_section_takes_the_leaderboards_paired_rl_difference_and_the_datasets_trials(
        tmp_path):
    """A study on the standard dataset has no dataset/ folder: the trials come from the dataset
    data.json names; the RL row is the leaderboard's paired difference over every seed."""
    _study_results(tmp_path)
    data = tmp_path / "elsewhere"
    data.mkdir()
    (data / "manifest.json").write_text(json.dumps({"trials": 3}))
    (tmp_path / "data.json").write_text(json.dumps({"dataset": str(data)}))
    (tmp_path / "benchmark").mkdir()
    board = {"reference": "best_qc", "methods": {"rl": {"success_difference_vs_reference": {
        "estimate": 0.033, "ci": [0.002, 0.066]}}}}
    (tmp_path / "benchmark" / "leaderboard.json").write_text(json.dumps(board))
    report = Report("t")
    power_section(report, tmp_path)
    text = report.to_markdown()
    assert "at 3 trials per grip" in text
    assert "| RL − best Q_C (held out) | 0.033 | 0.032 | 40 | 0.060 | yes | 12 |" in text
