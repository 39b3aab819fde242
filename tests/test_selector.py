"""RL selector: set-policy equivariance, exact metrics, training, report and bad input."""

from __future__ import annotations

import json
from itertools import permutations
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd
import pytest
import torch as th
from gymnasium import spaces
from sb3_contrib import MaskablePPO
from stable_baselines3.common.vec_env import DummyVecEnv
from typer.testing import CliRunner

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.selector import REPORT_FILE, run_selector
from classifiers.experiments.selector.evaluation import attempt_metrics, random_metrics
from classifiers.experiments.selector.policy import CONTEXTS, CandidateSetPolicy, masked_pool
from classifiers.experiments.selector.training import (
    make_selector_env,
    make_selector_model,
    torch_threads,
    train_selector,
)
from grip_env.config import load_config

K, F = 6, 3


class KnownOddsEnv(gym.Env):
    """Each episode: 2..K candidates with random features; p(hold) = sigmoid(3 x0 - 2 x1).

    The reward is that probability (the expected success), so the best choice is known exactly.
    """

    def __init__(self) -> None:
        self.observation_space = spaces.Dict({
            "features": spaces.Box(-5.0, 5.0, (K, F), np.float32),
            "mask": spaces.MultiBinary(K),
        })
        self.action_space = spaces.Discrete(K)

    @staticmethod
    def odds(features: np.ndarray) -> np.ndarray:
        return 1.0 / (1.0 + np.exp(-(3.0 * features[..., 0] - 2.0 * features[..., 1])))

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        count = int(self.np_random.integers(2, K + 1))
        self.features = np.zeros((K, F), np.float32)
        self.features[:count] = self.np_random.normal(size=(count, F)).clip(-5, 5)
        self.mask = np.zeros(K, np.int8)
        self.mask[:count] = 1
        return self._observation(), {}

    def _observation(self):
        return {"features": self.features.copy(), "mask": self.mask.copy()}

    def action_masks(self) -> np.ndarray:
        return self.mask.astype(bool)

    def step(self, action):
        reward = float(self.odds(self.features[int(action)]))
        return self._observation(), reward, True, False, {}


def _set_model(seed: int = 0, context: str = "none") -> MaskablePPO:
    return MaskablePPO(CandidateSetPolicy, KnownOddsEnv(), n_steps=64, batch_size=32, seed=seed,
                       policy_kwargs={"context": context})  # fmt: skip


def _probabilities_and_value(model, features, mask):
    obs, _ = model.policy.obs_to_tensor({"features": features, "mask": mask})
    with th.no_grad():
        dist = model.policy.get_distribution(obs, action_masks=mask.astype(bool)[None])
        value = model.policy.predict_values(obs)
    return dist.distribution.probs[0].numpy(), float(value[0, 0])


