"""Write ``set_policy_two_keys.zip`` and ``.json``: a set-policy zip of a one-attempt run (its
observation without ``failed``) and the action probabilities and values it gave when written.

Run with the code the zip must stay loadable from, e.g. before a change to the set policy:
``PYTHONPATH=/path/to/that/checkout .venv/bin/python tests/data/set_policy_two_keys.py``.
"""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch as th
from gymnasium import spaces
from sb3_contrib import MaskablePPO

from classifiers.experiments.selector.policy import CandidateSetPolicy

K, F = 6, 3
HERE = Path(__file__).parent


class KnownOdds(gym.Env):
    """One pick among 2..K candidates; the reward is sigmoid(3 x0 - 2 x1) of the pick."""

    def __init__(self) -> None:
        self.observation_space = spaces.Dict({
            "features": spaces.Box(-5.0, 5.0, (K, F), np.float32),
            "mask": spaces.MultiBinary(K),
        })
        self.action_space = spaces.Discrete(K)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        count = int(self.np_random.integers(2, K + 1))
        self.features = np.zeros((K, F), np.float32)
        self.features[:count] = self.np_random.normal(size=(count, F)).clip(-5, 5)
        self.mask = np.zeros(K, np.int8)
        self.mask[:count] = 1
        return {"features": self.features.copy(), "mask": self.mask.copy()}, {}

    def action_masks(self):
        return self.mask.astype(bool)

    def step(self, action):
        x = self.features[int(action)]
        reward = float(1.0 / (1.0 + np.exp(-(3.0 * x[0] - 2.0 * x[1]))))
        return {"features": self.features.copy(), "mask": self.mask.copy()}, reward, True, False, {}


def probe() -> dict[str, np.ndarray]:
    """Five observations (features and masks) the zip's outputs are recorded on."""
    rng = np.random.default_rng(7)
    masks = np.array([[1, 1, 1, 1, 1, 1], [1, 1, 0, 1, 1, 0], [1, 1, 1, 0, 0, 0],
                      [0, 1, 0, 1, 0, 1], [1, 1, 1, 1, 0, 0]], dtype=np.int8)
    return {"features": rng.normal(size=(5, K, F)).astype(np.float32), "mask": masks}


def outputs(model: MaskablePPO) -> tuple[np.ndarray, np.ndarray]:
    """(5, K) action probabilities and (5,) values of the probe."""
    observation = probe()
    tensor, _ = model.policy.obs_to_tensor(observation)
    with th.no_grad():
        dist = model.policy.get_distribution(tensor, action_masks=observation["mask"] > 0)
        values = model.policy.predict_values(tensor)
    return dist.distribution.probs.numpy(), values.numpy()[:, 0]


def main() -> None:
    th.set_num_threads(1)
    model = MaskablePPO(CandidateSetPolicy, KnownOdds(), n_steps=64, batch_size=32, seed=0,
                        policy_kwargs={"context": "attention", "net_arch": [8, 8]})  # fmt: skip
    model.learn(1024)
    model.save(HERE / "set_policy_two_keys.zip")
    probs, values = outputs(model)
    (HERE / "set_policy_two_keys.json").write_text(json.dumps(
        {"probabilities": probs.tolist(), "values": values.tolist()}, indent=1) + "\n")


if __name__ == "__main__":
    main()
