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
