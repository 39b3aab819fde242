"""The retry setting: an episode's attempts replay one trial index k, and its scoring from the
shared draws against the independence formula."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from cli_runs import assert_refused, cli

from classifiers.evaluation.synthetic import synthetic_grips
from classifiers.experiments.benchmark.retry import retry_leaderboard, retry_metrics
from classifiers.report.leaderboard import retry_table
from grip_env.columns import trial_robustness_columns, trial_success_columns
from grip_env.envs.accept import GripAcceptEnv
from grip_env.envs.backends import ReplayBackend
from grip_env.envs.select import GripSelectEnv

TRIALS = 5


def with_trials(table: pd.DataFrame, seed: int = 0) -> pd.DataFrame:
    """``table`` with per-trial successes that sum to its ``successes`` (a seeded placement)."""
    rng = np.random.default_rng(seed)
    trials = int(table["trials"].iloc[0])
    held = np.zeros((len(table), trials), dtype=bool)
    for row, count in enumerate(table["successes"].to_numpy(int)):
        held[row, rng.permutation(trials)[:count]] = True
    extra = pd.DataFrame(held, columns=list(trial_success_columns(trials)), index=table.index)
    levels = pd.DataFrame(np.where(held, 64.0, 8.0), columns=list(trial_robustness_columns(trials)),
                          index=table.index)
    return pd.concat([table, extra, levels], axis=1)


@pytest.fixture(scope="module")
def table() -> pd.DataFrame:
    return with_trials(synthetic_grips(n_objects=8, grips=(4, 9), trials=TRIALS, seed=3))


def _env(table: pd.DataFrame, cls: type = GripSelectEnv, **options: object) -> GripSelectEnv:
    defaults = {"max_candidates": 12, "max_attempts": 3}
    return cls(data=table, **(defaults | options))


def _recorded(table: pd.DataFrame, grip_id: object, trial: int) -> bool:
    row = table.loc[table["grip_id"] == grip_id].iloc[0]
    return bool(row[f"trial_success_{trial}"])


# ----------------------------------------------------------------------------- environment
def test_attempts_within_an_episode_replay_the_same_trial(table: pd.DataFrame) -> None:
    env = _env(table)
    assert env.trials == TRIALS
    seen = 0
    for episode in range(40):
        _, info = env.reset(seed=episode)
        k = info["trial"]
        terminated, slot = False, 0
        while not terminated:
            _, reward, terminated, _, step = env.step(slot)
            assert step["success"] == _recorded(table, step["grip_id"], k)  # trial k, every try
            assert reward == float(step["success"])
            slot, seen = slot + 1, seen + 1
    assert seen > 40  # some episodes retried


def test_the_failed_key_marks_exactly_the_failed_picks(table: pd.DataFrame) -> None:
    env = _env(table)
    assert set(env.observation_space.spaces) == {"features", "mask", "failed"}
    retried = 0
    for episode in range(40):
        observation, info = env.reset(seed=episode)
        assert not observation["failed"].any()
        k, tried_and_failed = info["trial"], set()
        terminated, slot = False, 2
        while not terminated:
            observation, _, terminated, _, step = env.step(slot)
            if not step["success"]:
                tried_and_failed.add(slot)
            assert set(np.flatnonzero(observation["failed"])) == tried_and_failed
            assert not observation["mask"][slot]  # executed: masked, whatever the outcome
            assert int(observation["failed"].sum()) == step["attempts"] - step["success"]
            assert step["success"] == _recorded(table, step["grip_id"], k)
            assert observation in env.observation_space
            slot = int(np.flatnonzero(observation["mask"])[0]) if not terminated else slot
        retried += len(tried_and_failed) > 1
    assert retried > 0  # some episodes failed twice or more


def test_one_attempt_keeps_the_two_key_observation(table: pd.DataFrame) -> None:
    env = _env(table, max_attempts=1)
    assert set(env.observation_space.spaces) == {"features", "mask"}
    observation, _ = env.reset(seed=0)
    assert set(observation) == {"features", "mask"}
    assert set(env.step(0)[0]) == {"features", "mask"}


def test_accept_marks_the_positions_executed_and_failed(table: pd.DataFrame) -> None:
    """GripAccept-v0's ``failed``: the positions executed and dropped, none skipped; at the
    same object and trial k it is GripSelect-v0's ``failed`` after picking those slots."""
    accept, select = _env(table, GripAcceptEnv), _env(table)
    assert set(accept.observation_space.spaces) == {"features", "progress", "failed"}
    assert accept.observation_space["failed"] == select.observation_space["failed"]
    retried = 0
    for episode in range(40):
        observation, info = accept.reset(seed=episode)
        assert not observation["failed"].any() and observation in accept.observation_space
        pinned = {"object_id": info["object_id"], "trial": info["trial"]}
        chosen, _ = select.reset(options=pinned)
        terminated, position, failed = False, 0, set()
        while not terminated:
            execute = (episode + position) % 3 != 1  # skip some candidates
            observation, _, terminated, _, step = accept.step(int(execute))
            if execute:
                if not step["success"]:
                    failed.add(position)
                chosen, _, _, _, picked = select.step(position)
                assert picked["grip_id"] == step["grip_id"]
                assert picked["success"] == step["success"]
                np.testing.assert_array_equal(chosen["failed"], observation["failed"])
            assert set(np.flatnonzero(observation["failed"])) == failed
            assert observation in accept.observation_space
            position += 1
        retried += len(failed) > 1
    assert retried > 0


