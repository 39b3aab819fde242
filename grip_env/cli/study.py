"""``grip-env study``: the whole main job on one config, ending in a report."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import DATA_HELP, ConfigFile, dataset_folder
from grip_env.cli.paths import check_output_dir
from grip_env.progress import shown
from grip_env.shutdown import stop_on_signals


def study(
    config: ConfigFile = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="study folder")] = Path("runs/default"),
    quick: Annotated[
        bool,
        typer.Option("--quick", help="tiny profile for tests: shrinks the settings the config "
                                     "leaves at their defaults, and says which"),
    ] = False,
    data: Annotated[
        Path | None,
        typer.Option("--data", "-d", help=f"learn on this {DATA_HELP} (its own recipe; a seeded "
                     "sample of it is re-simulated first); default: standard"),
    ] = None,
    regenerate: Annotated[
        bool,
        typer.Option("--regenerate", help="generate the dataset from the config's recipe into "
                                          "OUT/dataset instead of learning on --data"),
    ] = False,
    update_readme: Annotated[
        bool,
        typer.Option("--update-readme",
                     help="rewrite the results block of README (between its results markers) "
                          "and publish the study's figures beside it, in docs/_static/results"),
    ] = False,
    readme: Annotated[
        Path, typer.Option(help="the README --update-readme rewrites")
    ] = Path("README.md"),
) -> None:
    """Run the whole study and write OUT/report.md and OUT/report.html.

    Learns on the shipped standard dataset (or the one --data names), after re-simulating a
    seeded sample of it; --regenerate (and --quick, unless --data is given) generates the
    dataset from the config's recipe into OUT/dataset instead. Then it trains and evaluates
    the classifiers, runs the ablation, trains and evaluates the RL selector, scores every
    method on the benchmark's split, checks the labels (the calibration the dataset records
    for its label model and recipe, or grip-env calibrate's checks run anew), and writes the
    report. A rerun reuses every stage whose inputs
    (config fields, dataset, grip-env version, the code it runs) are unchanged and recomputes the
    others.
    Exit codes: 0 done, 1 internal error, 2 bad input, 130/143/129 stopped by a signal.
    """
    with stop_on_signals(f"rerun the same command to finish {out}"), user_errors(), shown():
        check_output_dir(out)
        from grip_env.config import load_config
        from grip_env.sim.engine import require_engine

        settings = load_config(config)
        require_engine(settings.sim.engine)  # its trials run in it: refused before any work
        data = study_data(data, regenerate, quick)
        if update_readme and not readme.is_file():
            raise ValueError(f"--readme {readme} is not a file")
        from classifiers.experiments.study import run_study
        from grip_env.dataset import DatasetMismatchError

        try:
            report = run_study(settings, out, quick=quick, log=typer.echo, data=data)
        except DatasetMismatchError as exc:  # its advice names generate's --overwrite
            reason = str(exc).split("; use --overwrite", 1)[0]
            raise ValueError(
                f"{reason}; choose another --out, or delete {out / 'dataset'} to regenerate it"
            ) from None
        if update_readme:
            _update_readme(out, readme)
    typer.echo(f"report: {report}")


def study_data(data: Path | None, regenerate: bool, quick: bool) -> Path | None:
    """The dataset folder the study learns on, or None to generate one from the recipe: the
    standard dataset unless ``--regenerate`` (or ``--quick`` without ``--data``) is given."""
    if regenerate and data is not None:
        raise ValueError(f"--data {data} and --regenerate: give one (--regenerate generates the "
                         "dataset into OUT/dataset, --data learns on a given one)")
    if regenerate or (quick and data is None):
        return None
    from grip_env.datasets import STANDARD

    return dataset_folder(data or Path(STANDARD))


def _update_readme(out: Path, readme: Path) -> None:
    """Publish the study's figures beside the README (with their stamp), rewrite its results
    block, and the leaderboard block of the benchmark page beside it (``docs/benchmark.md``,
    when it has the markers)."""
    from classifiers.experiments.study import package_version, study_dataset
    from classifiers.report.published import GALLERY, RESULTS_FOLDER, publish
    from classifiers.report.readme import (
        LEADERBOARD_BEGIN,
        LEADERBOARD_END,
        leaderboard_block,
        results_block,
        update_readme,
    )
    from classifiers.report.study_report import source_commit
    from grip_env.dataset import dataset_manifest, load

    data_dir = study_dataset(out)
    table = load(data_dir)
    generated = (dataset_manifest(data_dir).get("git_commit") or "unknown")[:7]
    commit = f"{source_commit()} (its dataset generated at {generated})"
    folder = readme.parent / RESULTS_FOLDER
    stamp = publish(out, folder, commit, _dataset_sha256(out, table))
    figures = [name for name in stamp["figures"] if name != GALLERY]
    from classifiers.report.answers import read_answers
    from classifiers.report.selector_diagnosis import study_diagnosis

    diagnosis = study_diagnosis(out, read_answers(out), root=readme.parent)
    update_readme(readme, results_block(out, table, commit, package_version(), figures,
                                        diagnosis=diagnosis))  # fmt: skip
    typer.echo(f"updated the results block of {readme} and its {len(stamp['figures'])} "
               f"figures in {folder}")
    page, board = readme.parent / "docs" / "benchmark.md", leaderboard_block(out)
    if board is not None and page.is_file() and LEADERBOARD_BEGIN in page.read_text():
        update_readme(page, board, LEADERBOARD_BEGIN, LEADERBOARD_END)
        typer.echo(f"updated the leaderboard of {page}")


def _dataset_sha256(out: Path, table: object) -> str:
    """The checksum of the dataset the study learned on, as its ``data.json`` records it."""
    import json

    from classifiers.learners.persistence import dataset_checksum

    recorded = out / "data.json"
    found = json.loads(recorded.read_text()).get("sha256") if recorded.is_file() else None
    return found or dataset_checksum(table)


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("study")(study)
