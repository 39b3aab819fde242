"""How much of a label is the grip, how much the engine, how much the draws.

Within one object, a grip's trial outcome in an engine under a draw is modelled as

    y[g, e, k] = mu + G[g] + E[e] + D[k] + GE[g, e] + GD[g, k] + ED[e, k] + GED[g, e, k]

(g the grip, e the engine, k the draw; every grip meets draw k in both engines: common random
numbers). Only the terms that differ between grips of the object can reorder them: ``G`` (the
grip, the same in both engines), ``GE`` (the engine's own view of the grip) and ``GD + GED`` (how
a grip fares under one draw). Their variances come from the balanced three-way table's mean
squares (random effects, method of moments; Searle, Casella & McCulloch, *Variance Components*,
1992, ch. 4). A label is the mean of T trials in one engine, so between the grips of an object
its variance is ``var G + var GE + (var GD + var GED) / T``; the shares of these three terms are
how much of the label's differences between grips is the grip, the engine and the draws.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: The shares' order: the grip, the engine's view of it, the draws.
SHARES = ("grip", "engine", "draws")


def grip_components(outcomes: NDArray[np.float64]) -> NDArray[np.float64]:
    """The per-trial variances of ``G``, ``GE`` and ``GD + GED`` (unbiased, each may come out
    negative by chance) from one object's outcomes of shape (grips, engines, draws).

    Raises:
        ValueError: not a three-way table with at least two grips, engines and draws, or with
            values that are not finite.
    """
    y = np.asarray(outcomes, dtype=float)
    if y.ndim != 3 or min(y.shape) < 2:
        raise ValueError(f"outcomes must be (grips, engines, draws), each at least 2, got shape "
                         f"{y.shape}")
    if not np.isfinite(y).all():
        raise ValueError("outcomes hold NaN or infinite values")
    g, e, k = y.shape
    mean = y.mean()
    by_grip, by_engine, by_draw = y.mean((1, 2)), y.mean((0, 2)), y.mean((0, 1))
    grip_engine, grip_draw, engine_draw = y.mean(2), y.mean(1), y.mean(0)
    ms_grip = e * k * np.sum((by_grip - mean) ** 2) / (g - 1)
    ms_grip_engine = k * np.sum((grip_engine - by_grip[:, None] - by_engine + mean) ** 2) / (
        (g - 1) * (e - 1))
    ms_grip_draw = e * np.sum((grip_draw - by_grip[:, None] - by_draw + mean) ** 2) / (
        (g - 1) * (k - 1))
    residual = (y - grip_engine[:, :, None] - grip_draw[:, None, :] - engine_draw[None]
                + by_grip[:, None, None] + by_engine[None, :, None] + by_draw - mean)
    ms_residual = np.sum(residual**2) / ((g - 1) * (e - 1) * (k - 1))
    engine = (ms_grip_engine - ms_residual) / k
    draws_only = (ms_grip_draw - ms_residual) / e
    grip = (ms_grip - ms_grip_engine - ms_grip_draw + ms_residual) / (e * k)
    return np.array([grip, engine, draws_only + ms_residual])


def label_shares(components: NDArray[np.float64], trials: int) -> NDArray[np.float64]:
    """The shares (``SHARES``, summing to 1) of a ``trials``-trial label's variance between the
    grips of an object, from per-trial components (one object's, or several objects' summed).
    A component estimated below zero counts as zero. NaN when none is positive.

    Raises:
        ValueError: ``trials`` is not a positive integer.
    """
    if isinstance(trials, bool) or not isinstance(trials, (int, np.integer)) or trials < 1:
        raise ValueError(f"trials must be a positive integer, got {trials!r}")
    grip, engine, draws = np.asarray(components, dtype=float)
    parts = np.maximum([grip, engine, draws / trials], 0.0)
    total = parts.sum()
    return parts / total if total > 0 else np.full(3, np.nan)