def test_accept_with_one_attempt_keeps_its_two_keys(table: pd.DataFrame) -> None:
    env = _env(table, GripAcceptEnv, max_attempts=1)
    assert set(env.observation_space.spaces) == {"features", "progress"}
    assert set(env.reset(seed=0)[0]) == {"features", "progress"}
    assert set(env.step(1)[0]) == {"features", "progress"}


def test_an_invalid_pick_marks_nothing_failed(table: pd.DataFrame) -> None:
    env = _env(table)
    observation, _ = env.reset(seed=0)
    padded = int(np.flatnonzero(observation["mask"] == 0)[0])
    observation, reward, terminated, _, info = env.step(padded)
    assert info["invalid_action"] and terminated and reward == -1.0
    assert not observation["failed"].any()


def test_replaying_an_object_without_its_trials_is_refused(table: pd.DataFrame) -> None:
    partial = table.assign(trial_success_2=table["trial_success_2"].astype(float))
    first = str(partial["object_id"].iloc[0])
    partial.loc[partial["object_id"] == partial["object_id"].iloc[0], "trial_success_2"] = np.nan
    env = _env(partial)
    env.reset(seed=0, options={"object_id": first, "trial": 0})
    with pytest.raises(ValueError, match=rf"object '{first}' lacks some of its trials'"):
        env.step(0)


def test_accept_env_replays_the_episode_trial(table: pd.DataFrame) -> None:
    env = _env(table, GripAcceptEnv)
    for episode in range(20):
        _, info = env.reset(seed=100 + episode)
        terminated = False
        while not terminated:
            _, _, terminated, _, step = env.step(1)
            assert step["success"] == _recorded(table, step["grip_id"], info["trial"])


def test_fresh_episodes_draw_k_from_the_seed(table: pd.DataFrame) -> None:
    def trials(seed: int) -> list[int]:
        env = _env(table)
        first = env.reset(seed=seed)[1]["trial"]
        return [first] + [env.reset()[1]["trial"] for _ in range(59)]

    drawn = trials(7)
    assert drawn == trials(7)  # reproducible from the seed
    assert drawn != trials(8)
    assert set(drawn) == set(range(TRIALS))  # every index drawn, not one k for every episode
    counts = np.bincount(drawn, minlength=TRIALS)
    assert counts.min() >= 4  # about uniform (12 expected each)


def test_rate_replay_and_data_without_trials(table: pd.DataFrame) -> None:
    env = _env(table, replay="rate")
    assert env.trials == 0 and "trial" not in env.reset(seed=0)[1]
    bare = synthetic_grips(n_objects=4, trials=TRIALS, seed=1)
    assert _env(bare).trials == 0  # auto: the old independent draws
    with pytest.raises(ValueError, match="replay='trial' needs every trial's outcome"):
        ReplayBackend(bare, replay="trial")
    with pytest.raises(ValueError, match="replay must be one of"):
        ReplayBackend(bare, replay="trials")


def test_max_attempts_beyond_the_candidates_is_refused(table: pd.DataFrame) -> None:
    with pytest.raises(ValueError, match="max_attempts 13 exceeds the 12 candidates"):
        _env(table, max_attempts=13)
    _env(table, max_attempts=12).close()


