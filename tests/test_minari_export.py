"""``grip-env export minari``: GripSelect-v0 episodes written as a Minari dataset and read back
with ``minari.load_dataset``: the mask inside the observation, rewards from the recorded trials,
the metadata Minari expects, the same episodes from the same seed, bad input refused."""

from __future__ import annotations

import json
from math import comb
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_runs import assert_refused, cli

minari = pytest.importorskip("minari")

from grip_env.dataset.split import objects_in_split  # noqa: E402
from grip_env.offline.behaviour import BehaviourPolicy  # noqa: E402
from grip_env.offline.minari_export import RECORD_KEY, ExportPlan, export_minari  # noqa: E402
from grip_env.offline.reference import (  # noqa: E402
    elementary_symmetric,
    oracle_return,
    random_return,
)

EPISODES = 3


@pytest.fixture
def minari_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    root = tmp_path / "minari"
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return root


@pytest.fixture
def exported(generated_dataset_dir: Path, minari_root: Path):
    code, output = cli("export", "minari", "--data", generated_dataset_dir, "--id",
                       "grip-test/uniform-v0", "--episodes", EPISODES, "--seed", 7)
    assert code == 0, output
    assert "wrote Minari dataset grip-test/uniform-v0" in output
    return minari.load_dataset("grip-test/uniform-v0")


def _rates(grips: pd.DataFrame) -> dict[str, np.ndarray]:
    """Each object's recorded success rates, lowest Q_C first (the environment's slot order)."""
    ordered = grips.sort_values("Q_C", kind="mergesort")
    return {str(k): (g["successes"] / g["trials"]).to_numpy() for k, g in
            ordered.groupby("object_id")}  # fmt: skip


def test_the_round_trip_keeps_every_episode_with_its_mask(exported, generated_grips):
    train = objects_in_split(sorted(generated_grips["object_id"].astype(str).unique()), "train",
                             0.25, 0)  # fmt: skip
    record = exported.storage.metadata[RECORD_KEY]
    assert record["objects"] == sorted(train)
    assert exported.total_episodes == EPISODES * len(train)
    assert exported.observation_space["mask"].n == 64
    rates = _rates(generated_grips)
    for episode in exported.iterate_episodes():
        object_id = record["objects"][int(episode.infos["object_index"][0])]
        mask = episode.observations["mask"]
        assert mask.shape == (len(episode) + 1, 64)
        assert mask[0].sum() == len(rates[object_id])  # every real candidate, no padding
        for t, action in enumerate(episode.actions):
            assert mask[t][action] == 1  # the behaviour policy picked a valid slot
            assert mask[t + 1][action] == 0  # executed: masked afterwards


def test_rewards_come_from_the_recorded_trials(exported, generated_grips):
    rates, record = _rates(generated_grips), exported.storage.metadata[RECORD_KEY]
    rewards, recorded = [], []
    for episode in exported.iterate_episodes():
        object_id = record["objects"][int(episode.infos["object_index"][0])]
        slots = episode.infos["slot"][1:]
        np.testing.assert_array_equal(slots, episode.actions)
        np.testing.assert_allclose(episode.infos["success_rate"][1:], rates[object_id][slots])
        assert np.isnan(episode.infos["success_rate"][0]) and episode.infos["slot"][0] == -1
        rewards.extend(episode.rewards)
        recorded.extend(rates[object_id][slots])
    rewards, recorded = np.array(rewards), np.array(recorded)
    assert set(np.unique(rewards)) <= {0.0, 1.0}
    assert np.all(rewards[recorded == 0.0] == 0.0) and np.all(rewards[recorded == 1.0] == 1.0)
    # Bernoulli draws of the recorded rates: the mean reward is their mean, within 4 sigma
    sigma = np.sqrt(np.sum(recorded * (1 - recorded))) / len(recorded)
    assert abs(rewards.mean() - recorded.mean()) <= 4 * sigma + 1e-12


