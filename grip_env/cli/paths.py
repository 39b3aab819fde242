"""Output paths checked before a command starts its work: where told, writable, of the right kind.

A command that would run for minutes and then fail to write (a read-only file system, ``--out``
naming a file where a folder is meant, or a folder where a file is meant) fails first instead,
with a one-line ``ValueError``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path


def output_dir(path: Path, option: str = "--out") -> Path:
    """Create directory ``path`` if needed and check that files can be written in it."""
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option} {path} is an existing file; give a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"{option} {path}: cannot create the directory ({_reason(exc)})") from None
    _probe(path, option)
    return path


def check_output_dir(path: Path, option: str = "--out") -> Path:
    """What :func:`output_dir` checks, without creating anything: a command that may still
    refuse its other inputs checks ``--out`` first and creates it only when all are sound."""
    if path.exists() and not path.is_dir():
        raise ValueError(f"{option} {path} is an existing file; give a directory")
    existing = next(parent for parent in (path, *path.parents) if parent.exists())
    if not existing.is_dir():
        raise ValueError(f"{option} {path}: {existing} is a file, not a directory")
    _probe(existing, option)
    return path


def output_file(path: Path, suffix: str, option: str = "--out") -> Path:
    """Check that file ``path`` (which must end in ``suffix``) can be written, before the work.

    The file is written exactly at ``path``: a name without ``suffix`` is refused rather than
    silently extended, and so is an existing directory.
    """
    if path.is_dir():
        raise ValueError(f"{option} {path} is a directory; give a file name such as "
                         f"{path / ('out' + suffix)}")
    if path.suffix.lower() != suffix:
        raise ValueError(f"{option} {path} must end in {suffix}")
    if path.parent.exists() and not path.parent.is_dir():
        raise ValueError(f"{option} {path}: {path.parent} is a file, not a directory")
    output_dir(path.parent, option)
    return path


def _probe(directory: Path, option: str) -> None:
    """Create and remove a file in ``directory`` (catches read-only file systems, even as root)."""
    try:
        with tempfile.NamedTemporaryFile(dir=directory, prefix=".grip-env-probe-"):
            pass
    except OSError as exc:
        raise ValueError(f"{option} {directory}: cannot write there ({_reason(exc)})") from None


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__
