"""``grip-env candidates``: the candidate grips of an object with their twelve measures."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.objects import (
    MESH_HELP,
    OBJECT_HELP,
    ContourOption,
    MmPerPxOption,
    PlannedObject,
    contour_words,
    load_objects,
    perceives,
    plan,
    require_grips,
    without_grips,
)
from grip_env.cli.options import ConfigFile
from grip_env.cli.paths import output_file

if TYPE_CHECKING:
    import pandas as pd

#: The suffixes ``--out`` takes, and what each writes.
TABLE_SUFFIXES = (".csv", ".parquet")


def candidates(
    obj: Annotated[str, typer.Argument(metavar="OBJECT", help=OBJECT_HELP)],
    top: Annotated[int | None, typer.Option(
        min=1, help="only the best N grips of each object by Q_C (default: every grip)")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="also write the table, with every candidate column of the "
                            "design's candidate table, to this .csv or .parquet file")] = None,
    config: ConfigFile = None,
    mm_per_px: MmPerPxOption = None,
    contour: ContourOption = None,
    digits: Annotated[int, typer.Option(
        min=0, max=12, help="decimals of the printed measures")] = 3,
) -> None:
    """Print the candidate grips of OBJECT, best first by Q_C: grip id, the twelve measures
    S1-S4, G1-G2, C1-C6 and the indexes Q_G and Q_C.

    Grips are planned where generate plans them: on the perceived contour by default (see
    --contour); the first line says which. Exit codes: 0 done; 2 bad input, or no object has a
    feasible grip (nothing is written).
    """
    with user_errors():
        from grip_env.config import load_config

        if out is not None:
            _check_table_file(out)
        cfg = load_config(config)
        objects = load_objects(obj, mm_per_px, cfg)
        perceive = perceives(contour, cfg)
        planned = plan(objects, cfg, perceive)
        require_grips(planned, perceive, cfg)
        table = _best(planned, top)
        of = planned[0].name if len(planned) == 1 else f"{len(planned)} objects"
        typer.echo(f"{len(table)} grips of {of}, planned on {contour_words(perceive)}, best "
                   "first by Q_C")
        empty = without_grips(planned)
        if empty:
            typer.echo(f"no feasible grip: {', '.join(empty)}")
        typer.echo(_printed(table, digits))
        if out is not None:
            _write(table, out)
            typer.echo(f"wrote {out}")


def _best(planned: list[PlannedObject], top: int | None) -> pd.DataFrame:
    """The candidates of every object (the best ``top`` of each), in object order."""
    import pandas as pd

    tables = [item.table if top is None else item.table.head(top)
              for item in planned if item.table is not None]
    return pd.concat(tables, ignore_index=True)


def _printed(table: pd.DataFrame, digits: int) -> str:
    """The printed columns: grip id, the twelve measures, Q_G and Q_C."""
    from grip_env.columns import FEATURES, INDEXES

    shown = table.loc[:, ["grip_id", *FEATURES, *INDEXES]]
    return shown.to_string(index=False, float_format=lambda value: f"{value:.{digits}f}")


def _check_table_file(out: Path) -> None:
    """Refuse an ``--out`` that is not a writable .csv or .parquet file, before any work."""
    suffix = out.suffix.lower()
    if suffix not in TABLE_SUFFIXES:
        raise ValueError(f"--out {out} must end in {' or '.join(TABLE_SUFFIXES)}")
    output_file(out, suffix)


def _write(table: pd.DataFrame, out: Path) -> None:
    if out.suffix.lower() == ".csv":
        table.to_csv(out, index=False)
    else:
        table.to_parquet(out, index=False)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI, with the shape names in its help."""
    from grip_env.objects.shapes import SHAPE_NAMES

    app.command("candidates", epilog=f"Shape names: {', '.join(SHAPE_NAMES)}. {MESH_HELP}")(
        candidates)
