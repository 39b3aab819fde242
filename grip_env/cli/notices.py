"""One-line ``warning:`` notices on stderr: things worth knowing that do not stop a command."""

from __future__ import annotations

from pathlib import Path

import typer


def warn_label_model(data: Path) -> None:
    """Say on stderr when dataset ``data`` was labelled by another label model than this code's
    (nothing for a bare table, or a dataset the command will refuse on its own)."""
    from grip_env.dataset import label_model_notice

    notice = label_model_notice(data)
    if notice is not None:
        typer.echo(f"warning: {notice}", err=True)
