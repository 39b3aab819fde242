"""``grip-env train``: cross-validate, plot and save the grip classifiers."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors


def train(
    data: Annotated[Path, typer.Option("--data", help="dataset directory (grip-env generate)")],
    out: Annotated[Path, typer.Option("--out", "-o", help="output directory (created if needed)")],
    config: Annotated[
        Path | None, typer.Option(help="YAML config (default: the embedded configs/default.yaml)")
    ] = None,
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
