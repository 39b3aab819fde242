"""Turning bad input into a clear CLI message and exit code 2."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

import typer

T = TypeVar("T")


@contextmanager
def user_errors() -> Iterator[None]:
    """Report ``ValueError``/``FileNotFoundError`` as ``error: ...`` with exit code 2."""
    try:
        yield
    except (ValueError, FileNotFoundError, PermissionError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(code=2) from None


def checked(call: Callable[[], T]) -> T:
    """Run ``call`` under :func:`user_errors`."""
    with user_errors():
        return call()
