"""Every trial's outcome by trial index: recorded by ``generate``, kept through packing and
loading, absent (with a clear error) from older datasets, and re-simulated for the standard
dataset exactly as its summaries say."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from grip_env.columns import DATASET_COLUMNS, trial_columns
from grip_env.config import Config
from grip_env.dataset import generate, load
from grip_env.dataset.jobs import with_outcomes
from grip_env.dataset.packing import pack
from grip_env.dataset.trial_outcomes import (
    TrialMismatchError,
    check_summaries,
    per_trial_outcomes,
    read_trial_shards,
    resimulation_order,
    with_trial_outcomes,
)
from grip_env.sim.disturbance import reached
from grip_env.sim.execution import trial_summary


def test_generate_records_every_trial_matching_its_summaries(generated_grips: pd.DataFrame,
                                                            ) -> None:
    trials = int(generated_grips["trials"].iloc[0])
    assert list(generated_grips.columns) == [*DATASET_COLUMNS, *trial_columns(trials)]
    success, robust = per_trial_outcomes(generated_grips)
    summary = trial_summary(robust, success)
    for name in ("trials", "successes", "robustness_mean", "robustness_std"):
        assert np.array_equal(summary[name], generated_grips[name].to_numpy()), name  # exact
    assert np.array_equal(success.mean(axis=1), generated_grips["success_rate"].to_numpy())
    assert np.array_equal(success, reached(robust, 64.0))  # the reference held, trial by trial


def test_packing_keeps_the_trial_columns(generated_dataset_dir: Path, tmp_path: Path) -> None:
    copy = shutil.copytree(generated_dataset_dir, tmp_path / "d")
    before = load(copy)
    pack(copy)
    pd.testing.assert_frame_equal(load(copy), before)


def test_an_older_dataset_loads_without_them(tmp_path: Path) -> None:
    from test_dataset import run

    grips = load(run(tmp_path / "old"))  # its job writes summaries only, as before
    assert list(grips.columns) == list(DATASET_COLUMNS)
    with pytest.raises(ValueError, match=r"records no per-trial outcomes.*trial_outcomes"):
        per_trial_outcomes(grips)


def test_a_dataset_resumed_across_the_change_keeps_what_every_object_has(tmp_path: Path) -> None:
    from test_dataset import CONFIG, toy_job

    def with_trials(task):  # type: ignore[no-untyped-def]
        rows = toy_job(task)
        n, t = len(rows), CONFIG.dataset.trials
        return with_outcomes(rows, rows, task.object_id, (np.zeros((n, t)), np.zeros((n, t), bool)))

    out = tmp_path / "mixed"
    generate(CONFIG, out, objects=3, workers=1, progress=False, job=toy_job)
    generate(CONFIG, out, objects=5, workers=1, progress=False, job=with_trials, overwrite=True)
    assert list(load(out).columns) == [*DATASET_COLUMNS, *trial_columns(CONFIG.dataset.trials)]


def test_with_outcomes_refuses_a_wrong_shape() -> None:
    rows = pd.DataFrame({c: [0.0] for c in DATASET_COLUMNS}).assign(object_id="a", grip_id="1")
    summary = {"trials": [2], "successes": [0], "robustness_mean": [0.0], "robustness_std": [0.0]}
    with pytest.raises(ValueError, match="grips x trials"):
        with_outcomes(rows, summary, "a", (np.zeros((2, 2)), np.zeros((2, 2), bool)))


def test_a_trial_that_does_not_give_the_summary_is_refused(generated_grips: pd.DataFrame) -> None:
    success, robust = per_trial_outcomes(generated_grips)
    check_summaries("x", generated_grips, robust, success)
    robust = robust.copy()
    robust[0, 0] = np.nextafter(robust[0, 0], np.inf)  # one unit in the last place
    with pytest.raises(TrialMismatchError, match="another robustness_"):
        check_summaries("x", generated_grips, robust, success)
    flipped = success.copy()
    flipped[0, 0] = ~flipped[0, 0]
    with pytest.raises(TrialMismatchError, match="another successes"):
        check_summaries("x", generated_grips, per_trial_outcomes(generated_grips)[1], flipped)


# ----------------------------------------------------------------------------- the standard one
def test_standard_order_is_split_v4_first() -> None:
    from classifiers.experiments.benchmark.split import STANDARD_TEST_OBJECTS_V4
    from grip_env.datasets import load_standard

    table = load_standard()
    held_out, training = resimulation_order(table, Config.model_validate(
        table.attrs["manifest"]["config"]))
    assert tuple(held_out) == STANDARD_TEST_OBJECTS_V4
    assert len(training) == 510 - 128 and not set(held_out) & set(training)


def test_the_standard_dataset_records_every_trial_as_its_summaries_say() -> None:
    from grip_env.datasets import load_standard

    table = load_standard()
    assert list(table.columns)[-10:] == list(trial_columns(5))
    assert table["object_id"].nunique() == 510
    success, robust = per_trial_outcomes(table)
    for object_id, group in table.groupby("object_id", sort=False):  # bit for bit
        at = group.index.to_numpy()
        check_summaries(str(object_id), group, robust[at], success[at])
    assert with_trial_outcomes(table) is table  # nothing more to add


@pytest.mark.slow
def test_record_trials_reproduces_a_committed_shard(tmp_path: Path) -> None:
    from grip_env.dataset.trial_outcomes import record_trials
    from grip_env.datasets import standard_path

    found = record_trials(standard_path(), tmp_path, limit=1, progress=False)
    assert found.new_objects == 1 and found.held_out_done == 1
    again = read_trial_shards(tmp_path)
    shipped = load(standard_path())
    shipped = shipped.loc[shipped["object_id"] == again["object_id"].iloc[0], list(again.columns)]
    pd.testing.assert_frame_equal(again, shipped.reset_index(drop=True), check_dtype=False,
                                  check_categorical=False)


def test_the_command_refuses_another_datasets_folder(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    from grip_env.dataset.trial_outcomes import INDEX_FILE, main

    (tmp_path / INDEX_FILE).write_text('{"fingerprint": "other", "label_model": "x", '
                                       '"trials": 5, "objects": {}}')
    before = sorted(tmp_path.iterdir())
    with pytest.raises(SystemExit) as stop:
        main(["standard", "--out", str(tmp_path), "--objects", "1"])
    assert stop.value.code == 2
    error = capsys.readouterr().err.strip().splitlines()
    assert len(error) == 1 and error[0].startswith("error: ") and "another dataset" in error[0]
    assert sorted(tmp_path.iterdir()) == before  # nothing written


def test_validate_checks_the_trials_summarise_to_the_row(generated_dataset_dir: Path,
                                                         tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    from grip_env.dataset import validate
    from grip_env.dataset.files import sha256_of
    from grip_env.dataset.manifest import read_manifest, write_manifest

    copy = shutil.copytree(generated_dataset_dir, tmp_path / "d")
    assert validate(copy) == []
    manifest = read_manifest(copy)
    object_id, record = next(iter(manifest["shards"].items()))
    shard = copy / record["file"]
    table = pq.read_table(shard)
    frame = table.to_pandas()
    frame["trial_success_0"] = ~frame["trial_success_0"]  # one trial's outcome changed
    pq.write_table(pa.Table.from_pandas(frame, schema=table.schema, preserve_index=False), shard)
    manifest["shards"][object_id]["sha256"] = sha256_of(shard)
    write_manifest(copy, manifest)
    assert any("successes is not the summary of trial_*_0..1" in p for p in validate(copy))


def _without_trials(directory: Path) -> None:
    """Make a generated dataset look as one made before the per-trial columns: pack it and
    rewrite its packed file with the summaries only."""
    import pyarrow.parquet as pq

    from grip_env.dataset.files import sha256_of
    from grip_env.dataset.manifest import read_manifest, write_manifest
    from grip_env.dataset.shards import GRIP_SCHEMA

    packed = pack(directory)
    pq.write_table(pq.read_table(packed).select(GRIP_SCHEMA.names), packed)
    manifest = read_manifest(directory)
    for record in manifest["shards"].values():
        record["sha256"] = sha256_of(packed)
    write_manifest(directory, manifest)


@pytest.mark.slow
def test_an_older_dataset_gets_its_trials_back_bit_for_bit(generated_dataset_dir: Path,
                                                          tmp_path: Path) -> None:
    """Re-simulated and attached, a dataset stripped of its trial columns is the one
    ``generate`` wrote, every trial in place."""
    from grip_env.dataset.trial_outcomes import attach_trials, record_trials

    original = load(generated_dataset_dir)
    old = shutil.copytree(generated_dataset_dir, tmp_path / "old")
    _without_trials(old)
    assert list(load(old).columns) == list(DATASET_COLUMNS)
    with pytest.raises(ValueError, match="holds no per-trial outcomes"):
        attach_trials(old, tmp_path / "nothing")
    found = record_trials(old, tmp_path / "trials", limit=2, progress=False)
    assert found.objects_done == 2
    with pytest.raises(ValueError, match="finish the re-simulation first"):
        attach_trials(old, tmp_path / "trials")
    record_trials(old, tmp_path / "trials", progress=False)  # resumes: the rest
    attach_trials(old, tmp_path / "trials")
    pd.testing.assert_frame_equal(load(old), original, check_exact=True)
    from grip_env.dataset import validate

    assert validate(old) == []


def test_a_table_that_records_its_trials_is_returned_as_it_is(generated_grips: pd.DataFrame,
                                                               tmp_path: Path) -> None:
    """A dataset ``generate`` writes holds every trial already: nothing is merged twice."""
    from grip_env.dataset.trial_outcomes import with_trial_outcomes

    assert with_trial_outcomes(generated_grips, tmp_path / "no-such-folder") is generated_grips
