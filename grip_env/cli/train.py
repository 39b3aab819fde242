"""``grip-env train``: cross-validate, plot and save the grip classifiers, regressors and
rankers (its help names them from the learning package's registries, when shown)."""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, Any

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.helptext import LearnerHelp
from grip_env.cli.inputs import learning_table
from grip_env.cli.notices import warn_label_model
from grip_env.cli.options import STANDARD_DATA, ConfigFile, DatasetDir, OutputDir
from grip_env.cli.paths import check_output_dir, output_dir
from grip_env.progress import shown
from grip_env.shutdown import stop_on_signals


class TrainSplit(StrEnum):
    """``--split``: fit the saved models on every object (``all``) or on the training objects
    of the benchmark's split only (``train``)."""

    all = "all"
    train = "train"


def train(
    out: OutputDir,
    data: DatasetDir = STANDARD_DATA,
    config: ConfigFile = None,
    models: Annotated[
        str | None,
        typer.Option(help="comma-separated classifier names, from {classifiers} "
                          "[default: config learning.models]"),
    ] = None,
    split: Annotated[TrainSplit, typer.Option(
        help="all: everything is fitted on every object of DATA; train: only on the training "
             "objects of the split grip-env benchmark scores DATA on (the standard split's 382 "
             "of the standard dataset's 510; else a seeded split, seed learning.seed), so its "
             "saved models can be benchmarked. Each model's JSON records its objects "
             "(trained_on)")] = TrainSplit.all,
) -> None:
    """Cross-validate classifiers, regressors and rankers; save each, refitted, in OUT/models/.

    Classifiers of grip success ({classifiers}; --models, default config learning.models):
    OUT/metrics.json (grouped CV), roc.png, calibration.png and OUT/models/NAME.json.
    Regressors of robustness_mean ({regressors}; config learning.regressors), when the dataset
    has it: OUT/regression.json and OUT/models/regressor_NAME.json. Rankers, one query per
    object ({rankers}; config learning.rankers): OUT/ranking.json and
    OUT/models/ranker_NAME.json. grip-env predict scores a dataset with any of these models.
    """
    with stop_on_signals(f"rerun the same command to redo {out}"), user_errors(), shown():
        from grip_env.config import load_config

        settings = load_config(config)
        if models is not None:
            settings = settings.override(learning={"models": model_names(models)})
        check_model_names(settings.learning.models)
        check_output_dir(out)
        table, chosen = _fitted_table(learning_table(data, settings), settings, split)
        output_dir(out)
        warn_label_model(data)
        from classifiers.experiments.training import train_and_save

        metrics = train_and_save(table, out, settings, chosen)
        blocks = {name: summary["roc_auc"] for name, summary in metrics["models"].items()}
        for name, block in blocks.items():
            typer.echo(auc_line(name, block, 12))
        for line in cautions(blocks, metrics["cv"]["n_objects"]):
            typer.echo(line)
        typer.echo(_fitted_on(table, chosen))
        typer.echo(f"wrote {out / 'metrics.json'}")


def _fitted_table(table: Any, settings: Any, split: TrainSplit) -> tuple[Any, dict[str, Any]]:
    """The grips the models are fitted on, and how they were chosen (``--split``)."""
    if split is TrainSplit.all:
        return table, {"split": "all"}
    from classifiers.evaluation.cross_validation import check_dataset
    from classifiers.experiments.benchmark.split import training_objects
    from classifiers.learners.persistence import dataset_checksum
    from grip_env.columns import FEATURES

    train_table, chosen = training_objects(table, settings)
    check_dataset(train_table, FEATURES, settings.learning.folds)
    return train_table, {**chosen, "dataset_sha256": dataset_checksum(table)}


def _fitted_on(table: Any, chosen: dict[str, Any]) -> str:
    """One line: which objects the saved models were fitted on."""
    objects = table["object_id"].nunique()
    if chosen["split"] == "all":
        return (f"models fitted on all {objects} objects (grip-env benchmark refuses them: "
                f"--split train fits them on the benchmark split's training objects)")
    auto = chosen["split_version"] == 0 and chosen["split_seed"] != 0  # not the default seed
    seed = f"; benchmark them with --seed {chosen['split_seed']}" if auto else ""
    return (f"models fitted on the {objects} training objects of {chosen['split_name']} "
            f"v{chosen['split_version']} ({chosen['held_out_objects']} held out){seed}")


def auc_line(name: str, block: dict[str, Any], width: int) -> str:
    """``name  ROC-AUC 0.712 [0.650, 0.770]``: the CV mean and its 95 % interval."""
    mean, (low, high) = block.get("mean"), block.get("ci") or (None, None)
    if mean is None:
        return f"{name:{width}s} ROC-AUC n/a (undefined on these folds)"
    interval = f" [{low:.3f}, {high:.3f}]" if low is not None and high is not None else ""
    return f"{name:{width}s} ROC-AUC {mean:.3f}{interval}"


def cautions(blocks: dict[str, dict[str, Any]], objects: int, subject: str = "") -> list[str]:
    """The lines under the scores when they cannot be judged: ``blocks`` (ROC-AUC per name)
    that predicted a constant, and too few objects (the report's rule,
    :mod:`classifiers.report.judge`). ``subject``: whose blocks they are, when not learners."""
    from classifiers.report.judge import constant_scores, small_data_caution

    lines = []
    constant = constant_scores(blocks)
    if constant:
        names = (f"{len(constant)} of {len(blocks)}" if len(constant) > 3 else
                 ", ".join(constant))  # fmt: skip
        lines.append(f"caution: {subject}{names} scored every grip alike in every fold (ROC-AUC "
                     f"0.500, zero-width interval): a constant prediction, nothing learnt from "
                     f"data this small")  # fmt: skip
    small = small_data_caution(objects)
    return [*lines, small] if small else lines


def model_names(text: str) -> tuple[str, ...]:
    """The names of a comma-separated ``--models`` value; refused when it names none."""
    names = tuple(name.strip() for name in text.split(",") if name.strip())
    if not names:
        raise ValueError(f"--models {text!r} names no model; give e.g. svm,knn")
    return names


def check_model_names(names: tuple[str, ...]) -> None:
    """Refuse an unknown or repeated model name before any work starts."""
    from classifiers.learners.models import MODEL_NAMES

    unknown = [name for name in names if name not in MODEL_NAMES]
    if unknown:
        raise ValueError(f"unknown model {unknown[0]!r}; choose from {', '.join(MODEL_NAMES)}")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ValueError(f"model {repeated[0]!r} is named twice")


def register(app: typer.Typer) -> None:
    """Add the command to the ``grip-env`` app."""
    app.command("train", cls=LearnerHelp)(train)