def test_cli_refuses_max_attempts_beyond_the_candidates(tmp_path: Path) -> None:
    config = tmp_path / "c.yaml"
    config.write_text("selector:\n  max_candidates: 8\n  max_attempts: 9\n")
    out = tmp_path / "out"
    code, output = cli("select", "--out", out, "--config", config)
    assert_refused(code, output, "max_attempts 9 exceeds max_candidates 8")
    assert not out.exists()


# ----------------------------------------------------------------------------- scoring
def _one_object(held: list[list[int]], scores: list[float]) -> tuple[pd.DataFrame, pd.DataFrame]:
    held_array = np.array(held, dtype=bool)
    candidates = pd.DataFrame({
        "object_id": "a", "candidate": range(len(held)),
        "success_rate": held_array.mean(axis=1)})
    candidates[list(trial_success_columns(held_array.shape[1]))] = held_array
    frame = pd.DataFrame({"method": "m", "seed": 0, "object_id": "a",
                          "candidate": range(len(held)), "score": scores})
    return candidates, frame


def test_shared_draws_hand_computed() -> None:
    # two grips that fail on the same draws (k = 2, 3), a third that holds exactly there
    held = [[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 1]]
    candidates, scores = _one_object(held, [3.0, 2.0, 1.0])
    found = retry_metrics(candidates, scores).iloc[0]
    assert found["shared_at_1"] == 0.5
    assert found["shared_at_2"] == 0.5  # the second grip fails when the first does
    assert found["shared_at_3"] == 1.0
    assert found["success_at_2"] == pytest.approx(0.75)  # 1 - 0.5 * 0.5: independence
    assert found["overstatement_at_2"] == pytest.approx(0.25)
    assert found["overstatement_at_1"] == 0.0
    assert found["ceiling"] == 1.0  # some grip holds at every k


def test_ties_are_averaged_exactly() -> None:
    held = [[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 1]]
    candidates, scores = _one_object(held, [0.0, 0.0, 0.0])  # all tied: a uniform order
    found = retry_metrics(candidates, scores).iloc[0]
    orders = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    array = np.array(held, dtype=bool)
    for m in (1, 2, 3):
        expected = np.mean([array[list(order[:m])].any(axis=0).mean() for order in orders])
        assert found[f"shared_at_{m}"] == pytest.approx(expected)


def test_shared_never_exceeds_independence_when_grips_fail_together(table: pd.DataFrame) -> None:
    from classifiers.experiments.benchmark.methods import baseline_scores

    candidates = table.assign(candidate=table.groupby("object_id").cumcount(),
                              object_id=table["object_id"].astype(str))
    metrics = retry_metrics(candidates, baseline_scores(candidates))
    first = metrics["shared_at_1"].to_numpy()
    assert np.allclose(first, metrics["success_at_1"].to_numpy())  # one attempt: no difference
    assert (np.diff(metrics[["shared_at_1", "shared_at_2", "shared_at_3"]].to_numpy(), axis=1)
            >= -1e-12).all()  # more attempts never hurt
    board = retry_leaderboard(metrics, reps=200)
    assert board["objects"] == 8 and set(board["methods"]) >= {"best_qc", "oracle", "random"}
    assert board["methods"]["best_qc"]["shared_at_2_minus_best_qc"]["estimate"] == 0.0
    assert "within 2 minus best_qc" in retry_table(board)


def test_scoring_needs_the_per_trial_columns() -> None:
    bare = synthetic_grips(n_objects=2, trials=3, seed=0)
    candidates = bare.assign(candidate=bare.groupby("object_id").cumcount())
    scores = candidates[["object_id", "candidate"]].assign(method="m", seed=0, score=0.0)
    with pytest.raises(ValueError, match="needs every trial's outcome"):
        retry_metrics(candidates, scores)


@pytest.mark.slow
def test_the_standard_retry_board_scores_every_held_out_object() -> None:
    from classifiers.experiments.benchmark.retry import standard_retry_board
    from classifiers.experiments.benchmark.split import STANDARD_TEST_OBJECTS_V4

    board = standard_retry_board(reps=100)  # the standard dataset records every trial
    assert board["split"]["scored_objects"] == board["objects"] == len(STANDARD_TEST_OBJECTS_V4)
    for row in board["methods"].values():
        assert row["overstatement_at_1"]["estimate"] == pytest.approx(0.0, abs=1e-12)
        shared = [row[f"shared_at_{m}"]["estimate"] for m in (1, 2, 3)]
        assert shared == sorted(shared)  # another attempt never lowers the chance


