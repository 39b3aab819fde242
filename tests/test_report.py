"""The paper's analyses and the report writer, on hand-built tables with known answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from classifiers.report import analysis
from classifiers.report.document import Report


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
    report.text("a & b")
    report.table(pd.DataFrame({"m": [0.12345]}, index=pd.Index(["svm"], name="model")))
    report.figure("figures/a.png", "caption")
    md, page = report.write(tmp_path)
    text = md.read_text()
    assert "## Section" in text and "| model | m |" in text and "| svm | 0.123 |" in text
    assert "![caption](figures/a.png)" in text
    assert "title &lt;x&gt;" in page.read_text() and "a &amp; b" in page.read_text()
