"""``grip-env benchmark``: an entry point's round trip, a skops model and an SB3 zip scored on
the standard split; bad input refused with one line, exit 2 and nothing written."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pandas as pd
import pytest
import skops.io as sio
from cli_runs import assert_refused, cli

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.benchmark.split import STANDARD_SPLIT
from classifiers.learners.models import make_model

METHODS = textwrap.dedent("""
    import numpy as np

    def by_qc(table):
        return -table["Q_C"].to_numpy()

    def first(table):
        return 0

    def seeded(table, seed):
        return np.random.default_rng(seed).random(len(table))

    def peeks(table):
        return table["success_rate"].to_numpy()

    def out_of_range(table):
        return len(table)

    def nan(table):
        return np.full(len(table), np.nan)

    def short(table):
        return np.zeros(len(table) - 1)

    def by_qg_sorted(table):
        return -table.sort_values("Q_G")["Q_G"]  # a Series in Q_G order, on the table's index

    def by_qc_shuffled(table):
        return (-table["Q_C"]).sample(frac=1.0, random_state=0)

    def other_index(table):
        return (-table["Q_C"]).set_axis(table.index + 1)

    def nothing(table):
        return None

    def text(table):
        return "0"

    def texts(table):
        return [str(v) for v in range(len(table))]

    class Noisy:
        def __init__(self, seed=0):
            self.rng = np.random.default_rng(seed)

        def __call__(self, table):
            return self.rng.random(len(table))

    class ByQC:
        def __call__(self, table):
            return -table["Q_C"].to_numpy()
""")


STANDARD_TEST_OBJECTS = STANDARD_SPLIT.test_objects  # the latest version's


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Synthetic grips whose first objects carry the standard split's ids, as a parquet."""
    table = synthetic_grips(n_objects=len(STANDARD_TEST_OBJECTS) + 13, grips=(6, 12), seed=4)
    ids = {i: name for i, name in enumerate(STANDARD_TEST_OBJECTS)}
    table["object_id"] = [ids.get(int(i), f"train_{i}") for i in table["object_id"]]
    table["grip_id"] = table["grip_id"].astype(str)
    path = tmp_path_factory.mktemp("bench") / "grips.parquet"
    table.to_parquet(path)
    return path


@pytest.fixture()
def methods(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "my_methods.py").write_text(METHODS)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    return tmp_path


def board(out: Path) -> dict:
    return json.loads((out / "leaderboard.json").read_text())


def test_entry_point_round_trip(data: Path, methods: Path) -> None:
    out = methods / "scored"
    code, output = cli("benchmark", "my_methods:by_qc", "--data", data, "--out", out,
                       "--reps", 200)  # fmt: skip
    assert code == 0, output
    found = board(out)
    mine, ref = found["methods"]["by_qc"], found["methods"]["best_qc"]
    for key in ("success", "robustness", "regret", "ndcg5", "success_at_3"):
        assert mine[key] == ref[key]  # scoring by -Q_C is the best-Q_C pick
    assert mine["verdict"] == "not distinguishable from best_qc"
    assert found["split"]["name"] == "grip-select-standard"
    assert found["split"]["version"] == STANDARD_SPLIT.version
    assert sorted(found["objects"] + found["degenerate_objects"]) == sorted(STANDARD_TEST_OBJECTS)
    assert "| by_qc |" in (out / "leaderboard.md").read_text()
    assert found["split"]["seeds"] == [0]  # a deterministic function: one run, seed 0
    assert "training seeds [0];" in (out / "leaderboard.md").read_text()
    assert (out / "performance_profile.png").stat().st_size > 0
    code, output = cli("benchmark", "my_methods:seeded", "--data", data, "--out", out / "s",
                       "--reps", 200)  # fmt: skip
    assert code == 0, output
    assert board(out / "s")["methods"]["seeded"]["runs"] == 5
    assert board(out / "s")["split"]["seeds"] == list(STANDARD_SPLIT.seeds)
    code, output = cli("benchmark", "my_methods:first", "--data", data, "--out", out / "f",
                       "--reps", 200)  # fmt: skip
    assert code == 0, output
    assert board(out / "f")["methods"]["first"]["success"] == board(out)["methods"]["best_qc"][
        "success"]  # slot 0 is the lowest Q_C  # fmt: skip


@pytest.mark.parametrize(("method", "fragment"), [
    ("my_methods:out_of_range", "invalid index"),
    ("my_methods:nan", "NaN"),
    ("my_methods:short", "scores"),
    ("my_methods:peeks", "success_rate"),
    ("my_methods:missing", "no function"),
    ("my_methods:other_index", "index"),
    ("my_methods:nothing", "returned None"),
    ("my_methods:text", "text '0'"),
    ("my_methods:texts", "text '0'"),
    ("nope.zip", "not found"),
])  # fmt: skip
def test_bad_functions_are_refused_and_nothing_written(
    data: Path, methods: Path, method: str, fragment: str
) -> None:
    out = methods / "never"
    assert_refused(*cli("benchmark", method, "--data", data, "--out", out), fragment)
    assert not out.exists()


def test_a_series_is_aligned_on_the_candidates_index(data: Path, methods: Path) -> None:
    """A Series in another row order scores each row by its own value (issue 44, item 3)."""
    for method, same_as in (("by_qg_sorted", "best_qg"), ("by_qc_shuffled", "best_qc")):
        out = methods / method
        code, output = cli("benchmark", f"my_methods:{method}", "--data", data, "--out", out,
                           "--reps", 100)  # fmt: skip
        assert code == 0, output
        found = board(out)["methods"]
        assert found[method]["success"] == found[same_as]["success"], method
        assert found[method]["ndcg5"] == found[same_as]["ndcg5"], method


