"""``grip-env validate``: check a dataset (schema, checksums, features, outcomes)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors


def validate(
    directory: Annotated[Path, typer.Argument(help="dataset directory written by generate")],
) -> None:
    """Check a dataset: schema, checksums, features and outcomes.

    Verifies the schema, the SHA-256 of every file, every feature recomputed from its
    descriptors, and outcome consistency. Exit code 0 when clean, 1 when a problem is found.
    """
    with user_errors():
        from grip_env.dataset import validate as validate_dataset
        from grip_env.dataset.manifest import read_manifest

        manifest = read_manifest(directory)
        problems = validate_dataset(directory)
    summary = f"{directory}: {manifest['rows']} grips, {len(manifest['objects'])} objects"
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
