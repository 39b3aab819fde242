"""``grip-env generate`` and ``grip-env validate`` from the command line, with the real job."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml
from typer.testing import CliRunner

from grip_env.cli import _register_commands, app
from grip_env.config import Config
from grip_env.dataset import load

_register_commands()
RUNNER = CliRunner()
SMALL = Config().override(dataset={"max_grips_per_object": 2, "trials": 2})


@pytest.fixture
def small_config(tmp_path: Path) -> Path:
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL.model_dump(mode="json")))
    return path


def cli(*args: str) -> tuple[int, str]:
    result = RUNNER.invoke(app, list(args))
    return result.exit_code, result.output


def test_help_lists_every_option() -> None:
    code, text = cli("generate", "--help")
    assert code == 0
    for option in ("--config", "--out", "--objects", "--trials", "--seed", "--workers",
                   "--backend", "--address", "--overwrite"):
        assert option in text
    assert cli("validate", "--help")[0] == 0


@pytest.mark.parametrize(("args", "message"), [
    (["--trials", "0"], "'--trials': Input should be greater than or equal to 1"),
    (["--workers", "0"], "'--workers': Input should be greater than or equal to 1"),
    (["--seed", "-1"], "'--seed': Input should be greater than or equal to 0"),
])
def test_a_count_or_seed_below_its_range_is_a_usage_error(
    tmp_path: Path, args: list[str], message: str
) -> None:
    """Refused by the range --help states (x>=1, x>=0): the entry point's one line says this."""
    result = RUNNER.invoke(app, ["generate", "--out", str(tmp_path / "d"), *args],
                           standalone_mode=False)
    assert result.exit_code != 0 and message in result.exception.format_message()
    assert not (tmp_path / "d").exists()


@pytest.mark.parametrize(("args", "message"), [
    (["--workers", "1000000000000"], "--workers: Input should be less than or equal to 1024"),
    (["--objects", "99999999999999999999"], "--objects: Input should be less than or equal to"),
    (["--address", "ray://host:10001"], "--address ray://host:10001 needs --backend ray"),
    (["--backend", "dask"], "unknown backend 'dask'"),
    (["--objects", "no_such_set"], "unknown object set 'no_such_set'"),
])
def test_bad_generate_input_exits_2_with_one_line(
    tmp_path: Path, args: list[str], message: str
) -> None:
    code, text = cli("generate", "--out", str(tmp_path / "d"), "--no-progress", *args)
    assert code == 2
    assert message in text and "Traceback" not in text
    assert len(text.strip().splitlines()) == 1


def test_unwritable_out_exits_2(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, text = cli("generate", "--out", str(blocker / "d"), "--objects", "1", "--no-progress")
    assert code == 2 and "not writable" in text


def test_validate_of_non_dataset_exits_2(tmp_path: Path) -> None:
    code, text = cli("validate", str(tmp_path))
    assert code == 2 and "not a grip-env dataset" in text


def _generate_command(config: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-c", "from grip_env.cli import main; main()", "generate",
            "--config", str(config), "--out", str(out), "--objects", "basic", "--seed", "5",
            "--workers", "1", "--no-progress", *extra]


@pytest.mark.slow
def test_killed_run_resumes_to_the_uninterrupted_dataset(
    tmp_path: Path, small_config: Path
) -> None:
    killed = tmp_path / "killed"
    process = subprocess.Popen(_generate_command(small_config, killed), start_new_session=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not list((killed / "grips").glob("part-*.parquet")) and process.poll() is None:
            assert time.monotonic() < deadline, "no shard appeared in time"
            time.sleep(0.05)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
        process.wait()
    assert process.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    before = json.loads((killed / "manifest.json").read_text())
    assert not before["complete"]

    assert subprocess.run(_generate_command(small_config, killed), check=False).returncode == 0
    clean = tmp_path / "clean"
    assert subprocess.run(_generate_command(small_config, clean), check=False).returncode == 0
    resumed, reference = load(killed), load(clean)
    assert len(reference) > 0
    pd.testing.assert_frame_equal(resumed, reference)

    code, text = cli("validate", str(killed))
    assert code == 0 and "OK" in text

    code, text = cli("generate", "--config", str(small_config), "--out", str(killed),
                     "--objects", "basic", "--seed", "6", "--no-progress")
    assert code == 2 and "dataset.seed: 5 -> 6" in text and "--overwrite" in text


@pytest.mark.slow
def test_validate_cli_flags_tampered_feature(tmp_path: Path, small_config: Path) -> None:
    out = tmp_path / "d"
    code, _ = cli("generate", "--config", str(small_config), "--out", str(out),
                  "--objects", "rectangle", "--workers", "1", "--no-progress")
    assert code == 0
    shard = sorted((out / "grips").glob("part-*.parquet"))[0]
    table = pq.read_table(shard)
    frame = table.to_pandas()
    frame.loc[0, "S2"] *= 1.5
    pq.write_table(table.from_pandas(frame, schema=table.schema, preserve_index=False), shard)
    code, text = cli("validate", str(out))
    assert code == 1
    assert "S2 differs" in text and "SHA-256" in text


def test_validate_of_a_too_old_dataset_says_regenerate_in_one_line(tmp_path: Path) -> None:
    from test_dataset import toy_job

    from grip_env.dataset import generate

    out = generate(SMALL, tmp_path / "d", objects=2, workers=1, progress=False, job=toy_job)
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["format_version"] = 1
    (out / "manifest.json").write_text(json.dumps(manifest))
    code, text = cli("validate", str(out))
    assert code == 2 and len(text.strip().splitlines()) == 1
    assert text.startswith(f"error: dataset {out} has format version 1, this grip-env reads "
                           "version 2; it is too old: regenerate it")


def test_validate_of_an_unfinished_dataset_lists_the_missing_shards_before_any_count(
    tmp_path: Path,
) -> None:
    from test_dataset import toy_job

    from grip_env.dataset import generate

    out = generate(SMALL, tmp_path / "d", objects=3, workers=1, progress=False, job=toy_job)
    manifest = json.loads((out / "manifest.json").read_text())
    first, second, third = (entry["object_id"] for entry in manifest["objects"])
    del manifest["shards"][first]  # the run stopped before this object's shard
    (out / "manifest.json").write_text(json.dumps(manifest))
    (out / manifest["shards"][second]["file"]).unlink()  # a shard lost since
    kept = manifest["shards"][third]["rows"]
    code, text = cli("validate", str(out))
    lines = text.strip().splitlines()
    assert code == 1
    assert lines[0] == f"{out}: 2 problem(s)", text
    assert f"object {first}: no shard" in lines[1] and "missing" in lines[2], text
    assert f"{out}: incomplete: {kept} grips in the shards of 1 of 3 objects" in lines[3], text
    assert len(lines) == 4, text
