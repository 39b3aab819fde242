"""A dataset of another label model: ``validate``, the envs, ``train`` and ``benchmark`` warn in
one line and still run; the study refuses it. A dataset of this code's label model gets neither.

The datasets are cheap (``toy_job`` rows, or the benchmark's synthetic grips replayed as a
dataset); "another label model" is the manifest edited to another id, or without one.
"""

from __future__ import annotations

import functools
import json
import shutil
import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pandas as pd
import pytest
from cli_runs import assert_refused, cli
from generate_runs import write_config
from test_dataset import toy_job

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.benchmark.split import STANDARD_TEST_OBJECTS
from grip_env.config import Config
from grip_env.dataset import ObjectTask, generate, with_outcomes
from grip_env.label_model import LABEL_MODEL, UNRECORDED
from grip_env.objects import PlanarObject

OTHER = "2025.01-old"
#: The label model a test dataset records: this code's, another one, or none (an older dataset).
RECORDS = {"current": LABEL_MODEL, "other": OTHER, "unrecorded": None}
ONLY_QC = {"models": ("rank_qc",), "regressors": ("rank_qc",), "rankers": ("rank_qc",)}
FAST = Config().override(perception={"source": "polygon"},
                         dataset={"trials": 2, "max_grips_per_object": 4, "workers": 1},
                         learning={"folds": 2, "repeats": 1, "seeds": 1, **ONLY_QC})  # fmt: skip


def by_qc(table: pd.DataFrame) -> np.ndarray:
    """A benchmark method (``test_label_model:by_qc``): the best-Q_C pick."""
    return -table["Q_C"].to_numpy()


def _relabelled(source: Path, target: Path, label_model: str | None) -> Path:
    """A copy of dataset ``source`` whose manifest records ``label_model`` (None: no key)."""
    shutil.copytree(source, target)
    manifest = json.loads((target / "manifest.json").read_text())
    manifest.pop("label_model")
    if label_model is not None:
        manifest["label_model"] = label_model
    (target / "manifest.json").write_text(json.dumps(manifest))
    return target


def _variants(source: Path, folder: Path) -> dict[str, Path]:
    return {name: _relabelled(source, folder / name, value) for name, value in RECORDS.items()}


@pytest.fixture(scope="module")
def toy(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Three objects of ``toy_job`` rows (sound for ``validate``), in each label-model variant."""
    folder = tmp_path_factory.mktemp("toy")
    source = generate(FAST, folder / "source", objects=3, progress=False, job=toy_job)
    return _variants(source, folder)


def _replayed(table: pd.DataFrame, task: ObjectTask) -> pd.DataFrame:
    rows = table[table["object_id"] == task.object_id]
    return with_outcomes(rows, rows, task.object_id)


@pytest.fixture(scope="module")
def standard(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The benchmark's synthetic grips (the standard split's objects among them) as a dataset."""
    table = synthetic_grips(n_objects=30, grips=(6, 12), seed=4)
    names = [STANDARD_TEST_OBJECTS[i] if i < len(STANDARD_TEST_OBJECTS) else f"train_{i}"
             for i in range(30)]  # fmt: skip
    table["object_id"] = [names[int(i)] for i in table["object_id"]]
    square = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]])
    objects = [PlanarObject.from_polygon(square, name) for name in names]
    folder = tmp_path_factory.mktemp("standard")
    source = generate(FAST, folder / "source", objects=objects, progress=False,
                      job=functools.partial(_replayed, table))  # fmt: skip
    return _variants(source, folder)


def _warnings(output: str) -> list[str]:
    return [line for line in output.splitlines() if line.startswith("warning:")]


def _assert_warned(output: str, variant: str) -> None:
    """One ``warning:`` line naming the dataset's label model and this code's, for another
    label model; none for this code's."""
    found = _warnings(output)
    if variant == "current":
        assert found == [], output
    else:
        assert len(found) == 1, output
        assert repr(RECORDS[variant] or UNRECORDED) in found[0] and repr(LABEL_MODEL) in found[0]


@pytest.mark.parametrize("variant", RECORDS)
def test_validate_names_the_label_model_and_warns_but_passes(toy, variant):
    code, output = cli("validate", toy[variant])
    assert code == 0, output
    assert f"label model {RECORDS[variant] or UNRECORDED}" in output
    _assert_warned(output, variant)


@pytest.mark.parametrize("env_id", ["GripSelect-v0", "GripAccept-v0"])
@pytest.mark.parametrize("variant", ["other", "unrecorded"])
def test_replay_env_warns_once_for_another_label_model(toy, env_id, variant):
    with pytest.warns(UserWarning, match="label model") as caught:
        gymnasium.make(env_id, data=toy[variant]).close()
    assert len([w for w in caught if "label model" in str(w.message)]) == 1


@pytest.mark.parametrize("env_id", ["GripSelect-v0", "GripAccept-v0"])
def test_replay_env_is_silent_for_this_label_model(toy, env_id):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gymnasium.make(env_id, data=toy["current"]).close()
    assert not [w for w in caught if "label model" in str(w.message)]


@pytest.mark.parametrize("variant", ["current", "other"])
def test_train_warns_and_still_runs(standard, variant, tmp_path):
    code, output = cli("train", "--data", standard[variant], "--out", tmp_path / "train",
                       "--config", write_config(tmp_path, FAST))
    assert code == 0, output
    assert (tmp_path / "train" / "metrics.json").is_file()
    _assert_warned(output, variant)


@pytest.mark.parametrize("variant", ["current", "other"])
def test_benchmark_warns_and_still_runs(standard, variant, tmp_path):
    code, output = cli("benchmark", "test_label_model:by_qc", "--data", standard[variant],
                       "--out", tmp_path / "bench", "--reps", 100)  # fmt: skip
    assert code == 0, output
    assert (tmp_path / "bench" / "leaderboard.json").is_file()
    _assert_warned(output, variant)


@pytest.mark.parametrize("variant", ["other", "unrecorded"])
def test_study_refuses_a_dataset_of_another_label_model(toy, variant, tmp_path):
    from classifiers.experiments.study import run_study

    out = tmp_path / "study"
    shutil.copytree(toy[variant], out / "dataset")
    code, output = cli("study", "--regenerate", "--out", out)
    found = repr(RECORDS[variant] or UNRECORDED)
    assert_refused(code, output, found, repr(LABEL_MODEL), "does not mix label models",
                   "empty folder")  # fmt: skip
    with pytest.raises(ValueError, match="does not mix label models"):
        run_study(FAST, out, log=lambda _: None)
    assert sorted(p.name for p in out.iterdir()) == ["dataset"]  # nothing else was started


def test_study_accepts_this_label_model_and_a_new_folder(toy, tmp_path):
    from classifiers.experiments.study import check_label_model

    check_label_model(toy["current"])
    check_label_model(tmp_path / "nothing yet")
