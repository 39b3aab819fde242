"""One held-out split: the dataset layer's function, and every user of a split agreeing with it."""

from __future__ import annotations

import pytest

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.training import held_out_scores
from grip_env.config import Config
from grip_env.dataset import held_out_objects, split_objects, split_table
from grip_env.envs import GripSelectEnv
from grip_env.envs import split_objects as env_split_objects


@pytest.fixture(scope="module")
def table():
    return synthetic_grips(n_objects=20, seed=3)


@pytest.mark.parametrize(("fraction", "seed"), [(0.25, 0), (0.4, 11)])
def test_envs_classifiers_and_the_table_split_hold_out_the_same_objects(table, fraction, seed):
    config = Config().override(learning={"test_fraction": fraction, "seed": seed,
                                         "models": ("logreg", "rank_qc")})
    train_ids, test_ids = held_out_objects(table["object_id"], config.learning)
    assert (train_ids, test_ids) == split_objects(table["object_id"], fraction, seed)
    assert env_split_objects is split_objects
    envs = {split: GripSelectEnv(data=table, config=config, split=split, max_candidates=8)
            for split in ("train", "test")}  # fmt: skip
    assert envs["train"].object_ids == train_ids and envs["test"].object_ids == test_ids
    train, test = split_table(table, config.learning)
    assert set(train["object_id"].astype(str)) == set(train_ids)
    assert set(test["object_id"].astype(str)) == set(test_ids)
    assert len(train) + len(test) == len(table)
    scores = held_out_scores(table, config)
    assert tuple(scores["split"]["test"]) == test_ids
    assert set(scores["models"]) == {"logreg", "rank_qc"}
    assert 0.0 <= scores["models"]["logreg"]["roc_auc"] <= 1.0


def test_a_new_split_seed_moves_the_held_out_objects(table):
    ids = table["object_id"]
    tests = {held_out_objects(ids, Config().override(learning={"seed": s}).learning)[1]
             for s in range(4)}  # fmt: skip
    assert len(tests) > 1
