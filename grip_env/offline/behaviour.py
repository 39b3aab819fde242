"""The behaviour policies that generate an offline dataset of ``GripSelect-v0`` episodes.

A behaviour policy picks a slot from an observation's ``mask`` with its own seeded generator; it
never looks at outcomes. Two are offered, as an offline-RL dataset states the policy that logged
it (D4RL's random/medium/expert; here with the probabilities written down):

- ``uniform``: every valid slot with probability ``1 / n_valid`` (full coverage: every candidate
  of every object can appear, which is what an offline learner needs to tell grips apart);
- ``epsilon-qc``: epsilon-greedy on the paper's index ``Q_C``: the valid slot of lowest ``Q_C``
  (slot order, ``candidate_order="q_c"``) with probability ``1 - epsilon``, else a uniform valid
  slot.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

POLICIES: tuple[str, ...] = ("uniform", "epsilon-qc")


@dataclass(frozen=True)
class BehaviourPolicy:
    """A seeded behaviour policy over the valid slots of ``GripSelect-v0`` observations."""

    name: str
    epsilon: float = 0.0

    def __post_init__(self) -> None:
        if self.name not in POLICIES:
            raise ValueError(f"behaviour policy must be one of {POLICIES}, got {self.name!r}")
        if not 0.0 <= self.epsilon <= 1.0:
            raise ValueError(f"epsilon must be in [0, 1], got {self.epsilon!r}")

    def act(self, observation: dict[str, NDArray[Any]], rng: np.random.Generator) -> int:
        """The slot to execute (one uniform draw, two for ``epsilon-qc``)."""
        valid = np.flatnonzero(observation["mask"])
        if not len(valid):
            raise ValueError("the observation has no valid slot")
        if self.name == "epsilon-qc" and rng.random() >= self.epsilon:
            return int(valid[0])  # slots hold the candidates lowest Q_C first
        return int(valid[int(rng.random() * len(valid))])

    def probabilities(self, mask: NDArray[Any]) -> NDArray[np.float64]:
        """The probability of each slot under ``mask`` (the logging propensities)."""
        valid = np.asarray(mask, dtype=bool)
        out = np.where(valid, 1.0 / max(int(valid.sum()), 1), 0.0)
        if self.name == "epsilon-qc" and valid.any():
            out *= self.epsilon
            out[np.flatnonzero(valid)[0]] += 1.0 - self.epsilon
        return out

    def describe(self) -> str:
        """One sentence naming the policy and its probabilities."""
        if self.name == "uniform":
            return "uniform random over the valid slots (probability 1/n_valid each)"
        return (f"epsilon-greedy on Q_C: the valid slot of lowest Q_C with probability "
                f"{1 - self.epsilon:g}, else uniform over the valid slots (epsilon "
                f"{self.epsilon:g})")  # fmt: skip
