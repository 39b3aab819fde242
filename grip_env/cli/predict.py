"""``grip-env predict``: score every grip of a dataset with a model saved by ``grip-env train``.

Models are read by :func:`classifiers.learners.persistence.load_model`: JSON metadata plus a skops
file
(only trusted types) or a torch ``state_dict`` (``weights_only``), never a pickle. A classifier
gives ``p_success``, the predicted probability that the grip holds; a regressor (saved as
``regressor_<name>``) gives ``robustness_pred``, the predicted ``robustness_mean``.
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

MODEL_SUFFIXES = (".json", ".skops", ".pt")
PROBABILITY_COLUMN = "p_success"
ROBUSTNESS_COLUMN = "robustness_pred"


def predict(
    model: Annotated[
        Path,
        typer.Option("--model", "-m",
                     help="a saved model: TRAIN_OUT/models/NAME.json (or its .skops/.pt file)"),
    ],
    data: DatasetDir,
    out: Annotated[
        Path, typer.Option("--out", "-o", help="predictions file (.parquet)")
    ] = Path("predictions.parquet"),
) -> None:
    """Write one row per grip of DATA: grip_id, object_id, the model's score and its name.

    The score is p_success (a classifier: probability that the grip holds) or robustness_pred
    (a regressor: predicted robustness_mean). The file is written whole or not at all. Exit
    codes: 0 done; 2 a bad model, dataset or --out; 130, 143, 129 stopped by SIGINT, SIGTERM,
    SIGHUP.
    """
    with stop_on_signals(f"nothing was written to {out}: rerun the same command"), user_errors():
        output_file(out, ".parquet")
        directory, name = model_location(model)
        from grip_env.dataset import load

        fitted, info = load_saved_model(directory, name)
        grips = load(data)
        table = predictions(fitted, info, grips)
        _write(table, out)
    typer.echo(f"wrote {out}: {len(table)} grips of {table['object_id'].nunique()} objects, "
               f"{table.columns[2]} from model {name}{_in_sample_note(info, grips)}")


def model_location(path: Path) -> tuple[Path, str]:
    """``(directory, name)`` of a saved model given by any of its files or its bare stem."""
    if path.is_dir():
        found = sorted(p.name for p in path.glob("*.json"))
        hint = f"; it holds {', '.join(found)}" if found else ""
        raise ValueError(f"--model {path} is a directory: give one model's .json file{hint}")
    name = path.stem if path.suffix in MODEL_SUFFIXES else path.name
    if not (path.parent / f"{name}.json").is_file():
        raise ValueError(f"--model {path}: no saved model {path.parent / (name + '.json')} "
                         "(grip-env train writes OUT/models/<name>.json)")
    return path.parent, name


def load_saved_model(directory: Path, name: str) -> tuple[Any, dict[str, Any]]:
    """The fitted pipeline and its metadata; a crafted or broken file is a ``ValueError``."""
    import pickle
    import zipfile

    from classifiers.learners.persistence import load_model

    try:
        return load_model(directory, name)
    except (pickle.UnpicklingError, RuntimeError, KeyError, TypeError, OSError,
            zipfile.BadZipFile) as exc:
        reason = " ".join(str(exc).split())[:300]
        raise ValueError(f"cannot load model {directory / name}: {type(exc).__name__}: "
                         f"{reason}") from None


def predictions(model: Any, info: dict[str, Any], grips: pd.DataFrame) -> pd.DataFrame:
    """``grip_id, object_id, <score>, model`` for every grip, in the dataset's row order."""
    import numpy as np
    import pandas as pd

    missing = [column for column in info["columns"] if column not in grips.columns]
    if missing:
        raise ValueError(f"the dataset lacks column(s) the model was trained on: "
                         f"{', '.join(missing)}")
    if "target" in info:
        column, score = ROBUSTNESS_COLUMN, np.asarray(model.predict(grips), dtype=float)
    else:
        column, score = PROBABILITY_COLUMN, _success_probability(model, grips)
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
