"""``grip-env validate``: check a dataset (schema, checksums, features, outcomes)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.notices import warn_label_model
from grip_env.cli.options import dataset_folder


def validate(
    directory: Annotated[Path, typer.Argument(
        help="dataset directory written by generate, or 'standard' for the shipped one",
        callback=dataset_folder)],
    resimulate: Annotated[int | None, typer.Option(
        min=1, help="also plan again a seeded sample of objects and simulate again this many of "
                    "their grips, with the dataset's own config and seeds (exact comparison)")
    ] = None,
    seed: Annotated[int, typer.Option(min=0, help="seed of the --resimulate sample")] = 0,
    workers: Annotated[int, typer.Option(min=1, help="worker processes for --resimulate")] = 2,
) -> None:
    """Check a dataset: schema, checksums, features and outcomes; with `--resimulate N`, that
    its candidates and labels are what this code makes.

    Verifies the schema, the SHA-256 of every file, every feature recomputed from its
    descriptors, and outcome consistency, and names the dataset's label model (a warning, not a
    problem, when it is not this grip-env's). `--resimulate N` re-plans a seeded sample of
    objects and re-simulates N of their grips, and counts what is identical bit for bit.
    Exit code 0 when clean, 1 when a problem (or a difference) is found.
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
    if problems:
        typer.echo(f"{summary}: {len(problems)} problem(s)")
        for problem in problems:
            typer.echo(f"  - {problem}")
        raise typer.Exit(code=1)
    typer.echo(f"{summary}: OK (schema, checksums, features, outcomes)")
    if resimulate is not None:
        _resimulate(directory, resimulate, seed, workers)


def _resimulate(directory: Path, grips: int, seed: int, workers: int) -> None:
    """Report the re-simulation; exit 1 when anything differs."""
    with user_errors():
        from grip_env.dataset.resimulation import resimulate

        found = resimulate(directory, grips, seed=seed, workers=workers)
    typer.echo(found.summary())
    if not found.identical:
        for difference in found.differences:
            typer.echo(f"  - {difference}")
        raise typer.Exit(code=1)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("validate")(validate)
