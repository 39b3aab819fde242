"""Where a grip's outcome comes from: a recorded dataset (replay) or PyBullet (live).

Both backends give the same three things to an environment: the object ids, each object's
candidate rows (the candidate/dataset column contract) and the outcome of executing one candidate,
drawn with the environment's random generator so that ``reset(seed=...)`` fixes everything.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.config import Config
from grip_env.datasets import resolve_data
from grip_env.envs.observation import CandidateSet
from grip_env.mesh_sets import named_set
from grip_env.objects import SHAPE_NAMES, PlanarObject, make_shape

ObjectsArg = str | Sequence[str | PlanarObject] | None
#: How a replayed execution is drawn: ``"trial"`` replays the recorded trial k of the episode
#: (every attempt of an episode the same k), ``"rate"`` draws Bernoulli(success rate) afresh
#: each execution; ``"auto"``: ``"trial"`` when the data records every trial's outcome.
REPLAY_MODES = ("auto", "trial", "rate")
_REPLAY_COLUMNS = ("object_id", "grip_id", "Q_C")
_AREA_TOLERANCE = 0.01  # relative; a named shape's contour is trusted for drawing within this


class OutcomeBackend(Protocol):
    """What an environment needs from a source of grip outcomes."""

    object_ids: tuple[str, ...]
    feature_cap: float | None  # the cap the features were computed with, when known

    def candidates(self, object_id: str) -> pd.DataFrame:
        """All candidate rows of one object (any order)."""

    def contour(self, object_id: str) -> NDArray[np.float64] | None:
        """The object's contour (N, 2) in mm, or None when unknown (drawing only)."""

    def execute(self, candidates: CandidateSet, slot: int, rng: np.random.Generator) -> bool:
        """Whether executing candidate ``slot`` of ``candidates`` lifts the object."""

    def close(self) -> None:
        """Release resources (idempotent)."""


def recorded_trial_count(backend: OutcomeBackend) -> int:
    """The trials a backend replays by index (``ReplayBackend`` with ``replay="trial"``), else 0:
    its episodes then draw one trial index k and every attempt replays trial k."""
    return int(getattr(backend, "trials", 0) or 0)


