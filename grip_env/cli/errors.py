"""Telling bad input (one line, exit code 2) from a bug (an internal error, exit code 1).

A command runs its work under :func:`user_errors`. The project's own input errors are the
``ValueError`` s a ``raise`` statement of grip-env (or of the file readers it calls: pandas,
pyarrow, YAML, pydantic) raises, and the operating system's refusals to open a path
(``FileNotFoundError``, ``PermissionError``). They end with ``error: <message>`` on one line and
exit code 2.

Anything else is a bug, not the user's input: a ``ValueError`` raised inside numpy, SciPy, torch,
PyBullet, MuJoCo, scikit-learn, Stable-Baselines3 or Gymnasium, or raised by an expression of ours
rather than a ``raise`` (numpy's "operands could not be broadcast"), and every other exception.
It prints its traceback, then ``internal error: ...`` with a hint to report it, and exits with 1.

After a stop signal (:mod:`grip_env.shutdown`) an exception is neither: library code turned the
interrupt into it (numpy's "not a valid PEP 3118 buffer format string"), so the command stops
as interrupted, with no error line.
"""

from __future__ import annotations

import linecache
import re
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import TypeVar

import typer
from typer.exceptions import TyperException

from grip_env.shutdown import raise_if_signalled

T = TypeVar("T")

#: Exit code of a bad input, and of an internal error.
INPUT_ERROR_CODE = 2
INTERNAL_ERROR_CODE = 1
#: Libraries whose own ValueErrors are bugs of ours when they reach the command line.
INTERNAL_LIBRARIES = ("numpy", "scipy", "torch", "pybullet", "pybullet_utils", "mujoco", "sklearn",
                      "stable_baselines3", "sb3_contrib", "gymnasium")  # fmt: skip
REPORT_HINT = ("this is a bug in grip-env, not in your input: please report it with the command, "
               "the traceback above and the output of `grip-env --version`")  # fmt: skip
_RAISE = re.compile(r"^\s*raise\b")


@contextmanager
def user_errors() -> Iterator[None]:
    """Report bad input as ``error: ...`` (exit 2) and anything else as an internal error (1)."""
    try:
        yield
    except (typer.Exit, typer.Abort, TyperException):  # Typer's own exits and usage errors
        raise
    except Exception as exc:
        raise_if_signalled()  # after a stop signal, the error is the signal's, turned into one
        if is_input_error(exc):
            typer.echo(f"error: {exc}", err=True)
            raise typer.Exit(code=INPUT_ERROR_CODE) from None
        report_internal(exc)
        raise typer.Exit(code=INTERNAL_ERROR_CODE) from None


def report_internal(exc: BaseException) -> None:
    """Print ``exc``'s traceback, then ``internal error: ...`` and :data:`REPORT_HINT`."""
    traceback.print_exception(exc)
    typer.echo(f"internal error: {type(exc).__name__}: {exc}", err=True)
    typer.echo(REPORT_HINT, err=True)


def checked(call: Callable[[], T]) -> T:
    """Run ``call`` under :func:`user_errors`."""
    with user_errors():
        return call()


def is_input_error(exc: BaseException) -> bool:
    """Whether ``exc`` reports bad input (see the module docstring) rather than a bug."""
    if isinstance(exc, FileNotFoundError | PermissionError | IsADirectoryError):
        return True
    if not isinstance(exc, ValueError) or _library_of_type(exc) in INTERNAL_LIBRARIES:
        return False
    frame = _innermost(exc.__traceback__)
    if frame is None:
        return True
    filename, lineno = frame
    if _library_of_file(filename) in INTERNAL_LIBRARIES:
        return False
    line = linecache.getline(filename, lineno)
    return not line or bool(_RAISE.match(line))  # a raise statement, ours or a file reader's


def _innermost(tb: TracebackType | None) -> tuple[str, int] | None:
    if tb is None:
        return None
    while tb.tb_next is not None:
        tb = tb.tb_next
    return tb.tb_frame.f_code.co_filename, tb.tb_lineno


def _library_of_type(exc: BaseException) -> str:
    return type(exc).__module__.split(".", 1)[0]


def _library_of_file(filename: str) -> str | None:
    """The installed package a source file belongs to (None outside site-packages)."""
    parts = Path(filename).parts
    if "site-packages" in parts:
        index = parts.index("site-packages")
        return parts[index + 1].removesuffix(".py") if index + 1 < len(parts) else None
    return None
