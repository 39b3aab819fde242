"""GripSelect-v0 and GripAccept-v0: API conformance, rewards, masking, seeding, split, rendering."""

from __future__ import annotations

import gymnasium
import numpy as np
import pandas as pd
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from hypothesis import given, settings
from hypothesis import strategies as st
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import grip_env  # noqa: F401  (registers the environments)
from grip_env.columns import CONTACTS, DATASET_COLUMNS, FEATURES
from grip_env.envs import (
    GripAcceptEnv,
    GripSelectEnv,
    LiveBackend,
    objects_in_split,
    split_objects,
)
from grip_env.objects import SHAPE_NAMES, make_shape

NAMES = ("rectangle", "triangle", "hexagon", "l_shape", "square", "disc")
SIZES = (5, 12, 3, 20, 8, 1)  # candidates per object; K = 8 below truncates two of them


def synthetic_dataset(
    names: tuple[str, ...] = NAMES, sizes: tuple[int, ...] = SIZES, seed: int = 0
) -> pd.DataFrame:
    """A small dataset with the contract's columns: random features, known outcome counts."""
    rng = np.random.default_rng(seed)
    frames = []
    for name, n in zip(names, sizes, strict=True):
        obj = make_shape(name)
        frame = pd.DataFrame(0.0, index=range(n), columns=list(DATASET_COLUMNS))
        frame["object_id"] = name
        frame["grasp_id"] = np.arange(n)
        frame["grip_id"] = [f"{name}/{i}/0" for i in range(n)]
        frame["two_finger"] = False
        contacts = obj.contour[rng.integers(0, len(obj.contour), size=(n, 3))]
        frame[list(CONTACTS)] = contacts.reshape(n, 6)
        frame[list(FEATURES)] = rng.uniform(0.0, 3.0, size=(n, len(FEATURES)))
        frame["Q_G"] = 0.0
        frame["Q_C"] = frame[list(FEATURES)].sum(axis=1)
        frame["area"] = obj.area
        frame["centroid_x"], frame["centroid_y"] = obj.centroid
        frame["trials"] = 5
        frame["successes"] = rng.integers(0, 6, size=n)
        frame["success_rate"] = frame["successes"] / 5
        frame["success"] = frame["success_rate"] >= 0.5
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


@pytest.fixture(scope="module")
def data() -> pd.DataFrame:
    return synthetic_dataset()


def select_env(data: pd.DataFrame, **options: object) -> GripSelectEnv:
    return GripSelectEnv(data, max_candidates=8, **options)


# ------------------------------------------------------------------------------ split
@settings(max_examples=60, deadline=None)
@given(
    ids=st.lists(st.text("abcdef", min_size=1, max_size=4), min_size=1, max_size=30, unique=True),
    fraction=st.floats(0.01, 0.99),
    seed=st.integers(0, 2**32 - 1),
)
def test_split_partitions_ids_deterministically_whatever_their_order(ids, fraction, seed):
    train, test = split_objects(ids, fraction, seed)
    assert not set(train) & set(test)
    assert sorted(train + test) == sorted(ids)
    assert split_objects(list(reversed(ids)), fraction, seed) == (train, test)
    if len(ids) >= 2:
        assert train and test


def test_split_sizes_follow_the_fraction_and_seed_changes_the_split():
    ids = [f"obj{i:02d}" for i in range(20)]
    splits = {split_objects(ids, 0.25, seed)[1] for seed in range(5)}
    assert all(len(test) == 5 for test in splits)
    assert len(splits) > 1
    assert split_objects(["only"], 0.5, 0) == (("only",), ())


@pytest.mark.parametrize("fraction", [0.0, 1.0, -0.1, float("nan")])
def test_split_refuses_bad_fraction(fraction):
    with pytest.raises(ValueError, match="test_fraction"):
        split_objects(["a", "b"], fraction)


def test_envs_use_split_objects(data):
    train, test = split_objects(NAMES, 0.34, 7)
    env_train = select_env(data, split="train", test_fraction=0.34, split_seed=7)
    env_test = select_env(data, split="test", test_fraction=0.34, split_seed=7)
    assert env_train.object_ids == train and env_test.object_ids == test
    seen = {env_test.reset(seed=s)[1]["object_id"] for s in range(40)}
    assert seen == set(test)
    with pytest.raises(ValueError, match="split"):
        objects_in_split(NAMES, "validation")


