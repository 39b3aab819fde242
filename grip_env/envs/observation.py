"""Feature vectors the agents see: feature subsets, normalisation, truncation and padding.

Every object's candidates become one :class:`CandidateSet` of fixed-size arrays at construction,
so ``reset`` and ``step`` only index numpy arrays.

Normalisation (``normalize=``):

- ``"log"`` (default): signed ``log1p``, ``sign(x) * log1p(|x|)``. The features are capped at
  ``feature_cap`` (DESIGN), so this maps them into ``[-log1p(cap), log1p(cap)]`` with no data.
- ``"standard"``: ``(x - mean) / std`` with mean and std of the candidates of the environment's
  own objects (its split), each feature on its own (std 0 counts as 1).
- ``"none"``: the raw features.

Truncation keeps the ``max_candidates`` best candidates by ``Q_C``, i.e. the lowest values (the
paper's features are 0 at best; ties keep table order); padded slots hold zeros and are masked out.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from grip_env.columns import CONTACTS, FEATURES, INDEXES

NORMALIZATIONS: tuple[str, ...] = ("log", "standard", "none")
FEATURE_CHOICES: tuple[str, ...] = FEATURES + INDEXES
# Largest value each feature can take, in units of feature_cap: Q_G sums six, Q_C ten.
_CAP_MULTIPLE = {**dict.fromkeys(FEATURES, 1.0), "Q_G": 6.0, "Q_C": 10.0}


def feature_subset(features: Sequence[str] | None) -> tuple[str, ...]:
    """Validated feature names (default: the twelve S1..C6)."""
    if features is None:
        return FEATURES
    names = (features,) if isinstance(features, str) else tuple(features)
    unknown = [name for name in names if name not in FEATURE_CHOICES]
    if unknown or not names:
        raise ValueError(f"features must be a non-empty subset of {FEATURE_CHOICES}, got {names!r}")
    if len(set(names)) != len(names):
        raise ValueError(f"features must not repeat a name, got {names!r}")
    return names


@dataclass(frozen=True)
class FeatureScaler:
    """Maps raw feature rows to the observation's scale (see the module docstring)."""

    method: str
    names: tuple[str, ...]
    cap: float
    mean: NDArray[np.float64]
    std: NDArray[np.float64]

    @classmethod
    def fit(
        cls, method: str, names: tuple[str, ...], cap: float, raw: NDArray[np.float64] | None
    ) -> FeatureScaler:
        """A scaler for ``method``; ``raw`` (n, F) rows are needed only by ``"standard"``."""
        if method not in NORMALIZATIONS:
            raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {method!r}")
        width = len(names)
        mean, std = np.zeros(width), np.ones(width)
        if method == "standard":
            if raw is None or len(raw) == 0:
                raise ValueError("normalize='standard' needs at least one candidate to fit on")
            mean = raw.mean(axis=0)
            std = np.where(raw.std(axis=0) > 0, raw.std(axis=0), 1.0)
        return cls(method, names, float(cap), mean, std)

    def transform(self, raw: NDArray[np.float64]) -> NDArray[np.float32]:
        """(n, F) raw features to float32 observations, clipped to :meth:`bounds`."""
        low, high = self.bounds()
        return np.clip(self._scale(np.asarray(raw, dtype=np.float64)), low, high).astype(np.float32)

    def bounds(self) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
        """Per-feature (low, high) of the transformed values."""
        top = self.cap * np.array([_CAP_MULTIPLE[name] for name in self.names])
        low, high = self._scale(-top[None, :])[0], self._scale(top[None, :])[0]
        return low.astype(np.float32), high.astype(np.float32)

    def _scale(self, raw: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.method == "log":
            return np.sign(raw) * np.log1p(np.abs(raw))
        if self.method == "standard":
            return (raw - self.mean) / self.std
        return raw


@dataclass(frozen=True)
class CandidateSet:
    """One object's candidates as padded arrays; row ``i < count`` has the i-th lowest ``Q_C``.

    Attributes:
        object_id: the object's id.
        count: number of real candidates (``<= max_candidates``).
        features: (K, F) float32 normalised features, zero in padded slots.
        mask: (K,) int8, 1 for real candidates.
        q_c: (K,) float64 ``Q_C`` (NaN in padded slots).
        success_rate: (K,) float64 recorded success rate (NaN when unknown, e.g. live).
        contacts: (K, 3, 2) float64 contact points P1..P3 in mm (for drawing).
        grip_ids: ``grip_id`` of each real candidate.
        rows: the kept candidate rows (all columns), for backends that execute them.
    """

    object_id: str
    count: int
    features: NDArray[np.float32]
    mask: NDArray[np.int8]
    q_c: NDArray[np.float64]
    success_rate: NDArray[np.float64]
    contacts: NDArray[np.float64]
    grip_ids: tuple[Any, ...]
    rows: pd.DataFrame


def best_candidates(frame: pd.DataFrame, max_candidates: int) -> pd.DataFrame:
    """The ``max_candidates`` best rows by ``Q_C`` (lowest first, stable for ties)."""
    ordered = frame.sort_values("Q_C", ascending=True, kind="mergesort")
    return ordered.head(max_candidates).reset_index(drop=True)


def raw_features(frame: pd.DataFrame, names: tuple[str, ...]) -> NDArray[np.float64]:
    """(n, F) raw feature values of ``frame``'s rows."""
    missing = [name for name in names if name not in frame.columns]
    if missing:
        raise ValueError(f"candidate table lacks feature columns {missing}")
    return _columns(frame, names)


def _columns(frame: pd.DataFrame, names: tuple[str, ...]) -> NDArray[np.float64]:
    """(n, len(names)) float64 values, column by column: on the dataset's wide rows a ``.loc``
    column selection costs a millisecond, and an environment selects on every object."""
    values = np.empty((len(frame), len(names)))
    for j, name in enumerate(names):
        values[:, j] = frame[name].to_numpy(dtype=np.float64)
    return values


def candidate_set(
    object_id: str, frame: pd.DataFrame, scaler: FeatureScaler, max_candidates: int
) -> CandidateSet:
    """Pad one object's candidate rows into a :class:`CandidateSet` of ``max_candidates`` slots."""
    return candidate_sets([object_id], [frame], scaler, max_candidates)[0]


def candidate_sets(
    object_ids: Sequence[str], frames: Sequence[pd.DataFrame], scaler: FeatureScaler,
    max_candidates: int,
) -> list[CandidateSet]:
    """:func:`candidate_set` of every object at once: one sort, one scaling and one column read
    for all of them (an environment on the standard dataset builds hundreds)."""
    if len(object_ids) != len(frames):
        raise ValueError(f"{len(object_ids)} object ids for {len(frames)} candidate tables")
    if not frames:
        return []
    sizes = np.array([len(frame) for frame in frames])
    table = pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]
    owner = np.repeat(np.arange(len(frames)), sizes)
    order = np.lexsort((table["Q_C"].to_numpy(dtype=np.float64), owner))  # stable, NaN last
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    kept = order[np.arange(len(order)) - np.repeat(starts, sizes) < max_candidates]
    rows = table.iloc[kept].reset_index(drop=True)
    features = scaler.transform(raw_features(rows, scaler.names))
    q_c = rows["Q_C"].to_numpy(dtype=np.float64)
    rate, contacts = _success_rate(rows), _columns(rows, CONTACTS).reshape(-1, 3, 2)
    grip_ids = rows["grip_id"].tolist()
    counts = np.minimum(sizes, max_candidates)
    bounds = np.concatenate([[0], np.cumsum(counts)])
    return [
        _padded_set(str(object_id), rows.iloc[a:b].reset_index(drop=True), features[a:b],
                    q_c[a:b], rate[a:b], contacts[a:b], tuple(grip_ids[a:b]), max_candidates)
        for object_id, a, b in zip(object_ids, bounds[:-1], bounds[1:], strict=True)
    ]  # fmt: skip


