"""Aggregates over runs and objects, as rliable computes them (Agarwal et al., NeurIPS 2021).

A method's scores form a matrix ``(runs, objects)``: one row per training seed, one column per
held-out object (rliable's "tasks"). Written here, not imported (rliable pulls in arch and
seaborn); the estimators and the resampling scheme are rliable's:

- :func:`iqm`: interquartile mean, ``scipy.stats.trim_mean(scores, 0.25, axis=None)`` over all
  runs x objects (``int(0.25 n)`` values cut from each end);
- :func:`probability_of_improvement`: per object, ``P(X > Y) + P(X = Y) / 2`` over all pairs of
  runs (the Mann-Whitney U statistic over ``n_x n_y``), averaged over objects;
- :func:`performance_profile`: fraction of runs x objects whose score exceeds each ``tau``;
- :func:`stratified_bootstrap`: rliable's ``StratifiedBootstrap``: within each object (the
  stratum) the runs are resampled with replacement; with ``task_bootstrap=True`` the objects are
  resampled too (the same objects for every method, so comparisons stay paired). The interval
  is the percentile interval of the statistic over the resamples.

Several methods resampled together (:func:`paired_bootstraps`) draw from streams keyed by what
the resample is of, never from one generator consumed method after method: the resampled objects
from a stream keyed by the seed and the object ids (shared by every method: comparisons stay
paired over the same objects), each method's runs within those objects from a stream keyed by
the seed, the object ids and the method's name (:func:`keyed_generator`). A method's interval,
and its paired difference to the reference, then depend only on its scores, the reference's,
the objects and the seed: not on which other methods are on the board, nor on their order.
Runs get a stream of their own per method because runs of two methods are independent
trainings: there is no pairing to keep between seed i of one and seed i of another.

``scripts/check_rliable.py`` checks them against rliable 1.2.0: identical point estimates,
intervals equal to Monte-Carlo error.

The leaderboard uses ``task_bootstrap=True``: the held-out objects are a sample of the objects a
robot meets, and the analytic baselines have one run, so resampling runs alone would give them a
zero-width interval. The runs-only interval (rliable's default) is reported beside it.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.stats import trim_mean

Statistic = Callable[[NDArray[np.float64]], NDArray[np.float64]]
CONFIDENCE = 0.95


def check_scores(scores: NDArray[np.float64], name: str = "scores") -> NDArray[np.float64]:
    """A finite ``(runs, objects)`` matrix with at least one run and one object."""
    matrix = np.asarray(scores, dtype=float)
    if matrix.ndim != 2 or 0 in matrix.shape:
        raise ValueError(f"{name} must be a (runs, objects) matrix, got shape {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise ValueError(f"{name} holds NaN or infinite values")
    return matrix


def iqm(scores: NDArray[np.float64]) -> NDArray[np.float64]:
    """Interquartile mean over the last two axes (runs, objects); leading axes are resamples."""
    scores = np.asarray(scores, dtype=float)
    flat = scores.reshape(*scores.shape[:-2], -1)
    return np.asarray(trim_mean(flat, 0.25, axis=-1))


def mean(scores: NDArray[np.float64]) -> NDArray[np.float64]:
    """Mean over the last two axes (runs, objects)."""
    return np.asarray(np.mean(scores, axis=(-2, -1)))


def probability_of_improvement(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[
        np.float64]:  # fmt: skip
    """P(X > Y) of rliable: per object over all run pairs (ties count 1/2), mean over objects.

    ``x`` is ``(..., runs_x, objects)``, ``y`` is ``(..., runs_y, objects)``.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    a, b = x[..., :, None, :], y[..., None, :, :]
    wins = (a > b) + 0.5 * (a == b)
    return np.asarray(wins.mean(axis=(-3, -2)).mean(axis=-1))


def performance_profile(scores: NDArray[np.float64], taus: NDArray[np.float64]) -> NDArray[
        np.float64]:  # fmt: skip
    """Fraction of runs x objects with score > tau, for each tau (last axis)."""
    scores = np.asarray(scores, dtype=float)
    flat = scores.reshape(*scores.shape[:-2], -1)
    return np.mean(flat[..., None, :] > np.asarray(taus)[:, None], axis=-1)