def test_a_selector_class_is_made_once_per_seed(data: Path, methods: Path) -> None:
    code, output = cli("benchmark", "my_methods:Noisy", "--data", data, "--out", methods / "n",
                       "--reps", 100)  # fmt: skip
    assert code == 0, output
    assert board(methods / "n")["methods"]["Noisy"]["runs"] == len(STANDARD_SPLIT.seeds)
    code, output = cli("benchmark", "my_methods:ByQC", "--data", data, "--out", methods / "q",
                       "--reps", 100)  # fmt: skip
    assert code == 0, output
    found = board(methods / "q")["methods"]
    assert found["ByQC"]["runs"] == 1 and found["ByQC"]["success"] == found["best_qc"]["success"]


def test_each_version_pins_the_split_of_its_default_objects() -> None:
    from classifiers.experiments.benchmark.split import DEFAULT_OBJECTS, STANDARD_SPLITS
    from grip_env.dataset.split import split_objects

    assert set(DEFAULT_OBJECTS) == set(STANDARD_SPLITS)
    for version, split in STANDARD_SPLITS.items():
        _, test = split_objects(DEFAULT_OBJECTS[version], split.test_fraction, split.split_seed)
        assert test == split.test_objects and split.version == version


def test_other_split_versions(data: Path, methods: Path) -> None:
    out = methods / "never"
    assert_refused(*cli("benchmark", "my_methods:by_qc", "--data", data, "--out", out,
                        "--split-version", 1), "v1", "--split-version")  # fmt: skip
    assert_refused(*cli("benchmark", "my_methods:by_qc", "--data", data, "--out", out,
                        "--split-version", 9), "unknown standard split version 9")  # fmt: skip
    assert not out.exists()


def test_dataset_without_the_standard_objects_is_refused_by_the_standard_split(
    methods: Path,
) -> None:
    path = methods / "other.parquet"
    synthetic_grips(n_objects=8, grips=(4, 6), seed=1).to_parquet(path)
    out = methods / "never"
    assert_refused(*cli("benchmark", "my_methods:by_qc", "--data", path, "--out", out,
                        "--split", "standard"), "standard split", "--split auto")  # fmt: skip
    assert not out.exists()


def test_skops_model_and_sb3_zips(data: Path, tmp_path: Path) -> None:
    table = pd.read_parquet(data)
    train = table[~table["object_id"].isin(STANDARD_TEST_OBJECTS)]
    model = make_model("logreg", 0).fit(train, train["success"].astype(bool))
    sio.dump(model, tmp_path / "logreg.skops")
    code, output = cli("benchmark", tmp_path / "logreg.skops", "--data", data, "--out",
                       tmp_path / "sk", "--reps", 200)  # fmt: skip
    assert code == 0, output
    assert 0 <= board(tmp_path / "sk")["methods"]["logreg"]["success"] <= 1

    good, bad = _sb3_zip(tmp_path, 64), _sb3_zip(tmp_path, 16)
    code, output = cli("benchmark", good, good, "--data", data, "--out", tmp_path / "rl",
                       "--name", "agent", "--reps", 200)  # fmt: skip
    assert code == 0, output
    assert board(tmp_path / "rl")["methods"]["agent"]["runs"] == 2
    out = tmp_path / "never"
    assert_refused(*cli("benchmark", bad, "--data", data, "--out", out), "do not match")
    assert not out.exists()
    plain = _ppo_zip(tmp_path)
    code, output = cli("benchmark", plain, "--data", data, "--out", tmp_path / "ppo",
                       "--reps", 200)  # fmt: skip
    assert code == 0, output
    assert board(tmp_path / "ppo")["methods"]["ppo"]["runs"] == 1
    # the training budget: an SB3 zip's environment steps (untrained: 0); a bare skops: none
    assert board(tmp_path / "ppo")["methods"]["ppo"]["budget"]["environment_steps"] == 0
    assert board(tmp_path / "sk")["methods"]["logreg"]["budget"]["text"] == "not recorded"


def _ppo_zip(folder: Path) -> Path:
    """An untrained plain PPO (no masks) with the stock multi-input policy, K = 64."""
    from stable_baselines3 import PPO

    from classifiers.experiments.selector.training import make_selector_env
    from grip_env.config import Config

    env = make_selector_env(synthetic_grips(n_objects=6, grips=(4, 6), seed=2), Config(),
                            split="all", n_envs=1)  # fmt: skip
    path = folder / "ppo.zip"
    PPO("MultiInputPolicy", env, n_steps=16, batch_size=16, seed=0).save(path)
    env.close()
    return path


def _sb3_zip(folder: Path, candidates: int) -> Path:
    """An untrained MaskablePPO with the selector's policy on GripSelect-v0 (K candidates)."""
    from classifiers.experiments.selector.training import make_selector_env, make_selector_model
    from grip_env.config import Config

    config = Config().override(selector={"max_candidates": candidates})
    env = make_selector_env(synthetic_grips(n_objects=6, grips=(4, 6), seed=2), config,
                            split="all", n_envs=1)  # fmt: skip
    model = make_selector_model(env, "set", seed=0, timesteps=16)
    path = folder / f"agent_{candidates}.zip"
    model.save(path)
    env.close()
    return path
