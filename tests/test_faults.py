"""What a long unattended ``grip-env generate`` meets, injected into a real run: a worker
killed with SIGKILL (process pool and Ray), a full disk, a second run into the same folder, and
files from elsewhere (names that try to leave the folder, crafted manifests and shards)."""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from generate_runs import (
    OBJECTS,
    assert_no_partial_files,
    assert_resumes_to,
    assert_stops_cleanly,
    generate_command,
    paused,
    shards_on_disk,
    stop,
    wait_until,
)

from grip_env.dataset import load, validate
from grip_env.dataset.shards import shard_path


def _pid_in(marker: Path) -> int:
    """The pid a paused process wrote to ``marker`` (the file can exist a moment before its
    text is written: read until it is there)."""
    deadline = time.monotonic() + 10.0
    while not (text := marker.read_text().strip()) and time.monotonic() < deadline:
        time.sleep(0.05)
    return int(text)


# ----------------------------------------------------------------------------- a lost worker
@pytest.mark.slow
def test_killed_pool_worker_costs_only_a_retry_of_its_object(
    tmp_path: Path, config: Path, reference: pd.DataFrame
) -> None:
    out, markers = tmp_path / "data", tmp_path / "markers"
    run = paused(generate_command(config, out, "--workers", "2"), "physics", markers)
    wait_until(lambda: (markers / "physics").exists(), run, 120, "a worker reached physics")
    worker = _pid_in(markers / "physics")
    assert worker != run.pid
    os.kill(worker, signal.SIGKILL)
    _, stderr = run.communicate(timeout=120)
    assert run.returncode == 0, stderr
    pd.testing.assert_frame_equal(load(out), reference)
    assert validate(out) == []


@pytest.mark.slow
def test_ray_survives_a_lost_worker_and_stops_cleanly_on_sigterm(
    tmp_path: Path, config: Path, reference: pd.DataFrame
) -> None:
    """A Ray worker killed mid-physics: Ray reruns its task (which reaches physics again, in a
    new worker); SIGTERM then stops the run cleanly, and a rerun finishes the dataset."""
    pytest.importorskip("ray")
    out, markers = tmp_path / "data", tmp_path / "markers"
    options = ("--workers", "2", "--backend", "ray")
    run = paused(generate_command(config, out, *options), "physics", markers, times=2)
    wait_until(lambda: (markers / "physics").exists(), run, 180, "a Ray worker reached physics")
    lost = _pid_in(markers / "physics")
    os.kill(lost, signal.SIGKILL)
    wait_until(lambda: (markers / "physics.2").exists(), run, 120, "Ray rescheduled the task")
    assert _pid_in(markers / "physics.2") != lost

    assert_stops_cleanly(run, signal.SIGTERM, out)  # exit code 143, no Ray process left
    assert_resumes_to(config, out, reference, "--workers", "2")


# ----------------------------------------------------------------------------- a full disk
def _mount_tmpfs(folder: Path, size: str) -> bool:
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return False
    command = ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)]
    try:
        return subprocess.run(command, capture_output=True, check=False).returncode == 0
    except OSError:
        return False


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[tuple[Path, dict]]:
    """A 64 KiB tmpfs where this process may mount one (root), else a 15 KB file-size limit;
    yields the folder and the ``subprocess.run`` options that make writes there fail part-way."""
    folder = tmp_path / "disk"
    folder.mkdir()
    if _mount_tmpfs(folder, "64k"):
        yield folder, {}
        subprocess.run(["umount", "-l", str(folder)], check=False)
        return

    def limit_file_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (15_000, 15_000))

    yield folder, {"preexec_fn": limit_file_size}


@pytest.mark.slow
def test_full_disk_gives_one_line_and_leaves_nothing_corrupt(
    tmp_path: Path, config: Path, reference: pd.DataFrame, small_disk: tuple[Path, dict]
) -> None:
    folder, options = small_disk
    out = folder / "data"
    done = subprocess.run(generate_command(config, out, "--workers", "1"), capture_output=True,
                          text=True, check=False, timeout=300, **options)
    assert done.returncode == 1, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith(f"error: cannot write the dataset in {out}: ")
    assert "No space left on device" in last or "File too large" in last
    assert "rerun the same command to finish" in last and "Traceback" not in done.stderr
    assert_no_partial_files(out)
    assert len(shards_on_disk(out)) < int(OBJECTS)
    # with room again, the same command finishes what the full disk stopped
    moved = tmp_path / "moved"
    subprocess.run(["cp", "-a", str(out), str(moved)], check=True)
    assert_resumes_to(config, moved, reference, "--workers", "1")


