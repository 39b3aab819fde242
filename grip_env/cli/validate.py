"""``grip-env validate``: check a dataset (schema, checksums, features, outcomes)."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from grip_env.cli.errors import checked, user_errors
from grip_env.cli.notices import warn_label_model
from grip_env.cli.options import dataset_folder
from grip_env.cli.paths import output_file
from grip_env.progress import shown

if TYPE_CHECKING:
    from grip_env.dataset.crosscheck import EngineCost


def validate(
    directory: Annotated[Path, typer.Argument(
        help="dataset directory written by generate, or 'standard' for the shipped one",
        callback=dataset_folder)],
    resimulate: Annotated[int | None, typer.Option(
        min=1, help="also plan again a seeded sample of objects and simulate again this many of "
                    "their grips, with the dataset's own config and seeds (exact comparison)")
    ] = None,
    retest: Annotated[int | None, typer.Option(
        min=1, help="also simulate every grip of this many seeded objects under new draws and "
                    "report the within-object test-retest of the labels")
    ] = None,
    crosscheck: Annotated[int | None, typer.Option(
        min=1, help="also simulate every grip of this many seeded objects in the other engine "
                    "(same grips, draws and protocol) and report how far the engines agree")
    ] = None,
    seed: Annotated[int, typer.Option(min=0, help="seed of the samples")] = 0,
    workers: Annotated[int, typer.Option(min=1, help="worker processes for the samples")] = 2,
    report: Annotated[Path | None, typer.Option(
        help="write what --resimulate, --retest and --crosscheck found to this JSON file (for "
             "the card); a cross-check keeps each object's outcomes in REPORT's stem + "
             "'.crosscheck/', so that the same command resumes it")
    ] = None,
) -> None:
    """Check a dataset: schema, checksums, features and outcomes; with `--resimulate N`, that
    its candidates and labels are what this code makes.

    Verifies the schema, the SHA-256 of every file, every feature recomputed from its
    descriptors, and outcome consistency, and names the dataset's label model (a warning, not a
    problem, when it is not this grip-env's). `--resimulate N` re-plans a seeded sample of
    objects and re-simulates N of their grips, and counts what is identical bit for bit.
    `--crosscheck N` simulates every grip of N seeded objects in the other engine (PyBullet or
    MuJoCo) and reports the agreement (per-trial success and kappa, within-object Spearman).
    Exit code 0 when clean, 1 when a problem (or a difference) is found.
    """
    with user_errors():
        from grip_env.dataset import validate as validate_dataset
        from grip_env.dataset.manifest import read_manifest
        from grip_env.label_model import label_model_of

        manifest = read_manifest(directory)
        if resimulate is not None or retest is not None:  # they simulate in its own engine
            from grip_env.label_model import engine_of
            from grip_env.sim.engine import require_engine

            require_engine(engine_of(manifest))
        if crosscheck is not None:
            from grip_env.dataset.crosscheck import check_crosscheckable

            check_crosscheckable(directory)
        problems = validate_dataset(directory)
    warn_label_model(directory)
    label_model = f"label model {label_model_of(manifest)}"
    if problems:  # the problems first, then what the shards on disk hold: not a whole dataset's
        typer.echo(f"{directory}: {len(problems)} problem(s)")
        for problem in problems:
            typer.echo(f"  - {problem}")
        typer.echo(f"{directory}: {_counts(directory, manifest)}, {label_model}")
        raise typer.Exit(code=1)
    typer.echo(f"{directory}: {manifest['rows']} grips, {len(manifest['objects'])} objects, "
               f"{label_model}: OK (schema, checksums, features, outcomes)")
    if report is not None:
        checked(lambda: output_file(report, ".json", "--report"))
    found: dict[str, object] = {}
    if retest is not None:
        found["retest"] = _retest(directory, retest, seed, workers)
    if resimulate is not None:
        found["resimulation"] = _resimulate(directory, resimulate, seed, workers)
    if crosscheck is not None:
        found["crosscheck"] = _crosscheck(directory, crosscheck, seed, workers, report)
    if report is not None:
        report.write_text(json.dumps(found, indent=1), encoding="utf-8")
    if resimulate is not None and found["resimulation"]["differences"]:
        raise typer.Exit(code=1)


def _counts(directory: Path, manifest: dict[str, Any]) -> str:
    """The grips and objects of the shards present on disk; "incomplete" when some are not."""
    from grip_env.dataset.manifest import shard_records

    total = len(manifest["objects"])
    present = [record for record in shard_records(manifest).values()
               if (directory / record.file).is_file()]
    rows = sum(record.rows for record in present)
    if len(present) == total:
        return f"{rows} grips, {total} objects"
    return (f"incomplete: {rows} grips in the shards of {len(present)} of {total} objects "
            f"({total - len(present)} without a shard on disk)")


def _resimulate(directory: Path, grips: int, seed: int, workers: int) -> dict[str, object]:
    """Report the re-simulation (every difference on its own line)."""
    with user_errors(), shown():
        from grip_env.dataset.resimulation import resimulate

        found = resimulate(directory, grips, seed=seed, workers=workers)
    typer.echo(found.summary())
    for difference in found.differences:
        typer.echo(f"  - {difference}")
    return {"grips": grips, "seed": seed, "summary": found.summary(), **asdict(found)}


def _crosscheck(directory: Path, objects: int, seed: int, workers: int,
                report: Path | None) -> dict[str, object]:
    """Report the agreement between engines and their costs (each object's outcomes kept beside
    ``report``, so that a rerun of an interrupted cross-check resumes)."""
    with user_errors(), shown():
        from grip_env.dataset.crosscheck import crosscheck

        parts = None if report is None else crosscheck_parts(report)
        found = crosscheck(directory, objects, seed=seed, workers=workers, parts=parts)
    typer.echo(found.summary())
    for group, figures in [*found.families.items(), *found.by_grips.items(),
                           *found.by_pieces.items()]:
        typer.echo(f"  {group} ({figures.objects} objects): success agree "
                   f"{figures.agreement:.1%}, kappa {figures.kappa:.2f}, within "
                   f"{figures.within:.2f} (retests {figures.retest_own:.2f}, "
                   f"{figures.retest_other:.2f}), pooled {figures.pooled:.2f}, top-1 "
                   f"{figures.top1_own:.0%} / {figures.top1_other:.0%}, mean robustness "
                   f"{figures.robustness_own:.1f} / {figures.robustness_other:.1f} g")
    for cost in found.cost:
        typer.echo(f"  {cost.engine}: {cost.ms_per_trial:.0f} ms a trial, "
                   f"{cost.us_per_step:.0f} us a step, {cost.trials_for_trustworthy:.1f} trials "
                   f"for a retest of 0.8: {cost.core_seconds_per_label:.2f} core-s a label"
                   f"{_measured(cost)}")
    return {"objects": objects, **found.as_dict()}


def _measured(cost: EngineCost) -> str:
    """The retest measured at each label size, and the label it makes trustworthy."""
    if not cost.retest_by_trials:
        return ""
    curve = ", ".join(f"{v:.2f}" for v in cost.retest_by_trials)
    return (f"; retest measured at 1..{len(cost.retest_by_trials)} trials {curve}: "
            f"{cost.trials_measured:.0f} trials, {cost.core_seconds_measured:.2f} core-s a label")


def crosscheck_parts(report: Path) -> Path:
    """The folder beside ``report`` that keeps a cross-check's per-object outcomes."""
    return report.with_name(report.stem + ".crosscheck")


def _retest(directory: Path, objects: int, seed: int, workers: int) -> dict[str, object]:
    """Report the within-object test-retest."""
    with user_errors(), shown():
        from grip_env.dataset.resimulation import retest

        found = retest(directory, objects, seed=seed, workers=workers)
    typer.echo(found.summary())
    return {"seed": seed, "summary": found.summary(), **asdict(found)}


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("validate")(validate)