class ReplayBackend:
    """Outcomes replayed from recorded trials.

    With ``replay="trial"`` (the default when the data records every trial's outcome,
    ``trial_success_0..T-1``), an episode draws one trial index k (:attr:`trials` > 0 tells the
    environment to) and executing a grip replays its recorded trial k: every grip's trial k met
    the same friction, mass and pose noise, so a failed first pick says something about the
    draw, and a retry in the same episode meets the same draw. With ``replay="rate"`` (the only
    choice for data without per-trial outcomes) executing a grip draws
    ``success ~ Bernoulli(successes / trials)`` (or its ``success_rate`` when the counts are
    absent) with the environment's generator, independently at every execution.

    Args:
        data: a dataset directory or file (read with ``grip_env.dataset.load``), ``"standard"``
            for the shipped standard dataset (:mod:`grip_env.datasets`), or a DataFrame with
            the dataset columns (at least ``object_id``, ``grip_id``, ``Q_C``, the contact points,
            the features, and ``trials``/``successes`` or ``success_rate``).
        objects: restrict to these object ids (names, or objects whose ``name`` is the id);
            objects also give the contours used for drawing.
        replay: ``"auto"``, ``"trial"`` or ``"rate"`` (:data:`REPLAY_MODES`); ``"trial"`` on
            data without per-trial outcomes raises ``ValueError``.

    A dataset directory labelled by another label model than this code's
    (:data:`grip_env.sim.LABEL_MODEL`) gives one ``UserWarning``.
    """

    def __init__(self, data: str | Path | pd.DataFrame, objects: ObjectsArg = None,
                 replay: str = "auto") -> None:
        if replay not in REPLAY_MODES:
            raise ValueError(f"replay must be one of {REPLAY_MODES}, got {replay!r}")
        if not isinstance(data, pd.DataFrame):
            data = resolve_data(data)
        frame = data if isinstance(data, pd.DataFrame) else _load_dataset(data)
        if not isinstance(data, pd.DataFrame):
            _warn_label_model(data)
        missing = [name for name in _REPLAY_COLUMNS if name not in frame.columns]
        if missing:
            raise ValueError(f"replay data lacks columns {missing}")
        if not {"trials", "successes"} <= set(frame.columns) and "success_rate" not in frame:
            raise ValueError("replay data needs 'trials' and 'successes' or 'success_rate'")
        self._frames = {str(key): rows for key, rows in frame.groupby("object_id", sort=True)}
        given = _given_objects(objects)
        if given is not None:
            unknown = sorted(set(given) - set(self._frames))
            if unknown:
                raise ValueError(f"objects {unknown} are not in the replay data")
            self._frames = {key: self._frames[key] for key in sorted(given)}
        if not self._frames:
            raise ValueError("replay data holds no grip")
        self.object_ids = tuple(self._frames)
        stored = {} if isinstance(data, pd.DataFrame) else _stored_contours(data)
        given_contours = {k: obj.contour for k, obj in (given or {}).items() if obj is not None}
        self._contours = {**stored, **given_contours}
        params = frame.attrs.get("params") or {}
        self.feature_cap: float | None = params.get("feature_cap")
        self.trials = self._replayed_trials(frame, replay)
        self._trial_success: dict[tuple[str, int], NDArray[np.bool_]] = {}

    @staticmethod
    def _replayed_trials(frame: pd.DataFrame, replay: str) -> int:
        from grip_env.dataset.shards import recorded_trial_successes

        recorded = recorded_trial_successes(frame.columns)
        if replay == "trial" and not recorded:
            raise ValueError("replay='trial' needs every trial's outcome (trial_success_0..T-1),"
                             " which this data does not record; use replay='rate'")
        return recorded if replay != "rate" else 0

    def candidates(self, object_id: str) -> pd.DataFrame:
        return self._frames[object_id]

    def contour(self, object_id: str) -> NDArray[np.float64] | None:
        if object_id not in self._contours:
            self._contours[object_id] = _named_shape_contour(object_id, self._frames[object_id])
        return self._contours[object_id]

    def execute(self, candidates: CandidateSet, slot: int, rng: np.random.Generator,
                trial: int | None = None) -> bool:
        """Whether candidate ``slot`` holds: its recorded trial ``trial`` when given (replay
        "trial"), else a Bernoulli draw of its success rate with ``rng``."""
        if trial is None:
            return bool(rng.random() < candidates.success_rate[slot])
        return bool(self._trial_outcomes(candidates)[slot, trial])

    def _trial_outcomes(self, candidates: CandidateSet) -> NDArray[np.bool_]:
        """(count, trials) recorded trial successes of the candidates, by slot (kept)."""
        key = (candidates.object_id, candidates.count)
        found = self._trial_success.get(key)
        if found is None:
            from grip_env.columns import trial_success_columns

            columns = list(trial_success_columns(self.trials))
            values = candidates.rows[columns]
            if values.isna().to_numpy().any():  # a NaN cast to bool would read as a hold
                raise ValueError(f"object {candidates.object_id!r} lacks some of its trials' "
                                 f"outcomes (trial_success_0..{self.trials - 1}): replay "
                                 f"objects that record every trial, or replay='rate'")
            found = values.to_numpy(bool)
            self._trial_success[key] = found
        return found

    def close(self) -> None:
        return None


