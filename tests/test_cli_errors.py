"""The CLI tells input errors (exit 2, one line) from bugs (an internal error, exit 1)."""

from __future__ import annotations

import numpy as np
import pytest
import typer
from typer.testing import CliRunner

from grip_env.cli.errors import INTERNAL_ERROR_CODE, REPORT_HINT, is_input_error, user_errors


def _raised(call) -> BaseException:
    try:
        call()
    except Exception as exc:
        return exc
    raise AssertionError("nothing was raised")


def _ours() -> None:
    raise ValueError("grasp.mu must be positive, got -1")


def test_a_raise_of_ours_and_a_missing_file_are_input_errors(tmp_path):
    assert is_input_error(_raised(_ours))
    assert is_input_error(_raised(lambda: open(tmp_path / "missing.yaml")))  # noqa: SIM115


def test_a_file_reader_refusing_a_file_is_an_input_error(tmp_path):
    import pandas as pd

    bad = tmp_path / "bad.parquet"
    bad.write_bytes(b"not parquet")
    assert is_input_error(_raised(lambda: pd.read_parquet(bad)))


def test_numpy_errors_are_internal_wherever_they_surface():
    assert not is_input_error(_raised(lambda: np.zeros(3).reshape(2, 2)))  # inside numpy
    assert not is_input_error(_raised(lambda: np.zeros(3) + np.zeros(2)))  # an expression of ours
    assert not is_input_error(_raised(lambda: np.zeros((2, 2)).sum(axis=3)))  # numpy's AxisError
    assert not is_input_error(_raised(lambda: {}["key"]))


def _command(kind: str) -> None:
    with user_errors():
        if kind == "input":
            _ours()
        elif kind == "numpy":
            np.zeros(3).reshape(2, 2)
        else:
            raise RuntimeError("a bug")


@pytest.mark.parametrize("kind", ["numpy", "bug"])
def test_an_internal_error_says_so_with_a_hint_and_exits_1(kind):
    app = typer.Typer()
    app.command()(_command)
    result = CliRunner().invoke(app, [kind])
    assert result.exit_code == INTERNAL_ERROR_CODE
    assert "Traceback" in result.output and "internal error: " in result.output
    assert result.output.strip().endswith(REPORT_HINT)


def test_an_input_error_is_one_line_and_exits_2():
    app = typer.Typer()
    app.command()(_command)
    result = CliRunner().invoke(app, ["input"])
    assert result.exit_code == 2
    assert result.output.strip() == "error: grasp.mu must be positive, got -1"
