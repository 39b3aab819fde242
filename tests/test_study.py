"""The main job end to end on the quick profile: every stage runs and reports; a rerun that adds a
model recomputes only the stages that read it, on the same dataset; the README block is the run's;
a signal stops it cleanly."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
from PIL import Image
from typer.testing import CliRunner

from classifiers.report.readme import (
    BEGIN,
    END,
    LEADERBOARD_BEGIN,
    LEADERBOARD_END,
    interval_text,
    readme_block,
)
from grip_env.cli import _register_commands, app
from grip_env.envs import GripSelectEnv

QUICK_MODELS = ["logreg", "knn", "rank_qc", "random"]


@pytest.mark.slow
@pytest.mark.parametrize("key, value", [("ablation_model", "forest"), ("models", ("svm", "nope")),
                                        ("regressors", ("svr2",)), ("rankers", ("ndcg",))])
def test_an_unknown_learner_is_refused_before_the_dataset(tmp_path, key, value):
    from classifiers.experiments.study import run_study
    from grip_env.config import Config

    config = Config().override(learning={key: value})
    bad = value if isinstance(value, str) else value[-1]
    with pytest.raises(ValueError, match=rf"^learning\.{key}: unknown model '{bad}'"):
        run_study(config, tmp_path / "run", log=lambda _: None)
    assert not (tmp_path / "run").exists()


def test_quick_study_reports_and_a_rerun_recomputes_only_what_changed(tmp_path):
    _register_commands()
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "--quick", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "--quick sets " in result.output and "learning.models=logreg,knn" in result.output
    report = (out / "report.md").read_text()
    for section in ("## Dataset", "## Features and outcomes", "## Grasp ranks against",
                    "## Classifiers", "## Ablation", "## RL selector", "## Leaderboard",
                    "## Parameters", "## Planning on the rendered contour against the true one",
                    "## Image models: what the twelve measures miss"):
        assert section in report
    assert "Not run." not in report and "Stage provenance" in report
    assert (out / "report.html").read_text().startswith("<!doctype html>")
    for figure in ("gallery", "grip_images", "feature_distributions", "correlations",
                   "success_by_Q_C"):
        with Image.open(out / "figures" / f"{figure}.png") as image:
            assert image.size[0] > 300 and image.size[1] > 200
    metrics = json.loads((out / "classifiers" / "metrics.json").read_text())
    assert list(metrics["models"]) == QUICK_MODELS
    selector = json.loads((out / "selector" / "selector.json").read_text())
    assert "oracle" in selector["policies"]
    _assert_one_split(out, metrics, selector)
    _assert_retry_selector_on_the_boards(out)
    manifest = (out / "dataset" / "manifest.json").read_text()

    config = tmp_path / "more.yaml"
    config.write_text("learning:\n  models: [" + ", ".join([*QUICK_MODELS, "svm"]) + "]\n")
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{BEGIN}\nold numbers\n{END}\n\nafter\n")
    page = tmp_path / "docs" / "benchmark.md"
    page.parent.mkdir()
    page.write_text(f"# b\n\n{LEADERBOARD_BEGIN}\nold board\n{LEADERBOARD_END}\n")
    again = CliRunner().invoke(app, ["study", "--quick", "--config", str(config), "--out",
                                     str(out), "--update-readme", "--readme", str(readme)])
    assert again.exit_code == 0, again.output
    assert "keeps learning.models from the config" in again.output
    assert "dataset: reusing" in again.output
    assert (out / "dataset" / "manifest.json").read_text() == manifest  # not regenerated
    assert "classifiers: learning changed, recomputing" in again.output
    assert "selector: learning.models changed, recomputing" in again.output
    assert "selector_retry: learning.models changed, recomputing" in again.output
    assert "ablation: reusing" in again.output and "calibration: reusing" in again.output
    assert "benchmark: learning changed, recomputing" in again.output
    assert (out / "benchmark" / "leaderboard.json").exists()
    assert "perception: reusing" in again.output and "images: reusing" in again.output
    metrics = json.loads((out / "classifiers" / "metrics.json").read_text())
    assert list(metrics["models"]) == [*QUICK_MODELS, "svm"]
    assert "| svm |" in (out / "report.md").read_text()
    stage = json.loads((out / "classifiers" / "stage.json").read_text())
    assert stage["inputs"]["learning"]["models"][-1] == "svm"
    _assert_readme_is_the_run(readme, metrics, json.loads(
        (out / "selector" / "selector.json").read_text()))
    board = json.loads((out / "benchmark" / "leaderboard.json").read_text())
    if board.get("methods"):  # the benchmark page shows the run's leaderboard
        text = page.read_text()
        assert "old board" not in text and "Split `" in text and "| best_qc |" in text


def _assert_retry_selector_on_the_boards(out: Path) -> None:
    """The quick dataset records every trial, so the retry selector is trained for three
    attempts and scored on both boards by the grips it picks after each failure."""
    retry = json.loads((out / "selector_retry" / "selector.json").read_text())
    assert retry["max_attempts"] == 3 and "rl" in retry["policies"]
    scores = pd.read_parquet(out / "selector_retry" / "scores.parquet")
    assert set(scores["method"]) == {"rl_retry"}
    for (_, _), order in scores.groupby(["object_id", "seed"])["score"]:
        # an order, not probabilities: count, count - 1, ... down the slots it picks in turn
        assert sorted(order.to_numpy()) == list(range(1, len(order) + 1))
    board = json.loads((out / "benchmark" / "leaderboard.json").read_text())
    if board.get("methods"):
        assert "environment steps" in board["methods"]["rl_retry"]["budget"]["text"]
        assert "rl_retry" in board["retry"]["methods"]


def _assert_one_split(out: Path, metrics: dict, selector: dict) -> None:
    """The env's test objects, the classifiers' held-out objects and the selector's are one set."""
    env = GripSelectEnv(data=out / "dataset", split="test", config=_quick_config())
    assert list(env.object_ids) == metrics["held_out"]["split"]["test"]
    assert set(selector["split"]["test"]) <= set(env.object_ids)
    assert selector["split"]["train"] == metrics["held_out"]["split"]["train"]
    ablation = json.loads((out / "ablation" / "ablation.json").read_text())
    assert ablation["held_out"]["split"] == metrics["held_out"]["split"]


