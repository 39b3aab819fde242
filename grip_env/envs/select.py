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

    ## Description

    Each episode is one object of the split. The agent sees every candidate grip's features at
    once and picks one; the grip is executed (its recorded trials replayed, or run in PyBullet).
    After a failure it may pick again, up to ``max_attempts``; failed candidates are masked.
    Replaying data that records every trial's outcome, an episode draws one trial index k
    (``info["trial"]``) and every attempt replays trial k of the grip picked: a retry meets the
    same friction, mass and pose noise as the failed pick, as on a real robot (the retry
    setting). Without per-trial outcomes each execution is a fresh Bernoulli draw of the grip's
    success rate.

    ## Action Space

    ``Discrete(K)``, ``K = max_candidates``: the slot of the grip to execute. :meth:`action_masks`
    gives the valid slots (for sb3-contrib's MaskablePPO). A masked slot (padding, or a grip that
    already failed) is not an error: it earns ``invalid_action_reward`` and ends the episode.

    ## Observation Space

    ``Dict(features=Box(-b, b, (K, F), float32), mask=MultiBinary(K))``, ``F = len(features)``.
    Slots hold the object's K best candidates, lowest ``Q_C`` first (or shuffled each episode,
    ``candidate_order="shuffled"``); padded slots are zero and masked. With ``max_attempts > 1``
    (the retry setting) the Dict also holds ``failed=MultiBinary(K)``: 1 at the slots executed
    this episode that dropped the object, 0 elsewhere (all 0 at reset). The mask alone cannot tell
    a failed slot from padding; ``failed`` says which grips the episode's draw defeated, which is
    what a retry can use. The episode's attempt count is ``failed.sum()`` (every attempt but a
    successful last one failed), so it is not a key of its own. With ``max_attempts = 1`` the
    space is the two keys only.

    ## Rewards

    ``success_reward`` (1) when the executed grip holds, ``failure_reward`` (0) when it drops,
    ``invalid_action_reward`` (-1) for a masked slot.

    ## Starting State

    An object drawn uniformly from the split's objects that have a candidate, with the
    environment's ``np_random`` (``reset(seed=...)`` fixes every draw), or the one named by
    ``reset(options={"object_id": ...})``; with trials replayed by index, the episode's trial
    k is drawn the same way, or pinned by ``reset(options={"trial": k})``.

    ## Episode End

    Terminates on success, after ``max_attempts`` executions, after an invalid action, or when no
    valid candidate remains; never truncated. A ``step`` after the end raises ``RuntimeError``.
    ``info`` holds ``object_id``, ``grip_id``, ``Q_C``, ``success_rate`` (recorded rate; None
    live), ``attempts``, ``success``, ``is_success`` (the same flag, under the name SB3's
    ``Monitor`` and ``EvalCallback`` read) and ``invalid_action``; ``reset``'s ``info`` also
    holds ``trial`` when trials are replayed by index.

    ## Arguments

    - ``data``: a dataset path or DataFrame, a shortcut for ``backend=ReplayBackend(data,
      objects)``; with neither ``data`` nor ``backend``, grips run live (in ``engine``).
    - ``objects``: object set name, or names / ``PlanarObject`` list (live: the objects; replay:
      a filter on the dataset's object ids). None: ``config.objects.set`` live, all replayed.
    - ``backend``: any :class:`~grip_env.envs.backends.OutcomeBackend` (instead of ``data``).
    - ``config``: grip-env :class:`~grip_env.config.Config` (default: ``load_config()``).
    - ``engine``: the physics engine of live trials, ``"pybullet"`` or ``"mujoco"`` (default: the
      config's ``sim.engine``); an unknown or uninstalled engine raises ``ValueError``.
    - ``max_candidates``, ``max_attempts``: K and executions per episode (default
      ``config.selector``); ``max_attempts`` above K raises ``ValueError``.
    - ``replay``: how a replayed execution is drawn: ``"trial"`` (the episode's trial k),
      ``"rate"`` (Bernoulli of the success rate, each execution independent) or ``"auto"``
      (``"trial"`` when the data records every trial's outcome).
    - ``success_reward``, ``failure_reward``, ``invalid_action_reward``: reward values.
    - ``features``: feature subset (names from S1..C6, Q_G, Q_C); default the twelve S1..C6.
    - ``split``: ``"train"``, ``"test"`` or ``"all"`` objects, from
      :func:`grip_env.dataset.split.split_objects` (``test_fraction`` and ``split_seed`` default
      to ``config.learning.test_fraction`` and ``config.learning.seed``).
    - ``normalize``: ``"log"`` (signed log1p), ``"standard"`` (z-score on the split's
      candidates) or ``"none"``.
    - ``candidate_order``: ``"q_c"`` (best first) or ``"shuffled"``.
    - ``render_mode``: ``None``, ``"rgb_array"`` or ``"human"``; ``render_style``: ``"scene"``
      (drawn by ``engine``: PyBullet's TinyRenderer or MuJoCo's OpenGL renderer; live only, its
      default) or ``"sketch"`` (2-D contour and
      contact triangles; the replay default).

    ## Version History

    - v0: initial version.

    ## Example

    >>> import gymnasium, grip_env
    >>> from classifiers.evaluation.synthetic import synthetic_grips
    >>> env = gymnasium.make("GripSelect-v0", data=synthetic_grips(n_objects=6, seed=0),
    ...                      max_candidates=8)
    >>> observation, info = env.reset(seed=0, options={"object_id": "3"})
    >>> info["object_id"], observation["features"].shape, observation["mask"].shape
    ('3', (8, 12), (8,))
    >>> _, reward, terminated, truncated, info = env.step(0)
    >>> terminated, truncated, reward == float(info["success"])
    (True, False, True)
    >>> env.step(0)
    Traceback (most recent call last):
    ...
    RuntimeError: the episode has ended (or never started): call reset() before step()
    """

    def _make_spaces(self) -> None:
        k, width = self.max_candidates, len(self.feature_names)
        low, high = self.scaler.bounds()
        self.observation_space = spaces.Dict({
            "features": spaces.Box(
                np.broadcast_to(low, (k, width)), np.broadcast_to(high, (k, width)),
                dtype=np.float32,
            ),
            "mask": spaces.MultiBinary(k),
            **({"failed": spaces.MultiBinary(k)} if self.retries else {}),
        })
        self.action_space = spaces.Discrete(k)
        self._found: CandidateSet | None = None
        self._slots = np.arange(k)
        self._features = np.zeros((k, width), dtype=np.float32)
        self._mask = np.zeros(k, dtype=np.int8)
        self._failed = np.zeros(k, dtype=np.int8)
        self._attempts = 0
        self._remaining = 0
        self._chosen: int | None = None
        self._outcome: bool | None = None

    def _start_episode(self, found: CandidateSet) -> None:
        """Lay the episode's candidates out in their (shuffled) slots."""
        slots = self._slots
        self._features = found.features if slots is self._identity else found.features[slots]
        self._mask = found.mask.copy()
        self._failed = np.zeros(self.max_candidates, dtype=np.int8)
        self._remaining = found.count
        self._chosen = None

    def step(self, action: Any) -> tuple[Observation, float, bool, bool, dict[str, Any]]:
        """Execute the candidate in slot ``action``."""
        slot = action_index(action, self.max_candidates)
        self._check_running()
        found = self._found
        assert found is not None
        row = int(self._slots[slot])
        info = self._grip_info(found, row)
        if not self._mask[slot]:
            self._chosen, self._outcome = None, None
            info.update(attempts=self._attempts, success=False, is_success=False,
                        invalid_action=True)
            return self._observation(), self.invalid_action_reward, self._end_if(True), False, info
        success = self._execute(found, row)
        self._attempts += 1
        self._mask[slot] = 0
        self._failed[slot] = not success
        self._remaining -= 1
        self._chosen, self._outcome = row, success
        reward = self.success_reward if success else self.failure_reward
        terminated = self._end_if(
            success or self._attempts >= self.max_attempts or not self._remaining
        )
        info.update(attempts=self._attempts, success=success, is_success=success,
                    invalid_action=False)
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, terminated, False, info

    def action_masks(self) -> NDArray[np.bool_]:
        """Valid actions (real candidates not yet failed), for sb3-contrib's MaskablePPO."""
        return self._mask.astype(bool)

    def _observation(self) -> Observation:
        observation = {"features": self._features.copy(), "mask": self._mask.copy()}
        if self.retries:
            observation["failed"] = self._failed.copy()
        return observation

    def _draw(self) -> NDArray[np.uint8]:
        found = self._found
        if found is None:
            return self._frame(None, None, None, "")
        title = f"{found.object_id}: {found.count} candidates, attempts {self._attempts}"
        return self._frame(found, self._chosen, self._outcome, title)

