"""``grip-env`` with a pause at one point of a run, so that a test can stop the run right there.

Run as ``python tests/interrupt_driver.py generate ...`` with

- ``GRIP_TEST_PAUSE``: ``planning`` (inside ``candidates``), ``physics`` (inside
  ``run_trial_outcomes``, which re-runs the real PyBullet trials for the whole pause) or
  ``write`` (a shard's temporary file written, not yet renamed);
- ``GRIP_TEST_MARKERS``: a directory; the first process to reach the point creates
  ``<dir>/<point>`` holding its pid, and pauses ``GRIP_TEST_PAUSE_SECONDS`` (default 60);
  with ``GRIP_TEST_PAUSES=n`` the next ones create ``<point>.2`` .. ``<point>.n`` and pause too.

Pool workers import this file as their main module (multiprocessing does that for
'forkserver' and 'spawn'), and Ray workers call :func:`install` as their process setup hook
(:data:`RAY_HOOK` names it), so the pause also happens inside workers. Everything else is the
real command: real planning, PyBullet and Parquet.
"""

from __future__ import annotations

import os
import time
from pathlib import Path


def _first_to_reach(point: str) -> bool:
    """Whether this call claims one of the ``GRIP_TEST_PAUSES`` pauses at ``point``."""
    markers = os.environ.get("GRIP_TEST_MARKERS")
    if os.environ.get("GRIP_TEST_PAUSE") != point or not markers:
        return False
    for count in range(1, int(os.environ.get("GRIP_TEST_PAUSES", "1")) + 1):
        name = point if count == 1 else f"{point}.{count}"
        try:
            descriptor = os.open(Path(markers) / name, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            continue
        os.write(descriptor, str(os.getpid()).encode())
        os.close(descriptor)
        return True
    return False


def _pause_seconds() -> float:
    return float(os.environ.get("GRIP_TEST_PAUSE_SECONDS", "60"))


#: Environment that makes Ray workers call :func:`install` (with this folder on PYTHONPATH).
RAY_HOOK = {
    "__RAY_WORKER_PROCESS_SETUP_HOOK_ENV_VAR": "interrupt_driver.install",
    "PYTHONPATH": os.pathsep.join(
        p for p in (str(Path(__file__).parent), os.environ.get("PYTHONPATH")) if p),
}
_installed: list[bool] = []


def install() -> None:
    """Put the pauses in place in this process (once)."""
    if not _installed:
        _installed.append(True)
        _install()


def _install() -> None:
    import grip_env.dataset.shards as shards
    import grip_env.planning.pipeline as pipeline
    import grip_env.sim as sim

    plan, simulate, write_atomically = (pipeline.candidates, sim.run_trial_outcomes,
                                        shards.write_atomically)

    def candidates(*args, **kwargs):  # type: ignore[no-untyped-def]
        if _first_to_reach("planning"):
            time.sleep(_pause_seconds())
        return plan(*args, **kwargs)

    def run_trial_outcomes(*args, **kwargs):  # type: ignore[no-untyped-def]
        result = simulate(*args, **kwargs)
        if _first_to_reach("physics"):
            deadline = time.monotonic() + _pause_seconds()
            while time.monotonic() < deadline:
                result = simulate(*args, **kwargs)
        return result

    def paused_write(path, write):  # type: ignore[no-untyped-def]
        def write_then_pause(temp):  # type: ignore[no-untyped-def]
            write(temp)
            if _first_to_reach("write"):
                time.sleep(_pause_seconds())
        return write_atomically(path, write_then_pause)

    pipeline.candidates, sim.run_trial_outcomes, shards.write_atomically = (
        candidates, run_trial_outcomes, paused_write
    )


if os.environ.get("GRIP_TEST_PAUSE"):
    install()

if __name__ == "__main__":
    from grip_env.cli import main

    main()
