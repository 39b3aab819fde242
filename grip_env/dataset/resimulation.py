"""``resimulate``: does a dataset hold what this code makes from its recipe? ``retest``: do its
labels rank one object's grips the same under new draws?

A seeded sample of a dataset's objects is planned again (perception, synthesis and the kept-grip
sampling, with the dataset's own config and object seeds) and a seeded sample of their recorded
grips is simulated again (the dataset's trials and seed). Both are compared bit for bit with what
the dataset holds: a reviewer reproducing a published label expects the same numbers, not close
ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TypeVar

import numpy as np
import pandas as pd

from grip_env.columns import DESCRIPTORS, FEATURES, INDEXES, ROBUSTNESS
from grip_env.config import Config
from grip_env.dataset.backends import in_this_process, worker_context
from grip_env.dataset.catalog import load_objects
from grip_env.dataset.jobs import ObjectTask, kept_grips
from grip_env.dataset.loading import load
from grip_env.dataset.manifest import read_manifest
from grip_env.progress import progress_bar

#: Grips re-simulated per sampled object (the sample spreads over N / this many objects).
GRIPS_PER_OBJECT = 5
#: The recorded outcome columns a re-simulated grip must reproduce exactly.
OUTCOME_COLUMNS = ("trials", "successes", *ROBUSTNESS)


@dataclass
class Resimulation:
    """What a re-simulation found; every count is of exact (bit-identical) agreement."""

    objects: int = 0
    candidates_identical: int = 0  # objects whose kept grips were planned again identically
    grips: int = 0
    outcomes_identical: int = 0  # grips whose trials, successes and robustness repeat exactly
    differences: list[str] = field(default_factory=list)

    @property
    def identical(self) -> bool:
        return (self.candidates_identical == self.objects and self.outcomes_identical == self.grips)

    def summary(self) -> str:
        return (f"re-planned {self.objects} objects: candidates identical on "
                f"{self.candidates_identical}; re-simulated {self.grips} grips: outcomes "
                f"identical on {self.outcomes_identical}")


_Item = TypeVar("_Item")
_Result = TypeVar("_Result")


def _map(
    function: Callable[[_Item], _Result], items: Sequence[_Item], workers: int, description: str
) -> list[_Result]:
    """``function`` over ``items`` in order: in this process, or on up to ``workers`` fresh
    worker processes (:func:`~grip_env.dataset.backends.in_this_process`); a progress bar named
    ``description`` counts the items done (shown under :func:`grip_env.progress.shown`)."""
    with progress_bar(len(items), description) as bar:
        if in_this_process(1 if len(items) < 2 else workers):
            results = []
            for item in items:
                results.append(function(item))
                bar.advance()
            return results
        size = max(1, min(workers, len(items)))
        with ProcessPoolExecutor(size, mp_context=worker_context()) as pool:
            futures = [pool.submit(function, item) for item in items]
            for _ in as_completed(futures):
                bar.advance()
            return [future.result() for future in futures]


@dataclass(frozen=True)
class _ObjectCheck:
    task: ObjectTask
    recorded: pd.DataFrame  # the object's rows in the dataset
    picked: tuple[int, ...]  # positions (in ``recorded``) of the grips to simulate again


def resimulate(path: str | Path, grips: int, seed: int = 0, workers: int = 1) -> Resimulation:
    """Plan again a seeded sample of the dataset's objects and simulate again ``grips`` of their
    recorded grips (about :data:`GRIPS_PER_OBJECT` an object), comparing both exactly.

    Raises:
        ValueError: ``grips`` is not a positive integer, the dataset is unfinished or unreadable,
            or its objects table lacks an object the sample asks for.
    """
    if isinstance(grips, bool) or not isinstance(grips, int | np.integer) or grips < 1:
        raise ValueError(f"--resimulate takes a positive number of grips, got {grips!r}")
    directory = Path(path)
    checks = _sample(directory, int(grips), seed)
    result = Resimulation()
    found = _map(_check_object, checks, workers, "resimulate")
    for check, (same_candidates, same_outcomes, notes) in zip(checks, found, strict=True):
        result.objects += 1
        result.candidates_identical += same_candidates
        result.grips += len(check.picked)
        result.outcomes_identical += same_outcomes
        result.differences += notes
    return result


def _sample(directory: Path, grips: int, seed: int) -> list[_ObjectCheck]:
    """The objects (seeded order) and grips (seeded, ``GRIPS_PER_OBJECT`` at most each) to check."""
    manifest = read_manifest(directory)
    table = load(directory)
    ids = list(pd.unique(table["object_id"]))
    rng = np.random.default_rng(seed)
    order = [ids[i] for i in rng.permutation(len(ids))]
    chosen = order[: min(len(order), math.ceil(grips / GRIPS_PER_OBJECT))]
    checks = _checks(directory, manifest, table, chosen)
    share = _shares(grips, [len(check.recorded) for check in checks])
    return [replace(check, picked=tuple(sorted(
        rng.choice(len(check.recorded), count, replace=False).tolist())))
        for check, count in zip(checks, share, strict=True)]


def _shares(grips: int, available: list[int]) -> list[int]:
    """Grips per object: ``grips`` spread as evenly as the objects' grip counts allow."""
    share = [0] * len(available)
    left = grips
    while left > 0 and any(s < a for s, a in zip(share, available, strict=True)):
        for i, count in enumerate(available):
            if left > 0 and share[i] < count:
                share[i] += 1
                left -= 1
    return share