# ------------------------------------------------------------------------------ registration, API
def test_registered_ids_make_the_classes(data):
    for env_id, cls in (("GripSelect-v0", GripSelectEnv), ("GripAccept-v0", GripAcceptEnv)):
        spec = gymnasium.spec(env_id)
        assert isinstance(spec.entry_point, str)
        env = gymnasium.make(env_id, data=data)
        assert isinstance(env.unwrapped, cls)
        env.close()


@pytest.mark.parametrize("env_id", ["GripSelect-v0", "GripAccept-v0"])
@pytest.mark.filterwarnings("ignore::UserWarning")
def test_gymnasium_and_sb3_checkers_pass_on_replay(env_id, data):
    env = gymnasium.make(env_id, data=data, max_candidates=8, max_attempts=2,
                         render_mode="rgb_array")
    gym_check_env(env.unwrapped)  # also renders every declared mode through env.spec
    sb3_check_env(env.unwrapped)
    env.close()


# ------------------------------------------------------------------------------ observations
def test_observation_keeps_the_k_lowest_q_c_in_order_and_pads(data):
    env = select_env(data, features=["Q_C", "S1"], normalize="none", objects=["l_shape"])
    obs, info = env.reset(seed=0)
    expected = np.sort(data.loc[data.object_id == "l_shape", "Q_C"].to_numpy())[:8]
    np.testing.assert_allclose(obs["features"][:, 0], expected, rtol=1e-6)
    assert info["candidates"] == 8 and obs["mask"].sum() == 8
    env = select_env(data, features=["Q_C"], normalize="none", objects=["hexagon"])
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(obs["mask"], [1, 1, 1, 0, 0, 0, 0, 0])
    assert np.all(obs["features"][3:] == 0)
    assert obs["features"].dtype == np.float32 and obs["features"].shape == (8, 1)


def test_candidate_sets_of_many_objects_match_each_objects_own_sort(data):
    """One vectorised pass equals sorting each object's rows on their own (ties keep table
    order, a NaN Q_C comes last), in an interleaved table with an object of no rows."""
    from grip_env.envs.observation import FeatureScaler, best_candidates, candidate_sets

    table = data.sample(frac=1.0, random_state=3).reset_index(drop=True)
    table.loc[table.index[::4], "Q_C"] = 1.5  # ties
    table.loc[table.index[5], "Q_C"] = np.nan
    ids = [*NAMES, "nothing"]
    frames = [table[table["object_id"] == name] for name in ids]
    scaler = FeatureScaler.fit("log", FEATURES, 100.0, None)
    for name, frame, found in zip(ids, frames, candidate_sets(ids, frames, scaler, 8), strict=True):
        expected = best_candidates(frame, 8)
        assert found.object_id == name and found.count == len(expected) == min(len(frame), 8)
        pd.testing.assert_frame_equal(found.rows, expected)
        assert found.grip_ids == tuple(expected["grip_id"])
        np.testing.assert_array_equal(found.features[: found.count],
                                      scaler.transform(expected[list(FEATURES)].to_numpy()))
        np.testing.assert_array_equal(found.q_c[: found.count], expected["Q_C"].to_numpy())
        np.testing.assert_array_equal(found.mask, np.arange(8) < found.count)
        assert np.isnan(found.q_c[found.count:]).all() and not found.features[found.count:].any()
        assert not found.features.flags.writeable
    with pytest.raises(ValueError, match="2 object ids for 1 candidate tables"):
        candidate_sets(ids[:2], frames[:1], scaler, 8)


def test_normalisations(data):
    raw = select_env(data, normalize="none", objects=["rectangle"]).reset(seed=0)[0]["features"]
    logged = select_env(data, normalize="log", objects=["rectangle"]).reset(seed=0)[0]["features"]
    np.testing.assert_allclose(logged[:5], np.log1p(raw[:5]), rtol=1e-6)
    env = GripSelectEnv(data, normalize="standard", max_candidates=32)
    stacked = np.vstack([s.features[: s.count] for s in env._sets])
    np.testing.assert_allclose(stacked.mean(axis=0), 0.0, atol=1e-5)
    np.testing.assert_allclose(stacked.std(axis=0), 1.0, atol=1e-5)
    low, high = env.scaler.bounds()
    assert np.all(low < stacked.min(axis=0)) and np.all(stacked.max(axis=0) < high)


