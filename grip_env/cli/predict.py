"""``grip-env predict``: score every grip of a dataset with a model saved by ``grip-env train``.

Models are read by :func:`classifiers.learners.persistence.load_model`: JSON metadata plus a skops
file (only trusted types), a torch ``state_dict`` (``weights_only``) or LightGBM's text model,
never a pickle. Each kind of model ``train`` writes gives its own score column: a classifier
``p_success`` (the predicted probability that the grip holds), a regressor (``regressor_<name>``)
``robustness_pred`` (the predicted ``robustness_mean``), a ranker (``ranker_<name>``)
``rank_score`` (higher = pick first; comparable within one object only).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from grip_env.cli.errors import user_errors
from grip_env.cli.options import DatasetDir
from grip_env.cli.paths import output_file
from grip_env.shutdown import stop_on_signals

if TYPE_CHECKING:
    import pandas as pd

MODEL_SUFFIXES = (".json", ".skops", ".pt", ".txt")
PROBABILITY_COLUMN = "p_success"
ROBUSTNESS_COLUMN = "robustness_pred"
RANK_COLUMN = "rank_score"
#: ``grip-env train`` saves its regressors and rankers under these prefixes (its classifiers bare)
REGRESSOR_PREFIX, RANKER_PREFIX = "regressor_", "ranker_"
AGENT_HINT = "RL agents are scored with grip-env benchmark AGENT.zip --data DATA --out OUT"


def predict(
    model: Annotated[
        Path,
        typer.Option("--model", "-m",
                     help="a model saved by grip-env train: TRAIN_OUT/models/NAME.json (or its "
                          ".skops/.pt/.txt file); a classifier, regressor_NAME or ranker_NAME"),
    ],
    data: DatasetDir,
    out: Annotated[
        Path, typer.Option("--out", "-o", help="predictions file (.parquet)")
    ] = Path("predictions.parquet"),
) -> None:
    """Write one row per grip of DATA: grip_id, object_id, the model's score and its name.

    The score is p_success (a classifier: probability that the grip holds), robustness_pred
    (a regressor: predicted robustness_mean) or rank_score (a ranker: higher = pick first,
    comparable within one object only). The file is written whole or not at all. Exit codes:
    0 done; 2 a bad model, dataset or --out; 130, 143, 129 stopped by SIGINT, SIGTERM, SIGHUP.
    """
    with stop_on_signals(f"nothing was written to {out}: rerun the same command"), user_errors():
        output_file(out, ".parquet")
        directory, name = model_location(model)
        from grip_env.dataset import load

        fitted, info = load_saved_model(directory, name)
        grips = load(data)
        # an image model draws each grip's planned-on contour, from the objects table
        shown = with_contours(grips, data) if "inputs" in info else grips
        table = predictions(fitted, info, shown)
        _write(table, out)
    typer.echo(f"wrote {out}: {len(table)} grips of {table['object_id'].nunique()} objects, "
               f"{table.columns[2]} from model {name}{_in_sample_note(info, grips)}")


def model_location(path: Path) -> tuple[Path, str]:
    """``(directory, name)`` of a saved model given by any of its files or its bare stem."""
    if path.suffix.lower() == ".zip":
        raise ValueError(f"--model {path}: a .zip is a Stable-Baselines3 agent, not a model "
                         f"grip-env train saves; {AGENT_HINT}")
    from classifiers.learners.persistence import model_format

    if path.is_dir():
        raise ValueError(f"--model {path} is a directory: give one model's .json file"
                         f"{_folder_hint(path)}")
    name = path.stem if path.suffix in MODEL_SUFFIXES else path.name
    meta = path.parent / f"{name}.json"
    if not meta.is_file():
        raise ValueError(f"--model {path}: no saved model {meta} "
                         "(grip-env train writes OUT/models/NAME.json)")
    if model_format(meta) is None:
        raise ValueError(f"--model {path}: {meta.name} is not a saved model (grip-env train "
                         f"writes them to OUT/models/){_folder_hint(path.parent)}")
    return path.parent, name


def _folder_hint(folder: Path) -> str:
    """Which models a folder holds (by their saved format), or those of its ``models/``."""
    from classifiers.learners.persistence import saved_models

    found = [f"{name}.json" for name in saved_models(folder)]
    if found:
        return f"; it holds {', '.join(found)}"
    inner = [f"models/{name}.json" for name in saved_models(folder / "models")]
    if inner:
        return f"; its models/ holds {', '.join(inner)}"
    return "; it holds no saved model"


def model_kind(info: dict[str, Any]) -> str:
    """``classifier``, ``regressor`` or ``ranker``: which of ``train``'s models ``info`` is."""
    name = str(info.get("name", ""))
    if info.get("format") == "lightgbm_text" or name.startswith(RANKER_PREFIX):
        return "ranker"
    if "target" in info or name.startswith(REGRESSOR_PREFIX):
        return "regressor"
    return "classifier"


