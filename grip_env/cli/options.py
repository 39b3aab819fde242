"""Options shared by several ``grip-env`` subcommands, spelled once."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

ConfigFile = Annotated[
    Path | None,
    typer.Option(help="YAML config (default: the built-in defaults, as in configs/default.yaml)"),
]
DatasetDir = Annotated[
    Path, typer.Option("--data", "-d", help="dataset directory (written by grip-env generate)")
]
OutputDir = Annotated[
    Path, typer.Option("--out", "-o", help="output directory (created if needed)")
]

MODEL_NAMES_HELP = "svm, mlp_torch, mlp_sklearn, knn, logreg, hgb, rank_qc, rank_qg, random"
"""The model names of ``classifiers.models.MODEL_NAMES`` (a test keeps them equal), for help
texts: importing the learning package to list them would load torch on every command."""
