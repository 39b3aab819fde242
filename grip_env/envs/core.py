"""``GripEnvBase``: what the grip environments share (objects, split, candidates, rewards, drawing).

An episode is one object, drawn uniformly with the environment's ``np_random`` from the objects
of its split that have at least one candidate, or pinned with ``reset(options={"object_id": id})``.
When the backend replays recorded trials by index (``ReplayBackend``, ``replay="trial"``), the
episode also draws one trial index k with ``np_random`` (``info["trial"]``), and every attempt of
the episode replays trial k: the same friction, mass and pose noise for every grip tried, as a
robot retrying on one object meets them.
A ``step`` after the episode ended raises (call ``reset``). Subclasses define the spaces
(:meth:`GripEnvBase._make_spaces`), ``reset`` and ``step``; the constructor, with its explicit
keyword signature, is this class's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.config import Config, load_config
from grip_env.dataset.split import objects_in_split
from grip_env.envs.backends import (
    LiveBackend,
    ObjectsArg,
    OutcomeBackend,
    ReplayBackend,
    recorded_trial_count,
)
from grip_env.envs.observation import (
    CandidateSet,
    FeatureScaler,
    candidate_set,
    candidate_sets,
    feature_subset,
    raw_features,
)
from grip_env.envs.rendering import RENDER_STYLES, HumanWindow, SceneCamera, draw_candidates

CANDIDATE_ORDERS: tuple[str, ...] = ("q_c", "shuffled")
_BACKEND_MEMBERS = ("object_ids", "feature_cap", "candidates", "contour", "execute", "close")


class GripEnvBase(gym.Env[dict[str, NDArray[Any]], np.int64]):
    """Shared construction of the grip environments; see ``GripSelectEnv`` for the options."""

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array"], "render_fps": 2}

    def __init__(
        self,
        data: str | Path | pd.DataFrame | None = None,
        objects: ObjectsArg = None,
        *,
        backend: OutcomeBackend | None = None,
        config: Config | None = None,
        max_candidates: int | None = None,
        max_attempts: int | None = None,
        success_reward: float = 1.0,
        failure_reward: float = 0.0,
        invalid_action_reward: float = -1.0,
        features: tuple[str, ...] | list[str] | None = None,
        split: str = "all",
        test_fraction: float | None = None,
        split_seed: int | None = None,
        normalize: str = "log",
        candidate_order: str = "q_c",
        render_mode: str | None = None,
        render_style: str | None = None,
        engine: str | None = None,
        replay: str = "auto",
    ) -> None:
        self.config = config if config is not None else load_config()
        if engine is not None:  # live trials in this engine (sim.engine), checked now
            from grip_env.sim.engine import require_engine

            require_engine(engine)
            self.config = self.config.override(sim={"engine": engine})
        selector = self.config.selector
        self.max_candidates = _at_least(
            "max_candidates", selector.max_candidates if max_candidates is None else max_candidates
        )
        self.max_attempts = _at_least(
            "max_attempts", selector.max_attempts if max_attempts is None else max_attempts
        )
        self.success_reward = float(success_reward)
        self.failure_reward = float(failure_reward)
        self.invalid_action_reward = float(invalid_action_reward)
        if candidate_order not in CANDIDATE_ORDERS:
            raise ValueError(
                f"candidate_order must be one of {CANDIDATE_ORDERS}, got {candidate_order!r}"
            )
        self.candidate_order = candidate_order
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']}, got {render_mode!r}"
            )
        self.render_mode = render_mode
        if self.max_attempts > self.max_candidates:
            raise ValueError(f"max_attempts {self.max_attempts} exceeds the {self.max_candidates}"
                             " candidates an episode shows (max_candidates): no episode can "
                             "use them")
        self.feature_names = feature_subset(features)
        self.backend = self._make_backend(data, objects, backend, replay)
        self.trials = recorded_trial_count(self.backend)
        self._trial: int | None = None
        self.render_style = self._checked_style(render_style)
        self._camera = SceneCamera(self.config) if self.render_style == "scene" else None
        self.object_ids = objects_in_split(
            self.backend.object_ids,
            split,
            self.config.learning.test_fraction if test_fraction is None else test_fraction,
            self.config.learning.seed if split_seed is None else split_seed,
        )
        self.split = split
        self._sets: list[CandidateSet | None] = [None] * len(self.object_ids)
        self.scaler = self._fit_scaler(normalize)
        if isinstance(self.backend, ReplayBackend):
            frames = [self.backend.candidates(object_id) for object_id in self.object_ids]
            self._sets = list(candidate_sets(self.object_ids, frames, self.scaler,
                                             self.max_candidates))  # fmt: skip
        self._window: HumanWindow | None = None
        self._identity = np.arange(self.max_candidates)
        self._identity.flags.writeable = False
        self._ended = True  # no episode yet: step() needs a reset() first
        self._make_spaces()

    @property
    def retries(self) -> bool:
        """Whether an episode may execute more than one grip (``max_attempts > 1``): then the
        observation also says which candidates were tried and failed (``"failed"``)."""
        return self.max_attempts > 1

    def _make_spaces(self) -> None:
        """Set ``observation_space``, ``action_space`` and the episode state (subclasses)."""
        raise NotImplementedError

    def _make_backend(
        self, data: str | Path | pd.DataFrame | None, objects: ObjectsArg,
        backend: OutcomeBackend | None, replay: str,
    ) -> OutcomeBackend:
        """``backend`` as given, else replay of ``data`` (``replay``: how executions are drawn),
        else live trials on ``objects`` (in ``sim.engine``)."""
        if backend is None:
            if data is None:
                return LiveBackend(objects, self.config)
            return ReplayBackend(data, objects, replay)
        if data is not None or objects is not None:
            raise ValueError("pass either backend= or data=/objects= (data= is a shortcut for "
                             "backend=ReplayBackend(data, objects)), not both")  # fmt: skip
        missing = [name for name in _BACKEND_MEMBERS if not hasattr(backend, name)]
        if missing:
            raise ValueError(f"backend {type(backend).__name__} lacks {missing} of OutcomeBackend")
        return backend

    # ------------------------------------------------------------------ episodes
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, NDArray[Any]], dict[str, Any]]:
        """Start an episode on a new object (``options={"object_id": ...}`` picks it; with
        trials replayed by index, ``options={"trial": k}`` pins the episode's trial k, as an
        evaluation that runs every k does); ``info`` has ``object_id``, ``candidates``,
        ``attempts`` and, when the backend replays trials by index, ``trial`` (the episode's k)."""
        super().reset(seed=seed)
        options = dict(options or {})
        pinned = self._pinned_trial(options.pop("trial", None))
        found = self._found = self._episode_candidates(options)
        self._slots = self._shuffled_slots(found.count)
        if pinned is not None:
            self._trial = pinned
        else:
            self._trial = int(self.np_random.integers(self.trials)) if self.trials else None
        self._attempts, self._outcome = 0, None
        self._start_episode(found)
        if self.render_mode == "human":
            self.render()
        info = {"object_id": found.object_id, "candidates": found.count, "attempts": 0}
        if self._trial is not None:
            info["trial"] = self._trial
        return self._observation(), info

    def _pinned_trial(self, trial: Any) -> int | None:
        """``reset``'s ``trial`` option, checked: an index of the replayed trials (or None)."""
        if trial is None:
            return None
        if not self.trials:
            raise ValueError("reset option 'trial' needs trials replayed by index (data with "
                             "every trial's outcome, replay='trial' or 'auto')")
        if isinstance(trial, bool) or not isinstance(trial, int | np.integer) or not (
                0 <= trial < self.trials):
            raise ValueError(f"reset option 'trial' must be an integer in [0, {self.trials}), "
                             f"got {trial!r}")
        return int(trial)

    def _execute(self, found: CandidateSet, row: int) -> bool:
        """Execute candidate ``row``: the episode's trial k when replayed by index."""
        if self._trial is None:
            return self.backend.execute(found, row, self.np_random)
        return self.backend.execute(found, row, self.np_random, trial=self._trial)  # type: ignore[call-arg]

    def _start_episode(self, found: CandidateSet) -> None:
        """Set the environment's own episode state for ``found`` (subclasses)."""
        raise NotImplementedError

    def _observation(self) -> dict[str, NDArray[Any]]:
        """The current observation (subclasses)."""
        raise NotImplementedError

    def _episode_candidates(self, options: dict[str, Any] | None) -> CandidateSet:
        """The episode's object: ``options["object_id"]`` if given, else a uniform draw."""
        options = dict(options or {})
        object_id = options.pop("object_id", None)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; the options are "
                             "'object_id' and 'trial'")  # fmt: skip
        self._ended = False
        if object_id is None:
            return self._sample_candidates()
        if str(object_id) not in self.object_ids:
            self._ended = True
            raise ValueError(f"object_id {object_id!r} is not among the {len(self.object_ids)} "
                             f"objects of split {self.split!r}")  # fmt: skip
        found = self._candidate_set(self.object_ids.index(str(object_id)))
        if not found.count:
            self._ended = True
            raise ValueError(f"object {object_id!r} has no feasible grip")
        return found

    def _check_running(self) -> None:
        """Refuse a step before the first reset or after the episode ended."""
        if self._ended:
            raise RuntimeError("the episode has ended (or never started): call reset() before "
                               "step()")  # fmt: skip

    def _end_if(self, terminated: bool) -> bool:
        """Record whether the step ended the episode, and return it."""
        self._ended = bool(terminated)
        return self._ended

    def _checked_style(self, style: str | None) -> str:
        """``"scene"`` (PyBullet, live only; the live default) or ``"sketch"`` (2-D)."""
        live = isinstance(self.backend, LiveBackend)
        if style is None:
            return "scene" if live else "sketch"
        if style not in RENDER_STYLES:
            raise ValueError(f"render_style must be one of {RENDER_STYLES}, got {style!r}")
        if style == "scene" and not live:
            raise ValueError("render_style='scene' needs the live backend (data=None)")
        return style

    # ------------------------------------------------------------------ candidates
    def _fit_scaler(self, normalize: str) -> FeatureScaler:
        raw = None
        if normalize == "standard":
            frames = [self.backend.candidates(object_id) for object_id in self.object_ids]
            raw = raw_features(pd.concat(frames, ignore_index=True), self.feature_names)
        cap = self.backend.feature_cap or self.config.grasp.feature_cap
        return FeatureScaler.fit(normalize, self.feature_names, cap, raw)

    def _candidate_set(self, index: int) -> CandidateSet:
        """The padded candidates of object ``index`` (computed once)."""
        found = self._sets[index]
        if found is None:
            object_id = self.object_ids[index]
            frame = self.backend.candidates(object_id)
            found = candidate_set(object_id, frame, self.scaler, self.max_candidates)
            self._sets[index] = found
        return found

    def _sample_candidates(self) -> CandidateSet:
        """An object with at least one candidate, uniformly from the split.

        Objects without a candidate are rejected and redrawn, so the draw sequence does not depend
        on which objects were already computed.
        """
        rng, total, sets = self.np_random, len(self.object_ids), self._sets
        while True:
            index = int(rng.random() * total)  # uniform index; cheaper than rng.integers
            found = sets[index] or self._candidate_set(index)
            if found.count:
                return found
            if all(s is not None and not s.count for s in self._sets):
                raise ValueError(f"no object of split {self.split!r} has a feasible grip")

    def _shuffled_slots(self, count: int) -> NDArray[np.intp]:
        """Slot order for an episode: identity, or the real candidates permuted."""
        if self.candidate_order == "q_c":
            return self._identity
        slots = np.arange(self.max_candidates)
        slots[:count] = self.np_random.permutation(count)
        return slots

    # ------------------------------------------------------------------ info and drawing
    @staticmethod
    def _grip_info(found: CandidateSet, row: int) -> dict[str, Any]:
        """object_id, grip_id, Q_C and success_rate of candidate ``row``.

        Unknown values are None (a padded slot's ``Q_C``, a live grip's ``success_rate``) so that
        infos compare equal across identical runs; a padded slot's ``grip_id`` is -1 or "".
        """
        if row >= found.count:
            grip_id = -1 if found.grip_ids and isinstance(found.grip_ids[0], int) else ""
            return {"object_id": found.object_id, "grip_id": grip_id, "Q_C": None,
                    "success_rate": None}
        rate = float(found.success_rate[row])
        return {
            "object_id": found.object_id,
            "grip_id": found.grip_ids[row],
            "Q_C": float(found.q_c[row]),
            "success_rate": None if rate != rate else rate,
        }

    def render(self) -> NDArray[np.uint8] | None:
        """The episode drawn as an RGB array (``"rgb_array"``) or in a window (``"human"``).

        ``render_style="scene"`` (the live default): the scene drawn by the live trials' engine
        (PyBullet's TinyRenderer, or MuJoCo's OpenGL renderer through EGL), the hand holding the
        chosen or current candidate (executed without noise). ``"sketch"`` (the replay default):
        the object's contour (when known), its candidates' contact triangles, and the chosen or
        current candidate highlighted: green held, red dropped, blue not executed yet.
        """
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode= to make()")
            return None
        frame = self._draw()
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:
            self._window = HumanWindow(self.metadata["render_fps"])
        self._window.show(frame)
        return None

    def _draw(self) -> NDArray[np.uint8]:
        raise NotImplementedError

    def _frame(
        self, found: CandidateSet | None, chosen: int | None, outcome: bool | None, title: str
    ) -> NDArray[np.uint8]:
        """Draw ``found``'s real candidates, slot ``chosen`` highlighted."""
        if found is None:  # before the first reset
            return draw_candidates(None, np.zeros((0, 3, 2)), title="no episode yet")
        if self._camera is not None and isinstance(self.backend, LiveBackend):
            grip = None if chosen is None else found.rows.iloc[chosen]
            return self._camera.frame(self.backend.object(found.object_id), grip)
        contacts = found.contacts[: found.count]
        contour = self.backend.contour(found.object_id)
        return draw_candidates(contour, contacts, chosen, outcome, title)

    def close(self) -> None:
        """Close the window and the backend (idempotent)."""
        if self._window is not None:
            self._window.close()
            self._window = None
        if self._camera is not None:
            self._camera.close()
        self.backend.close()


def _at_least(name: str, value: int, low: int = 1) -> int:
    if int(value) != value or value < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)


def action_index(action: Any, size: int) -> int:
    """The integer action, checked against ``Discrete(size)``."""
    if isinstance(action, int | np.integer):
        slot = int(action)
    else:
        value = np.asarray(action)
        if value.size != 1 or not np.issubdtype(value.dtype, np.integer):
            raise ValueError(f"action must be one integer in [0, {size}), got {action!r}")
        slot = int(value.reshape(()))
    if not 0 <= slot < size:
        raise ValueError(f"action must be in [0, {size}), got {slot}")
    return slot
