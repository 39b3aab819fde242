"""Running ``grip-env`` commands in-process for tests, and the shape of a refusal."""

from __future__ import annotations

from typer.testing import CliRunner

from grip_env.cli import _register_commands, app

_register_commands()
RUNNER = CliRunner()


def cli(*args: object) -> tuple[int, str]:
    """Exit code and output of ``grip-env ARGS``."""
    result = RUNNER.invoke(app, [str(a) for a in args])
    return result.exit_code, result.output


def assert_refused(code: int, output: str, *fragments: str) -> None:
    """Exit code 2, one ``error:`` line naming every fragment, no traceback."""
    lines = [line for line in output.splitlines() if line.strip()]
    assert code == 2, output
    assert len(lines) == 1 and lines[0].startswith("error: "), output
    for fragment in fragments:
        assert fragment in lines[0], output
