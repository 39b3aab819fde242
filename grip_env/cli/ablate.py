"""``grip-env ablate``: the feature-ablation study (with / without hand features, ε, LOFO)."""

from __future__ import annotations

from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.inputs import learning_table
from grip_env.cli.options import MODEL_NAMES_HELP, STANDARD_DATA, ConfigFile, DatasetDir, OutputDir
from grip_env.cli.paths import check_output_dir, output_dir
from grip_env.progress import shown
from grip_env.shutdown import stop_on_signals


def ablate(
    out: OutputDir,
    data: DatasetDir = STANDARD_DATA,
    config: ConfigFile = None,
    model: Annotated[
        str | None,
        typer.Option(help=f"model cross-validated on every feature set: {MODEL_NAMES_HELP} "
                     "[default: the config's learning.ablation_model]"),
    ] = None,
) -> None:
    """Write OUT/ablation.json (metrics, paired differences, importances) and OUT/ablation.png."""
    with stop_on_signals(f"rerun the same command to redo {out}"), user_errors(), shown():
        from grip_env.cli.train import auc_line, cautions, check_model_names
        from grip_env.config import load_config

        settings = load_config(config)
        model = model or settings.learning.ablation_model
        check_model_names((model,))
        check_output_dir(out)
        table = learning_table(data, settings)
        output_dir(out)
        from classifiers.experiments.ablation import run_ablation

        result = run_ablation(table, out, settings, model)
        blocks = {name: entry["models"][model]["roc_auc"]
                  for name, entry in result["feature_sets"].items()}  # fmt: skip
        for name, block in blocks.items():
            typer.echo(auc_line(name, block, 18))
        for line in cautions(blocks, result["cv"]["n_objects"], f"{model} on feature sets "):
            typer.echo(line)
        typer.echo(f"wrote {out / 'ablation.json'}")


def register(app: typer.Typer) -> None:
    """Add the command to the ``grip-env`` app."""
    app.command("ablate")(ablate)
