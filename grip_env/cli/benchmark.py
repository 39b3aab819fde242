"""``grip-env benchmark``: score a user's grip selector on the standard split of a dataset, or on
a seeded split of its own objects when it lacks the standard ones."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.notices import warn_label_model
from grip_env.cli.options import STANDARD_DATA, ConfigFile, DatasetDir, OutputDir
from grip_env.shutdown import stop_on_signals


class SplitMode(StrEnum):
    """``--split``: the standard split when DATA has its objects, else a seeded one (``auto``),
    or the standard split only (``standard``)."""

    auto = "auto"
    standard = "standard"


def benchmark(
    methods: Annotated[
        list[str],
        typer.Argument(help="the method: an SB3 .zip (MaskablePPO or PPO on GripSelect-v0), a "
                            "d3rlpy .d3 (an offline policy trained on a Minari export), a "
                            "model grip-env train saved (NAME.json or its .skops, .pt, .txt), a "
                            ".skops model, or module:function (or module:Class, or module:obj "
                            "with predict(observation)); several = runs (seeds) of one method",
                            show_default=False),
    ],
    out: OutputDir,
    data: DatasetDir = STANDARD_DATA,
    name: Annotated[str | None, typer.Option(help="method name [default: the first METHOD's "
                                                  "file stem or function name]")] = None,
    config: ConfigFile = None,
    reps: Annotated[int, typer.Option(min=100, max=100_000,
                                      help="bootstrap resamples")] = 2000,
    split: Annotated[SplitMode, typer.Option(
        help="auto: the latest standard split whose held-out objects all have grips in DATA, "
             "else a seeded split of DATA's own objects (named auto-not-standard: not "
             "comparable with standard-split scores); standard: the standard split or an error "
             "saying what fits")] = SplitMode.auto,
    split_version: Annotated[int | None, typer.Option(
        min=1,
        help="standard split version (implies --split standard) [default: the latest, 4: the "
             "standard dataset]; 3 = the default study's dataset of 80 objects, 2 = of the "
             "60-object set with meshes, 1 = before the default objects gained meshes")] = None,
    seed: Annotated[int, typer.Option(min=0, help="seed of the auto split")] = 0,
) -> None:
    """Score METHODS on the standard split (grip-select-standard v4: 128 held-out objects of the
    standard dataset, their 64 best candidates by Q_C) against best-Q_C, best-Q_G, epsilon, random
    and the oracle. A dataset without grips of the standard objects (a small one, or one whose
    planning kept no grip of one of them) is scored on a seeded split of its own objects,
    named auto-not-standard, unless --split standard is given.

    A function method takes one object's candidate table (outcomes removed, rows in slot order)
    and returns a score per row (higher = pick first) or one row index; with a `seed` argument it
    is called once per training seed 0..4; `module` is imported from the current folder first.
    An object with predict(observation) (an SB3-style policy) gets each object's GripSelect-v0
    observation and returns a slot; a declared action_space other than the split's is refused.
    A method trained on a held-out object (by its record: a saved model's trained_on, NAME.json
    beside an agent's NAME.zip or a d3rlpy NAME.d3, an RL Zoo run's args.yml, a function's
    trained_on) is refused; one without a record is scored and marked. The leaderboard lists
    the method's training budget (environment steps, or the dataset's transitions). Writes
    OUT/leaderboard.json, OUT/leaderboard.md and the performance-profile and attempts figures;
    bad input writes nothing (exit 2).
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
        from classifiers.report.leaderboard import write_leaderboard_markdown

        warn_label_model(data)
        table = check_grip_table(data)
        if GROUP_COLUMN not in table.columns:
            raise ValueError(f"dataset {data} has no {GROUP_COLUMN!r} column")
        label = name or _default_name(methods[0])
        board = benchmark_method(table, methods, label, cfg, reps, split_version, split.value,
                                 seed)  # fmt: skip
        _check_out(out)
        written = [*write_leaderboard(board, out), write_leaderboard_markdown(board, out)]
    from classifiers.report.judge import leaderboard_caution

    row, chosen = board["methods"][label], board["split"]
    caution = leaderboard_caution(board)
    typer.echo(f"split {chosen['name']} v{chosen['version']}"
               + (f": {chosen['note']}" if chosen.get("note") else ""))  # fmt: skip
    typer.echo(f"{label}: top-1 success {row['success']:.3f} [{row['success_ci'][0]:.3f}, "
               f"{row['success_ci'][1]:.3f}], normalised IQM {row['iqm']['estimate']:.3f} "
               f"[{row['iqm']['ci'][0]:.3f}, {row['iqm']['ci'][1]:.3f}], "
               f"{'no verdict' if caution else row['verdict']}")  # fmt: skip
    if caution:
        typer.echo(f"caution: {caution}")
    if row.get("training"):
        typer.echo(f"{label}: {row['training']['note']}")
    if row.get("budget"):
        typer.echo(f"{label}: training budget {row['budget']['text']}")
    typer.echo(f"wrote {written[0]} and {written[-1]}")


def _default_name(spec: str) -> str:
    from classifiers.experiments.benchmark import MODEL_SUFFIXES

    path = Path(spec)
    if path.suffix.lower() in (".zip", ".d3", *MODEL_SUFFIXES):
        return path.stem
    if path.name and path.with_name(f"{path.name}.json").is_file():  # a saved model's bare name
        return path.name
    return spec.rpartition(":")[2]


def _check_out(out: Path) -> None:
    from grip_env.cli.paths import output_dir

    output_dir(out)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("benchmark")(benchmark)
