"""The RL selector for the retry task: it trains on the training objects whose every trial is
recorded (refused otherwise, never replayed as independent draws), and a retry policy, which
sees its failures, is scored by what it does after each one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_runs import assert_refused, cli
from test_retry import TRIALS, with_trials

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.selector.recorded import retry_training_objects
from grip_env.config import Config
from grip_env.dataset.split import held_out_objects


def _config(max_attempts: int = 3) -> Config:
    return Config().override(selector={"max_candidates": 12, "max_attempts": max_attempts,
                                       "n_envs": 2, "rollout_steps": 64, "batch_size": 32,
                                       "n_epochs": 1},
                             learning={"models": ("logreg",)})  # fmt: skip


@pytest.fixture(scope="module")
def table() -> pd.DataFrame:
    found = with_trials(synthetic_grips(n_objects=16, grips=(4, 9), trials=TRIALS, seed=11))
    return found.assign(object_id=found["object_id"].astype(str))


def _partial(table: pd.DataFrame, config: Config, unrecorded: int) -> tuple[pd.DataFrame, list]:
    """``table`` with the first ``unrecorded`` training objects' trials missing (NaN)."""
    train, _ = held_out_objects(table["object_id"], config.learning)
    gone = list(train[:unrecorded])
    columns = [c for c in table.columns if c.startswith("trial_")]
    partial = table.astype({c: float for c in columns})
    partial.loc[partial["object_id"].isin(gone), columns] = np.nan
    return partial, gone


def test_one_attempt_needs_no_trials(table: pd.DataFrame) -> None:
    assert retry_training_objects(table, _config(1)) is None
    bare = table[[c for c in table.columns if not c.startswith("trial_")]]
    assert retry_training_objects(bare, _config(1)) is None


def test_the_retry_task_refuses_a_table_without_trials(table: pd.DataFrame) -> None:
    bare = table[[c for c in table.columns if not c.startswith("trial_")]]
    with pytest.raises(ValueError, match=r"selector\.max_attempts 3 .* does not record"):
        retry_training_objects(bare, _config())


def test_objects_without_trials_are_refused_or_left_out_and_counted(table: pd.DataFrame) -> None:
    config = _config()
    train, _ = held_out_objects(table["object_id"], config.learning)
    partial, gone = _partial(table, config, 3)
    with pytest.raises(ValueError, match=rf"3 of the {len(train)} training objects lack"):
        retry_training_objects(partial, config)
    used = retry_training_objects(partial, config, recorded_only=True)
    assert used is not None
    assert set(used.objects) == set(train) - set(gone) and set(used.missing) == set(gone)
    assert used.summary() == (f"trained on {len(train) - 3} of the {len(train)} training "
                              "objects (3 left out: their trials are not recorded yet)")
    everything = retry_training_objects(table, config)
    assert everything is not None and everything.objects == train and not everything.missing


def test_the_cli_refuses_the_retry_task_without_trials(tmp_path: Path,
                                                       generated_grips: pd.DataFrame) -> None:
    config = tmp_path / "retry.yaml"
    config.write_text("selector:\n  max_attempts: 3\n")
    bare = tmp_path / "bare.parquet"
    generated_grips[[c for c in generated_grips.columns
                     if not c.startswith("trial_")]].to_parquet(bare)  # fmt: skip
    out = tmp_path / "out"
    code, output = cli("select", "--out", out, "--data", bare, "--config", config)
    assert_refused(code, output, "selector.max_attempts 3 (the retry task)", "--trials")
    assert not out.exists()


@pytest.fixture(scope="module", params=["flat", "set"])
def trained(request: pytest.FixtureRequest, table: pd.DataFrame,
            tmp_path_factory: pytest.TempPathFactory):  # fmt: skip
    from classifiers.experiments.selector.training import train_selector

    config = _config()
    partial, gone = _partial(table, config, 2)
    out = tmp_path_factory.mktemp("retry")
    result = train_selector(partial, config, out, request.param, timesteps=256, progress=False,
                            recorded_only=True)  # fmt: skip
    if request.param == "set":  # the set policy reads what failed, not only the mask
        assert hasattr(result.model.policy.mlp_extractor, "failure_encoder")
    return result, out, partial, gone


def test_the_retry_selector_trains_on_the_recorded_objects_only(trained) -> None:
    result, out, _, gone = trained
    assert "failed" in result.model.observation_space.spaces
    recorded = json.loads((out / "model.json").read_text())
    record = recorded["trained_on"]
    assert record["split"] == "train" and record["trials_recorded"] == result.objects.summary()
    objects = record["objects"]
    assert result.objects is not None and sorted(objects) == sorted(result.objects.objects)
    assert not set(objects) & set(gone)


def test_a_retry_policy_is_scored_by_its_picks_after_each_failure(trained, table) -> None:
    """The benchmark's scores of a retry zip (its picks in turn, each failure shown) give, on
    the shared draws, exactly what GripSelect-v0 gives the deterministic policy when its
    episodes are pinned to every trial k."""
    from classifiers.experiments.benchmark.methods import sb3_scores
    from classifiers.experiments.benchmark.retry import policy_retry_metrics, retry_metrics
    from classifiers.experiments.benchmark.split import candidate_table
    from classifiers.experiments.selector.evaluation import held_out_candidate_sets

    result, out, _, _ = trained
    config = _config()
    sets = held_out_candidate_sets(table, config)
    scores = sb3_scores(out / "model.zip", sets, 0, "rl_retry")
    candidates = candidate_table(sets)
    static = retry_metrics(candidates, scores).set_index("object_id")

    def policy(observation: dict, mask: np.ndarray) -> int:
        return int(result.model.predict(observation, action_masks=mask, deterministic=True)[0])

    ids = [found.object_id for found in sets]
    episodes = policy_retry_metrics(table, ids, policy, config).set_index("object_id")
    for m in (1, 2, 3):
        np.testing.assert_allclose(static.loc[ids, f"shared_at_{m}"],
                                   episodes.loc[ids, f"shared_at_{m}"], atol=1e-12)
