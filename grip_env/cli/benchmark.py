"""``grip-env benchmark``: score a user's grip selector on the standard split of a dataset."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.notices import warn_label_model
from grip_env.cli.options import ConfigFile, DatasetDir, OutputDir
from grip_env.shutdown import stop_on_signals


def benchmark(
    methods: Annotated[
        list[str],
        typer.Argument(help="the method: an SB3 .zip (MaskablePPO or PPO on GripSelect-v0), a "
                            ".skops model, or module:function; several = runs (seeds) of one "
                            "method", show_default=False),
    ],
    data: DatasetDir,
    out: OutputDir,
    name: Annotated[str | None, typer.Option(help="method name [default: the first METHOD's "
                                                  "file stem or function name]")] = None,
    config: ConfigFile = None,
    reps: Annotated[int, typer.Option(min=100, max=100_000,
                                      help="bootstrap resamples")] = 2000,
    split_version: Annotated[int | None, typer.Option(
        help="standard split version [default: the latest, 3]; 2 = default datasets of the "
             "60-object set with meshes, 1 = before the default objects gained meshes")] = None,
) -> None:
    """Score METHODS on the standard split (grip-select-standard v3: 17 held-out objects of the
    default dataset, their 64 best candidates by Q_C) against best-Q_C, best-Q_G, epsilon, random
    and the oracle.

    A function method takes one object's candidate table (outcomes removed, rows in slot order)
    and returns a score per row (higher = pick first) or one row index; with a `seed` argument it
    is called once per training seed 0..4. Writes OUT/leaderboard.json, OUT/leaderboard.md and
    the performance-profile and attempts figures; bad input writes nothing (exit 2).
    """
    with stop_on_signals(f"rerun the same command to redo {out}"), user_errors():
        from grip_env.config import load_config
        from grip_env.dataset.split import GROUP_COLUMN

        if out.exists() and not out.is_dir():
            raise ValueError(f"--out {out} is an existing file; give a directory")
        cfg = load_config(config)
        from classifiers.experiments.benchmark import benchmark_method
        from classifiers.experiments.benchmark.leaderboard import write_leaderboard
        from classifiers.experiments.selector.data import check_grip_table

        warn_label_model(data)
        table = check_grip_table(data)
        if GROUP_COLUMN not in table.columns:
            raise ValueError(f"dataset {data} has no {GROUP_COLUMN!r} column")
        label = name or _default_name(methods[0])
        board = benchmark_method(table, methods, label, cfg, reps, split_version)
        _check_out(out)
        written = write_leaderboard(board, out)
    row = board["methods"][label]
    typer.echo(f"{label}: top-1 success {row['success']:.3f}, normalised IQM "
               f"{row['iqm']['estimate']:.3f} [{row['iqm']['ci'][0]:.3f}, "
               f"{row['iqm']['ci'][1]:.3f}], {row['verdict']}")  # fmt: skip
    typer.echo(f"wrote {written[0]} and {written[1]}")


def _default_name(spec: str) -> str:
    path = Path(spec)
    return path.stem if path.suffix.lower() in (".zip", ".skops") else spec.rpartition(":")[2]


def _check_out(out: Path) -> None:
    from grip_env.cli.paths import output_dir

    output_dir(out)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("benchmark")(benchmark)