def test_an_adaptive_policy_is_scored_on_every_trial(table: pd.DataFrame) -> None:
    """The policy that always takes the first valid slot is the best-Q_C static order: its
    episodes, pinned to each trial k, give retry_metrics' exact shared-draw figures."""
    from classifiers.experiments.benchmark.methods import baseline_scores
    from classifiers.experiments.benchmark.retry import policy_retry_metrics
    from grip_env.config import Config

    config = Config().override(selector={"max_candidates": 12})
    ids = sorted(table["object_id"].astype(str).unique())
    data = table.assign(object_id=table["object_id"].astype(str))
    first_valid = policy_retry_metrics(data, ids, lambda obs, mask: int(np.argmax(mask)), config)
    candidates = data.sort_values(["object_id", "Q_C"], kind="mergesort").assign(
        candidate=lambda f: f.groupby("object_id").cumcount())
    static = retry_metrics(candidates, baseline_scores(candidates).query("method == 'best_qc'"))
    for m in (1, 2, 3):
        assert np.allclose(first_valid[f"shared_at_{m}"], static[f"shared_at_{m}"])


def test_the_trial_option_pins_k(table: pd.DataFrame) -> None:
    env = _env(table)
    assert env.reset(seed=0, options={"trial": 3})[1]["trial"] == 3
    with pytest.raises(ValueError, match=r"'trial' must be an integer in \[0, 5\)"):
        env.reset(options={"trial": 5})
    with pytest.raises(ValueError, match="needs trials replayed by index"):
        _env(table, replay="rate").reset(options={"trial": 0})


@pytest.mark.parametrize("cls", [GripSelectEnv, GripAcceptEnv])
def test_gymnasiums_checker_passes_with_trials_replayed(table: pd.DataFrame, cls: type) -> None:
    from gymnasium.utils.env_checker import check_env

    env = _env(table, cls)
    assert env.trials == TRIALS
    check_env(env, skip_render_check=True)  # seeded resets (the trial draw included) repeat
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    assert "failed" in env.observation_space.spaces  # the retry observation of both
    sb3_check_env(env)


# ----------------------------------------------------------------------------- the selector's own
def test_the_selectors_attempt_metrics_use_the_shared_draws_by_hand() -> None:
    from classifiers.experiments.selector.evaluation import attempt_metrics, shared_attempt_metrics

    held = np.array([[1, 1, 0, 0], [1, 1, 0, 0], [0, 0, 1, 1]], dtype=bool)
    # the second grip fails exactly when the first does: a second attempt adds nothing
    assert shared_attempt_metrics(held, 2) == pytest.approx((0.5, 0.5, 1.5))
    assert shared_attempt_metrics(held, 3) == pytest.approx((0.5, 1.0, 2.0))
    assert attempt_metrics(held.mean(axis=1), 2) == pytest.approx((0.5, 0.75, 1.5))


@pytest.mark.parametrize("max_attempts", [1, 2, 3, 5])
def test_the_selectors_random_shared_figures_average_every_order(max_attempts: int) -> None:
    from itertools import permutations

    from classifiers.experiments.selector.evaluation import (
        shared_attempt_metrics,
        shared_random_metrics,
    )

    held = np.random.default_rng(max_attempts).random((4, 6)) < 0.4
    brute = np.mean([shared_attempt_metrics(held[list(order)], max_attempts)
                     for order in permutations(range(4))], axis=0)  # fmt: skip
    np.testing.assert_allclose(shared_random_metrics(held, max_attempts), brute, atol=1e-12)


def _selector_config():
    from grip_env.config import Config

    return Config().override(selector={"max_candidates": 12, "max_attempts": 3},
                             learning={"models": ("logreg",)})  # fmt: skip


def _selector_model(data: pd.DataFrame, config):
    from classifiers.experiments.selector.training import make_selector_env, make_selector_model

    return make_selector_model(make_selector_env(data, config, "train", 1), "set", seed=0)


@pytest.fixture(scope="module")
def many() -> pd.DataFrame:
    table = with_trials(synthetic_grips(n_objects=16, grips=(4, 9), trials=TRIALS, seed=5))
    return table.assign(object_id=table["object_id"].astype(str))


