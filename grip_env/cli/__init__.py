"""The ``grip-env`` command line: one subcommand per job.

Each job lives in its own module here and registers itself on ``app``. Bad input ends with a
one-line message and exit code 2, never a traceback.
"""

from __future__ import annotations

import importlib
import sys
from typing import Annotated

import typer
from typer.core import TyperCommand

from grip_env.cli.helptext import Command, Group

SUMMARY = "Learn which Barrett BH8-280 grips hold"

app = typer.Typer(
    name="grip-env",
    cls=Group,
    help=f"{SUMMARY}.",  # completed with the command names by _register_commands
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="markdown",
)


def package_version() -> str:
    """The installed distribution's version (the package's own when run from a bare checkout)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("grip-env")
    except PackageNotFoundError:
        from grip_env import __version__

        return __version__


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"grip-env {package_version()}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_print_version, is_eager=True,
                     help="print the version and exit"),
    ] = False,
) -> None:
    """The group's options; its help is ``app.info.help`` (the summary and every command)."""


_COMMAND_MODULES = (
    "show", "candidates", "study", "generate", "validate", "train", "ablate", "select",
    "calibrate", "predict", "benchmark", "power", "export",
)


def _register_commands() -> None:
    """Add every command once (a second call changes nothing), each shown by
    :class:`~grip_env.cli.helptext.Command` unless it asks for its own, and name them all in the
    group's help."""
    if not app.registered_commands:
        for name in _COMMAND_MODULES:
            importlib.import_module(f"grip_env.cli.{name}").register(app)
    for info in app.registered_commands:
        if info.cls in (None, TyperCommand):  # typer's default: the command asked for none
            info.cls = Command
    names = dict.fromkeys(info.name for info in app.registered_commands if info.name)
    app.info.help = f"{SUMMARY}: {', '.join(names)}."


def main() -> None:
    """Console-script entry point; a usage error (bad option value, missing argument) is one line.

    Exit codes: 0 done, 1 failed (an internal error says so, with a hint to report it), 2 bad
    input; commands document their own (e.g. 130 on SIGINT).
    """
    _register_commands()
    if len(sys.argv) < 2:
        app()  # no arguments: the help, as Typer shows it
        return
    try:
        code = app(standalone_mode=False)
    except typer.Abort:
        typer.echo("aborted", err=True)
        sys.exit(1)
    except Exception as exc:  # click's UsageError and kin (vendored by Typer): one line
        usage = hasattr(exc, "format_message") and isinstance(getattr(exc, "exit_code", 0), int)
        if not usage:
            from grip_env.cli.errors import INTERNAL_ERROR_CODE, report_internal

            report_internal(exc)
            sys.exit(INTERNAL_ERROR_CODE)
        typer.echo(f"error: {exc.format_message()}{_help_hint(exc)}", err=True)
        sys.exit(exc.exit_code)
    sys.exit(code if isinstance(code, int) else 0)


def _help_hint(exc: Exception) -> str:
    context = getattr(exc, "ctx", None)
    path = getattr(context, "command_path", None)
    return f" (see {path} --help)" if path else ""