class LiveBackend:
    """Outcomes from executing the grip in PyBullet: one trial per execution, with the noise.

    Candidates come from ``grip_env.pipeline.candidates`` (computed once per object, on first
    use); a trial's seed is drawn from the environment's generator.

    Args:
        objects: a named object set, or a list of shape names / ``PlanarObject``; None takes
            ``config.objects.set``.
        config: the grip-env configuration (grasp parameters, synthesis, simulation, noise).
    """

    def __init__(self, objects: ObjectsArg, config: Config) -> None:
        self._objects = _live_objects(objects, config)
        self.object_ids = tuple(self._objects)
        self._config = config
        self.feature_cap: float | None = config.grasp.feature_cap

    def candidates(self, object_id: str) -> pd.DataFrame:
        from grip_env.planning.pipeline import candidates

        return candidates(self._objects[object_id], self._config.grasp, self._config)

    def contour(self, object_id: str) -> NDArray[np.float64] | None:
        return self._objects[object_id].contour

    def object(self, object_id: str) -> PlanarObject:
        """The object simulated under ``object_id``."""
        return self._objects[object_id]

    def execute(self, candidates: CandidateSet, slot: int, rng: np.random.Generator) -> bool:
        from grip_env.sim import run_trials

        seed = int(rng.integers(2**31 - 1))
        grip = candidates.rows.iloc[[slot]]
        outcome = run_trials(self._objects[candidates.object_id], grip, self._config, 1, seed)
        return bool(outcome["successes"].iloc[0] > 0)

    def close(self) -> None:
        return None


def _load_dataset(path: str | Path) -> pd.DataFrame:
    from grip_env.dataset import load

    if not Path(path).exists():
        raise ValueError(f"dataset not found: {path}")
    return load(path)


def _warn_label_model(path: str | Path) -> None:
    """Warn (once per backend) when the dataset was labelled by another label model."""
    from gymnasium import logger

    from grip_env.dataset import label_model_notice

    notice = label_model_notice(path)
    if notice is not None:
        logger.warn("%s", notice)


def _stored_contours(path: str | Path) -> dict[str, NDArray[np.float64]]:
    """Contours stored beside a dataset (none when the dataset keeps no objects table)."""
    from grip_env.dataset import load_objects

    try:
        return {obj.name: obj.contour for obj in load_objects(path)}
    except (ValueError, OSError):
        return {}


def _given_objects(objects: ObjectsArg) -> dict[str, PlanarObject | None] | None:
    """Object ids (with the object when one was given) from the ``objects`` argument."""
    if objects is None:
        return None
    if isinstance(objects, str):
        return {obj.name: obj for obj in named_set(objects).objects}
    given: dict[str, PlanarObject | None] = {}
    for item in objects:
        if isinstance(item, PlanarObject):
            given[item.name] = item
        elif isinstance(item, str):
            given[item] = None
        else:
            raise ValueError(f"objects must be names or PlanarObject, got {item!r}")
    if not given:
        raise ValueError("objects must not be empty")
    return given


def _live_objects(objects: ObjectsArg, config: Config) -> dict[str, PlanarObject]:
    if objects is None or isinstance(objects, str):
        name = objects if objects is not None else config.objects.set
        found = named_set(name, config.dataset.seed, config.objects).objects
    else:
        found = [item if isinstance(item, PlanarObject) else _shape(item) for item in objects]
    names = [obj.name for obj in found]
    if not names:
        raise ValueError("objects must not be empty")
    if len(set(names)) != len(names):
        raise ValueError(f"object names must be unique, got {names}")
    return {obj.name: obj for obj in found}


def _shape(item: Any) -> PlanarObject:
    if not isinstance(item, str):
        raise ValueError(f"objects must be names or PlanarObject, got {item!r}")
    return make_shape(item)


def _named_shape_contour(object_id: str, rows: pd.DataFrame) -> NDArray[np.float64] | None:
    """A named shape's contour when its recorded area and centroid match (else unknown)."""
    needed = {"area", "centroid_x", "centroid_y"}
    if object_id not in SHAPE_NAMES or not needed <= set(rows.columns):
        return None
    shape = make_shape(object_id)
    first = rows.iloc[0]
    size = np.sqrt(shape.area)
    offset = np.hypot(*(first[["centroid_x", "centroid_y"]].to_numpy(float) - shape.centroid))
    if abs(shape.area - first["area"]) > _AREA_TOLERANCE * shape.area or offset > 0.01 * size:
        return None
    return shape.contour