@pytest.mark.parametrize("context", CONTEXTS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_set_policy_is_permutation_equivariant(seed, context):
    model = _set_model(seed, context)
    model.learn(64)  # trained weights: a freshly initialised score head is nearly flat
    rng = np.random.default_rng(seed)
    features = rng.normal(size=(K, F)).astype(np.float32)
    mask = np.array([1, 1, 0, 1, 1, 0], dtype=np.int8)
    order = rng.permutation(K)
    probs, value = _probabilities_and_value(model, features, mask)
    shuffled_probs, shuffled_value = _probabilities_and_value(model, features[order], mask[order])
    np.testing.assert_allclose(shuffled_probs, probs[order], atol=1e-6)
    assert shuffled_value == pytest.approx(value, abs=1e-5)
    assert probs[mask == 0].max() == 0.0
    assert probs.sum() == pytest.approx(1.0)
    action, _ = model.predict({"features": features, "mask": mask}, action_masks=mask.astype(bool),
                              deterministic=True)  # fmt: skip
    shuffled_action, _ = model.predict(
        {"features": features[order], "mask": mask[order]}, action_masks=mask[order].astype(bool),
        deterministic=True,
    )  # fmt: skip
    assert order[int(shuffled_action)] == int(action)


@pytest.mark.parametrize("context", CONTEXTS)
def test_set_policy_ignores_padded_slots(context):
    model = _set_model(context=context)
    model.learn(64)
    features = np.random.default_rng(3).normal(size=(K, F)).astype(np.float32)
    mask = np.array([1, 1, 1, 0, 0, 0], dtype=np.int8)
    probs, value = _probabilities_and_value(model, features, mask)
    garbage = features.copy()
    garbage[3:] = 4.0
    probs_garbage, value_garbage = _probabilities_and_value(model, garbage, mask)
    np.testing.assert_allclose(probs_garbage, probs, atol=1e-6)
    assert value_garbage == pytest.approx(value, abs=1e-5)


def test_masked_pool_by_hand():
    embeddings = th.tensor([[[1.0, -2.0], [3.0, 4.0], [100.0, 100.0]]])
    mask = th.tensor([[1.0, 1.0, 0.0]])
    np.testing.assert_allclose(masked_pool(embeddings, mask).numpy(), [[2.0, 1.0, 3.0, 4.0]])
    assert masked_pool(embeddings, th.zeros(1, 3)).abs().sum() == 0.0


def test_attempt_metrics_by_hand():
    first, within, attempts = attempt_metrics(np.array([0.5, 0.2, 0.9]), max_attempts=2)
    assert (first, within, attempts) == pytest.approx((0.5, 1 - 0.5 * 0.8, 1 + 0.5))


@pytest.mark.parametrize("max_attempts", [1, 2, 3, 5])
def test_random_metrics_average_every_order(max_attempts):
    p = np.array([0.9, 0.1, 0.4, 0.0])
    brute = np.mean([attempt_metrics(p[list(o)], max_attempts) for o in permutations(range(4))],
                    axis=0)  # fmt: skip
    np.testing.assert_allclose(random_metrics(p, max_attempts), brute, atol=1e-12)


@pytest.mark.slow
def test_short_training_beats_random_on_known_odds():
    env = DummyVecEnv([KnownOddsEnv for _ in range(4)])
    env.seed(0)
    with torch_threads(1):
        model = make_selector_model(env, "set", seed=0)
        model.learn(2048)
    probe = KnownOddsEnv()
    chosen, random, best = [], [], []
    for episode in range(200):
        obs, _ = probe.reset(seed=10_000 + episode)
        action, _ = model.predict(obs, action_masks=probe.action_masks(), deterministic=True)
        odds = probe.odds(probe.features)[probe.mask == 1]
        chosen.append(probe.odds(probe.features[int(action)]))
        random.append(odds.mean())
        best.append(odds.max())
    assert np.mean(chosen) > np.mean(random) + 0.5 * (np.mean(best) - np.mean(random))


@pytest.fixture(scope="module")
def grips() -> pd.DataFrame:
    return synthetic_grips(n_objects=16, grips=(4, 10), seed=2)


@pytest.fixture(scope="module")
def small_config():
    return load_config().override(
        selector={"max_candidates": 12, "max_attempts": 2}, learning={"models": ("logreg",)}
    )


@pytest.mark.slow
@pytest.mark.parametrize("policy", ["set", "flat"])
def test_run_selector_writes_report_model_and_curve(grips, small_config, tmp_path, policy):
    from test_retry import with_trials

    grips = with_trials(grips)  # two attempts an episode replay one trial k: they need them
    report = run_selector(grips, tmp_path, small_config, policy=policy, timesteps=128,
                          progress=False)  # fmt: skip
    assert json.loads((tmp_path / REPORT_FILE).read_text()) == report
    for name in ("model.zip", "learning_curve.png"):
        assert (tmp_path / name).stat().st_size > 0
    assert any((tmp_path / "tb").iterdir())
    policies = report["policies"]
    assert set(policies) == {"rl", "random", "best_qc", "best_qg", "classifier_logreg", "oracle",
                             "oracle_robustness"}  # fmt: skip
    for scores in policies.values():
        low, high = scores["success_rate"]["ci"]
        assert 0.0 <= low <= scores["success_rate"]["mean"] <= high <= 1.0
        assert 1.0 <= scores["expected_attempts"]["mean"] <= 2.0
    oracle = policies["oracle"]["success_rate"]["mean"]
    assert all(s["success_rate"]["mean"] <= oracle + 1e-12 for s in policies.values())
    split = report["split"]
    assert set(split["train"]).isdisjoint(split["test"])
    record = json.loads((tmp_path / "model.json").read_text())["trained_on"]  # for benchmark
    assert record["objects"] == sorted(split["train"]) and record["split"] == "train"
    assert len(policies["rl"]["per_object"]) == len(split["test"])
    assert report["training"]["policy"] == policy
    assert MaskablePPO.load(tmp_path / "model.zip").num_timesteps == report["training"]["timesteps"]
    _assert_held_out_scalars(tmp_path / "tb", report)


def test_batched_policy_orders_are_the_environments_one_at_a_time_picks(grips, small_config):
    """policy_orders and action_probabilities, one forward pass for every set, give what
    asking the policy set by set gives, a tried slot masked (and, the retry setting of
    small_config, marked failed) before the next attempt."""
    from classifiers.experiments.selector.evaluation import (
        action_probabilities,
        held_out_candidate_sets,
        policy_orders,
    )

    env = make_selector_env(grips, small_config, "train", 1, 0)
    model = make_selector_model(env, "set", 0, None, timesteps=64, settings=small_config.selector)
    assert "failed" in model.observation_space.spaces  # max_attempts 2: the policy reads it
    model.learn(64)  # a fresh score head is nearly flat
    sets = held_out_candidate_sets(grips, small_config)
    assert len(sets) > 1
    probabilities = action_probabilities(model, sets)
    for found, orders, p in zip(sets, policy_orders(model, sets, 3), probabilities, strict=True):
        mask, expected = found.mask.copy(), []
        for _ in range(min(3, found.count)):
            observation = {"features": found.features, "mask": mask.copy()}
            if "failed" in model.observation_space.spaces:  # as GripSelect-v0 shows a retry
                observation["failed"] = found.mask - mask
            action, _ = model.predict(observation, action_masks=mask.astype(bool),
                                      deterministic=True)  # fmt: skip
            expected.append(int(action))
            mask[int(action)] = 0
        np.testing.assert_array_equal(orders, expected)
        assert len(set(orders)) == len(orders) and np.all(orders < found.count)
        np.testing.assert_allclose(p[: found.count].sum(), 1.0, rtol=1e-5)
        assert not p[found.count:].any()
    env.close()


def _assert_held_out_scalars(tb: Path, report: dict) -> None:
    """TensorBoard has the held-out first-pick success of each rollout, with its references."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    (run,) = [path for path in tb.iterdir() if path.is_dir()]
    events = EventAccumulator(str(run))
    events.Reload()
    assert {"eval/held_out_first_pick_success", "eval/best_qc", "eval/oracle"} <= set(
        events.Tags()["scalars"])
    logged = [e.value for e in events.Scalars("eval/held_out_first_pick_success")]
    curve = report["training"]["held_out_curve"]
    assert len(curve) >= 1 and np.allclose(logged, [v for _, v in curve][: len(logged)])
    oracle = events.Scalars("eval/oracle")[-1].value
    assert np.isclose(oracle, report["policies"]["oracle"]["success_rate"]["mean"])
    assert all(0.0 <= v <= oracle + 1e-6 for v in logged)


def test_unknown_policy_is_refused(grips, small_config, tmp_path):
    with pytest.raises(ValueError, match="policy"):
        train_selector(grips, small_config, tmp_path, policy="transformer", timesteps=8)


def test_dataset_without_outcomes_is_refused(grips, small_config, tmp_path):
    bare = grips.drop(columns=["trials", "successes", "success_rate", "success"])
    with pytest.raises(ValueError, match="outcome"):
        run_selector(bare, tmp_path, small_config, timesteps=8, progress=False)


def test_cli_reports_bad_policy_with_exit_code_2(grips, tmp_path):
    from grip_env.cli import _register_commands, app

    _register_commands()
    path = tmp_path / "grips.parquet"
    grips.to_parquet(path)
    result = CliRunner().invoke(
        app, ["select", "--data", str(path), "--out", str(tmp_path / "o"), "--policy", "bad"]
    )
    assert result.exit_code == 2
    assert "policy" in result.output


@pytest.mark.slow
def test_live_training_executes_grips_in_pybullet(tmp_path):
    config = load_config().override(
        objects={"set": "basic", "procedural_count": 0}, selector={"max_candidates": 16}
    )
    trained = train_selector(None, config, tmp_path, live=True, timesteps=32, progress=False)
    assert trained.model.num_timesteps == 32  # a short run collects a short rollout, not 512
    timesteps, rewards = trained.timesteps, trained.rewards
    assert trained.held_out == ()  # live training has no recorded held-out outcomes
    assert list(timesteps) == list(range(1, 33))  # one attempt per episode: each step ends one
    assert set(rewards) <= {0.0, 1.0}
    assert (tmp_path / "model.zip").exists()


def test_robustness_reward_pays_the_picked_grips_robustness(grips, small_config):
    config = small_config.override(selector={"reward": "robustness"})
    reference = config.sim.reference_level_g
    env = make_selector_env(grips, config, "train", n_envs=1, seed=3).envs[0]
    expected = dict(zip(grips["grip_id"], grips["robustness_mean"] / reference, strict=True))
    rewards = []
    for episode in range(5):
        env.reset(seed=episode)
        _, reward, _, _, info = env.step(0)
        assert reward == pytest.approx(expected[info["grip_id"]])
        rewards.append(reward)
    assert len(set(rewards)) > 1 and not set(rewards) <= {0.0, 1.0}
    with pytest.raises(ValueError, match="replay"):
        make_selector_env(None, config, "train", n_envs=1)
    with pytest.raises(ValueError, match="robustness_mean"):
        make_selector_env(grips.drop(columns="robustness_mean"), config, "train", n_envs=1)


@pytest.mark.slow
def test_context_policy_sees_the_other_candidates_and_saves_its_context(tmp_path):
    features = np.random.default_rng(4).normal(size=(K, F)).astype(np.float32)
    mask = np.array([1, 1, 1, 1, 0, 0], dtype=np.int8)
    changed = features.copy()
    changed[3] += 2.0  # another candidate: only a context policy's other scores may move
    for context in CONTEXTS:
        model = _set_model(context=context)
        model.learn(64)
        probs, _ = _probabilities_and_value(model, features, mask)
        moved, _ = _probabilities_and_value(model, changed, mask)
        ratio, moved_ratio = probs[0] / probs[1], moved[0] / moved[1]
        if context == "none":
            assert moved_ratio == pytest.approx(ratio, rel=1e-5)
        else:
            assert abs(moved_ratio - ratio) > 1e-6 * ratio
        model.save(tmp_path / f"{context}.zip")
        assert MaskablePPO.load(tmp_path / f"{context}.zip").policy.context == context
    with pytest.raises(ValueError, match="context"):
        _set_model(context="transformer")


def test_expected_success_reward_pays_the_recorded_success_rate(grips, small_config):
    config = small_config.override(selector={"reward": "expected_success", "max_attempts": 1})
    env = make_selector_env(grips, config, "train", n_envs=1, seed=3).envs[0]
    expected = dict(zip(grips["grip_id"], grips["success_rate"], strict=True))
    rewards = []
    for episode in range(8):
        env.reset(seed=episode)
        _, reward, terminated, _, info = env.step(0)
        assert terminated and reward == pytest.approx(expected[info["grip_id"]])
        rewards.append(reward)
    assert not set(rewards) <= {0.0, 1.0}
    with pytest.raises(ValueError, match="replay"):
        make_selector_env(None, config, "train", n_envs=1)
    with pytest.raises(ValueError, match="max_attempts 1"):
        make_selector_env(grips, small_config.override(selector={"reward": "expected_success"}),
                          "train", n_envs=1)  # fmt: skip


@pytest.mark.slow
def test_selector_trained_on_robustness_reports_first_pick_robustness(grips, small_config,
                                                                       tmp_path):
    config = small_config.override(selector={"reward": "robustness", "max_attempts": 1})
    report = run_selector(grips, tmp_path, config, timesteps=64, progress=False)
    assert report["reward"] == "robustness"
    policies = report["policies"]
    oracle = policies["oracle_robustness"]["first_pick_robustness"]["mean"]
    for scores in policies.values():
        assert 0.0 <= scores["first_pick_robustness"]["mean"] <= oracle + 1e-12
    best_possible = grips.groupby("object_id")["robustness_mean"].max()
    test_ids = report["split"]["test"]
    assert oracle <= best_possible[best_possible.index.astype(str).isin(test_ids)].mean() + 1e-9


def test_training_baselines_are_the_expected_episode_rewards(grips, small_config):
    from classifiers.experiments.selector.evaluation import training_baselines
    from grip_env.dataset.split import split_objects

    one = small_config.override(selector={"max_attempts": 1})
    lines = training_baselines(grips, one)
    train_ids, _ = split_objects(grips["object_id"].astype(str), 0.25, 0)
    train = grips[grips["object_id"].astype(str).isin(train_ids)]
    shown = train.sort_values("Q_C", kind="stable").groupby("object_id").head(12)
    per_object = shown.groupby("object_id")["success_rate"]
    assert lines["random"] == pytest.approx(per_object.mean().mean())
    assert lines["oracle"] == pytest.approx(per_object.max().mean())
    best = shown.groupby("object_id").first()["success_rate"].mean()
    assert lines["best Q_C"] == pytest.approx(best)
    two = training_baselines(grips, small_config)  # two attempts: at least as likely to hold
    assert all(two[name] >= lines[name] - 1e-12 for name in lines)
    robust = training_baselines(grips, one.override(selector={"reward": "robustness"}))
    reference = one.sim.reference_level_g
    assert robust["oracle"] == pytest.approx(
        shown.groupby("object_id")["robustness_mean"].max().mean() / reference
    )
    assert training_baselines(grips, small_config.override(selector={"reward": "robustness"})) == {}
