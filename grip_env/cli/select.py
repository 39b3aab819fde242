"""``grip-env select``: train the RL grip selector, compare it with baselines on unseen objects."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import STANDARD_DATA, ConfigFile, DatasetDir, OutputDir
from grip_env.cli.paths import check_output_dir, output_dir
from grip_env.shutdown import stop_on_signals


class Policy(StrEnum):
    """Selector policies: ``set`` (one shared scorer per candidate) or ``flat`` (a plain MLP)."""

    set = "set"
    flat = "flat"


def select(
    out: OutputDir,
    data: DatasetDir = STANDARD_DATA,
    config: ConfigFile = None,
    timesteps: Annotated[
        int | None,
        typer.Option(min=1, help="training timesteps [default: config selector.timesteps]"),
    ] = None,
    policy: Annotated[
        Policy,
        typer.Option(help="set (one shared scorer per candidate, order-free) or flat (plain MLP)"),
    ] = Policy.set,
    live: Annotated[
        bool,
        typer.Option("--live", help="train on live PyBullet trials instead of replaying (slow)"),
    ] = False,
    progress: Annotated[bool, typer.Option(help="show a progress bar")] = True,
    trials: Annotated[
        Path | None,
        typer.Option(help="re-simulated per-trial outcomes of DATA (a folder of shards, "
                          "python -m grip_env.dataset.trial_outcomes), for the retry task "
                          "(selector.max_attempts > 1) on a dataset made before they were kept"),
    ] = None,
    recorded_only: Annotated[
        bool,
        typer.Option("--recorded-only", help="the retry task on the training objects whose "
                     "trials are recorded, leaving out (and counting) the rest"),
    ] = False,
) -> None:
    """Train a MaskablePPO selector on the training objects of DATA and evaluate it on the rest.

    Writes OUT/selector.json (first-pick success with 95% intervals for the selector, random,
    best Q_C, best Q_G, classifiers and the oracle, and success within selector.max_attempts:
    on the shared draws when DATA records every trial's outcome, else with the attempts taken
    as independent, as its "attempts" entry says), OUT/model.zip (Stable-Baselines3), the
    TensorBoard logs OUT/tb and OUT/learning_curve.png. With selector.max_attempts > 1 (the
    retry task) the attempts replay one trial index k an episode: every training object's trials
    must be recorded (in DATA, or --trials), else it is refused (or, with --recorded-only, left
    out and counted).
    """
    with stop_on_signals(f"rerun the same command to redo {out}"), user_errors():
        from grip_env.config import check_setting, load_config

        cfg = load_config(config)
        if timesteps is not None:
            check_setting("selector", "timesteps", timesteps, "--timesteps")
        from classifiers.experiments.selector import REPORT_FILE, run_selector
        from classifiers.experiments.selector.data import check_grip_table
        from classifiers.experiments.selector.recorded import (
            retry_training_objects,
            with_recorded_trials,
        )

        check_output_dir(out)
        table = check_grip_table(data)
        if trials is not None:
            table = with_recorded_trials(table, trials)
        if not live:
            recorded = retry_training_objects(table, cfg, recorded_only)  # refused before writing
            if recorded is not None:
                typer.echo(recorded.summary())
        output_dir(out)
        report = run_selector(table, out, cfg, policy.value, timesteps, live, progress,
                              recorded_only)
    for name, scores in report["policies"].items():
        rate = scores["success_rate"]
        low, high = rate["ci"]
        typer.echo(f"{name:>20}: first pick holds {rate['mean']:.3f}  [{low:.3f}, {high:.3f}]")
    typer.echo(f"wrote {out / REPORT_FILE}")


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("select")(select)