# ----------------------------------------------------------------------------- two runs, one folder
@pytest.mark.slow
def test_second_run_into_the_same_folder_is_refused_while_the_first_runs(
    tmp_path: Path, config: Path
) -> None:
    out, markers = tmp_path / "data", tmp_path / "markers"
    first = paused(generate_command(config, out, "--workers", "1"), "planning", markers)
    wait_until(lambda: (markers / "planning").exists(), first, 120, "the first run started")
    second = subprocess.run(generate_command(config, out, "--workers", "1"),
                            capture_output=True, text=True, check=False, timeout=120)
    assert second.returncode == 2
    assert second.stderr.strip() == (
        f"error: {out} is locked by another grip-env generate (pid {first.pid}) writing there; "
        "wait for it to finish (or stop it), or choose another --out"
    )
    code, *_ = stop(first, signal.SIGINT)
    assert code == 130
    assert_no_partial_files(out)


def test_lock_is_released_however_the_writer_ends(tmp_path: Path) -> None:
    from grip_env.dataset.lock import DatasetLockedError, dataset_lock

    # a second descriptor on the same file conflicts, as another process's would
    refused = pytest.raises(DatasetLockedError, match=f"pid {os.getpid()}")
    with dataset_lock(tmp_path), refused, dataset_lock(tmp_path):
        pass
    killed = subprocess.Popen(
        [sys.executable, "-c", "import time; from pathlib import Path; "
         "from grip_env.dataset.lock import dataset_lock\n"
         f"with dataset_lock(Path({str(tmp_path)!r})):\n    print('held', flush=True); "
         "time.sleep(60)"], stdout=subprocess.PIPE, text=True)
    assert killed.stdout.readline().strip() == "held"
    killed.kill()
    killed.wait()
    with dataset_lock(tmp_path):  # not stale: the system released it with the process
        pass


# ----------------------------------------------------------------------------- untrusted files
def test_object_names_cannot_leave_the_output_folder(tmp_path: Path) -> None:
    for name in ("../x", "../../etc/passwd", "/abs/path", "a/../../b", "..", "x\\..\\y"):
        path = shard_path(tmp_path, 3, name)
        assert path.parent == tmp_path / "grips"
        assert path.resolve().parent == (tmp_path / "grips").resolve()
        assert "/" not in path.name and "\\" not in path.name


@pytest.fixture
def dataset(tmp_path: Path) -> Path:
    from test_dataset import toy_job

    from grip_env.config import Config
    from grip_env.dataset import generate

    config = Config().override(dataset={"trials": 2, "max_grips_per_object": 3})
    return generate(config, tmp_path / "d", objects=2, workers=1, progress=False, job=toy_job)


@pytest.mark.parametrize("file", ["../outside.parquet", "grips/../../outside.parquet",
                                  "/etc/passwd", "grips/sub/part-000000-x.parquet"])
def test_manifest_naming_a_file_outside_the_dataset_is_refused(dataset: Path, file: str) -> None:
    manifest = json.loads((dataset / "manifest.json").read_text())
    next(iter(manifest["shards"].values()))["file"] = file
    (dataset / "manifest.json").write_text(json.dumps(manifest))
    for call in (load, validate):
        with pytest.raises(ValueError, match=r"is corrupt: object .* names shard file"):
            call(dataset)


def test_shard_of_another_schema_is_refused_by_load(dataset: Path) -> None:
    shard = shards_on_disk(dataset)[0]
    table = pq.read_table(shard)
    position = table.schema.get_field_index("trials")
    table = table.set_column(position, "trials", pa.array(np.full(len(table), "2")))
    pq.write_table(table, shard)
    with pytest.raises(ValueError, match="column trials has type string, expected int64"):
        load(dataset, verify=False)
    assert any("column trials has type string" in p for p in validate(dataset))


def test_dataset_loaders_use_no_pickle() -> None:
    """Datasets are JSON (manifest) and Parquet only: no loader can unpickle a file."""
    import grip_env.dataset as package

    folder = Path(package.__file__).parent
    for module in folder.glob("*.py"):
        text = module.read_text()
        loads_files = [word for word in ("pickle.load(", "pd.read_pickle", "joblib.load",
                                         "torch.load", "yaml.load(", "eval(", "exec(")
                       if word in text]
        assert not loads_files, f"{module.name} uses {loads_files}"