def test_the_metadata_is_what_minari_expects(exported, generated_grips, generated_dataset_dir):
    meta = exported.storage.metadata
    spec = exported.spec
    assert spec.env_spec.id == "GripSelect-v0"
    assert spec.env_spec.kwargs == {"data": str(generated_dataset_dir.resolve()),
                                    "split": "train"}  # fmt: skip
    assert json.loads(meta["eval_env_spec"])["kwargs"]["split"] == "test"
    assert meta["author"] == {"The grip-env authors"}
    assert meta["code_permalink"].startswith("grip-env ")
    assert "uniform random over the valid slots" in meta["algorithm_name"]
    # reference scores: the exact random and oracle returns on the held-out objects (one pick)
    ids = sorted(generated_grips["object_id"].astype(str).unique())
    rates = _rates(generated_grips)
    held_out = objects_in_split(ids, "test", 0.25, 0)
    assert meta["ref_min_score"] == pytest.approx(np.mean([rates[o].mean() for o in held_out]))
    assert meta["ref_max_score"] == pytest.approx(np.mean([rates[o].max() for o in held_out]))
    record = meta[RECORD_KEY]
    assert not set(record["objects"]) & set(held_out)
    assert record["behaviour_policy"]["name"] == "uniform" and record["seed"] == 7
    assert record["episodes_per_object"] == EPISODES
    from classifiers.learners.persistence import dataset_checksum
    from grip_env.dataset import load

    table = load(generated_dataset_dir)
    table.attrs = {}
    assert record["dataset_sha256"] == dataset_checksum(table)
    env = exported.recover_environment()  # the env spec makes the environment again
    assert set(env.unwrapped.object_ids) == set(record["objects"])
    evaluation = exported.recover_environment(eval_env=True)
    assert set(evaluation.unwrapped.object_ids) == set(held_out)
    env.close()
    evaluation.close()


def _arrays(dataset) -> list[np.ndarray]:
    out = []
    for episode in dataset.iterate_episodes():
        out += [episode.actions, episode.rewards, episode.observations["features"],
                episode.infos["object_index"]]
    return out


def test_the_same_seed_gives_the_same_episodes(generated_dataset_dir: Path, minari_root: Path):
    data = str(generated_dataset_dir)
    first = export_minari(ExportPlan("grip-test/a-v0", data, episodes_per_object=4, seed=3))
    again = export_minari(ExportPlan("grip-test/b-v0", data, episodes_per_object=4, seed=3))
    other = export_minari(ExportPlan("grip-test/c-v0", data, episodes_per_object=4, seed=4))
    for a, b in zip(_arrays(first), _arrays(again), strict=True):
        np.testing.assert_array_equal(a, b)
    assert not all(np.array_equal(a, c) for a, c in zip(_arrays(first), _arrays(other),
                                                        strict=True))  # fmt: skip


def test_epsilon_greedy_on_q_c_picks_the_lowest_q_c_slot_as_stated():
    policy = BehaviourPolicy("epsilon-qc", epsilon=0.2)
    mask = np.array([0, 1, 1, 1, 0, 1], dtype=np.int8)
    expected = np.array([0, 0.8 + 0.05, 0.05, 0.05, 0, 0.05])
    np.testing.assert_allclose(policy.probabilities(mask), expected)
    rng = np.random.default_rng(0)
    picks = np.array([policy.act({"mask": mask}, rng) for _ in range(20_000)])
    frequencies = np.bincount(picks, minlength=6) / len(picks)
    np.testing.assert_allclose(frequencies, expected, atol=0.01)
    uniform = BehaviourPolicy("uniform")
    np.testing.assert_allclose(uniform.probabilities(mask), np.where(mask, 0.25, 0.0))


def test_the_reference_returns_are_exact_expectations():
    rates = np.array([0.5, 0.0, 1.0, 0.25])
    assert random_return(rates, 1) == pytest.approx(rates.mean())
    assert oracle_return(rates, 1) == 1.0
    assert oracle_return(np.array([0.5, 0.2]), 2) == pytest.approx(1 - 0.5 * 0.8)
    # two picks without repeats: every pair alike
    pairs = [1 - (1 - rates[i]) * (1 - rates[j]) for i in range(4) for j in range(i + 1, 4)]
    assert random_return(rates, 2) == pytest.approx(np.mean(pairs))
    assert elementary_symmetric(np.array([1.0, 2.0, 3.0]), 2) == 11.0
    assert comb(4, 4) == 1 and random_return(rates, 9) == pytest.approx(1.0)