def _quick_config():
    from classifiers.experiments.study import study_config
    from grip_env.config import Config

    return study_config(Config(), quick=True)


def _assert_readme_is_the_run(readme: Path, metrics: dict, selector: dict) -> None:
    block = readme_block(readme)
    assert "old numbers" not in block and readme.read_text().endswith("\nafter\n")
    for name, scores in metrics["models"].items():
        assert (f"| {name} | {interval_text(scores['roc_auc'], 2)} | "
                f"{interval_text(scores['top1_success'], 2)} |") in block
    for name, scores in selector["policies"].items():
        assert f"| {name} | {interval_text(scores['success_rate'], 2)} |" in block
    assert "**Does a learned pick beat best-Q_C, and best-Q_G?**" in block
    # the figures beside the README are this run's, as the committed README's test checks;
    # its gallery line is the published one
    from test_published_results import _check_one_run

    from classifiers.report.published import GALLERY, figure_markdown

    readme.write_text(figure_markdown(GALLERY) + "\n" + readme.read_text())
    _check_one_run(readme)


def test_study_refuses_a_bad_config(tmp_path):
    _register_commands()
    bad = tmp_path / "bad.yaml"
    bad.write_text("grasp:\n  mu: -1\n")
    result = CliRunner().invoke(app, ["study", "--config", str(bad), "--out", str(tmp_path / "s")])
    assert result.exit_code == 2
    assert "grasp.mu" in result.output


def test_update_readme_refuses_a_readme_without_the_markers(tmp_path):
    _register_commands()
    readme = tmp_path / "README.md"
    readme.write_text("# no block\n")
    from classifiers.report.readme import update_readme

    with pytest.raises(ValueError, match="has no results block"):
        update_readme(readme, "x")
    result = CliRunner().invoke(app, ["study", "--quick", "--update-readme", "--readme",
                                      str(tmp_path / "missing.md"), "--out", str(tmp_path / "s")])
    assert result.exit_code == 2 and "is not a file" in result.output


@pytest.mark.slow
def test_sigterm_stops_a_quick_study_cleanly(tmp_path):
    out = tmp_path / "study"
    command = [sys.executable, "-c", "from grip_env.cli import main; main()", "study", "--quick",
               "--out", str(out)]
    run = subprocess.Popen(command, start_new_session=True, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not (out / "dataset" / "manifest.json").exists():
        assert run.poll() is None, run.communicate()
        assert time.monotonic() < deadline, "the study never started its dataset"
        time.sleep(0.05)
    sent = time.monotonic()
    run.send_signal(signal.SIGTERM)
    try:
        _, stderr = run.communicate(timeout=30)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 128 + signal.SIGTERM, stderr
    assert time.monotonic() - sent < 5.0
    assert stderr.strip().splitlines()[-1] == (
        f"interrupted by SIGTERM: stopped cleanly; rerun the same command to finish {out}")
    assert "Traceback" not in stderr
