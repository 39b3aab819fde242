"""The benchmark knows what each method was trained on: a method that saw a held-out object of
the split is refused (its score would be in-sample); one without a record is scored and marked."""

from __future__ import annotations

import json
import textwrap
from collections import OrderedDict
from pathlib import Path

import pandas as pd
import pytest
import yaml
from cli_runs import assert_refused, cli

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.benchmark.provenance import RECORD_KEY, write_agent_record
from grip_env.config import Config


@pytest.fixture(scope="module")
def trained(generated_dataset_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``grip-env train`` on a generated dataset, once on every object, once with --split train."""
    out = tmp_path_factory.mktemp("leak")
    config = out / "learn.yaml"
    config.write_text(yaml.safe_dump({"learning": {
        "models": ["logreg"], "regressors": ["ridge"], "rankers": ["rank_qc"], "folds": 2,
        "repeats": 1, "seeds": 1}}))  # fmt: skip
    for split in ("all", "train"):
        code, output = cli("train", "--data", generated_dataset_dir, "--out", out / split,
                           "--config", config, "--split", split)  # fmt: skip
        assert code == 0, output
    return out


@pytest.mark.slow
def test_train_split_train_fits_on_the_benchmark_splits_training_objects_only(
    trained: Path, generated_dataset_dir: Path,
) -> None:
    from classifiers.experiments.benchmark.split import DatasetObjects, choose_split
    from classifiers.learners.persistence import dataset_checksum
    from grip_env.dataset import load

    table = load(generated_dataset_dir)
    split, _ = choose_split(DatasetObjects.of(table))
    everything = sorted(set(table["object_id"].astype(str)))
    for name in ("logreg", "regressor_ridge", "ranker_rank_qc"):
        record = json.loads((trained / "train" / "models" / f"{name}.json").read_text())
        assert record[RECORD_KEY]["objects"] == sorted(set(everything) - set(split.test_objects))
        assert record[RECORD_KEY]["split_name"] == split.name
        assert record[RECORD_KEY]["dataset_sha256"] == dataset_checksum(table)  # the source
        record = json.loads((trained / "all" / "models" / f"{name}.json").read_text())
        assert record[RECORD_KEY]["objects"] == everything


@pytest.mark.slow
def test_benchmark_refuses_a_model_fitted_on_held_out_objects(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path,
) -> None:
    out = tmp_path / "never"
    for file in ("logreg.json", "logreg.skops", "regressor_ridge.json"):
        assert_refused(*cli("benchmark", trained / "all" / "models" / file, "--data",
                            generated_dataset_dir, "--out", out), "held-out objects",
                       "in-sample", "--split train")  # fmt: skip
        assert not out.exists()


@pytest.mark.slow
def test_benchmark_scores_a_model_fitted_on_the_training_objects(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path,
) -> None:
    code, output = cli("benchmark", trained / "train" / "models" / "logreg.json", "--data",
                       generated_dataset_dir, "--out", tmp_path / "lb", "--reps", 100)  # fmt: skip
    assert code == 0, output
    board = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    training = board["methods"]["logreg"]["training"]
    assert training["status"] == "checked" and "none of the" in training["note"]
    assert "none of the" in output
    assert "`logreg`: trained on" in (tmp_path / "lb" / "leaderboard.md").read_text()


@pytest.mark.slow
def test_a_model_saved_before_the_records_is_refused_by_its_dataset_checksum(
    trained: Path, generated_dataset_dir: Path, tmp_path: Path,
) -> None:
    """An older ``grip-env train`` always fitted on everything and recorded only the checksum."""
    models = tmp_path / "old"
    models.mkdir()
    for suffix in (".json", ".skops"):
        (models / f"logreg{suffix}").write_bytes((trained / "all" / "models" /
                                                  f"logreg{suffix}").read_bytes())  # fmt: skip
    meta = json.loads((models / "logreg.json").read_text())
    del meta[RECORD_KEY]
    (models / "logreg.json").write_text(json.dumps(meta))
    assert_refused(*cli("benchmark", models / "logreg.json", "--data", generated_dataset_dir,
                        "--out", tmp_path / "never"), "dataset_sha256", "in-sample")  # fmt: skip


# ------------------------------------------------------------------ SB3 zips, RL Zoo, functions
@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, pd.DataFrame, tuple[str, ...]]:
    """Synthetic grips of 16 objects as a parquet, and the held-out objects of its auto split."""
    from classifiers.experiments.benchmark.split import DatasetObjects, choose_split

    table = synthetic_grips(n_objects=16, grips=(6, 12), seed=4)
    table["object_id"] = "obj_" + table["object_id"].astype(str)
    table["grip_id"] = table["grip_id"].astype(str)
    path = tmp_path_factory.mktemp("zips") / "grips.parquet"
    table.to_parquet(path)
    split, _ = choose_split(DatasetObjects.of(table))
    return path, table, split.test_objects


def test_a_saved_model_is_checked_by_its_metadata(data, tmp_path: Path) -> None:
    """``NAME.json`` (as ``grip-env predict`` takes it) and its ``.skops`` carry ``trained_on``."""
    from classifiers.experiments.benchmark.provenance import training_record
    from classifiers.learners.models import make_model
    from classifiers.learners.persistence import save_model

    path, table, held_out = data
    for name, rows in (("seen", table), ("clean", table[~table["object_id"].isin(held_out)])):
        model = make_model("logreg", 0).fit(rows, rows["success"].astype(bool))
        save_model(model, tmp_path / "models", name,
                   {RECORD_KEY: training_record(rows["object_id"], split="all")})  # fmt: skip
    for file in ("seen.json", "seen.skops"):
        assert_refused(*cli("benchmark", tmp_path / "models" / file, "--data", path, "--out",
                            tmp_path / "never"), "held-out objects", "seen.json")  # fmt: skip
    code, output = cli("benchmark", tmp_path / "models" / "clean.json", "--data", path,
                       "--out", tmp_path / "lb", "--reps", 100)  # fmt: skip
    assert code == 0 and "none of the" in output, output
    code, output = cli("benchmark", tmp_path / "models" / "clean", "--data", path,
                       "--out", tmp_path / "bare", "--reps", 100)  # the bare name, as predict
    assert code == 0 and "clean: top-1 success" in output, output


def _agent(folder: Path, table: pd.DataFrame, name: str, record: bool = True) -> Path:
    """An untrained plain PPO on GripSelect-v0 of ``table``'s objects (split "all")."""
    from stable_baselines3 import PPO

    from classifiers.experiments.selector.training import make_selector_env

    env = make_selector_env(table, Config(), split="all", n_envs=1)
    path = folder / f"{name}.zip"
    PPO("MultiInputPolicy", env, n_steps=16, batch_size=16, seed=0).save(path)
    if record:
        write_agent_record(path, env)
    env.close()
    return path


def test_an_agent_is_checked_by_the_record_beside_its_zip(data, tmp_path: Path) -> None:
    path, table, held_out = data
    seen = _agent(tmp_path, table, "seen")
    assert_refused(*cli("benchmark", seen, "--data", path, "--out", tmp_path / "never"),
                   f"{len(held_out)} of the split's {len(held_out)} held-out objects",
                   "seen.json")  # fmt: skip
    clean = _agent(tmp_path, table[~table["object_id"].isin(held_out)], "clean")
    code, output = cli("benchmark", clean, "--data", path, "--out", tmp_path / "lb",
                       "--reps", 100)  # fmt: skip
    assert code == 0, output
    assert json.loads((tmp_path / "lb" / "leaderboard.json").read_text())["methods"]["clean"][
        "training"]["status"] == "checked"  # fmt: skip
    bare = _agent(tmp_path, table, "bare", record=False)
    code, output = cli("benchmark", bare, "--data", path, "--out", tmp_path / "b", "--reps", 100)
    assert code == 0, output
    assert "not recorded" in output
    board = json.loads((tmp_path / "b" / "leaderboard.json").read_text())
    assert board["methods"]["bare"]["training"]["status"] == "unrecorded"
    assert "cannot check" in (tmp_path / "b" / "leaderboard.md").read_text()


def _rl_zoo_run(folder: Path, agent: Path, env_kwargs: dict) -> Path:
    """``agent`` laid out as ``rl_zoo3.train`` saves a run (exp_manager.py: ``<run>/<env>.zip``
    and ``<run>/<env>/args.yml``, an OrderedDict of the arguments)."""
    run = folder / "logs" / "ppo" / "GripSelect-v0_1"
    (run / "GripSelect-v0").mkdir(parents=True)
    zipped = run / "GripSelect-v0.zip"
    zipped.write_bytes(agent.read_bytes())
    args = OrderedDict([("algo", "ppo"), ("env", "GripSelect-v0"), ("env_kwargs", env_kwargs)])
    (run / "GripSelect-v0" / "args.yml").write_text(yaml.dump(args))
    return zipped


def test_an_rl_zoo_agent_is_checked_by_its_recorded_env_kwargs(
    data, generated_dataset_dir: Path, tmp_path: Path,
) -> None:
    """The env's split "train" of a dataset is the benchmark's auto split of it: held out."""
    agent = _agent(tmp_path, data[1], "zoo", record=False)
    dataset = str(generated_dataset_dir)
    everything = _rl_zoo_run(tmp_path / "a", agent, {"data": dataset})  # split "all"
    assert_refused(*cli("benchmark", everything, "--data", dataset, "--out", tmp_path / "never"),
                   "args.yml", "in-sample")  # fmt: skip
    clean = _rl_zoo_run(tmp_path / "b", agent, {"data": dataset, "split": "train"})
    code, output = cli("benchmark", clean, "--data", dataset, "--out", tmp_path / "lb",
                       "--reps", 100)  # fmt: skip
    assert code == 0, output
    assert "args.yml" in output and "none of the" in output


def test_a_function_declares_what_it_learnt_from(
    data, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
) -> None:
    path, _, held_out = data
    (tmp_path / "fns.py").write_text(textwrap.dedent(f"""
        def by_qc(table):
            return -table["Q_C"].to_numpy()

        def fitted(table):
            return -table["Q_C"].to_numpy()

        def analytic(table):
            return -table["Q_C"].to_numpy()

        fitted.trained_on = ["elsewhere", {held_out[0]!r}]
        analytic.trained_on = ()
    """))
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert_refused(*cli("benchmark", "fns:fitted", "--data", path, "--out", tmp_path / "never"),
                   held_out[0], "fns:fitted.trained_on")  # fmt: skip
    code, output = cli("benchmark", "fns:analytic", "--data", path, "--out", tmp_path / "a",
                       "--reps", 100)  # fmt: skip
    assert code == 0 and "trained on 0 recorded objects" in output, output
    code, output = cli("benchmark", "fns:by_qc", "--data", path, "--out", tmp_path / "q",
                       "--reps", 100)  # fmt: skip
    assert code == 0 and "not recorded" in output, output
