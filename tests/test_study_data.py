"""A study on a given dataset (``--data``): it learns under the dataset's own recipe and first
re-simulates a seeded sample of it (the replication stage)."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from classifiers.experiments.study import (
    REPLICATION,
    REPLICATION_GRIPS_QUICK,
    given_dataset,
    run_stage,
    study_dataset,
)
from grip_env.cli import _register_commands, app
from grip_env.config import Config


def _quiet(_: str) -> None:
    pass


def test_a_given_dataset_is_learnt_under_its_own_recipe(generated_dataset_dir, tmp_path):
    mine = Config().override(dataset={"trials": 7, "workers": 2}, learning={"folds": 3},
                             sim={"ramp_ratio": 1.5})
    run = given_dataset(mine, generated_dataset_dir, tmp_path, quick=False, log=_quiet)
    assert run.config.dataset.trials == 2  # the dataset's, not the user's 7
    assert run.config.sim.ramp_ratio == Config().sim.ramp_ratio
    assert run.config.learning.folds == 3 and run.config.dataset.workers == 2
    assert run.table["object_id"].nunique() == 8  # basic 4 + procedural 4


def test_the_replication_stage_finds_the_dataset_reproduced_and_is_reused(
        generated_dataset_dir, tmp_path):
    run = given_dataset(Config(), generated_dataset_dir, tmp_path, quick=True, log=_quiet)
    assert set(run_stage(REPLICATION, run)) == {"replication"}
    found = json.loads((tmp_path / REPLICATION.result).read_text())
    assert found["grips"] == REPLICATION_GRIPS_QUICK and found["objects"] == 2
    assert found["identical"] and found["outcomes_identical"] == REPLICATION_GRIPS_QUICK
    assert found["candidates_identical"] == 2 and found["differences"] == []
    assert run_stage(REPLICATION, run) == {}  # same dataset, same seed: reused


def test_a_study_folder_names_the_dataset_it_learnt_on(tmp_path):
    assert study_dataset(tmp_path) == tmp_path / "dataset"
    (tmp_path / "data.json").write_text(json.dumps({"dataset": "/data/standard"}))
    assert str(study_dataset(tmp_path)) == "/data/standard"


def test_study_with_a_folder_that_holds_no_dataset_writes_nothing(tmp_path):
    _register_commands()
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "--data", str(tmp_path), "--out", str(out)])
    assert result.exit_code == 2
    assert "holds no grip-env dataset" in result.output
    assert not out.exists()


def test_the_study_learns_on_the_standard_dataset_unless_told_to_generate(tmp_path):
    from grip_env.cli.study import study_data
    from grip_env.datasets import SHIPPED

    assert study_data(tmp_path, regenerate=False, quick=False) == tmp_path
    assert study_data(None, regenerate=True, quick=False) is None
    assert study_data(None, regenerate=False, quick=True) is None  # the tiny profile generates
    assert study_data(tmp_path, regenerate=False, quick=True) == tmp_path
    manifest = json.loads((SHIPPED / "manifest.json").read_text())
    if manifest.get("complete"):
        assert study_data(None, regenerate=False, quick=False) == SHIPPED


def test_study_with_both_data_and_regenerate_writes_nothing(tmp_path):
    _register_commands()
    out = tmp_path / "study"
    result = CliRunner().invoke(app, ["study", "--data", str(tmp_path), "--regenerate",
                                      "--out", str(out)])
    assert result.exit_code == 2
    assert "--regenerate: give one" in result.output.splitlines()[-1]
    assert not out.exists()
