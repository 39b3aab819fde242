"""``GripAccept-v0``: candidates shown one at a time, each skipped or executed."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from grip_env.envs.core import GripEnvBase, action_index
from grip_env.envs.observation import CandidateSet

Observation = dict[str, NDArray[Any]]
SKIP, EXECUTE = 0, 1
PROGRESS = ("position", "attempts", "pool")


class GripAcceptEnv(GripEnvBase):
    """Decide, candidate after candidate, whether to execute it (1) or skip it (0).

    ## Description

    Each episode is one object of the split; its best ``max_candidates`` candidates are shown one
    at a time, lowest ``Q_C`` first (``candidate_order="q_c"``) or in a new random order each
    episode (``"shuffled"``), and each is skipped or executed. Replayed with every trial's
    outcome, every execution of an episode replays the same trial index k (``info["trial"]`` at
    ``reset``), as :class:`~grip_env.envs.select.GripSelectEnv` does.

    ## Action Space

    ``Discrete(2)``: 0 skips the current candidate, 1 executes it. Every action is valid;
    :meth:`action_masks` is all True.

    ## Observation Space

    ``Dict(features=Box(F), progress=Box(0, 1, (3,)))``: the current candidate's normalised
    features, and ``progress`` = (candidates already shown / K, executions used /
    max_attempts, the object's candidate count / K). With ``max_attempts > 1`` (the retry
    setting) the Dict also holds ``failed=MultiBinary(K)``, as
    :class:`~grip_env.envs.select.GripSelectEnv`'s does: 1 at the positions in the episode's
    showing order (the slots: position i shows the candidate GripSelect-v0 puts in slot i) whose
    candidate was executed and dropped, 0 elsewhere (all 0 at reset). ``progress`` counts the
    executions; ``failed`` says which candidates the episode's draw defeated: with
    ``candidate_order="q_c"``, their rank by ``Q_C``. With ``max_attempts = 1`` the space is the
    two keys only.

    ## Rewards

    Executing earns ``success_reward`` or ``failure_reward``; skipping earns 0, except that
    skipping the last candidate earns ``failure_reward`` (the object was never lifted).

    ## Starting State

    As :class:`~grip_env.envs.select.GripSelectEnv`: a uniform draw from the split, or
    ``reset(options={"object_id": ...})``; the first candidate is shown.

    ## Episode End

    Terminates on success, after ``max_attempts`` executions, or when the candidates run out;
    never truncated. A ``step`` after the end raises ``RuntimeError``. ``info`` holds
    ``object_id``, ``grip_id``, ``Q_C``, ``success_rate`` (recorded rate; None live) of the
    candidate acted on, ``attempts``, ``executed``, ``success``, ``is_success`` (the same flag,
    for SB3's ``Monitor``) and ``invalid_action`` (always False).

    ## Arguments

    Those of :class:`~grip_env.envs.select.GripSelectEnv` (the same constructor).

    ## Version History

    - v0: initial version.

    ## Example

    >>> import gymnasium, grip_env
    >>> from classifiers.evaluation.synthetic import synthetic_grips
    >>> env = gymnasium.make("GripAccept-v0", data=synthetic_grips(n_objects=6, seed=0),
    ...                      max_candidates=8)
    >>> observation, info = env.reset(seed=0, options={"object_id": "3"})
    >>> observation["features"].shape, observation["progress"].tolist()
    ((12,), [0.0, 0.0, 1.0])
    >>> _, reward, terminated, truncated, info = env.step(1)
    >>> terminated, info["executed"]
    (True, True)
    """

    def _make_spaces(self) -> None:
        low, high = self.scaler.bounds()
        k = self.max_candidates
        self.observation_space = spaces.Dict({
            "features": spaces.Box(low, high, dtype=np.float32),
            "progress": spaces.Box(0.0, 1.0, (len(PROGRESS),), dtype=np.float32),
            **({"failed": spaces.MultiBinary(k)} if self.retries else {}),
        })
        self.action_space = spaces.Discrete(2)
        self._found: CandidateSet | None = None
        self._slots = np.arange(self.max_candidates)
        self._position = 0
        self._attempts = 0
        self._failed = np.zeros(self.max_candidates, dtype=np.int8)
        self._shown: int | None = None
        self._outcome: bool | None = None

    def _start_episode(self, found: CandidateSet) -> None:
        """Show the episode's first candidate."""
        self._position = 0
        self._failed = np.zeros(self.max_candidates, dtype=np.int8)
        self._shown = int(self._slots[0])

    def step(self, action: Any) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """Skip (0) or execute (1) the current candidate."""
        execute = action_index(action, 2) == EXECUTE
        self._check_running()
        found = self._found
        assert found is not None
        row = int(self._slots[min(self._position, found.count - 1)])
        info = self._grip_info(found, row)
        success, reward = False, 0.0
        if execute:
            success = self._execute(found, row)
            self._attempts += 1
            self._failed[self._position] = not success
            reward = self.success_reward if success else self.failure_reward
        self._position += 1
        exhausted = self._position >= found.count
        if exhausted and not execute:
            reward = self.failure_reward
        terminated = self._end_if(success or self._attempts >= self.max_attempts or exhausted)
        self._shown = row if terminated else int(self._slots[self._position])
        self._outcome = success if execute and terminated else None
        info.update(
            attempts=self._attempts, executed=execute, success=success, is_success=success,
            invalid_action=False,
        )
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, terminated, False, info

    def action_masks(self) -> NDArray[np.bool_]:
        """Both actions are always valid."""
        return np.ones(2, dtype=bool)

    def _observation(self) -> Observation:
        found = self._found
        assert found is not None
        row = int(self._slots[min(self._position, found.count - 1)])
        progress = np.array(
            [
                min(self._position, found.count) / self.max_candidates,
                self._attempts / self.max_attempts,
                found.count / self.max_candidates,
            ],
            dtype=np.float32,
        )
        observation = {"features": found.features[row].copy(), "progress": progress}
        if self.retries:
            observation["failed"] = self._failed.copy()
        return observation

    def _draw(self) -> NDArray[np.uint8]:
        found = self._found
        if found is None:
            return self._frame(None, None, None, "")
        title = (
            f"{found.object_id}: candidate {min(self._position + 1, found.count)}/{found.count},"
            f" attempts {self._attempts}"
        )
        return self._frame(found, self._shown, self._outcome, title)
