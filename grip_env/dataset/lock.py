"""One writer per dataset directory: an exclusive lock on ``DIR/.generate.lock``.

The lock is an ``flock`` held for the whole run, so the system releases it however the writer
ends (even ``kill -9``): a stale lock file never blocks a later run. The file stays, holding the
last writer's process id. Where ``fcntl`` is missing (Windows) no lock is taken.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

LOCK_FILE = ".generate.lock"


class DatasetLockedError(ValueError):
    """Another process is writing the dataset directory."""


@contextmanager
def dataset_lock(directory: Path) -> Iterator[None]:
    """Hold the directory's writer lock for the block.

    Raises:
        DatasetLockedError: another run holds it; the message names its process id.
    """
    try:
        import fcntl
    except ImportError:
        yield
        return
    path = Path(directory) / LOCK_FILE
    descriptor = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(descriptor, 32, 0).decode(errors="replace").strip() or "unknown"
            raise DatasetLockedError(
                f"{directory} is locked by another grip-env generate (pid {holder}) writing "
                "there; wait for it to finish (or stop it), or choose another --out"
            ) from None
        os.ftruncate(descriptor, 0)
        os.pwrite(descriptor, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        os.close(descriptor)