def test_feature_subset_sets_the_width(data):
    env = select_env(data, features=("S1", "C4", "C6"))
    assert env.observation_space["features"].shape == (8, 3)
    assert env.reset(seed=1)[0]["features"].shape == (8, 3)


@pytest.mark.parametrize("options", [
    {"features": ["S9"]}, {"features": []}, {"normalize": "minmax"}, {"split": "dev"},
    {"candidate_order": "random"}, {"max_attempts": 0}, {"max_candidates": 0},
    {"objects": ["pear"]}, {"render_mode": "video"},
])
def test_bad_options_raise_value_error(data, options):
    with pytest.raises(ValueError):
        GripSelectEnv(data, **options)


def test_replay_data_must_hold_outcomes(data):
    with pytest.raises(ValueError, match="trials"):
        GripSelectEnv(data.drop(columns=["trials", "successes", "success_rate"]))


# ------------------------------------------------------------------------------ rewards and masks
def with_rates(data: pd.DataFrame, successes: int) -> pd.DataFrame:
    fixed = data.copy()
    fixed["successes"] = successes
    return fixed


def test_replay_reward_follows_the_recorded_success_rate(data):
    always = select_env(with_rates(data, 5), success_reward=2.0)
    never = select_env(with_rates(data, 0), failure_reward=-0.5)
    for seed in range(20):
        always.reset(seed=seed)
        never.reset(seed=seed)
        assert always.step(0)[1] == 2.0
        assert never.step(0)[1] == -0.5
    env = select_env(with_rates(data, 2), objects=["rectangle"])
    env.reset(seed=0)
    wins = 0
    for _ in range(4000):
        env.reset()
        wins += env.step(0)[4]["success"]
    assert abs(wins / 4000 - 0.4) < 0.03  # 4 sigma of Bernoulli(0.4) over 4000 draws


def test_failed_candidates_are_masked_until_attempts_run_out(data):
    env = select_env(with_rates(data, 0), max_attempts=3, objects=["l_shape"])
    obs, _ = env.reset(seed=0)
    for attempt, slot in enumerate((4, 0, 7), start=1):
        obs, reward, terminated, truncated, info = env.step(slot)
        assert info["attempts"] == attempt and not info["success"] and reward == 0.0
        assert obs["mask"][slot] == 0 and not env.action_masks()[slot]
        assert terminated == (attempt == 3) and not truncated
    assert obs["mask"].sum() == 5


def test_success_ends_the_episode_with_grip_info(data):
    env = select_env(with_rates(data, 5), max_attempts=3, objects=["rectangle"])
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(1)
    row = data[data.object_id == "rectangle"].sort_values("Q_C").iloc[1]
    assert terminated and reward == 1.0
    assert info["grip_id"] == row["grip_id"] and info["object_id"] == "rectangle"
    assert info["Q_C"] == pytest.approx(row["Q_C"]) and info["success_rate"] == 1.0


@pytest.mark.parametrize("slot", [6, 7])  # padding of the 5-candidate rectangle
def test_masked_action_is_penalised_not_raised(data, slot):
    env = select_env(data, invalid_action_reward=-3.0, objects=["rectangle"])
    env.reset(seed=0)
    _, reward, terminated, _, info = env.step(slot)
    assert (reward, terminated, info["invalid_action"]) == (-3.0, True, True)
    assert info["grip_id"] == "" and info["Q_C"] is None and info["attempts"] == 0


def test_repeating_a_failed_grip_is_invalid(data):
    env = select_env(with_rates(data, 0), max_attempts=3, objects=["rectangle"])
    env.reset(seed=0)
    env.step(2)
    _, reward, terminated, _, info = env.step(2)
    assert info["invalid_action"] and terminated and reward == -1.0


