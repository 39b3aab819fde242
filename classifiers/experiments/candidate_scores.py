"""Per-seed scores of every candidate of every held-out object: what a benchmark aggregates.

Each learner of ``learning.models`` (classifiers), ``learning.regressors`` and
``learning.rankers`` is fitted ``learning.seeds`` times, with seeds ``learning.seed + k``, on the
grips of the study split's training objects (:func:`grip_env.dataset.split.held_out_objects`;
the split itself stays fixed by ``learning.seed``, only the models' own randomness changes) and
scores every candidate of each held-out object. The RL selector does the same per
``selector.seeds`` (:func:`classifiers.experiments.selector.seeds.run_selectors`).

Files in a study folder:

- ``classifiers/scores.parquet``: the learners' scores (written by ``grip-env train``);
- ``selector/scores.parquet``: the RL selector's (method ``"rl"``);
- ``selector/seed_<s>/``: one selector run per seed ``s`` (``model.zip``, ``selector.json``,
  ``learning_curve.png``, ``tb/``); ``selector/selector.json`` and ``selector/model.zip`` are
  the first seed's, with a ``"seeds"`` list summarising every run.

Columns (:data:`SCORE_COLUMNS`), one row per (object, seed, method, candidate):

- ``object_id`` (str): a held-out object;
- ``seed`` (int64): the training seed;
- ``method`` (str): ``classifier_<name>``, ``regressor_<name>``, ``ranker_<name>`` or ``rl``;
- ``candidate`` (int64): the slot of the grip in the object's ``GripSelect-v0`` candidate set
  (its grips by ``Q_C`` ascending, stable, the first ``selector.max_candidates``);
- ``grip_id`` (str): the grip, to join with the dataset's recorded outcomes (on the dataset's
  ``grip_id`` as ``str``: the real datasets' ids are strings such as ``"proc_0_00000/13/0"``);
- ``score`` (float64): higher = pick first. Classifiers: the ranking score
  (:func:`classifiers.evaluation.cross_validation.ranking_score`); regressors: predicted
  ``robustness_mean``;
  rankers: the ranker's score (comparable within one object only); ``rl``: the policy's action
  probability (masked softmax). Ties go to the lower slot (``argsort(-score, kind="stable")``).

Every method has every seed; a deterministic learner (logreg, knn, the rank baselines) repeats
identical scores. The analytic baselines (Q_C, Q_G, random, oracle) are functions of the
recorded outcomes and are not stored here.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator

from classifiers.evaluation.cross_validation import (
    GROUP_COLUMN,
    LABEL_COLUMN,
    ranking_score,
)
from classifiers.evaluation.regression import TARGET_COLUMN, has_target
from classifiers.learners.models import make_model, make_regressor
from classifiers.learners.parallel import run_all
from classifiers.learners.ranking import make_ranker, relevance
from grip_env.columns import FEATURES
from grip_env.config import Config
from grip_env.dataset.split import split_table
from grip_env.envs.observation import best_candidates

SCORES_FILE = "scores.parquet"
SCORE_COLUMNS = ("object_id", "seed", "method", "candidate", "grip_id", "score")


def training_seeds(first: int, count: int) -> tuple[int, ...]:
    """``(first, first + 1, ..., first + count - 1)``; ``count < 1`` → ValueError."""
    if count < 1:
        raise ValueError(f"seeds must be at least 1, got {count}")
    return tuple(first + k for k in range(count))


def held_out_candidates(table: pd.DataFrame, config: Config) -> dict[str, pd.DataFrame]:
    """Each held-out object's candidate rows, in slot order (as ``GripSelect-v0`` shows them)."""
    _, test = split_table(table, config.learning)
    frames = test.groupby(test[GROUP_COLUMN].astype(str), sort=True)
    found = {oid: best_candidates(frame, config.selector.max_candidates)
             for oid, frame in frames}  # fmt: skip
    return {oid: rows for oid, rows in found.items() if len(rows)}


def score_frame(object_id: str, seed: int, method: str, rows: pd.DataFrame,
                score: np.ndarray) -> pd.DataFrame:
    """One object's rows of :data:`SCORE_COLUMNS`; wrong length or NaN scores → ValueError."""
    score = _checked(np.asarray(score, dtype=np.float64), len(rows), method, seed)
    return pd.DataFrame({
        "object_id": str(object_id), "seed": np.int64(seed), "method": method,
        "candidate": np.arange(len(rows), dtype=np.int64),
        "grip_id": rows["grip_id"].astype(str).to_numpy(), "score": score,
    })  # fmt: skip


def _checked(score: np.ndarray, count: int, method: str, seed: int) -> np.ndarray:
    """``score`` when it holds ``count`` finite values, else a ValueError naming the run."""
    if score.shape != (count,) or not np.isfinite(score).all():
        raise ValueError(f"{method} seed {seed}: scores of shape {score.shape} (finite: "
                         f"{bool(np.isfinite(score).all())}) for {count} candidates")
    return score


