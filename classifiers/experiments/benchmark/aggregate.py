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

``scripts/check_rliable.py`` checks them against rliable 1.2.0: identical point estimates,
intervals equal to Monte-Carlo error.

The leaderboard uses ``task_bootstrap=True``: the held-out objects are a sample of the objects a
robot meets, and the analytic baselines have one run, so resampling runs alone would give them a
zero-width interval. The runs-only interval (rliable's default) is reported beside it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

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


def paired_bootstraps(
    scores: Mapping[str, NDArray[np.float64]], reps: int = 2000, seed: int = 0,
    task_bootstrap: bool = True,
) -> dict[str, NDArray[np.float64]]:
    """Resamples ``(reps, runs, objects)`` of every method, with the same objects in each
    resample for all methods (runs drawn independently per method)."""
    matrices = {name: check_scores(m, name) for name, m in scores.items()}
    objects = {m.shape[1] for m in matrices.values()}
    if len(objects) != 1:
        raise ValueError(f"every method must score the same objects, got counts {sorted(objects)}")
    rng = np.random.default_rng(seed)
    tasks = object_resamples(objects.pop(), reps, rng, task_bootstrap)
    return {name: m[resample_indices(*m.shape, reps, rng, tasks)] for name, m in matrices.items()}


def estimate(point: NDArray[np.float64], resampled: NDArray[np.float64]) -> dict[str, object]:
    """``{"estimate", "ci"}``: the point value and the percentile interval of the resamples."""
    tail = 100 * (1 - CONFIDENCE) / 2
    low, high = np.percentile(resampled, [tail, 100 - tail], axis=0)
    return {"estimate": _plain(point), "ci": [_plain(low), _plain(high)]}


def _plain(value: NDArray[np.float64]) -> float | list[float]:
    array = np.asarray(value, dtype=float)
    return float(array) if array.ndim == 0 else array.tolist()
