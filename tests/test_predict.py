"""``grip-env predict`` on a dataset generated for real, with models saved by ``grip-env train``;
crafted model files are refused without running their code."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import skops.io as sio
import torch
import yaml
from cli_runs import assert_refused, cli
from sklearn.base import BaseEstimator
from sklearn.pipeline import Pipeline

from classifiers.learners.baselines import ColumnSelector
from classifiers.learners.persistence import load_model
from grip_env.columns import FEATURES
from grip_env.dataset import load


@pytest.fixture(scope="module")
def trained(generated_dataset_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``grip-env train`` output on the generated dataset: logreg, the torch MLP, a regressor."""
    out = tmp_path_factory.mktemp("trained")
    config = out / "learn.yaml"
    config.write_text(yaml.safe_dump({"learning": {
        "models": ["logreg", "mlp_torch"], "regressors": ["ridge"], "folds": 2, "repeats": 1}}))
    code, output = cli("train", "--data", generated_dataset_dir, "--out", out / "train",
                       "--config", config)
    assert code == 0, output
    return out / "train" / "models"


def test_predict_scores_every_grip_as_the_python_lines_do(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path
) -> None:
    out = tmp_path / "predictions.parquet"
    code, output = cli("predict", "--model", trained / "logreg.json",
                       "--data", generated_dataset_dir, "--out", out)
    assert code == 0, output
    assert "in-sample" in output  # trained on these grips: said so
    table = pd.read_parquet(out)
    grips = load(generated_dataset_dir)
    assert list(table.columns) == ["grip_id", "object_id", "p_success", "model"]
    assert table["grip_id"].tolist() == grips["grip_id"].tolist()
    assert table["object_id"].tolist() == grips["object_id"].tolist()
    assert set(table["model"]) == {"logreg"}
    # the README's Python lines give the same numbers
    model, info = load_model(trained, "logreg")
    expected = model.predict_proba(grips)[:, list(model.classes_).index(True)]
    np.testing.assert_allclose(table["p_success"], expected)
    assert ((table["p_success"] >= 0) & (table["p_success"] <= 1)).all()
    assert table["p_success"].std() > 0  # the features move it
    assert info["features"] == list(FEATURES)


def test_predict_with_the_torch_mlp_and_a_regressor(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path
) -> None:
    grips = load(generated_dataset_dir)
    code, output = cli("predict", "--model", trained / "mlp_torch.pt",
                       "--data", generated_dataset_dir, "--out", tmp_path / "mlp.parquet")
    assert code == 0, output
    mlp = pd.read_parquet(tmp_path / "mlp.parquet")
    assert len(mlp) == len(grips) and mlp["p_success"].between(0, 1).all()
    code, output = cli("predict", "--model", trained / "regressor_ridge",
                       "--data", generated_dataset_dir, "--out", tmp_path / "ridge.parquet")
    assert code == 0, output
    ridge = pd.read_parquet(tmp_path / "ridge.parquet")
    assert list(ridge.columns) == ["grip_id", "object_id", "robustness_pred", "model"]
    model, _ = load_model(trained, "regressor_ridge")
    np.testing.assert_allclose(ridge["robustness_pred"], model.predict(grips))


def test_bad_model_data_or_out_end_in_one_line(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path
) -> None:
    model = trained / "logreg.json"
    data = generated_dataset_dir
    assert_refused(*cli("predict", "--model", trained, "--data", data), "directory",
                   "logreg.json")
    assert_refused(*cli("predict", "--model", trained / "nope.json", "--data", data),
                   "nope.json")
    assert_refused(*cli("predict", "--model", model, "--data", tmp_path), "not a grip-env dataset")
    assert_refused(*cli("predict", "--model", model, "--data", data, "--out", tmp_path / "p.csv"),
                   ".parquet")
    assert_refused(*cli("predict", "--model", model, "--data", data, "--out", tmp_path),
                   "directory")


