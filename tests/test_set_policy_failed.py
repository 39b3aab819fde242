"""The set policy reads ``failed`` (the retry setting): what dropped moves the remaining scores,
candidate order still does not matter, and a zip without ``failed`` loads as it was written."""

from __future__ import annotations

import importlib.util
import json
from functools import cache
from pathlib import Path

import numpy as np
import pytest
import torch as th
from gymnasium import spaces
from hypothesis import given, settings
from hypothesis import strategies as st
from sb3_contrib import MaskablePPO
from test_selector import F, K, KnownOddsEnv

from classifiers.experiments.selector.policy import CONTEXTS, CandidateSetPolicy

DATA = Path(__file__).parent / "data"


class RetryOddsEnv(KnownOddsEnv):
    """Up to three picks among 2..K candidates (each held with its known odds), with
    GripSelect-v0's ``failed`` key."""

    def __init__(self) -> None:
        super().__init__()
        self.observation_space = spaces.Dict({**self.observation_space.spaces,
                                              "failed": spaces.MultiBinary(K)})

    def reset(self, *, seed=None, options=None):
        self.failed = np.zeros(K, np.int8)
        self.attempts = 0
        return super().reset(seed=seed, options=options)

    def _observation(self):
        return {**super()._observation(), "failed": self.failed.copy()}

    def step(self, action):
        held = bool(self.np_random.random() < self.odds(self.features[int(action)]))
        self.attempts += 1
        self.mask[int(action)] = 0
        self.failed[int(action)] = not held
        done = held or self.attempts >= 3 or not self.mask.any()
        return self._observation(), float(held), done, False, {}


def _model(context: str, seed: int = 0) -> MaskablePPO:
    model = MaskablePPO(CandidateSetPolicy, RetryOddsEnv(), n_steps=64, batch_size=32, seed=seed,
                        policy_kwargs={"context": context})  # fmt: skip
    model.learn(64)  # trained weights: a freshly initialised score head is nearly flat
    return model


@cache
def _trained(context: str) -> MaskablePPO:
    return _model(context)


def _outputs(model, features, mask, failed=None):
    observation = {"features": features, "mask": mask}
    if failed is not None:
        observation["failed"] = failed
    tensor, _ = model.policy.obs_to_tensor(observation)
    with th.no_grad():
        dist = model.policy.get_distribution(tensor, action_masks=mask.astype(bool)[None])
        value = model.policy.predict_values(tensor)
    return dist.distribution.probs[0].numpy(), float(value[0, 0])


FEATURES = np.random.default_rng(5).normal(size=(K, F)).astype(np.float32)


@pytest.mark.parametrize("context", CONTEXTS)
def test_which_slot_failed_moves_the_remaining_scores(context):
    """Slots 0-2 remain in every case; slot 3 or slot 4 failed (the other is padding), or
    neither has been tried: the policy's odds between the remaining candidates differ."""
    model = _trained(context)
    assert "failure_encoder" in dict(model.policy.mlp_extractor.named_children())
    remaining = np.array([1, 1, 1, 0, 0, 0], dtype=np.int8)
    none_failed, _ = _outputs(model, FEATURES, remaining, np.zeros(K, np.int8))
    three, value_three = _outputs(model, FEATURES, remaining, np.eye(K, dtype=np.int8)[3])
    four, value_four = _outputs(model, FEATURES, remaining, np.eye(K, dtype=np.int8)[4])
    for probs in (none_failed, three, four):
        assert probs[3:].max() == 0.0 and probs.sum() == pytest.approx(1.0)
    odds = [p[0] / p[1] for p in (none_failed, three, four)]
    assert abs(odds[1] - odds[2]) > 1e-4 * odds[1]
    assert abs(odds[0] - odds[1]) > 1e-4 * odds[0]
    assert value_three != pytest.approx(value_four, abs=1e-6)


@pytest.mark.parametrize("context", CONTEXTS)
def test_a_failed_slot_counts_by_its_features_not_its_slot(context):
    """The same failed grip in another slot (the padding moved with it) changes nothing."""
    model = _trained(context)
    remaining = np.array([1, 1, 1, 0, 0, 0], dtype=np.int8)
    moved = FEATURES.copy()
    moved[[3, 5]] = moved[[5, 3]]
    probs, value = _outputs(model, FEATURES, remaining, np.eye(K, dtype=np.int8)[3])
    moved_probs, moved_value = _outputs(model, moved, remaining, np.eye(K, dtype=np.int8)[5])
    np.testing.assert_allclose(moved_probs, probs, atol=1e-6)
    assert moved_value == pytest.approx(value, abs=1e-5)


