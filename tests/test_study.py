"""The main job end to end on the quick profile: every stage runs, reports, and reruns reuse."""

from __future__ import annotations

import json

import pytest
from PIL import Image
from typer.testing import CliRunner

from grip_env.cli import _register_commands, app


@pytest.mark.slow
def test_quick_study_writes_a_full_report_and_reuses_stages(tmp_path):
    _register_commands()
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "--quick", "--out", str(out)])
    assert result.exit_code == 0, result.output
    report = (out / "report.md").read_text()
    for section in ("## Dataset", "## Features and outcomes", "## Grasp ranks against",
                    "## Classifiers", "## Ablation", "## RL selector", "## Parameters"):
        assert section in report
    assert "Not run." not in report
    assert (out / "report.html").read_text().startswith("<!doctype html>")
    for figure in ("gallery", "feature_distributions", "correlations", "success_by_Q_C"):
        with Image.open(out / "figures" / f"{figure}.png") as image:
            assert image.size[0] > 300 and image.size[1] > 200
    metrics = json.loads((out / "classifiers" / "metrics.json").read_text())
    assert set(metrics["models"]) == {"logreg", "knn", "rank_qc", "random"}
    selector = json.loads((out / "selector" / "selector.json").read_text())
    assert "oracle" in selector["policies"]

    again = CliRunner().invoke(app, ["study", "--quick", "--out", str(out)])
    assert again.exit_code == 0, again.output
    assert "classifiers: reusing" in again.output and "selector: reusing" in again.output


def test_study_refuses_a_bad_config(tmp_path):
    _register_commands()
    bad = tmp_path / "bad.yaml"
    bad.write_text("grasp:\n  mu: -1\n")
    result = CliRunner().invoke(app, ["study", "--config", str(bad), "--out", str(tmp_path / "s")])
    assert result.exit_code == 2
    assert "grasp.mu" in result.output
