"""``grip-env power``: how the study's intervals narrow with objects and trials (a power curve)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import MODEL_NAMES_HELP, ConfigFile, OutputDir, dataset_folders
from grip_env.cli.paths import check_output_dir, output_dir
from grip_env.progress import shown
from grip_env.shutdown import stop_on_signals

_SIZES = "comma-separated sizes, e.g. 10,20,40"


def power(
    data: Annotated[
        list[Path],
        typer.Option("--data", "-d", help="dataset directory; repeat to pool datasets of the "
                     "same simulator for the objects axis (every grip cut to the fewest trials "
                     "any holds); the trials axis runs on the first; 'standard' for the "
                     "shipped one", callback=dataset_folders),
    ],
    out: OutputDir,
    config: ConfigFile = None,
    objects: Annotated[
        str | None, typer.Option(help=f"objects axis, {_SIZES} [default: 1/4, 1/2, 3/4, all]")
    ] = None,
    trials: Annotated[
        str | None, typer.Option(help=f"trials axis, {_SIZES} [default: 1, 2, 4, ..., all]")
    ] = None,
    selector_objects: Annotated[
        str, typer.Option(help=f"objects at which the RL selector is retrained ({_SIZES}; "
                          "about a minute each; empty: none)")
    ] = "",
    selector_trials: Annotated[
        str, typer.Option(help=f"trials at which the RL selector is retrained ({_SIZES})")
    ] = "",
    replicates: Annotated[int, typer.Option(min=1, help="seeded subsamples per size")] = 2,
    seed: Annotated[int, typer.Option(min=0, help="subsampling seed")] = 0,
    model: Annotated[
        str | None,
        typer.Option(help=f"the classifier: {MODEL_NAMES_HELP} [default: the config's "
                     "learning.ablation_model]"),
    ] = None,
    partial: Annotated[
        bool, typer.Option(help="use the finished objects of an unfinished dataset")
    ] = False,
) -> None:
    """Subsample the dataset by objects and by trials per grip, measure the three questions'
    95% interval half-widths on each subsample, fit h² = (a + b/t)/n and project the objects
    each target needs. Writes OUT/power.json and OUT/power.png; a study shows them when OUT is
    its power/ folder."""
    with stop_on_signals(f"rerun the same command to redo {out}"), user_errors(), shown():
        from grip_env.cli.train import check_model_names
        from grip_env.config import load_config

        settings = load_config(config)
        model = model or settings.learning.ablation_model
        check_model_names((model,))
        sizes = {name: parse_sizes(text, option) for name, text, option in (
            ("objects", objects, "--objects"), ("trials", trials, "--trials"),
            ("selector_objects", selector_objects, "--selector-objects"),
            ("selector_trials", selector_trials, "--selector-trials"))}  # fmt: skip
        from classifiers.evaluation.half_widths import FIGURE_FILE
        from classifiers.experiments.power import run_power
        from classifiers.report.power import plot_power
        from grip_env.dataset import load

        check_output_dir(out)
        tables = [load(path, allow_partial=partial) for path in data]
        output_dir(out)
        summary = run_power(
            tables, out, settings, sizes["objects"] or None, sizes["trials"] or None, replicates,
            seed, model, sizes["selector_objects"], sizes["selector_trials"],
            source={"datasets": ", ".join(str(p) for p in data)}, log=typer.echo,
        )
        for quantity, needed in summary["projection"].items():
            found = ", ".join(f"{n} at {t} trials" for t, n in needed.items())
            typer.echo(f"{quantity}: target {summary['targets'][quantity]} needs {found}")
        plot_power(summary, out / FIGURE_FILE)
        typer.echo(f"wrote {out / 'power.json'} and {out / FIGURE_FILE}")


def parse_sizes(text: str | None, option: str) -> tuple[int, ...]:
    """The positive integers of a comma-separated option (empty: none)."""
    if text is None:
        return ()
    sizes = []
    for part in (p.strip() for p in text.split(",") if p.strip()):
        if not part.isdigit() or int(part) < 1:
            raise ValueError(f"{option} {text!r}: {part!r} is not a positive integer")
        sizes.append(int(part))
    return tuple(sizes)


def register(app: typer.Typer) -> None:
    """Add the command to the ``grip-env`` app."""
    app.command("power")(power)
