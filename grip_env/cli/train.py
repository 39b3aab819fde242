"""``grip-env train``: cross-validate, plot and save the grip classifiers."""

from __future__ import annotations

from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import ConfigFile, DatasetDir, OutputDir


def train(
    data: DatasetDir,
    out: OutputDir,
    config: ConfigFile = None,
    models: Annotated[
        str | None,
        typer.Option(help="comma-separated model names [default: config learning.models]"),
    ] = None,
) -> None:
    """Write OUT/metrics.json (grouped CV), roc.png, calibration.png and OUT/models/."""
    with user_errors():
        from classifiers.training import train_and_save
        from grip_env.config import load_config
        from grip_env.dataset import load

        settings = load_config(config)
        if models is not None:
            names = tuple(name.strip() for name in models.split(",") if name.strip())
            settings = settings.override(learning={"models": names})
        metrics = train_and_save(load(data), out, settings)
        for name, summary in metrics["models"].items():
            auc = summary["roc_auc"]["mean"]
            typer.echo(f"{name:12s} ROC-AUC {auc:.3f}" if auc is not None else name)
        typer.echo(f"wrote {out / 'metrics.json'}")


def register(app: typer.Typer) -> None:
    """Add the command to the ``grip-env`` app."""
    app.command("train")(train)
