"""``grip-env validate``: check a dataset (schema, checksums, features, outcomes)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.notices import warn_label_model


def validate(
    directory: Annotated[Path, typer.Argument(help="dataset directory written by generate")],
) -> None:
    """Check a dataset: schema, checksums, features and outcomes.

    Verifies the schema, the SHA-256 of every file, every feature recomputed from its
    descriptors, and outcome consistency, and names the dataset's label model (a warning, not a
    problem, when it is not this grip-env's). Exit code 0 when clean, 1 when a problem is found.
    """
    with user_errors():
        from grip_env.dataset import validate as validate_dataset
        from grip_env.dataset.manifest import read_manifest
        from grip_env.label_model import label_model_of

        manifest = read_manifest(directory)
        problems = validate_dataset(directory)
    warn_label_model(directory)
    summary = (f"{directory}: {manifest['rows']} grips, {len(manifest['objects'])} objects, "
               f"label model {label_model_of(manifest)}")
    if not problems:
        typer.echo(f"{summary}: OK (schema, checksums, features, outcomes)")
        return
    typer.echo(f"{summary}: {len(problems)} problem(s)")
    for problem in problems:
        typer.echo(f"  - {problem}")
    raise typer.Exit(code=1)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("validate")(validate)