@pytest.mark.parametrize("action", [8, -1, 2.5, np.array([1, 2])])
def test_out_of_space_action_raises(data, action):
    env = select_env(data)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)


# ------------------------------------------------------------------------------ seeding
def rollout(env: gymnasium.Env, seed: int, steps: int = 60) -> list[tuple]:
    obs, info = env.reset(seed=seed)
    trace = [(info["object_id"], obs["features"].tobytes())]
    for _ in range(steps):
        action = int(np.flatnonzero(env.action_masks())[0])
        obs, reward, terminated, _, info = env.step(action)
        trace.append((info["object_id"], info["grip_id"], reward))
        if terminated:
            obs, info = env.reset()
            trace.append((info["object_id"], obs["features"].tobytes()))
    return trace


@pytest.mark.parametrize("cls", [GripSelectEnv, GripAcceptEnv])
@pytest.mark.parametrize("order", ["q_c", "shuffled"])
def test_reset_seed_gives_identical_episodes(data, cls, order):
    env_a = cls(data, max_candidates=8, max_attempts=2, candidate_order=order)
    env_b = cls(data, max_candidates=8, max_attempts=2, candidate_order=order)
    first = rollout(env_a, 3)
    assert rollout(env_b, 3) == first
    assert rollout(env_a, 3) == first  # same env, re-seeded
    assert rollout(env_a, 4) != first


def test_shuffled_order_permutes_the_real_candidates(data):
    env = select_env(data, candidate_order="shuffled", objects=["l_shape"], normalize="none",
                     features=["Q_C"])
    orders = {env.reset(seed=s)[0]["features"][:, 0].tobytes() for s in range(10)}
    assert len(orders) > 1
    obs, _ = env.reset(seed=0)
    expected = np.sort(data.loc[data.object_id == "l_shape", "Q_C"].to_numpy())[:8]
    np.testing.assert_allclose(np.sort(obs["features"][:, 0]), expected, rtol=1e-6)


# ------------------------------------------------------------------------------ GripAccept
def accept_env(data: pd.DataFrame, **options: object) -> GripAcceptEnv:
    return GripAcceptEnv(data, max_candidates=8, **options)


def test_accept_shows_candidates_best_first_and_ends_when_they_run_out(data):
    env = accept_env(data, objects=["rectangle"], failure_reward=-0.5, max_attempts=8)
    obs, info = env.reset(seed=0)
    q_c, rewards, terminated = [], [], False
    while not terminated:
        assert obs["progress"][0] == pytest.approx(len(q_c) / 8)
        obs, reward, terminated, _, info = env.step(0)
        q_c.append(info["Q_C"])
        rewards.append(reward)
    assert q_c == sorted(q_c) and len(q_c) == 5
    assert rewards == [0.0] * 4 + [-0.5]
    assert obs["progress"][2] == pytest.approx(5 / 8)


def test_accept_ends_on_success_and_on_attempts(data):
    env = accept_env(with_rates(data, 5), objects=["l_shape"])
    env.reset(seed=0)
    env.step(0)
    _, reward, terminated, _, info = env.step(1)
    assert terminated and reward == 1.0 and info["executed"] and info["attempts"] == 1
    env = accept_env(with_rates(data, 0), objects=["l_shape"], max_attempts=2)
    env.reset(seed=0)
    assert not env.step(1)[2]
    obs, reward, terminated, _, info = env.step(1)
    assert terminated and info["attempts"] == 2 and obs["progress"][1] == 1.0


def test_accept_features_are_the_current_candidates(data):
    env = accept_env(data, objects=["l_shape"], normalize="none", features=["Q_C"])
    obs, _ = env.reset(seed=0)
    expected = np.sort(data.loc[data.object_id == "l_shape", "Q_C"].to_numpy())
    for value in expected[:3]:
        assert obs["features"][0] == pytest.approx(value, rel=1e-6)
        obs = env.step(0)[0]