def test_the_selectors_evaluation_scores_retries_as_the_environment_replays_them(
        many: pd.DataFrame) -> None:  # fmt: skip
    """Every selector's success within 3 attempts is what ``GripSelect-v0`` gives its picks when
    an episode's attempts replay one trial k (each test object, every k): the RL policy, and
    best-Q_C as the first valid slot; the result says the attempts shared the draw."""
    from classifiers.experiments.benchmark.retry import policy_retry_metrics
    from classifiers.experiments.selector.evaluation import evaluate_selectors

    config = _selector_config()
    model = _selector_model(many, config)
    report = evaluate_selectors(model, many, config, n_boot=200)
    assert report["attempts"]["draws"] == "shared" and report["attempts"]["trials"] == TRIALS
    test = report["split"]["test"]

    def agent(observation: dict, mask: np.ndarray) -> int:
        return int(model.predict(observation, action_masks=mask, deterministic=True)[0])

    for name, policy in (("rl", agent), ("best_qc", lambda obs, mask: int(np.argmax(mask)))):
        played = policy_retry_metrics(many, test, policy, config, attempts=3)
        within = report["policies"][name]["success_within_attempts"]["mean"]
        assert within == pytest.approx(played["shared_at_3"].mean(), abs=1e-12), name


def test_without_per_trial_outcomes_the_evaluation_says_it_assumes_independence(
        many: pd.DataFrame) -> None:  # fmt: skip
    from classifiers.experiments.selector.evaluation import attempt_metrics, evaluate_selectors

    config = _selector_config()
    bare = many.drop(columns=[c for c in many.columns if str(c).startswith("trial_")])
    model = _selector_model(bare, config)
    report = evaluate_selectors(model, bare, config, n_boot=200)
    scoring = report["attempts"]
    assert scoring["draws"] == "independent"
    assert "does not record each trial's outcome" in scoring["note"]
    test = report["split"]["test"]
    expected = [attempt_metrics(group.sort_values("Q_C", kind="stable")["success_rate"]
                                .to_numpy(float), 3)[1]
                for _, group in bare[bare["object_id"].isin(test)].groupby("object_id")]
    within = report["policies"]["best_qc"]["success_within_attempts"]["mean"]
    assert within == pytest.approx(np.mean(expected), abs=1e-12)


def test_the_learning_curves_baselines_are_the_shared_draw_episode_rewards(
        many: pd.DataFrame) -> None:  # fmt: skip
    """With trials replayed by index, best-Q_C's expected episode reward on the training objects
    is the mean over their trials of a hold within the attempts, as the environment plays it."""
    from classifiers.experiments.benchmark.retry import policy_retry_metrics
    from classifiers.experiments.selector.evaluation import training_baselines
    from grip_env.dataset.split import held_out_objects

    config = _selector_config()
    lines = training_baselines(many, config)
    train, _ = held_out_objects(many["object_id"], config.learning)
    played = policy_retry_metrics(many, list(train), lambda obs, mask: int(np.argmax(mask)),
                                  config, attempts=3)  # fmt: skip
    assert lines["best Q_C"] == pytest.approx(played["shared_at_3"].mean(), abs=1e-12)
    bare = many.drop(columns=[c for c in many.columns if str(c).startswith("trial_")])
    assert training_baselines(bare, config)["best Q_C"] != pytest.approx(lines["best Q_C"])


def test_the_leaderboard_says_what_its_attempts_table_assumes() -> None:
    from classifiers.report.leaderboard import attempts_caption, retry_lines

    without = attempts_caption({"methods": {}})
    assert "does not record each trial's outcome" in without and "overstate" in without
    with_retry = attempts_caption({"methods": {}, "retry": {}})
    assert "retry section scores the same attempts on the shared draws" in with_retry
    assert retry_lines({"methods": {}}) == []


def test_an_object_missing_its_trials_is_refused_not_read_as_a_hold(many: pd.DataFrame) -> None:
    from classifiers.experiments.selector.evaluation import training_baselines
    from grip_env.dataset.split import held_out_objects

    config = _selector_config()
    train, _ = held_out_objects(many["object_id"], config.learning)
    partial = many.assign(trial_success_0=many["trial_success_0"].astype(float))
    partial.loc[partial["object_id"] == train[0], "trial_success_0"] = np.nan
    with pytest.raises(ValueError, match=rf"object '{train[0]}' lacks some of its trials'"):
        training_baselines(partial, config)


def test_the_study_refuses_retry_attempts_beyond_the_candidates(tmp_path: Path) -> None:
    config = tmp_path / "c.yaml"
    config.write_text("selector:\n  max_candidates: 8\n  retry_attempts: 9\n")
    out = tmp_path / "out"
    code, output = cli("study", "--quick", "--out", out, "--config", config)
    assert_refused(code, output, "retry_attempts 9 exceeds max_candidates 8")
    assert not out.exists()
