"""How a label's within-object repeatability grows with its trials, measured rather than modelled.

An object run twice (2T trials a grip) holds every split of its trials into two disjoint sets of
n <= T: the Spearman between the grips' mean robustness over one set and over the other is the
within-object retest of an n-trial label, measured. Averaged over seeded splits and then over
objects, it gives the retest at 1..T trials a grip without Spearman-Brown's assumption that one
reliability holds for every object. Objects differ (grips of very different quality rank alike
after one trial; near-equal grips need many), and the mean over objects of each object's
Spearman-Brown curve rises more slowly than Spearman-Brown applied to the mean: from one trial
it overstates the retest at five, from five it understates it at three (BENCHMARKS.md, "The
trials a label needs, measured").
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.stats import rankdata

#: The within-object retest a trustworthy label reaches (the labels' target, BENCHMARKS.md).
TRUSTWORTHY = 0.8
#: Seeded splits of an object's trials averaged at each label size.
SPLITS = 200


def trials_for(retest: float, trials: int, target: float = TRUSTWORTHY) -> float:
    """Trials a grip whose mean reaches a within-object retest of ``target``, from the retest
    measured at ``trials`` a grip (Spearman-Brown: the trials' labels average as independent
    draws, as BENCHMARKS.md found on the standard dataset). NaN when not measured, inf when the
    measured retest is not positive."""
    if not math.isfinite(retest):
        return float("nan")
    if retest <= 0:
        return float("inf")
    if retest >= 1:
        return 1.0
    single = retest / (trials - (trials - 1) * retest)
    return target * (1 - single) / ((1 - target) * single)


def retest_curve(outcomes: Sequence[NDArray[np.float64]], splits: int = SPLITS,
                 seed: int = 0) -> NDArray[np.float64]:
    """Mean within-object retest of an n-trial label, n = 1..T, from each object's
    ``(grips, 2T)`` robustness matrix: the Spearman between the grips' means over two disjoint
    random sets of n trials, averaged over ``splits`` seeded splits (the same for every object
    with as many trials) and then over objects, skipping the splits and objects where it is
    undefined (grips all alike). NaN where no object defines it."""
    if splits < 1:
        raise ValueError(f"a retest curve needs 1 or more splits, got {splits}")
    if not outcomes:
        return np.array([])
    size = min(m.shape[1] for m in outcomes) // 2
    if size < 1:
        raise ValueError(f"a retest curve needs 2 or more trials a grip, got {2 * size}")
    order = split_order(splits, 2 * size, seed)
    per_object = np.array([_object_curve(np.asarray(m, float)[:, :2 * size], order)
                           for m in outcomes])
    defined = np.isfinite(per_object)
    total = np.where(defined, per_object, 0.0).sum(axis=0)
    count = defined.sum(axis=0)
    return np.divide(total, count, out=np.full(size, np.nan), where=count > 0)


def split_order(splits: int, trials: int, seed: int) -> NDArray[np.int64]:
    """``splits`` seeded random orders of ``trials`` trials, (splits, trials): the same for
    every object with as many trials."""
    return np.random.default_rng(seed).random((splits, trials)).argsort(axis=1)


def _object_curve(matrix: NDArray[np.float64], order: NDArray[np.int64]) -> NDArray[np.float64]:
    """One object's retest at n = 1..T, each the mean over the splits that define it."""
    size = order.shape[1] // 2
    curve = np.full(size, np.nan)
    if matrix.shape[0] < 2:
        return curve
    for n in range(1, size + 1):
        first = matrix[:, order[:, :n]].mean(axis=2)  # (grips, splits)
        second = matrix[:, order[:, n:2 * n]].mean(axis=2)
        rho = _column_spearman(first, second)
        if np.isfinite(rho).any():
            curve[n - 1] = float(np.nanmean(rho))
    return curve


def _column_spearman(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Spearman between ``a[:, j]`` and ``b[:, j]`` for every column j (average ranks for ties;
    NaN where either column is constant)."""
    ra, rb = (rankdata(x, axis=0) for x in (a, b))
    ra -= ra.mean(axis=0)
    rb -= rb.mean(axis=0)
    norm = np.sqrt((ra**2).sum(axis=0) * (rb**2).sum(axis=0))
    flat = (np.ptp(a, axis=0) == 0) | (np.ptp(b, axis=0) == 0)
    return np.where(flat, np.nan, (ra * rb).sum(axis=0) / np.where(flat, 1.0, norm))


def trials_measured(curve: Sequence[float], target: float) -> float:
    """The fewest trials whose measured retest reaches ``target``; when none of the curve's does,
    Spearman-Brown from its last point (a trial count beyond the measured ones). NaN for a curve
    not measured."""
    values = np.asarray(curve, float)
    if not len(values) or not np.isfinite(values[-1]):
        return float("nan")
    reached = np.flatnonzero(values >= target)
    if len(reached):
        return float(reached[0] + 1)
    needed = trials_for(float(values[-1]), len(values), target)
    return max(needed, float(len(values))) if math.isfinite(needed) else needed