def test_predict_takes_every_model_train_writes_each_with_its_column(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path
) -> None:
    """Classifiers, regressors and rankers, the lambdarank ranker (LightGBM's text model) too."""
    from classifiers.learners.persistence import saved_models

    grips = load(generated_dataset_dir)
    names = saved_models(trained)
    assert {"logreg", "regressor_ridge", "ranker_lambdarank", "ranker_rank_qc"} <= set(names)
    for name in names:
        out = tmp_path / f"{name}.parquet"
        code, output = cli("predict", "--model", trained / f"{name}.json",
                           "--data", generated_dataset_dir, "--out", out)
        assert code == 0, (name, output)
        table = pd.read_parquet(out)
        column = ("rank_score" if name.startswith("ranker_") else
                  "robustness_pred" if name.startswith("regressor_") else "p_success")
        assert list(table.columns) == ["grip_id", "object_id", column, "model"], name
        assert f"{column} from model {name}" in output
        model, _ = load_model(trained, name)
        if column != "p_success":
            np.testing.assert_allclose(table[column], model.predict(grips))
    # the ranker given by its LightGBM file; its scores order each object's grips
    code, output = cli("predict", "--model", trained / "ranker_lambdarank.txt",
                       "--data", generated_dataset_dir, "--out", tmp_path / "lgbm.parquet")
    assert code == 0, output
    scores = pd.read_parquet(tmp_path / "lgbm.parquet")["rank_score"]
    assert scores.notna().all() and scores.std() > 0


def test_a_folder_lists_its_models_only(trained: Path, generated_dataset_dir: Path) -> None:
    data = generated_dataset_dir
    code, output = cli("predict", "--model", trained, "--data", data)
    assert_refused(code, output, "directory", "logreg.json", "regressor_ridge.json",
                   "ranker_lambdarank.json")
    train_out = trained.parent  # metrics.json, ranking.json, regression.json, models/
    code, output = cli("predict", "--model", train_out, "--data", data)
    assert_refused(code, output, "directory", "models/logreg.json", "models/ranker_lambdarank")
    for other in ("metrics.json", "ranking.json", "regression.json"):
        assert (train_out / other).is_file()
        assert other not in output
        assert_refused(*cli("predict", "--model", train_out / other, "--data", data),
                       f"{other} is not a saved model", "models/logreg.json")


def test_an_agent_zip_is_pointed_to_benchmark(tmp_path: Path, generated_dataset_dir: Path) -> None:
    for agent in (tmp_path / "selector" / "model.zip", Path("model.ZIP")):
        assert_refused(*cli("predict", "--model", agent, "--data", generated_dataset_dir),
                       "Stable-Baselines3 agent", "grip-env benchmark AGENT.zip --data")


# ----------------------------------------------------------------------------- crafted files
class Planted(BaseEstimator):
    """An estimator whose restoring leaves a mark: a loader that ran it would be caught."""

    marker: Path | None = None

    def __setstate__(self, state: dict) -> None:
        Path(state["marker"]).write_text("ran")
        self.__dict__.update(state)


class _Touch:
    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple:
        return (Path.write_text, (self.marker, "ran"))


def test_a_skops_model_with_an_untrusted_type_is_refused_unrun(
    generated_dataset_dir: Path, tmp_path: Path
) -> None:
    marker = tmp_path / "ran.txt"
    planted = Planted()
    planted.__dict__["marker"] = str(marker)
    pipeline = Pipeline([("select", ColumnSelector(tuple(FEATURES))), ("model", planted)])
    sio.dump(pipeline, tmp_path / "evil.skops")
    (tmp_path / "evil.json").write_text(json.dumps(
        {"name": "evil", "format": "skops", "columns": list(FEATURES)}))
    assert_refused(*cli("predict", "--model", tmp_path / "evil.json",
                        "--data", generated_dataset_dir, "--out", tmp_path / "p.parquet"),
                   "trusted", "Planted")
    assert not marker.exists() and not (tmp_path / "p.parquet").exists()


def test_a_torch_model_holding_a_pickled_call_is_refused_unrun(
    generated_dataset_dir: Path, tmp_path: Path
) -> None:
    marker = tmp_path / "ran.txt"
    torch.save({"weights": _Touch(marker)}, tmp_path / "evil.pt")
    (tmp_path / "evil.json").write_text(json.dumps({
        "name": "evil", "format": "torch_state_dict", "estimator": "TorchMLPClassifier",
        "columns": list(FEATURES), "params": {}, "fitted": {}}))
    assert_refused(*cli("predict", "--model", tmp_path / "evil.json",
                        "--data", generated_dataset_dir, "--out", tmp_path / "p.parquet"),
                   "cannot load model")
    assert not marker.exists()
    (tmp_path / "evil.pt").write_bytes(b"not a torch file")
    assert_refused(*cli("predict", "--model", tmp_path / "evil.json",
                        "--data", generated_dataset_dir), "cannot load model")
