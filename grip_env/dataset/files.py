"""Crash-safe file writing: write to a temporary sibling, flush to disk, then rename atomically."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path

_CHUNK = 1 << 20


def sha256_of(path: Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with path.open("rb") as stream:
        while chunk := stream.read(_CHUNK):
            digest.update(chunk)
    return digest.hexdigest()


def write_atomically(path: Path, write: Callable[[Path], None]) -> str:
    """Call ``write(temp_path)``, then move the result onto ``path``; returns its SHA-256.

    A reader never sees a half-written ``path``: it is either absent, the old file or the new one.
    """
    temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(temp)
        with temp.open("rb+") as stream:
            os.fsync(stream.fileno())
        checksum = sha256_of(temp)
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)
    return checksum


def write_text_atomically(path: Path, text: str) -> str:
    """Atomically replace ``path`` with ``text`` (UTF-8); returns its SHA-256."""
    return write_atomically(path, lambda temp: temp.write_text(text, encoding="utf-8"))


def check_writable(directory: Path) -> None:
    """Create ``directory`` if needed and make sure files can be written in it.

    Raises:
        ValueError: the path is a file, or the directory cannot be created or written.
    """
    if directory.exists() and not directory.is_dir():
        raise ValueError(f"output path {directory} exists and is not a directory")
    try:
        directory.mkdir(parents=True, exist_ok=True)
        probe = directory / f".write-probe.{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise ValueError(f"output directory {directory} is not writable: {exc.strerror}") from None