def learner_scores(table: pd.DataFrame, config: Config) -> pd.DataFrame:
    """The scores of every configured learner and seed (see the module docstring).

    The fits run in ``learning.workers`` processes, one thread each, when the training grips
    number at least :data:`~classifiers.learners.parallel.PARALLEL_MIN_GRIPS`; a
    learner that no seed changes (:func:`seed_free`: knn, logreg, ridge, the rank baselines) is
    fitted once and its scores repeated for every seed. The table is the same whatever the
    number of workers.
    """
    learning = config.learning
    train, _ = split_table(table, learning)
    candidates = held_out_candidates(table, config)
    if not candidates or train[LABEL_COLUMN].nunique() < 2:
        return empty_scores()
    jobs = _jobs(train, table, config)
    seeds = training_seeds(learning.seed, learning.seeds)
    free = {method for method, (make, _) in jobs.items() if seed_free(make)}
    fitted_seed = {(method, seed): seeds[0] if method in free else seed
                   for method in jobs for seed in seeds}  # fmt: skip
    fits = list(dict.fromkeys((method, fitted) for (method, _), fitted in fitted_seed.items()))
    stacked = pd.concat(candidates.values(), ignore_index=True)
    found = run_all(_fitted_scores, [(train, stacked, method, *jobs[method], seed)
                                     for method, seed in fits], len(train), learning.workers)
    scores = dict(zip(fits, found, strict=True))
    runs = [(seed, method) for seed in seeds for method in jobs]
    return _score_table(candidates, stacked, runs,
                        [scores[method, fitted_seed[method, seed]] for seed, method in runs])


def _score_table(candidates: dict[str, pd.DataFrame], stacked: pd.DataFrame,
                 runs: list[tuple[int, str]], scores: list[np.ndarray]) -> pd.DataFrame:
    """:data:`SCORE_COLUMNS` of every (seed, method) run's ``scores`` of the ``stacked``
    candidates (each object's in slot order, objects in ``candidates``' order), built column by
    column; a NaN score or one of the wrong length is a ValueError naming the run."""
    for (seed, method), score in zip(runs, scores, strict=True):
        _checked(score, len(stacked), method, seed)
    sizes = [len(rows) for rows in candidates.values()]
    object_ids = np.repeat(np.array(list(candidates), dtype=object), sizes)
    slots = np.concatenate([np.arange(size, dtype=np.int64) for size in sizes])
    count = len(runs)
    return pd.DataFrame({
        "object_id": np.tile(object_ids, count),
        "seed": np.repeat(np.array([seed for seed, _ in runs], dtype=np.int64), len(stacked)),
        "method": np.repeat(np.array([method for _, method in runs], dtype=object), len(stacked)),
        "candidate": np.tile(slots, count),
        "grip_id": np.tile(stacked["grip_id"].astype(str).to_numpy(dtype=object), count),
        "score": np.concatenate(scores).astype(np.float64),
    })  # fmt: skip


Maker = Callable[[int], BaseEstimator]


def _jobs(train: pd.DataFrame, table: pd.DataFrame,
          config: Config) -> dict[str, tuple[Maker, np.ndarray]]:
    """Method → (estimator factory by seed, training target), for every configured learner."""
    learning = config.learning
    labels = train[LABEL_COLUMN].to_numpy().astype(bool)
    jobs = {f"classifier_{n}": (_maker(make_model, n), labels) for n in learning.models}
    if has_target(table):
        target = train[TARGET_COLUMN].to_numpy(float)
        jobs |= {f"regressor_{n}": (_maker(make_regressor, n), target)
                 for n in learning.regressors}  # fmt: skip
    grades = relevance(train, config.sim)
    return jobs | {f"ranker_{n}": (_maker(make_ranker, n), grades) for n in learning.rankers}


def seed_free(make: Maker) -> bool:
    """Whether no parameter of ``make(seed)`` depends on the seed: such a learner (fitted by a
    deterministic algorithm, as every registered one without a ``random_state`` is) gives the
    same scores for every seed."""
    return _plain_params(make(0)) == _plain_params(make(1))


def _plain_params(estimator: BaseEstimator) -> dict[str, object]:
    """The estimator's nested parameters that are values, not estimators or step lists."""
    return {key: value for key, value in estimator.get_params(deep=True).items()
            if not isinstance(value, BaseEstimator | list)}  # fmt: skip


def _fitted_scores(train: pd.DataFrame, stacked: pd.DataFrame, method: str, make: Maker,
                   target: np.ndarray, seed: int) -> np.ndarray:
    """The scores of every held-out candidate by ``make(seed)`` fitted on ``train``, in one
    call (row by row: a score never depends on the other rows of the call, except the chance
    baselines', which draw one seeded number a row)."""
    model = make(seed).fit(train, target)
    return _score(method, model, stacked)


def _maker(factory: Callable[..., BaseEstimator], name: str) -> Maker:
    return lambda seed: factory(name, seed, FEATURES)


def _score(method: str, model: BaseEstimator, rows: pd.DataFrame) -> np.ndarray:
    if method.startswith("classifier_"):
        return ranking_score(model, rows)
    return np.asarray(model.predict(rows), dtype=float)


def empty_scores() -> pd.DataFrame:
    """A score table with no rows and the columns' types."""
    return pd.DataFrame({
        "object_id": pd.Series(dtype=str), "seed": pd.Series(dtype=np.int64),
        "method": pd.Series(dtype=str), "candidate": pd.Series(dtype=np.int64),
        "grip_id": pd.Series(dtype=str), "score": pd.Series(dtype=np.float64),
    })  # fmt: skip


def write_scores(frames: Iterable[pd.DataFrame] | pd.DataFrame, path: str | Path) -> Path:
    """Concatenate and write a score table as Parquet; returns the path."""
    frame = frames if isinstance(frames, pd.DataFrame) else pd.concat(list(frames),
                                                                      ignore_index=True)
    missing = [c for c in SCORE_COLUMNS if c not in frame.columns]
    if missing:
        raise ValueError(f"score table lacks columns {missing}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    frame.loc[:, list(SCORE_COLUMNS)].to_parquet(path, index=False)
    return path