# ------------------------------------------------------------------------------ rendering
def test_rgb_array_frames_have_a_fixed_size_and_show_the_outcome(data):
    env = select_env(with_rates(data, 5), render_mode="rgb_array", objects=["rectangle"])
    before = env.render()
    env.reset(seed=0)
    pending = env.render()
    env.step(0)
    after = env.render()
    assert before.shape == pending.shape == after.shape == (400, 400, 3)
    assert after.dtype == np.uint8

    def greenish(frame):
        r, g, b = (frame[..., i].astype(int) for i in range(3))
        return int(((g - r > 40) & (g - b > 40)).sum())

    assert greenish(after) > 50 and greenish(pending) == 0


def test_render_style_is_checked_and_the_scene_needs_the_live_backend(data):
    assert select_env(data).render_style == "sketch"
    with pytest.raises(ValueError, match="live backend"):
        select_env(data, render_style="scene")
    with pytest.raises(ValueError, match="render_style"):
        select_env(data, render_style="movie")


@pytest.mark.slow
def test_live_render_shows_the_pybullet_scene_and_the_sketch_on_request():
    env = GripSelectEnv(objects=["square"], max_candidates=4, render_mode="rgb_array")
    assert env.render_style == "scene"
    obs, _ = env.reset(seed=0)
    empty = env.render()
    env.step(int(np.argmax(obs["mask"])))
    holding = env.render()
    assert empty.shape == holding.shape == (400, 400, 3) and holding.dtype == np.uint8
    # the scene is shaded 3-D (many grey levels), the hand appears once a grip is executed
    assert len(np.unique(holding.reshape(-1, 3), axis=0)) > 100
    assert np.mean(np.any(empty != holding, axis=-1)) > 0.05
    env.close()
    sketch = GripSelectEnv(objects=["square"], max_candidates=4, render_mode="rgb_array",
                           render_style="sketch")
    sketch.reset(seed=0)
    assert sketch.render().shape == (400, 400, 3)
    sketch.close()


@pytest.mark.parametrize("env_class", [GripSelectEnv, GripAcceptEnv])
def test_is_success_is_reported_for_sb3_monitor(data, env_class):
    from stable_baselines3.common.monitor import Monitor

    env = Monitor(env_class(data, max_candidates=8, max_attempts=2),
                  info_keywords=("is_success",))
    for seed in range(5):
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            action = int(np.argmax(obs["mask"])) if "mask" in obs else 1
            obs, reward, terminated, truncated, info = env.step(action)
            assert info["is_success"] is info["success"]
            done = terminated or truncated
        assert info["episode"]["is_success"] == (reward == 1.0)
    env.close()


def test_human_mode_is_harmless_when_headless(data, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    env = select_env(data, render_mode="human")
    with pytest.warns(UserWarning, match="display"):
        env.reset(seed=0)
    assert env.render() is None
    env.step(0)
    env.close()
    env.close()


# ------------------------------------------------------------------------------ vector envs, RL
def test_sync_vector_env_batches_episodes(data):
    envs = gymnasium.make_vec("GripSelect-v0", num_envs=3, vectorization_mode="sync",
                              data=data, max_candidates=8)
    obs, info = envs.reset(seed=5)
    assert obs["features"].shape == (3, 8, 12) and obs["mask"].shape == (3, 8)
    obs, reward, terminated, _, info = envs.step(np.zeros(3, dtype=np.int64))
    assert reward.shape == (3,) and terminated.all()
    assert set(info["object_id"]) <= set(NAMES)
    envs.close()


def test_sb3_subproc_vec_env_runs(data):
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    # "module:id" makes gymnasium import grip_env (and so register the ids) in each worker.
    venv = make_vec_env("grip_env:GripAccept-v0", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv,
                        env_kwargs={"data": data, "max_candidates": 8},
                        vec_env_kwargs={"start_method": "fork"})
    venv.reset()
    for _ in range(10):
        _, reward, _, _ = venv.step(np.ones(2, dtype=np.int64))
        assert reward.shape == (2,)
    venv.close()


@pytest.mark.slow
def test_maskable_ppo_trains(data):
    from sb3_contrib import MaskablePPO

    env = select_env(data, max_attempts=2)
    model = MaskablePPO("MultiInputPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0,
                        device="cpu")
    model.learn(total_timesteps=256)
    action, _ = model.predict(env.reset(seed=0)[0], action_masks=env.action_masks())
    assert env.action_masks()[int(action)]


@pytest.mark.slow
def test_ppo_trains_on_flattened_observations(data):
    from gymnasium.wrappers import FlattenObservation
    from stable_baselines3 import PPO

    for env in (FlattenObservation(select_env(data)), FlattenObservation(accept_env(data))):
        model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0, device="cpu")
        model.learn(total_timesteps=256)