def resample_indices(runs: int, objects: int, reps: int, rng: np.random.Generator,
                     object_index: NDArray[np.intp] | None = None) -> tuple[NDArray, NDArray]:
    """Index arrays ``(reps, runs, objects)`` into a scores matrix: runs drawn within each
    (possibly resampled) object, as ``StratifiedBootstrap`` draws them."""
    run_index = rng.integers(runs, size=(reps, runs, objects))
    if object_index is None:
        object_index = np.broadcast_to(np.arange(objects), (reps, objects))
    return run_index, np.broadcast_to(object_index[:, None, :], (reps, runs, objects))


def object_resamples(objects: int, reps: int, rng: np.random.Generator,
                     task_bootstrap: bool = True) -> NDArray[np.intp] | None:
    """The objects of each resample, shared by every method (None: objects kept)."""
    return rng.integers(objects, size=(reps, objects)) if task_bootstrap else None


def stratified_bootstrap(
    scores: NDArray[np.float64], statistic: Statistic, reps: int = 2000, seed: int = 0,
    task_bootstrap: bool = True,
) -> dict[str, object]:
    """Point estimate and 95 % percentile interval of ``statistic`` on ``scores``."""
    matrix = check_scores(scores)
    rng = np.random.default_rng(seed)
    runs, objects = matrix.shape
    tasks = object_resamples(objects, reps, rng, task_bootstrap)
    index = resample_indices(runs, objects, reps, rng, tasks)
    return estimate(statistic(matrix), statistic(matrix[index]))


def keyed_generator(seed: int, *key: object) -> np.random.Generator:
    """A generator whose stream is fixed by ``seed`` and ``key`` alone (their text, hashed with
    SHA-256: the same on every machine and Python, unlike ``hash``)."""
    digest = hashlib.sha256(json.dumps([str(part) for part in key]).encode()).digest()
    words = np.frombuffer(digest, dtype=np.uint32).tolist()
    return np.random.default_rng(np.random.SeedSequence([int(seed), *words]))


def paired_bootstraps(
    scores: Mapping[str, NDArray[np.float64]], reps: int = 2000, seed: int = 0,
    task_bootstrap: bool = True, objects: Sequence[str] | None = None,
) -> dict[str, NDArray[np.float64]]:
    """Resamples ``(reps, runs, objects)`` of every method: the same resampled objects for all
    methods (a stream keyed by ``seed`` and ``objects``, the matrices' column ids; default their
    positions), each method's runs from a stream keyed by ``seed``, ``objects`` and its name. A
    method's resamples are the same whatever other methods are passed with it, in any order."""
    matrices = {name: check_scores(m, name) for name, m in scores.items()}
    counts = {m.shape[1] for m in matrices.values()}
    if len(counts) != 1:
        raise ValueError(f"every method must score the same objects, got counts {sorted(counts)}")
    count = counts.pop()
    ids = [str(i) for i in (range(count) if objects is None else objects)]
    if len(ids) != count:
        raise ValueError(f"{len(ids)} object ids for matrices of {count} objects")
    tasks = object_resamples(count, reps, keyed_generator(seed, "objects", *ids), task_bootstrap)
    return {name: m[resample_indices(*m.shape, reps, keyed_generator(seed, "runs", name, *ids),
                                     tasks)]
            for name, m in matrices.items()}  # fmt: skip


def estimate(point: NDArray[np.float64], resampled: NDArray[np.float64]) -> dict[str, object]:
    """``{"estimate", "ci"}``: the point value and the percentile interval of the resamples."""
    tail = 100 * (1 - CONFIDENCE) / 2
    low, high = np.percentile(resampled, [tail, 100 - tail], axis=0)
    return {"estimate": _plain(point), "ci": [_plain(low), _plain(high)]}


def _plain(value: NDArray[np.float64]) -> float | list[float]:
    array = np.asarray(value, dtype=float)
    return float(array) if array.ndim == 0 else array.tolist()
