"""``grip-env benchmark`` on any dataset (issue 35): the standard split when its objects have
grips, else a seeded split of the dataset's own objects named as not the standard one; an
explicit standard split refused with what to run instead; objects with no grips named as such;
a ``module:function`` method imported from the current folder, or a message saying where it was
looked for."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from cli_runs import assert_refused, cli

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.benchmark.split import (
    AUTO_SPLIT_NAME,
    STANDARD_SPLITS,
    DatasetObjects,
    auto_split,
    choose_split,
)
from grip_env.dataset.split import split_objects

PICK = "def pick(table):\n    return 0\n"


def _grips(ids: list[str], seed: int = 4) -> pd.DataFrame:
    """Synthetic grips (6 to 12 a object, 5 trials each) under the object ids ``ids``."""
    table = synthetic_grips(n_objects=len(ids), grips=(6, 12), seed=seed)
    table["object_id"] = [ids[int(i)] for i in table["object_id"]]
    table["grip_id"] = table["grip_id"].astype(str)
    return table


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A three-object dataset, as a parquet grip table."""
    path = tmp_path_factory.mktemp("small") / "grips.parquet"
    _grips(["square", "disc", "bean"]).to_parquet(path)
    return path


@pytest.fixture()
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A fresh current folder; ``sys.path`` restored afterwards (the loader prepends the cwd)."""
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.chdir(tmp_path)
    return tmp_path


def board(out: Path) -> dict:
    return json.loads((out / "leaderboard.json").read_text())


def test_small_dataset_is_scored_on_a_named_auto_split(small: Path, folder: Path) -> None:
    (folder / "issue35_pick.py").write_text(PICK)
    out = folder / "lb"
    code, output = cli("benchmark", "issue35_pick:pick", "--data", small, "--out", out,
                       "--reps", 200)  # fmt: skip
    assert code == 0, output
    assert f"split {AUTO_SPLIT_NAME} v0: not the standard split" in output
    split = board(out)["split"]
    assert split["name"] == AUTO_SPLIT_NAME and split["version"] == 0
    assert split["standard"] is False and "do not compare" in split["note"]
    _, test = split_objects(["square", "disc", "bean"], 0.25, 0)
    assert split["test_objects"] == list(test) and split["split_seed"] == 0
    markdown = (out / "leaderboard.md").read_text()
    assert AUTO_SPLIT_NAME in markdown and "not the standard split" in markdown
    code, output = cli("benchmark", "issue35_pick:pick", "--data", small, "--out",
                       folder / "lb1", "--reps", 200, "--seed", 1)  # fmt: skip
    assert code == 0, output
    assert board(folder / "lb1")["split"]["split_seed"] == 1


def test_explicit_standard_split_on_a_small_dataset_says_what_to_run(
    small: Path, folder: Path
) -> None:
    (folder / "issue35_pick2.py").write_text(PICK)
    out = folder / "never"
    code, output = cli("benchmark", "issue35_pick2:pick", "--data", small, "--out", out,
                       "--split", "standard")  # fmt: skip
    assert_refused(code, output, "lacks 127 of the 128", "grip-select-standard v4",
                   "not in it", "--split auto")  # fmt: skip
    assert "generate" not in output
    assert not out.exists()


def test_generated_dataset_gets_the_auto_split(generated_dataset_dir: Path, folder: Path) -> None:
    """A real dataset directory of 8 objects (the session's generated one)."""
    from grip_env.dataset import load

    table = load(generated_dataset_dir)
    rates = table.groupby("object_id")["success_rate"].nunique()
    rankable = set(rates.index[rates > 1])
    assert rankable, "the simulation gave every object one success rate"
    objects = DatasetObjects.of(table)
    seed = next(s for s in range(50) if rankable & set(auto_split(objects, s).test_objects))
    (folder / "issue35_pick3.py").write_text(PICK)
    out = folder / "lb"
    code, output = cli("benchmark", "issue35_pick3:pick", "--data", generated_dataset_dir,
                       "--out", out, "--reps", 200, "--seed", seed)  # fmt: skip
    assert code == 0, output
    split = board(out)["split"]
    assert split["name"] == AUTO_SPLIT_NAME and split["standard"] is False
    assert split["test_objects"] == list(auto_split(objects, seed).test_objects)
    retry = board(out)["retry"]  # a dataset generated now records every trial: the retry task
    assert retry["attempts"] == 3 and retry["objects"] == len(split["test_objects"])
    assert set(retry["methods"]) == set(board(out)["methods"]) >= {"best_qc", "oracle"}
    assert "Retry: success within m attempts" in (out / "leaderboard.md").read_text()


def _standard_like(without: str) -> pd.DataFrame:
    """Grips of every held-out object of v2 and v3 but ``without``, which the dataset's manifest
    records with no grips, plus training objects."""
    held = sorted(set(STANDARD_SPLITS[2].test_objects) | set(STANDARD_SPLITS[3].test_objects))
    ids = [oid for oid in held if oid != without] + [f"train_{i}" for i in range(6)]
    table = _grips(ids, seed=5)
    table.attrs["manifest"] = {"shards": {without: {"rows": 0},
                                          ids[0]: {"rows": int((table["object_id"] == ids[0])
                                                               .sum())}}}  # fmt: skip
    return table


def test_an_object_with_no_grips_is_named_and_auto_takes_the_version_that_fits() -> None:
    objects = DatasetObjects.of(_standard_like("urdf_518"))
    assert objects.without_grips == ("urdf_518",)
    assert objects.fitting_versions() == [2]
    split, note = choose_split(objects)
    assert (split.name, split.version) == ("grip-select-standard", 2)
    assert "of the 128 held-out objects of the standard split" in note  # v4, the latest
    assert "scored on v2" in note
    with pytest.raises(ValueError) as refused:
        choose_split(objects, "standard", version=3)
    message = str(refused.value)
    for fragment in ("lacks 1 of the 17", "urdf_518 is in it with no grips",
                     "--split-version 2", "--split auto"):  # fmt: skip
        assert fragment in message
    assert "generate" not in message and "\n" not in message
    assert choose_split(objects, "auto", version=2)[0].version == 2  # a version is explicit


def test_benchmark_method_records_the_fallback(folder: Path) -> None:
    from classifiers.experiments.benchmark import benchmark_method
    from grip_env.config import Config

    (folder / "issue35_pick4.py").write_text(PICK)
    found = benchmark_method(_standard_like("urdf_518"), ["issue35_pick4:pick"], "pick",
                             Config(), reps=100)  # fmt: skip
    assert found["split"]["version"] == 2 and found["split"]["standard"] is True
    assert "scored on v2" in found["split"]["note"]
    assert sorted(found["objects"] + found["degenerate_objects"]) == sorted(
        STANDARD_SPLITS[2].test_objects)  # fmt: skip


def test_auto_split_needs_two_objects() -> None:
    with pytest.raises(ValueError, match="at least 2 objects"):
        choose_split(DatasetObjects(("square",)))


def test_function_from_the_current_folder_in_a_fresh_process(small: Path, tmp_path: Path) -> None:
    """The installed ``grip-env`` script, run in the folder that holds ``mysel.py``."""
    (tmp_path / "mysel.py").write_text(PICK)
    script = Path(sys.executable).with_name("grip-env")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run([str(script), "benchmark", "mysel:pick", "--data", str(small),
                           "--out", "lb", "--reps", "100"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert board(tmp_path / "lb")["methods"]["pick"]["runs"] == 1


def test_a_module_not_found_names_the_folder_and_the_form(small: Path, folder: Path) -> None:
    out = folder / "never"
    assert_refused(*cli("benchmark", "issue35_nowhere:pick", "--data", small, "--out", out),
                   "no module 'issue35_nowhere'", str(folder), "'module:function'")  # fmt: skip
    (folder / "issue35_file.py").write_text(PICK)
    assert_refused(*cli("benchmark", "issue35_file.py:pick", "--data", small, "--out", out),
                   "without '.py': 'issue35_file:pick'")  # fmt: skip
    (folder / "issue35_needs.py").write_text("import issue35_absent_dependency\n" + PICK)
    assert_refused(*cli("benchmark", "issue35_needs:pick", "--data", small, "--out", out),
                   "importing 'issue35_needs'", "issue35_absent_dependency")  # fmt: skip
    (folder / "issue35_broken.py").write_text("raise RuntimeError('broken at import')\n")
    assert_refused(*cli("benchmark", "issue35_broken:pick", "--data", small, "--out", out),
                   "RuntimeError: broken at import")  # fmt: skip
    assert not out.exists()


def test_an_auto_split_shows_as_many_candidates_as_the_config_trains_on():
    objects = DatasetObjects(("a", "b", "c", "d"))
    assert auto_split(objects, 0).max_candidates == 64
    split, _ = choose_split(objects, seed=0, max_candidates=8)
    assert split.name == "auto-not-standard" and split.max_candidates == 8


def test_split_v4_holds_out_a_quarter_of_the_shipped_standard_datasets_objects() -> None:
    from classifiers.experiments.benchmark.split import DEFAULT_OBJECTS, STANDARD_SPLIT
    from grip_env.datasets import SHIPPED

    shipped = pd.read_parquet(SHIPPED / "grips", columns=["object_id"])["object_id"]
    assert DEFAULT_OBJECTS[4] == tuple(sorted(set(shipped.astype(str))))
    assert STANDARD_SPLIT.version == 4 and len(STANDARD_SPLIT.test_objects) == 128
    assert sum(oid.startswith("urdf_") for oid in STANDARD_SPLIT.test_objects) >= 30