# ------------------------------------------------------------------------------ live backend
def test_make_without_arguments_is_live_on_the_default_set():
    env = gymnasium.make("GripSelect-v0")
    assert isinstance(env.unwrapped.backend, LiveBackend)
    assert set(env.unwrapped.object_ids) == set(SHAPE_NAMES)
    obs, info = env.reset(seed=0)
    assert info["object_id"] in SHAPE_NAMES and 0 < obs["mask"].sum() <= 64
    found = env.unwrapped._candidate_set(env.unwrapped.object_ids.index(info["object_id"]))
    assert np.all(np.diff(found.q_c[: found.count]) >= 0)  # lowest Q_C first
    env.close()


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ["GripSelect-v0", "GripAccept-v0"])
@pytest.mark.filterwarnings("ignore::UserWarning")
def test_checkers_pass_on_live(env_id):
    env = gymnasium.make(env_id, objects=["rectangle"], max_candidates=4,
                         render_mode="rgb_array")
    gym_check_env(env.unwrapped)
    sb3_check_env(env.unwrapped)
    env.close()


@pytest.mark.slow
def test_live_steps_run_pybullet_deterministically():
    env = GripSelectEnv(objects=["rectangle"], max_candidates=4, max_attempts=2)
    outcomes = []
    for _ in range(2):
        env.reset(seed=11)
        _, reward, _, _, info = env.step(0)
        outcomes.append((reward, info["success"], info["grip_id"]))
        assert info["success_rate"] is None and info["attempts"] == 1
        assert info["grip_id"].startswith("rectangle/")
    assert outcomes[0] == outcomes[1]


def test_missing_dataset_path_is_a_value_error(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        GripSelectEnv(tmp_path / "no-such-dataset")


@pytest.mark.slow
def test_docs_sb3_snippet_runs_on_a_generated_dataset(generated_dataset_dir, capsys):
    """The SB3 block of ``docs/environments/sb3.md``, shortened (fewer steps and episodes), on a
    real dataset."""
    from pathlib import Path

    page = Path(__file__).resolve().parents[1] / "docs" / "environments" / "sb3.md"
    section = page.read_text()
    code = section[section.index("```python") + len("```python"):section.index("```\n\n")]
    assert 'data = "standard"' in code and "learn(5_000)" in code and "range(500)" in code
    code = code.replace('data = "standard"', f"data = {str(generated_dataset_dir)!r}")
    code = code.replace("learn(5_000)", "learn(64)").replace("range(500)", "range(10)")
    exec(compile(code, str(page), "exec"), {})
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert line.startswith("first pick holds: selector ") and ", best Q_C " in line


@pytest.mark.slow
def test_the_sb3_pages_best_q_c_figure_is_what_its_snippet_prints_now():
    """The page quotes one printed line of its snippet. Its best-Q_C half does not depend on
    training (slot 0 of the same 500 seeded test episodes), so it must be today's figure."""
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "environments" / "sb3.md").read_text()
    quoted = re.findall(r"`first pick holds: selector (\d\.\d\d), best Q_C (\d\.\d\d)`", page)
    assert len(quoted) == 1, "the page quotes one printed line"
    test = gymnasium.make("GripSelect-v0", data="standard", split="test")
    best_q_c = []
    for episode in range(500):
        test.reset(seed=episode)
        best_q_c.append(test.step(0)[-1]["is_success"])
    assert quoted[0][1] == f"{np.mean(best_q_c):.2f}"


