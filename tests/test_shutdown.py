"""SIGINT, SIGTERM and SIGHUP to a real ``grip-env generate``, at planning, mid-physics and
mid-write, on the process pool and in-process: the run stops within 5 s with exit code
128 + signal and one line, leaves no process behind and no partial file, and the same command
then finishes the dataset exactly as an uninterrupted run would have made it. (SIGTERM to a
Ray run is in test_faults.py, with a lost Ray worker, to start Ray only once.)"""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from generate_runs import (
    assert_resumes_to,
    assert_stops_cleanly,
    generate_command,
    paused,
    shards_on_disk,
    wait_until,
)

from grip_env.shutdown import Interrupted, exit_code

CASES = [
    # signal, where the run is stopped, extra generate options
    (signal.SIGINT, "planning", ("--workers", "2")),
    (signal.SIGTERM, "physics", ("--workers", "2")),
    (signal.SIGHUP, "write", ("--workers", "2")),
    (signal.SIGINT, "physics", ("--workers", "1")),
]


@pytest.mark.slow
@pytest.mark.parametrize(("signum", "point", "options"), CASES,
                         ids=[f"{s.name}-{p}-{o[1]}w" for s, p, o in CASES])
def test_signal_stops_cleanly_and_the_rerun_finishes(
    tmp_path: Path, config: Path, reference: pd.DataFrame, signum: signal.Signals, point: str,
    options: tuple[str, ...],
) -> None:
    out, markers = tmp_path / "data", tmp_path / "markers"
    # the write pause is short: a shard being written is finished before the run stops
    run = paused(generate_command(config, out, *options), point, markers,
                 seconds=1.0 if point == "write" else 60.0)
    wait_until(lambda: (markers / point).exists(), run, 120, f"the run reached {point}")

    stderr = assert_stops_cleanly(run, signum, out)

    assert exit_code(signum) == 128 + signum
    message = stderr.strip().splitlines()
    assert message[-1] == (f"interrupted by {signum.name}: stopped cleanly; "
                           f"rerun the same command to finish {out}")
    assert "Traceback" not in stderr
    if point == "write":  # the shard being written when the signal came is complete and kept
        assert len(shards_on_disk(out)) >= 1
    assert_resumes_to(config, out, reference, *options)


# ----------------------------------------------------------------------------- the mechanism
def _python(code: str) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a fresh interpreter (the mechanism ends the children of its process)."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=False, timeout=60)


def test_stop_on_signals_exits_with_the_signal_code_and_restores_handlers() -> None:
    done = _python(
        "import os, signal, time\n"
        "from grip_env.shutdown import stop_on_signals\n"
        "before = signal.getsignal(signal.SIGTERM)\n"
        "try:\n"
        "    with stop_on_signals('rerun it'):\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "        time.sleep(30)\n"
        "finally:\n"
        "    assert signal.getsignal(signal.SIGTERM) is before\n"
    )
    assert done.returncode == 143
    assert done.stderr == "interrupted by SIGTERM: stopped cleanly; rerun it\n"


def test_deferred_signal_takes_effect_when_the_block_ends() -> None:
    done = _python(
        "import signal\n"
        "from grip_env.shutdown import deferred_signals, stop_on_signals\n"
        "with stop_on_signals():\n"
        "    with deferred_signals():\n"
        "        signal.raise_signal(signal.SIGHUP)\n"
        "        print('finished the block')\n"
        "    print('not reached')\n"
    )
    assert done.returncode == 129 and done.stdout == "finished the block\n"


def test_a_signal_during_an_import_takes_effect_when_the_import_ends(tmp_path: Path) -> None:
    """An extension's import runs Python from C++, where an exception cannot unwind (torch's
    aborted the selector with SIGABRT): a signal that lands inside an import is held until the
    module is whole, then stops the command with its code."""
    (tmp_path / "slow_module.py").write_text(
        "import os, signal, time\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(0.5)\n"
        "print('imported whole', flush=True)\n")
    done = _python(
        "import sys, time\n"
        f"sys.path.insert(0, {str(tmp_path)!r})\n"
        "from grip_env.shutdown import stop_on_signals\n"
        "with stop_on_signals('rerun it'):\n"
        "    import slow_module\n"
        "    time.sleep(30)\n"
        "    print('not reached')\n"
    )
    assert done.returncode == 143, done.stderr
    assert done.stdout == "imported whole\n"
    assert done.stderr == "interrupted by SIGTERM: stopped cleanly; rerun it\n"


def test_children_still_running_are_ended_and_work_without_signal_is_untouched() -> None:
    done = _python(
        "import os, signal, subprocess, sys, time\n"
        "from grip_env.shutdown import stop_on_signals\n"
        "with stop_on_signals():\n"
        "    total = sum(range(10))\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)'])\n"
        "print(total, child.pid, flush=True)\n"
        "with stop_on_signals():\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "    time.sleep(30)\n"
    )
    total, child = done.stdout.split()
    assert done.returncode == 130 and total == "45"
    assert not Path(f"/proc/{child}").exists() or "Z" in Path(f"/proc/{child}/stat").read_text()


# A job that loses the interrupt, as library code can (numpy turns it into a ValueError while
# parsing a buffer format for scikit-learn's gradient boosting; scikit-learn's MLP catches it).
_LOSING_JOB = (
    "import os, signal, time\n"
    "def job(k):\n"
    "    try:\n"
    "        if k == 0:\n"
    "            os.kill(os.getpid(), signal.SIGTERM)\n"
    "        time.sleep(1)\n"
    "    except KeyboardInterrupt:\n"
    "        pass\n"
    "    print(k, flush=True)\n"
)


def _losing(work: str, advice: str = "") -> subprocess.CompletedProcess[str]:
    """``work`` (one line) run under ``stop_on_signals(advice)`` beside the losing ``job``."""
    return _python(_LOSING_JOB + (
        "from classifiers.learners.parallel import run_all\n"
        "from grip_env.shutdown import stop_on_signals\n"
        f"with stop_on_signals({advice!r}):\n"
        f"    {work}\n"
    ))


def test_an_interrupt_a_job_lost_stops_the_jobs_at_its_end() -> None:
    # before the checkpoint the jobs ran on until the watchdog killed them at 4 s
    done = _losing("run_all(job, [(k,) for k in range(20)], grips=0, workers=1)", "rerun it")
    assert done.returncode == 143 and done.stdout == "0\n"
    assert done.stderr == "interrupted by SIGTERM: stopped cleanly; rerun it\n"


def test_a_signal_the_work_lost_still_ends_the_command_with_its_code() -> None:
    done = _losing("job(0)")
    assert done.returncode == 143 and done.stdout == "0\n"
    assert done.stderr == "interrupted by SIGTERM: stopped cleanly\n"


def test_an_error_the_interrupt_was_turned_into_is_not_reported() -> None:
    done = _python(
        "import os, signal, time\n"
        "from grip_env.cli.errors import user_errors\n"
        "from grip_env.shutdown import stop_on_signals\n"
        "with stop_on_signals('rerun it'), user_errors():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "        time.sleep(1)\n"
        "    except KeyboardInterrupt as exc:\n"
        "        raise TypeError('not a valid PEP 3118 buffer format string') from exc\n"
    )
    assert done.returncode == 143
    assert done.stderr == "interrupted by SIGTERM: stopped cleanly; rerun it\n"


def test_interrupted_is_a_keyboard_interrupt() -> None:
    assert issubclass(Interrupted, KeyboardInterrupt)
    assert Interrupted(signal.SIGTERM).exit_code == 143
