"""``grip-env calibrate``: measured checks that the simulated labels measure the grip."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import ConfigFile, dataset_folder
from grip_env.cli.paths import output_dir
from grip_env.progress import shown
from grip_env.shutdown import stop_on_signals


def calibrate(
    config: ConfigFile = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="output folder")] = Path(
        "runs/calibration"
    ),
    data: Annotated[
        Path | None,
        typer.Option("--data", "-d", help="dataset for the decile checks (a study's, or "
                     "'standard')", callback=dataset_folder),
    ] = None,
    workers: Annotated[int, typer.Option(min=1, help="worker processes (one object each)")] = 2,
    quick: Annotated[bool, typer.Option("--quick", help="a few dozen trials, for tests")] = False,
    cone_objects: Annotated[
        int | None,
        typer.Option(min=2, help="objects paired in the cone check (default: the size "
                                 "chosen by measurement, in calibration.json's settings)"),
    ] = None,
    cone_trials: Annotated[
        int | None,
        typer.Option(min=1, help="trials per grip in the cone check (default: as chosen)"),
    ] = None,
) -> None:
    """Write OUT/calibration.md (and .html, .json, figures): each check measured, pass or fail.

    Checks: the best grip of three boxes holds the reference level at the design friction; a
    grip outside the friction cone holds less than the best grip; test-retest Spearman and
    ICC(1) of robustness; with `--data`, Spearman of Q_C (and Q_G) decile with mean robustness.
    """
    with stop_on_signals(f"rerun the same command to redo {out}"), user_errors(), shown():
        from grip_env.config import load_config
        from grip_env.sim.engine import require_engine

        cfg = load_config(config)
        require_engine(cfg.sim.engine)
        output_dir(out)
        from classifiers.report.calibration import write_calibration
        from grip_env.calibration import CalibrationSettings
        from grip_env.calibration import calibrate as run

        dataset = None
        if data is not None:
            from grip_env.dataset import load

            dataset = load(data)
        settings = (CalibrationSettings.quick(workers) if quick
                    else CalibrationSettings(workers=workers))  # fmt: skip
        sizes = {k: v for k, v in (("cone_objects", cone_objects), ("cone_trials", cone_trials))
                 if v is not None}  # fmt: skip
        settings = replace(settings, **sizes)
        result, trials = run(cfg, settings, dataset, log=typer.echo)
        md = write_calibration(out, result, trials)
        for name, check in result["checks"].items():
            verdict = {True: "pass", False: "FAIL", None: "-"}[check["passed"]]
            typer.echo(f"{name:12s} {verdict:5s} {check['target']}"
                       + (f" ({check['reason']})" if check.get("reason") else ""))
        typer.echo(f"wrote {md}")


def register(app: typer.Typer) -> None:
    """Add the command to the ``grip-env`` app."""
    app.command("calibrate")(calibrate)