# ------------------------------------------------------------------ conventions (issue 20)
@pytest.mark.parametrize("env_class", [GripSelectEnv, GripAcceptEnv])
def test_reset_options_pin_the_object(data, env_class):
    env = env_class(data, max_candidates=8)
    for seed in range(4):
        _, info = env.reset(seed=seed, options={"object_id": "hexagon"})
        assert info["object_id"] == "hexagon" and info["candidates"] == 3
    with pytest.raises(ValueError, match="object_id 'cube' is not among the 6 objects"):
        env.reset(options={"object_id": "cube"})
    with pytest.raises(ValueError, match=r"unknown reset options \['objekt'\]"):
        env.reset(options={"objekt": "disc"})
    with pytest.raises(RuntimeError, match="call reset"):  # the refused reset started nothing
        env.step(0)


def test_a_pinned_object_outside_the_split_is_refused(data):
    _, test = split_objects(NAMES, 0.34, 7)
    env = select_env(data, split="train", test_fraction=0.34, split_seed=7)
    with pytest.raises(ValueError, match="split 'train'"):
        env.reset(options={"object_id": test[0]})


@pytest.mark.parametrize("env_class", [GripSelectEnv, GripAcceptEnv])
def test_step_after_the_end_raises_and_executes_nothing(data, env_class):
    env = env_class(data, max_candidates=8, max_attempts=1)
    with pytest.raises(RuntimeError, match="never started"):
        env.step(0)
    env.reset(seed=0, options={"object_id": "disc"})
    terminated = False
    while not terminated:
        terminated = env.step(1 if env_class is GripAcceptEnv else 0)[2]
    masks = env.action_masks().copy()
    with pytest.raises(RuntimeError, match="episode has ended"):
        env.step(0)
    assert np.array_equal(env.action_masks(), masks)  # nothing was executed or masked
    env.reset(seed=1)
    env.step(0)  # a new episode steps again


def test_a_backend_can_be_passed_in_and_data_is_its_shortcut(data):
    from grip_env.envs import ReplayBackend

    by_backend = GripSelectEnv(backend=ReplayBackend(data), max_candidates=8)
    by_data = GripSelectEnv(data, max_candidates=8)
    first = by_backend.reset(seed=3)[0]
    assert np.array_equal(first["features"], by_data.reset(seed=3)[0]["features"])
    with pytest.raises(ValueError, match="either backend= or data="):
        GripSelectEnv(data, backend=ReplayBackend(data))
    with pytest.raises(ValueError, match="lacks"):
        GripSelectEnv(backend=object())


class _AlwaysHolds:
    """A user's own outcome source: the dataset's candidates, every grip holds."""

    def __init__(self, data):
        from grip_env.envs import ReplayBackend

        self._replay = ReplayBackend(data)
        self.object_ids, self.feature_cap = self._replay.object_ids, self._replay.feature_cap
        self.candidates, self.contour = self._replay.candidates, self._replay.contour

    def execute(self, candidates, slot, rng):
        return True

    def close(self):
        self._replay.close()


def test_a_users_own_backend_decides_the_outcomes(data):
    env = gymnasium.make("GripSelect-v0", backend=_AlwaysHolds(data), max_candidates=8,
                         max_attempts=3)
    for seed in range(3):
        env.reset(seed=seed)
        _, reward, terminated, _, info = env.step(0)
        assert reward == 1.0 and terminated and info["is_success"]


def test_constructors_have_explicit_keyword_signatures():
    import inspect

    for env_class in (GripSelectEnv, GripAcceptEnv):
        parameters = inspect.signature(env_class).parameters
        kinds = {p.kind for p in parameters.values()}
        assert inspect.Parameter.VAR_KEYWORD not in kinds
        assert inspect.Parameter.VAR_POSITIONAL not in kinds
        assert {"data", "objects", "backend", "config", "max_candidates", "split"} <= set(
            parameters)


@pytest.mark.parametrize("module", ["select", "accept"])
def test_docstrings_have_gymnasiums_sections_and_a_running_example(module):
    import doctest
    import importlib

    found = importlib.import_module(f"grip_env.envs.{module}")
    env_class = GripSelectEnv if module == "select" else GripAcceptEnv
    for section in ("Description", "Action Space", "Observation Space", "Rewards",
                    "Starting State", "Episode End", "Arguments", "Version History"):
        assert f"## {section}" in (env_class.__doc__ or "")
    result = doctest.testmod(found, raise_on_error=False, verbose=False)
    assert result.attempted >= 5 and result.failed == 0