def _index(manifest: dict, object_id: str) -> int:
    return next(int(e["index"]) for e in manifest["objects"] if e["object_id"] == object_id)


def _check_object(check: _ObjectCheck) -> tuple[bool, int, list[str]]:
    """(candidates identical, grips whose outcomes are identical, what differed)."""
    from grip_env.sim import run_trials

    task, recorded, config = check.task, check.recorded, check.task.config
    notes = []
    kept = kept_grips(task)
    planned_alike = same_candidates(kept, recorded)
    if not planned_alike:
        notes.append(f"{task.object_id}: the candidates planned again differ from the recorded")
    grips = recorded.iloc[list(check.picked)]
    outcome = run_trials(task.obj, _as_planned(grips, kept, task.object_id), config,
                         config.dataset.trials, config.dataset.seed)
    same = np.ones(len(grips), dtype=bool)
    for name in OUTCOME_COLUMNS:
        same &= np.asarray(outcome[name]) == grips[name].to_numpy()
    notes += [f"{grip}: the outcome simulated again differs from the recorded"
              for grip in grips["grip_id"][~same]]
    return planned_alike, int(same.sum()), notes


def _as_planned(grips: pd.DataFrame, kept: pd.DataFrame, object_id: str) -> pd.DataFrame:
    """The recorded grips with the grip ids the generation simulated them under (the planner's
    ``<contour name>/<local id>``; a per-grip draw scheme keys on it) and the dataset's object id
    (the common draws' key)."""
    owner = str(kept["object_id"].iloc[0]) if len(kept) else object_id
    local = [str(g).removeprefix(f"{object_id}/") for g in grips["grip_id"]]
    return grips.assign(grip_id=[f"{owner}/{g}" for g in local], object_id=object_id)


def same_candidates(kept: pd.DataFrame, recorded: pd.DataFrame) -> bool:
    """Whether the re-planned kept grips equal the recorded ones, bit for bit, in order."""
    numeric = list(DESCRIPTORS + FEATURES + INDEXES)
    if len(kept) != len(recorded):
        return False
    a = kept[numeric].to_numpy(float)
    b = recorded[numeric].to_numpy(float)
    return bool(np.array_equal(a, b, equal_nan=True))


#: Objects with fewer kept grips (or tied labels) give no within-object Spearman.
MIN_RETEST_GRIPS = 4
#: Bootstrap resamples (over objects) of the within-object retest's interval.
BOOTSTRAP = 2000


@dataclass
class Retest:
    """Within-object test-retest of a dataset's labels: the recorded mean robustness against
    the mean over as many new trials (draws ``trials``..``2 trials - 1``)."""

    objects: int
    scored: int  # objects with at least MIN_RETEST_GRIPS grips and untied labels
    grips: int
    within: float  # mean over scored objects of the Spearman between recorded and retest
    interval: tuple[float, float]  # 95 % bootstrap interval over objects
    pooled: float  # Spearman over all retested grips

    def summary(self) -> str:
        low, high = self.interval
        return (f"within-object retest {self.within:.2f} [{low:.2f}, {high:.2f}] over "
                f"{self.scored} of {self.objects} objects ({self.grips} grips), pooled "
                f"{self.pooled:.2f}")


def retest(path: str | Path, objects: int, seed: int = 0, workers: int = 1) -> Retest:
    """Simulate every recorded grip of a seeded sample of ``objects`` objects again under new
    draws (trials ``T``..``2T - 1``) and compare the grips' order within each object.

    Raises:
        ValueError: ``objects`` is not a positive integer, or the dataset is unreadable.
    """
    checks = _retest_sample(Path(path), objects, seed)
    means = _map(_retest_means, checks, workers, "retest")
    return _retest_figures(checks, means, seed)