def test_the_shared_draw_reference_returns_by_hand():
    from grip_env.offline.reference import shared_oracle_return, shared_random_return

    held = np.array([[1, 1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0]], dtype=bool)  # 3 grips, 4 trials
    rates = held.mean(axis=1)
    # one pick: the mean rate, as without shared draws
    assert shared_random_return(held, 1) == pytest.approx(rates.mean())
    assert shared_oracle_return(held, rates, 1) == pytest.approx(0.5)
    # two picks: at k = 0..3, 1, 2, 2, 3 grips failed; a pair all fails w.p. C(f, 2) / 3
    assert shared_random_return(held, 2) == pytest.approx(1 - (0 + 1 + 1 + 3) / 3 / 4)
    assert shared_oracle_return(held, rates, 2) == pytest.approx(0.5)  # grips 0, 1: k 0, 1
    assert shared_oracle_return(held, rates, 3) == pytest.approx(0.75)  # k = 3 defeats all
    assert oracle_return(rates, 2) == pytest.approx(1 - 0.5 * 0.75)  # independence: 0.625


def test_an_existing_id_is_refused_unless_overwrite(exported, generated_dataset_dir, minari_root):
    files = sorted((p, p.stat().st_mtime_ns) for p in minari_root.rglob("*"))
    refused = cli("export", "minari", "--data", generated_dataset_dir, "--id",
                  "grip-test/uniform-v0", "--episodes", 1)  # fmt: skip
    assert_refused(*refused, "grip-test/uniform-v0", "already exists", "--overwrite")
    assert sorted((p, p.stat().st_mtime_ns) for p in minari_root.rglob("*")) == files
    code, output = cli("export", "minari", "--data", generated_dataset_dir, "--id",
                       "grip-test/uniform-v0", "--episodes", 1, "--overwrite")  # fmt: skip
    assert code == 0, output
    replaced = minari.load_dataset("grip-test/uniform-v0")
    assert replaced.total_episodes == exported.total_episodes // EPISODES


@pytest.mark.parametrize(("args", "fragment"), [
    (("--id", "no-version"), "invalid Minari dataset id"),
    (("--id", "x/name-v0"), "invalid Minari dataset id"),
])  # fmt: skip
def test_a_bad_id_is_refused_with_nothing_written(args, fragment, generated_dataset_dir,
                                                  minari_root):  # fmt: skip
    assert_refused(*cli("export", "minari", "--data", generated_dataset_dir, *args), fragment)
    assert not any(minari_root.rglob("*.hdf5"))


def test_a_missing_dataset_is_refused(tmp_path: Path, minari_root: Path):
    assert_refused(*cli("export", "minari", "--data", tmp_path / "none", "--id", "ab/c-v0"),
                   "none")
    assert not any(minari_root.rglob("*.hdf5"))


def test_a_retry_export_keeps_the_failed_key(generated_dataset_dir: Path, minari_root: Path):
    code, output = cli("export", "minari", "--data", generated_dataset_dir, "--id",
                       "grip-test/retry-v0", "--episodes", EPISODES, "--seed", 3,
                       "--max-attempts", 3)
    assert code == 0, output
    dataset = minari.load_dataset("grip-test/retry-v0")
    assert set(dataset.observation_space.spaces) == {"features", "mask", "failed"}
    assert "Dict(features, mask, failed)" in dataset.storage.metadata["description"]
    record = dataset.storage.metadata[RECORD_KEY]
    assert "replayed by every attempt" in record["reward"]  # generate records every trial
    retried = 0
    for episode in dataset.iterate_episodes():
        failed, mask = episode.observations["failed"], episode.observations["mask"]
        assert len(episode) <= 3 and not failed[0].any()
        for t, (action, reward) in enumerate(zip(episode.actions, episode.rewards, strict=True)):
            expected = failed[t].copy()
            expected[action] = reward == 0  # a drop marks the slot failed, a hold ends it
            assert np.array_equal(failed[t + 1], expected)
            assert mask[t + 1][action] == 0
        retried += len(episode) > 1
    assert retried > 0
