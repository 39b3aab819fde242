"""Which of an object's candidates a dataset keeps (``dataset.sampling``, DESIGN).

Keeping only the best grips by Q_C would truncate the range any comparison with Q_C is made on,
so by default the kept grips are a stratified sample of the object's Q_C ranking:

- ``stratified``: ``ceil(BEST_FRACTION * k)`` grips from the best end (lowest Q_C), the other
  ones one seeded pick in each of equal-rank strata that cover the rest of the ranking, down to
  the worst candidate;
- ``best``: the ``k`` lowest Q_C;
- ``uniform``: ``k`` ranks drawn uniformly without replacement.

The draw depends only on the object's sampling seed and its candidate table, never on workers.
Kept grips come in ranking order (best Q_C first).
"""

from __future__ import annotations

import math
from typing import get_args

import numpy as np
import pandas as pd

from grip_env.config import DatasetConfig

SAMPLING_METHODS: tuple[str, ...] = get_args(DatasetConfig.model_fields["sampling"].annotation)
#: Share of the kept grips that ``stratified`` takes from the best end of the Q_C ranking.
BEST_FRACTION = 0.25


def kept_ranks(available: int, keep: int, method: str, seed: int) -> np.ndarray:
    """Ranks (0 = best Q_C) of the grips kept out of ``available``, ascending.

    Raises:
        ValueError: unknown method, or negative counts.
    """
    if method not in SAMPLING_METHODS:
        raise ValueError(f"unknown sampling {method!r}; choose from {', '.join(SAMPLING_METHODS)}")
    if available < 0 or keep < 0:
        raise ValueError(f"counts must be >= 0, got available={available}, keep={keep}")
    if keep >= available:
        return np.arange(available)
    if method == "best":
        return np.arange(keep)
    rng = np.random.default_rng(seed)
    if method == "uniform":
        return np.sort(rng.choice(available, size=keep, replace=False))
    best = math.ceil(BEST_FRACTION * keep)
    rest = keep - best
    if rest == 0:
        return np.arange(best)
    # rest strata of (almost) equal size over ranks best .. available-1: never empty
    edges = best + (np.arange(rest + 1) * (available - best)) // rest
    picks = edges[:-1] + (rng.random(rest) * np.diff(edges)).astype(np.int64)
    return np.concatenate([np.arange(best), picks])


def keep_grips(table: pd.DataFrame, dataset: DatasetConfig, seed: int) -> pd.DataFrame:
    """The rows of a candidate table that the dataset keeps, best Q_C first."""
    ranked = table.sort_values("Q_C", kind="stable")
    ranks = kept_ranks(len(ranked), dataset.max_grips_per_object, dataset.sampling, seed)
    return ranked.iloc[ranks]


def sampling_record(dataset: DatasetConfig) -> dict[str, object]:
    """What the manifest records about the choice of kept grips."""
    return {
        "method": dataset.sampling,
        "max_grips_per_object": dataset.max_grips_per_object,
        "best_fraction": BEST_FRACTION if dataset.sampling == "stratified" else None,
        "ranked_by": "Q_C",
    }