def retest_sample(path: str | Path, objects: int,
                  seed: int = 0) -> list[tuple[ObjectTask, pd.DataFrame]]:
    """The objects :func:`retest` simulates again: a seeded sample of ``objects`` objects with
    at least :data:`MIN_RETEST_GRIPS` grips, each as (the task that planned it, its recorded
    rows).

    Raises:
        ValueError: as :func:`retest`.
    """
    return [(check.task, check.recorded) for check in _retest_sample(Path(path), objects, seed)]


def _retest_sample(directory: Path, objects: int, seed: int) -> list[_ObjectCheck]:
    if isinstance(objects, bool) or not isinstance(objects, int | np.integer) or objects < 1:
        raise ValueError(f"--retest takes a positive number of objects, got {objects!r}")
    manifest = read_manifest(directory)
    table = load(directory, allow_partial=True)
    sizes = table.groupby("object_id", sort=False).size()
    eligible = sizes.index[sizes >= MIN_RETEST_GRIPS].tolist()
    rng = np.random.default_rng(seed)
    chosen = [eligible[i] for i in rng.permutation(len(eligible))[: int(objects)]]
    return _checks(directory, manifest, table, chosen)


def recorded_objects(directory: str | Path, table: pd.DataFrame,
                     object_ids: Sequence[str]) -> list[tuple[ObjectTask, pd.DataFrame]]:
    """Each of ``object_ids`` as (the task that planned it, its rows of ``table``, the dataset
    ``directory`` loaded).

    Raises:
        ValueError: the dataset's objects table lacks one of them.
    """
    directory = Path(directory)
    checks = _checks(directory, read_manifest(directory), table, list(object_ids))
    return [(check.task, check.recorded) for check in checks]


def _checks(directory: Path, manifest: dict, table: pd.DataFrame,
            chosen: list[str]) -> list[_ObjectCheck]:
    """Every recorded grip of the ``chosen`` objects, with the task that planned them.

    Raises:
        ValueError: the objects table lacks one of them.
    """
    config = Config.model_validate(manifest["config"])
    objects = {obj.name: obj for obj in load_objects(directory)}
    lacking = [object_id for object_id in chosen if object_id not in objects]
    if lacking:
        raise ValueError(f"dataset {directory}: its objects table lacks {lacking[0]!r} "
                         f"(and {len(lacking) - 1} more), so it cannot be re-planned")
    seeds = {entry["object_id"]: entry["seed"] for entry in manifest["objects"]}
    checks = []
    for object_id in chosen:
        rows = table[table["object_id"] == object_id].reset_index(drop=True)
        task = ObjectTask(_index(manifest, object_id), object_id, objects[object_id], config,
                          seeds[object_id])
        checks.append(_ObjectCheck(task, rows, tuple(range(len(rows)))))
    return checks


def _retest_means(check: _ObjectCheck) -> np.ndarray:
    """Each recorded grip's mean robustness over trials T..2T-1 (the same draws as a dataset
    made with trial_offset T)."""
    from grip_env.sim import run_trial_outcomes

    config, trials = check.task.config, check.task.config.dataset.trials
    grips = check.recorded.assign(object_id=check.task.object_id)
    outcome = run_trial_outcomes(check.task.obj, grips.reset_index(drop=True), config, trials,
                                 config.dataset.seed, trial_offset=trials)
    return outcome.groupby("grip", sort=True)["robustness"].mean().to_numpy()


def _retest_figures(checks: list[_ObjectCheck], means: list[np.ndarray], seed: int) -> Retest:
    from scipy import stats

    scores, recorded_all, retest_all = [], [], []
    for check, again in zip(checks, means, strict=True):
        recorded = check.recorded["robustness_mean"].to_numpy()
        recorded_all.append(recorded)
        retest_all.append(again)
        if np.ptp(recorded) > 0 and np.ptp(again) > 0:
            scores.append(float(stats.spearmanr(recorded, again).statistic))
    scored = np.asarray(scores)
    rng = np.random.default_rng(seed)
    if len(scored):
        boot = rng.choice(scored, (BOOTSTRAP, len(scored))).mean(axis=1)
        interval = (float(np.quantile(boot, 0.025)), float(np.quantile(boot, 0.975)))
        within = float(scored.mean())
    else:
        interval, within = (float("nan"), float("nan")), float("nan")
    pooled = (float(stats.spearmanr(np.concatenate(recorded_all),
                                    np.concatenate(retest_all)).statistic)
              if checks else float("nan"))
    return Retest(len(checks), len(scored), int(sum(len(c.recorded) for c in checks)), within,
                  interval, pooled)
