"""Helpers for tests that run ``grip-env generate`` as a real subprocess and stop it.

The process tree is read from /proc here, independently of the code under test.
"""

from __future__ import annotations

import functools
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import pandas as pd
import pytest
import yaml
from interrupt_driver import RAY_HOOK

import grip_env
from grip_env.config import Config
from grip_env.dataset import load, validate

DRIVER = Path(__file__).with_name("interrupt_driver.py")
#: The small run every test uses: three procedural objects, two grips each, one trial.
SMALL = Config().override(dataset={"max_grips_per_object": 2, "trials": 1, "seed": 4})
OBJECTS = "3"
STOP_SECONDS = 5.0


def write_config(directory: Path, config: Config = SMALL) -> Path:
    path = directory / "small.yaml"
    path.write_text(yaml.safe_dump(config.model_dump(mode="json")))
    return path


@functools.cache
def small_config() -> Path:
    """The config file of :data:`SMALL`, written once per test session."""
    return write_config(Path(tempfile.mkdtemp(prefix="grip-env-config-")))


def generate_command(config: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, str(DRIVER), "generate", "--config", str(config), "--out", str(out),
            "--objects", OBJECTS, "--no-progress", *extra]


def start(command: list[str], **env: str) -> subprocess.Popen[str]:
    """Start a command in its own session, so that every process it starts can be found."""
    return subprocess.Popen(
        command, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, env={**os.environ, **env},
    )


def paused(command: list[str], point: str, markers: Path, seconds: float = 60.0, times: int = 1,
           ) -> subprocess.Popen[str]:
    """Start ``command`` so that it pauses at ``point``, in any process (interrupt_driver.py)."""
    markers.mkdir(parents=True, exist_ok=True)
    return start(command, GRIP_TEST_PAUSE=point, GRIP_TEST_MARKERS=str(markers),
                 GRIP_TEST_PAUSE_SECONDS=str(seconds), GRIP_TEST_PAUSES=str(times), **RAY_HOOK)


def wait_until(condition: Callable[[], bool], process: subprocess.Popen[str], timeout: float,
               what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if process.poll() is not None:
            raise AssertionError(f"the run ended ({process.returncode}) before {what}: "
                                 f"{process.stderr.read() if process.stderr else ''}")
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


def _processes() -> dict[int, tuple[int, int, str]]:
    """pid -> (parent pid, session id, state) of every process."""
    found = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2:].split()
            found[int(entry.name)] = (int(fields[1]), int(fields[3]), fields[0])
    return found


def family(pid: int) -> set[int]:
    """Running descendants of ``pid`` and every running process of its session."""
    table = _processes()
    members = {p for p, (_, session, state) in table.items() if session == pid and state != "Z"}
    frontier = [pid]
    while frontier:
        parent = frontier.pop()
        children = [p for p, (ppid, _, state) in table.items() if ppid == parent and state != "Z"]
        members.update(children)
        frontier += children
    members.discard(pid)
    return members


def running(pids: set[int]) -> set[int]:
    table = _processes()
    return {pid for pid in pids if pid in table and table[pid][2] != "Z"}


def stop(process: subprocess.Popen[str], signum: int) -> tuple[int, float, str, set[int]]:
    """Send ``signum`` to the run's main process only; returns (exit code, seconds to exit,
    stderr, processes of the run still running ``STOP_SECONDS`` after the signal)."""
    before = family(process.pid)
    sent = time.monotonic()
    os.kill(process.pid, signum)
    try:
        _, stderr = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    took = time.monotonic() - sent
    left = running(before | family(process.pid))
    while left and time.monotonic() < sent + STOP_SECONDS:
        time.sleep(0.05)
        left = running(left)
    for pid in left:  # do not leave them to other tests
        os.kill(pid, signal.SIGKILL)
    return process.returncode, took, stderr, left


def assert_stops_cleanly(process: subprocess.Popen[str], signum: signal.Signals, out: Path) -> str:
    """Stop the run with ``signum`` (see :func:`stop`) and check that it stopped cleanly: exit
    code 128 + signum within ``STOP_SECONDS``, no process of it left running, a last line that
    says so, and no partial file in ``out``. Returns its stderr."""
    code, took, stderr, left = stop(process, signum)
    assert code == 128 + signum, stderr
    assert took < STOP_SECONDS, f"took {took:.1f} s to stop"
    assert not left, f"processes left running: {left}"
    last = stderr.strip().splitlines()[-1]
    assert last.startswith(f"interrupted by {signum.name}: stopped cleanly"), stderr
    assert_no_partial_files(out)
    return stderr


def shards_on_disk(out: Path) -> list[Path]:
    return sorted((out / "grips").glob("*")) if (out / "grips").is_dir() else []


def assert_no_partial_files(out: Path) -> None:
    """Nothing half-written: no temporary file, and every shard on disk is listed and intact."""
    temporary = [p.name for p in out.rglob("*.tmp")]
    assert not temporary, f"temporary files left: {temporary}"
    manifest = json.loads((out / "manifest.json").read_text())
    listed = {Path(record["file"]).name for record in manifest["shards"].values()}
    assert {p.name for p in shards_on_disk(out)} <= listed
    assert all(problem.endswith("no shard (run unfinished)") for problem in validate(out))


def reference_dataset(config: Path) -> pd.DataFrame:
    """The dataset of an uninterrupted run of ``config``, computed once per state of the
    source (a tree being edited while the tests run gets a fresh reference)."""
    return _reference(config, _source_state())


def _source_state() -> tuple[tuple[str, int], ...]:
    package = Path(grip_env.__file__).parent
    return tuple(sorted((str(p), p.stat().st_mtime_ns) for p in package.rglob("*.py")))


@functools.cache
def _reference(config: Path, source: tuple[tuple[str, int], ...]) -> pd.DataFrame:
    out = Path(tempfile.mkdtemp(prefix="grip-env-reference-")) / "data"
    try:
        done = subprocess.run(generate_command(config, out, "--workers", "1"),
                              capture_output=True, text=True, check=False, timeout=300)
        assert done.returncode == 0, done.stderr
        return load(out)
    finally:
        shutil.rmtree(out.parent, ignore_errors=True)


def assert_resumes_to(config: Path, out: Path, reference: pd.DataFrame, *extra: str) -> None:
    """Rerunning the same command finishes the dataset, equal to an uninterrupted run."""
    finished = subprocess.run(generate_command(config, out, *extra), capture_output=True,
                              text=True, check=False, timeout=300)
    assert finished.returncode == 0, finished.stderr
    pd.testing.assert_frame_equal(load(out), reference)
    assert validate(out) == []


@pytest.fixture
def config() -> Path:
    """A small run's config file."""
    return small_config()


@pytest.fixture
def reference(config: Path) -> pd.DataFrame:
    """The dataset of an uninterrupted run (shared by the shutdown and fault tests)."""
    return reference_dataset(config)