def load_saved_model(directory: Path, name: str) -> tuple[Any, dict[str, Any]]:
    """The fitted pipeline and its metadata; a crafted or broken file is a ``ValueError``."""
    import json
    import pickle
    import zipfile

    from classifiers.learners.persistence import load_model

    try:
        return load_model(directory, name)
    except (pickle.UnpicklingError, RuntimeError, KeyError, TypeError, OSError,
            zipfile.BadZipFile, json.JSONDecodeError) as exc:
        reason = " ".join(str(exc).split())[:300]
        raise ValueError(f"cannot load model {directory / name}: {type(exc).__name__}: "
                         f"{reason}") from None


def with_contours(grips: pd.DataFrame, data: Path) -> pd.DataFrame:
    """The grips with the contours they were planned on, from the dataset's objects table."""
    from classifiers.learners.grip_images import attach_contours
    from grip_env.dataset import read_objects

    return attach_contours(grips, read_objects(data))


def predictions(model: Any, info: dict[str, Any], grips: pd.DataFrame) -> pd.DataFrame:
    """``grip_id, object_id, <score>, model`` for every grip, in the dataset's row order."""
    import numpy as np
    import pandas as pd

    missing = [column for column in info["columns"] if column not in grips.columns]
    if missing:
        raise ValueError(f"the dataset lacks column(s) the model was trained on: "
                         f"{', '.join(missing)}")
    kind = model_kind(info)
    if kind == "classifier":
        column, score = PROBABILITY_COLUMN, _success_probability(model, grips)
    else:
        column = RANK_COLUMN if kind == "ranker" else ROBUSTNESS_COLUMN
        score = np.asarray(model.predict(grips), dtype=float) if len(grips) else np.zeros(0)
    return pd.DataFrame({
        "grip_id": grips["grip_id"].to_numpy(),
        "object_id": grips["object_id"].to_numpy(),
        column: score,
        "model": info.get("name", "model"),
    })


def _success_probability(model: Any, grips: pd.DataFrame) -> Any:
    import numpy as np

    if len(grips) == 0:
        return np.zeros(0)
    proba = model.predict_proba(grips)
    classes = list(model.classes_)
    return proba[:, classes.index(True)] if True in classes else np.zeros(len(grips))


def _write(table: pd.DataFrame, out: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from grip_env.dataset.files import write_atomically

    arrow = pa.Table.from_pandas(table, preserve_index=False)
    write_atomically(out, lambda temp: pq.write_table(arrow, temp))


def _in_sample_note(info: dict[str, Any], grips: pd.DataFrame) -> str:
    """A warning when the model was trained on these very grips (its scores are in-sample)."""
    from classifiers.learners.persistence import dataset_checksum

    if info.get("dataset_sha256") == dataset_checksum(grips):
        return " (note: the model was trained on this dataset: the scores are in-sample)"
    return ""


def register(app: typer.Typer) -> None:
    """Add the command to the CLI."""
    app.command("predict")(predict)
