"""``GripSelect-v0``: choose one grip among an object's candidates."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from grip_env.envs.core import GripEnvBase, action_index
from grip_env.envs.observation import CandidateSet

Observation = dict[str, NDArray[Any]]


class GripSelectEnv(GripEnvBase):
    """Pick the grip to execute from all candidates of one object at once.

    Each episode draws one object of the split. The agent sees every candidate's features and
    picks one; the grip is executed (replayed from recorded trials, or run in PyBullet) and the
    reward is ``success_reward`` or ``failure_reward``. After a failure the agent may pick again
    (up to ``max_attempts``); failed candidates are masked. Choosing a masked slot (padding or an
    already failed grip) is not an error: it earns ``invalid_action_reward``, ends the episode and
    sets ``info["invalid_action"] = True``.

    Observation: ``Dict(features=Box(-b, b, (K, F), float32), mask=MultiBinary(K))`` where
    ``K = max_candidates`` and ``F = len(features)``. Slots hold the K best candidates, lowest
    ``Q_C`` first (or shuffled: ``candidate_order="shuffled"``); padded slots are zero and masked.
    Action: ``Discrete(K)``; :meth:`action_masks` gives the valid slots (sb3-contrib MaskablePPO).

    The episode terminates on success, when ``max_attempts`` grips were executed, after an invalid
    action, or when no valid candidate remains. ``info`` holds ``object_id``, ``grip_id``, ``Q_C``,
    ``success_rate`` (recorded rate; None live), ``attempts``, ``success``, ``is_success`` (the
    same flag, under the name SB3's ``Monitor`` and ``EvalCallback`` read: on the last step it is
    whether the episode succeeded) and ``invalid_action``.

    Args:
        data: a dataset path or DataFrame (replay backend); None runs grips live in PyBullet.
        objects: object set name, or names / ``PlanarObject`` list (live: the objects; replay: a
            filter on the dataset's object ids). None: ``config.objects.set`` live, all replayed.
        config: grip-env :class:`~grip_env.config.Config` (default: ``Config()``, the values of
            ``configs/default.yaml``).
        max_candidates: K (default ``config.selector.max_candidates``).
        max_attempts: executions per episode (default ``config.selector.max_attempts``).
        success_reward, failure_reward, invalid_action_reward: reward values.
        features: feature subset (names from S1..C6, Q_G, Q_C); default the twelve S1..C6.
        split: ``"train"``, ``"test"`` or ``"all"`` objects, from
            :func:`~grip_env.envs.split_objects` (``test_fraction``, ``split_seed`` default to
            ``config.learning.test_fraction`` and ``config.learning.seed``).
        normalize: ``"log"`` (signed log1p), ``"standard"`` (z-score on the split's candidates)
            or ``"none"``.
        candidate_order: ``"q_c"`` (best first) or ``"shuffled"`` (a new order each episode).
        render_mode: ``None``, ``"rgb_array"`` or ``"human"``.
        render_style: ``"scene"`` (PyBullet through TinyRenderer; live only, its default) or
            ``"sketch"`` (2-D contour and contact triangles; the replay default).
    """

    def __init__(self, data: Any = None, objects: Any = None, **options: Any) -> None:
        super().__init__(data, objects, **options)
        k, width = self.max_candidates, len(self.feature_names)
        low, high = self.scaler.bounds()
        self.observation_space = spaces.Dict({
            "features": spaces.Box(
                np.broadcast_to(low, (k, width)), np.broadcast_to(high, (k, width)),
                dtype=np.float32,
            ),
            "mask": spaces.MultiBinary(k),
        })
        self.action_space = spaces.Discrete(k)
        self._found: CandidateSet | None = None
        self._slots = np.arange(k)
        self._features = np.zeros((k, width), dtype=np.float32)
        self._mask = np.zeros(k, dtype=np.int8)
        self._attempts = 0
        self._remaining = 0
        self._chosen: int | None = None
        self._outcome: bool | None = None

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Start an episode on a new object; ``info`` has ``object_id`` and ``candidates``."""
        super().reset(seed=seed)
        found = self._found = self._sample_candidates()
        self._slots = slots = self._shuffled_slots(found.count)
        self._features = found.features if slots is self._identity else found.features[slots]
        self._mask = found.mask.copy()
        self._remaining = found.count
        self._attempts, self._chosen, self._outcome = 0, None, None
        if self.render_mode == "human":
            self.render()
        info = {"object_id": found.object_id, "candidates": found.count, "attempts": 0}
        return self._observation(), info

    def step(self, action: Any) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """Execute the candidate in slot ``action``."""
        slot = action_index(action, self.max_candidates)
        found = self._found
        if found is None:
            raise RuntimeError("call reset() before step()")
        row = int(self._slots[slot])
        info = self._grip_info(found, row)
        if not self._mask[slot]:
            self._chosen, self._outcome = None, None
            info.update(attempts=self._attempts, success=False, is_success=False,
                        invalid_action=True)
            return self._observation(), self.invalid_action_reward, True, False, info
        success = self.backend.execute(found, row, self.np_random)
        self._attempts += 1
        self._mask[slot] = 0
        self._remaining -= 1
        self._chosen, self._outcome = row, success
        reward = self.success_reward if success else self.failure_reward
        terminated = success or self._attempts >= self.max_attempts or not self._remaining
        info.update(attempts=self._attempts, success=success, is_success=success,
                    invalid_action=False)
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, terminated, False, info

    def action_masks(self) -> NDArray[np.bool_]:
        """Valid actions (real candidates not yet failed), for sb3-contrib's MaskablePPO."""
        return self._mask.astype(bool)

    def _observation(self) -> Observation:
        return {"features": self._features.copy(), "mask": self._mask.copy()}

    def _draw(self) -> NDArray[np.uint8]:
        found = self._found
        if found is None:
            return self._frame(None, None, None, "")
        title = f"{found.object_id}: {found.count} candidates, attempts {self._attempts}"
        return self._frame(found, self._chosen, self._outcome, title)