def _padded_set(
    object_id: str, rows: pd.DataFrame, features: NDArray[np.float32], q_c: NDArray[np.float64],
    rate: NDArray[np.float64], contacts: NDArray[np.float64], grip_ids: tuple[Any, ...],
    size: int,
) -> CandidateSet:
    """One object's kept candidates padded to ``size`` slots, read-only."""
    count = len(rows)
    padded_features = np.zeros((size, features.shape[1]), dtype=np.float32)
    padded_features[:count] = features
    mask = np.zeros(size, dtype=np.int8)
    mask[:count] = 1
    padded_contacts = np.zeros((size, 3, 2))
    padded_contacts[:count] = contacts
    arrays = (padded_features, mask, _padded(q_c, size), _padded(rate, size), padded_contacts)
    for array in arrays:
        array.flags.writeable = False  # shared by every episode on this object
    return CandidateSet(object_id, count, *arrays, grip_ids=grip_ids, rows=rows)


def _success_rate(rows: pd.DataFrame) -> NDArray[np.float64]:
    if "successes" in rows.columns and "trials" in rows.columns:
        trials = rows["trials"].to_numpy(dtype=np.float64)
        if np.any(trials <= 0):
            raise ValueError("every recorded grip needs trials >= 1")
        return rows["successes"].to_numpy(dtype=np.float64) / trials
    if "success_rate" in rows.columns:
        return rows["success_rate"].to_numpy(dtype=np.float64)
    return np.full(len(rows), np.nan)


def _padded(values: NDArray[np.float64], size: int) -> NDArray[np.float64]:
    out = np.full(size, np.nan)
    out[: len(values)] = values
    return out
