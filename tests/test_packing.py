"""Packing a finished dataset into one file: the same grips load, validate and resume."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd
import pytest

from grip_env.dataset import generate, load, validate
from grip_env.dataset.packing import main, pack
from grip_env.dataset.shards import PACKED_FILE


@pytest.fixture
def packed(generated_dataset_dir: Path, tmp_path: Path) -> Path:
    copy = tmp_path / "data"
    shutil.copytree(generated_dataset_dir, copy)
    pack(copy)
    return copy


def test_a_packed_dataset_loads_the_same_grips_from_one_file(generated_dataset_dir, packed):
    pd.testing.assert_frame_equal(load(packed), load(generated_dataset_dir))
    assert [p.name for p in (packed / "grips").iterdir()] == ["grips.parquet"]
    records = json.loads((packed / "manifest.json").read_text())["shards"].values()
    assert {r["file"] for r in records} == {PACKED_FILE}
    assert sorted(r["offset"] for r in records) == sorted(
        sum(r["rows"] for r in records if r["offset"] < record["offset"]) for record in records)


def test_a_packed_dataset_validates_clean_and_a_changed_byte_is_found(packed):
    assert validate(packed) == []
    path = packed / PACKED_FILE
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    assert any("SHA-256 differs" in line for line in validate(packed))
    with pytest.raises(ValueError, match="corrupt"):
        load(packed)


def test_a_manifest_placing_rows_past_the_packed_file_is_refused(packed):
    manifest = json.loads((packed / "manifest.json").read_text())
    next(iter(manifest["shards"].values()))["offset"] = 10**6
    (packed / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ValueError, match="places rows"):
        load(packed)
    assert any("places rows" in line for line in validate(packed))


def test_packing_twice_or_generating_again_changes_nothing(generated_dataset_dir, packed):
    before = (packed / PACKED_FILE).read_bytes()
    pack(packed)
    manifest = json.loads((packed / "manifest.json").read_text())
    from grip_env.config import Config

    config = Config().override(
        objects={"set": "basic", "procedural_count": 4, "mesh_count": 0},
        dataset={"trials": 2, "max_grips_per_object": 6, "workers": 1},
    )
    generate(config, packed, progress=False)  # finished: nothing to simulate
    assert (packed / PACKED_FILE).read_bytes() == before
    assert json.loads((packed / "manifest.json").read_text())["shards"] == manifest["shards"]
    pd.testing.assert_frame_equal(load(packed), load(generated_dataset_dir))


def test_an_unfinished_dataset_is_not_packed(generated_dataset_dir, tmp_path, capsys):
    copy = tmp_path / "data"
    shutil.copytree(generated_dataset_dir, copy)
    manifest = json.loads((copy / "manifest.json").read_text())
    manifest["shards"] = dict(list(manifest["shards"].items())[:1])
    manifest["complete"] = False
    (copy / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(SystemExit) as exit_:
        main([str(copy)])
    assert exit_.value.code == 2
    assert "unfinished (1 of" in capsys.readouterr().err
    assert not (copy / PACKED_FILE).exists()
