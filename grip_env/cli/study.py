"""``grip-env study``: the whole main job on one config, ending in a report."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import ConfigFile
from grip_env.cli.paths import output_dir


def study(
    config: ConfigFile = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="study folder")] = Path("runs/default"),
    quick: Annotated[bool, typer.Option("--quick", help="tiny profile for tests")] = False,
) -> None:
    """Run the whole study and write OUT/report.md and OUT/report.html.

    Generates the dataset, trains and evaluates the classifiers, runs the ablation, trains and
    evaluates the RL selector, then writes the report. Rerunning reuses every finished stage.
    """
    with user_errors():
        output_dir(out)
        from classifiers.study import run_study
        from grip_env.config import load_config
        from grip_env.dataset import DatasetMismatchError

        try:
            report = run_study(load_config(config), out, quick=quick, log=typer.echo)
        except DatasetMismatchError as exc:  # its advice names generate's --overwrite
            reason = str(exc).split("; use --overwrite", 1)[0]
            raise ValueError(
                f"{reason}; choose another --out, or delete {out / 'dataset'} to regenerate it"
            ) from None
    typer.echo(f"report: {report}")


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("study")(study)