@settings(max_examples=30, deadline=None)
@given(
    context=st.sampled_from(CONTEXTS),
    order=st.permutations(range(K)),
    failed_slots=st.sets(st.integers(0, K - 1), max_size=2),
    padded=st.sets(st.integers(0, K - 1), max_size=2),
    seed=st.integers(0, 2**16),
)
def test_the_failed_aware_policy_is_permutation_equivariant(context, order, failed_slots, padded,
                                                            seed):  # fmt: skip
    order = np.array(order)
    features = np.random.default_rng(seed).normal(size=(K, F)).astype(np.float32)
    failed = np.zeros(K, np.int8)
    failed[sorted(failed_slots)] = 1
    mask = np.ones(K, np.int8)
    mask[sorted(failed_slots | padded)] = 0
    if not mask.any():
        mask[next(i for i in range(K) if not failed[i])] = 1
    model = _trained(context)
    probs, value = _outputs(model, features, mask, failed)
    shuffled, shuffled_value = _outputs(model, features[order], mask[order], failed[order])
    np.testing.assert_allclose(shuffled, probs[order], atol=1e-6)
    assert shuffled_value == pytest.approx(value, abs=1e-5)
    assert probs[mask == 0].max(initial=0.0) == 0.0


def _fixture_module():
    spec = importlib.util.spec_from_file_location("set_policy_two_keys",
                                                  DATA / "set_policy_two_keys.py")  # fmt: skip
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_zip_without_failed_loads_and_acts_as_written():
    """``set_policy_two_keys.zip`` was written by the set policy before it read ``failed``
    (tests/data/set_policy_two_keys.py); it loads with the same parameters and the same outputs."""
    outputs = _fixture_module().outputs
    model = MaskablePPO.load(DATA / "set_policy_two_keys.zip")
    assert set(model.observation_space.spaces) == {"features", "mask"}
    assert not any("failure" in name for name, _ in model.policy.named_parameters())
    expected = json.loads((DATA / "set_policy_two_keys.json").read_text())
    probs, values = outputs(model)
    np.testing.assert_allclose(probs, expected["probabilities"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(values, expected["values"], rtol=0, atol=1e-6)


def test_a_failed_aware_zip_round_trips(tmp_path):
    model = _trained("attention")
    model.save(tmp_path / "retry.zip")
    loaded = MaskablePPO.load(tmp_path / "retry.zip")
    failed = np.eye(K, dtype=np.int8)[4]
    mask = np.array([1, 1, 1, 1, 0, 0], dtype=np.int8)
    np.testing.assert_allclose(_outputs(loaded, FEATURES, mask, failed)[0],
                               _outputs(model, FEATURES, mask, failed)[0], atol=0)  # fmt: skip


def test_read_failed_false_sees_a_failure_only_as_a_masked_slot(tmp_path):
    """The ablation: with ``read_failed=False`` the retry observation's ``failed`` is ignored
    (no failure encoder), so which slot failed does not move the remaining scores; it saves
    and loads as such."""
    model = MaskablePPO(CandidateSetPolicy, RetryOddsEnv(), n_steps=64, batch_size=32, seed=0,
                        policy_kwargs={"read_failed": False})  # fmt: skip
    model.learn(64)
    assert not any("failure" in name for name, _ in model.policy.named_parameters())
    remaining = np.array([1, 1, 1, 0, 0, 0], dtype=np.int8)
    three, value = _outputs(model, FEATURES, remaining, np.eye(K, dtype=np.int8)[3])
    four, other_value = _outputs(model, FEATURES, remaining, np.eye(K, dtype=np.int8)[4])
    np.testing.assert_allclose(three, four, atol=1e-7)
    assert value == pytest.approx(other_value, abs=1e-7)
    model.save(tmp_path / "ablation.zip")
    assert MaskablePPO.load(tmp_path / "ablation.zip").policy.read_failed is False
