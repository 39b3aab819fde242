"""A stop signal ends the learning commands cleanly: train, ablate and select on a real dataset."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from generate_runs import STOP_SECONDS, stop

from grip_env.shutdown import exit_code

CASES = [
    ("train", signal.SIGINT, ("--models", "svm,mlp_torch")),
    ("ablate", signal.SIGTERM, ()),
    ("select", signal.SIGHUP, ("--timesteps", "100000")),
]


@pytest.mark.slow
@pytest.mark.parametrize(("command", "signum", "options"), CASES,
                         ids=[f"{c}-{s.name}" for c, s, _ in CASES])
def test_a_learning_command_stops_cleanly_on_a_signal(
    tmp_path: Path, generated_dataset_dir: Path, command: str, signum: signal.Signals,
    options: tuple[str, ...],
) -> None:
    out = tmp_path / "out"
    run = subprocess.Popen(
        [sys.executable, "-c", "from grip_env.cli import main; main()", command,
         "--data", str(generated_dataset_dir), "--out", str(out), *options],
        start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    started = time.monotonic()  # OUT is made inside the signal handlers: then the work begins
    while not out.exists() and run.poll() is None and time.monotonic() - started < 120:
        time.sleep(0.05)
    time.sleep(1.0)  # the work under way (each command runs for much longer)
    assert run.poll() is None, run.communicate()
    code, took, stderr, left = stop(run, signum)
    assert code == exit_code(signum) == 128 + signum, stderr
    assert took < STOP_SECONDS, f"took {took:.1f} s to stop"
    assert not left, f"processes left running: {left}"
    assert stderr.strip().splitlines()[-1].startswith(f"interrupted by {signum.name}: "
                                                      "stopped cleanly")
    assert "Traceback" not in stderr
