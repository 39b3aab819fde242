"""Tiny data gets a caution on the console, as the report gives one: ``train``, ``ablate`` and
``benchmark`` print intervals, and one line when there are too few objects to judge or a learner
predicted a constant."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml
from cli_runs import cli

from classifiers.evaluation.cross_validation import evaluate_models
from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.report.judge import FEW_OBJECTS, constant_scores, small_data_caution
from grip_env.config import LearningConfig

INTERVAL = re.compile(r"ROC-AUC \d\.\d{3} \[\d\.\d{3}, \d\.\d{3}\]")


def test_a_learner_that_predicts_a_constant_is_named() -> None:
    """hgb's leaves need 20 grips: on 8 objects of 3-5 grips its every prediction is the base
    rate, so every fold's ROC-AUC is exactly 0.5; logreg learns something."""
    table = synthetic_grips(n_objects=8, grips=(3, 5), seed=0)
    config = LearningConfig(folds=2, repeats=2)
    blocks = {name: summary["roc_auc"]
              for name, summary in evaluate_models(table, ["hgb", "logreg"], config=config)[
                  "models"].items()}  # fmt: skip
    assert blocks["hgb"]["mean"] == 0.5 and blocks["hgb"]["ci"] == [0.5, 0.5]
    assert constant_scores(blocks) == ["hgb"]
    assert small_data_caution(FEW_OBJECTS) is None
    assert "only 8 object(s)" in small_data_caution(8)


def test_benchmark_cautions_on_a_handful_of_held_out_objects(tmp_path: Path,
                                                              monkeypatch) -> None:  # fmt: skip
    path = tmp_path / "tiny.parquet"
    table = synthetic_grips(n_objects=8, grips=(4, 6), seed=1)
    table["grip_id"] = table["grip_id"].astype(str)
    table.to_parquet(path)
    (tmp_path / "pickers.py").write_text("def by_qc(table):\n    return -table['Q_C']\n")
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    code, output = cli("benchmark", "pickers:by_qc", "--data", path, "--out", tmp_path / "lb",
                       "--reps", 100)  # fmt: skip
    assert code == 0, output
    line = next(text for text in output.splitlines() if text.startswith("by_qc: top-1"))
    assert re.search(r"top-1 success \d\.\d{3} \[\d\.\d{3}, \d\.\d{3}\]", line), line
    assert line.endswith("no verdict"), line
    assert any(text.startswith("caution: ") and f"fewer than {FEW_OBJECTS}" in text
               for text in output.splitlines()), output  # fmt: skip


@pytest.mark.slow
def test_train_and_ablate_print_intervals_and_cautions(generated_dataset_dir: Path,
                                                       tmp_path: Path) -> None:  # fmt: skip
    """On the 8 generated objects: intervals beside each ROC-AUC, and the small-data caution."""
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump({"learning": {
        "models": ["logreg", "hgb"], "regressors": ["ridge"], "rankers": ["rank_qc"],
        "folds": 2, "repeats": 1, "seeds": 1, "ablation_model": "hgb"}}))  # fmt: skip
    for command in ("train", "ablate"):
        code, output = cli(command, "--data", generated_dataset_dir, "--out", tmp_path / command,
                           "--config", config)  # fmt: skip
        assert code == 0, output
        assert INTERVAL.search(output), output
        cautions = [line for line in output.splitlines() if line.startswith("caution: ")]
        assert any(f"fewer than {FEW_OBJECTS}" in line for line in cautions), output
