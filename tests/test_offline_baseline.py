"""Agents as benchmark entries: a d3rlpy policy trained on a Minari export, an observation
policy with ``predict``, each with its training budget; leakage through the export's record and
a mismatched action space refused with one line, exit 2 and nothing written."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_runs import assert_refused, cli

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.benchmark.provenance import budget_text
from classifiers.experiments.benchmark.split import STANDARD_SPLIT

POLICIES = textwrap.dedent("""
    import numpy as np
    from gymnasium import spaces


    class FirstValid:
        \"\"\"SB3-style: predict(observation) -> (action, state); the lowest-Q_C slot.\"\"\"

        action_space = spaces.Discrete(64)
        trained_on = ()
        training_budget = {"environment_steps": 1234}

        def predict(self, observation, deterministic=True):
            return int(np.flatnonzero(observation["mask"])[0]), None


    first_valid = FirstValid()


    class Narrow:
        action_space = spaces.Discrete(10)

        def predict(self, observation):
            return 0


    class Padded:
        def predict(self, observation):
            return 63
""")


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Synthetic grips whose first objects carry the standard split's ids, as a parquet."""
    held_out = STANDARD_SPLIT.test_objects
    table = synthetic_grips(n_objects=len(held_out) + 13, grips=(6, 12), seed=4)
    ids = dict(enumerate(held_out))
    table["object_id"] = [ids.get(int(i), f"train_{i}") for i in table["object_id"]]
    table["grip_id"] = table["grip_id"].astype(str)
    path = tmp_path_factory.mktemp("offline") / "grips.parquet"
    table.to_parquet(path)
    return path


@pytest.fixture()
def policies(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    (tmp_path / "my_policies.py").write_text(POLICIES)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    return tmp_path


def _board(out: Path) -> dict:
    return json.loads((out / "leaderboard.json").read_text())


def test_an_observation_policy_is_scored_as_its_picks(data: Path, policies: Path):
    out = policies / "first"
    code, output = cli("benchmark", "my_policies:first_valid", "--data", data, "--out", out,
                       "--reps", 200)  # fmt: skip
    assert code == 0, output
    board = _board(out)
    mine, best_qc = board["methods"]["first_valid"], board["methods"]["best_qc"]
    # the first valid slot is the lowest Q_C: the same picks as best-Q_C, object for object
    assert mine["success"] == best_qc["success"]
    frame = pd.DataFrame(board["per_object"])
    mine_rows = frame[frame["method"] == "first_valid"].set_index("object_id")["success"]
    qc_rows = frame[frame["method"] == "best_qc"].set_index("object_id")["success"]
    pd.testing.assert_series_equal(mine_rows.sort_index(), qc_rows.sort_index())
    assert mine["budget"]["environment_steps"] == 1234
    assert "1,234 environment steps" in output
    table = (out / "leaderboard.md").read_text()
    assert "| training budget |" in table and "none (analytic)" in table


@pytest.mark.parametrize(("spec", "fragment"), [
    ("my_policies:Narrow", "action space Discrete(10) does not match"),
    ("my_policies:Padded", "invalid index 63"),
])  # fmt: skip
def test_a_policy_that_does_not_fit_the_split_is_refused(data, policies, spec, fragment):
    out = policies / "never"
    code, output = cli("benchmark", spec, "--data", data, "--out", out)
    assert_refused(code, output, fragment)
    assert not out.exists()


def test_budget_text_says_steps_or_transitions():
    assert budget_text({"environment_steps": 20000}) == "20,000 environment steps"
    assert budget_text({"transitions": 7640, "episodes": 7640, "gradient_steps": 500,
                        "source": "Minari dataset a/b-v0"}) == (
        "7,640 transitions (7,640 episodes, 500 gradient steps) of Minari dataset a/b-v0")
    assert budget_text({}) == "not recorded"


# ------------------------------------------------------------------ d3rlpy on a Minari export
@pytest.fixture
def minari_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    pytest.importorskip("minari")
    pytest.importorskip("d3rlpy")
    root = tmp_path / "minari"
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return root


def _export(dataset: Path, dataset_id: str, *extra: object) -> None:
    code, output = cli("export", "minari", "--data", dataset, "--id", dataset_id, "--episodes",
                       4, *extra)  # fmt: skip
    assert code == 0, output


@pytest.mark.slow
def test_cql_trained_on_an_export_is_benchmarked_with_its_budget(
    generated_dataset_dir: Path, minari_root: Path, tmp_path: Path
):
    import minari

    from classifiers.experiments.benchmark.methods import load_d3rlpy
    from classifiers.experiments.offline_rl import train_offline_runs

    _export(generated_dataset_dir, "grip-test/uniform-v0")
    paths = train_offline_runs("grip-test/uniform-v0", [tmp_path / "a.d3", tmp_path / "b.d3"],
                               [3, 3], steps=40, batch_size=16)  # fmt: skip
    record = json.loads(paths[0].with_suffix(".json").read_text())
    exported = minari.load_dataset("grip-test/uniform-v0")
    assert record["budget"]["transitions"] == exported.total_steps
    assert record["budget"]["episodes"] == exported.total_episodes
    assert record["trained_on"]["objects"] == exported.storage.metadata["grip_env"]["objects"]
    # the same seed, the same policy
    x = np.random.default_rng(0).random((5, 64 * 12 + 64)).astype(np.float32)
    first, second = (load_d3rlpy(p) for p in paths)
    np.testing.assert_array_equal(first.predict_value(x, np.arange(5)),
                                  second.predict_value(x, np.arange(5)))
    out = tmp_path / "board"
    code, output = cli("benchmark", paths[0], "--data", generated_dataset_dir, "--out", out,
                       "--name", "cql", "--reps", 200)  # fmt: skip
    assert code == 0, output
    row = _board(out)["methods"]["cql"]
    assert row["training"]["status"] == "checked"
    assert row["budget"]["transitions"] == exported.total_steps
    assert f"{exported.total_steps:,} transitions" in (out / "leaderboard.md").read_text()


@pytest.mark.slow
def test_a_policy_trained_on_held_out_objects_is_refused(
    generated_dataset_dir: Path, minari_root: Path, tmp_path: Path
):
    from classifiers.experiments.offline_rl import main, train_offline

    _export(generated_dataset_dir, "grip-test/all-v0", "--split", "all")
    path = train_offline("grip-test/all-v0", tmp_path / "leaky.d3", steps=5, batch_size=16)
    out = tmp_path / "never"
    assert_refused(*cli("benchmark", path, "--data", generated_dataset_dir, "--out", out),
                   "leaky.d3 was trained on", "held-out objects")
    assert not out.exists()
    # a split of 32 candidates: the policy's 64 actions do not fit
    (tmp_path / "k32.yaml").write_text("selector:\n  max_candidates: 32\n")
    main(["grip-test/all-v0", str(tmp_path / "cli"), "--steps", "5", "--batch-size", "16",
          "--seeds", "1"])  # the module's command line
    path = tmp_path / "cli" / "cql_s1.d3"
    assert json.loads(path.with_suffix(".json").read_text())["seed"] == 1
    path.with_suffix(".json").unlink()  # no record: scored and marked, but it does not fit
    assert_refused(*cli("benchmark", path, "--data", generated_dataset_dir, "--out", out,
                        "--config", tmp_path / "k32.yaml"), "do not match")  # fmt: skip
    assert not out.exists()
