"""Options shared by several ``grip-env`` subcommands, spelled once."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

ConfigFile = Annotated[
    Path | None,
    typer.Option(help="YAML config (default: the built-in defaults, as in configs/default.yaml)"),
]


def dataset_folder(value: Path | None) -> Path | None:
    """A ``--data`` value as a folder: ``standard`` is the shipped standard dataset
    (:func:`grip_env.datasets.resolve_data`); a bad one ends the command with one line, exit 2."""
    if value is None:
        return None
    from grip_env.cli.errors import checked
    from grip_env.datasets import resolve_data

    return checked(lambda: resolve_data(value))


def dataset_folders(values: list[Path]) -> list[Path]:
    """:func:`dataset_folder` of each value of a repeated ``--data``."""
    return [folder for folder in map(dataset_folder, values) if folder is not None]


DATA_HELP = "dataset directory (written by grip-env generate), or 'standard' for the shipped one"
DatasetDir = Annotated[Path, typer.Option("--data", "-d", help=DATA_HELP, callback=dataset_folder)]
#: The default of a learning command's ``--data``: the shipped standard dataset.
STANDARD_DATA = Path("standard")
OutputDir = Annotated[
    Path, typer.Option("--out", "-o", help="output directory (created if needed)")
]

MODEL_NAMES_HELP = "svm, mlp_torch, mlp_sklearn, knn, logreg, hgb, rank_qc, rank_qg, random"
"""The model names of ``classifiers.learners.models.MODEL_NAMES`` (a test keeps them equal), for
help
texts: importing the learning package to list them would load torch on every command."""
