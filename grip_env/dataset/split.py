"""The held-out objects: the one function every user of a train/test split by object calls.

The environments (``split="train"/"test"``), the classifiers' held-out scores, the ablation's
held-out importances, the RL selector, its baselines and every figure built on held-out objects
take their objects from :func:`split_objects`, keyed by ``learning.test_fraction`` and
``learning.seed`` (:func:`held_out_objects`), so all of them are scored on the same objects.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Literal

import numpy as np

from grip_env.config import LearningConfig

if TYPE_CHECKING:
    import pandas as pd

Split = Literal["train", "test", "all"]
SPLITS: tuple[str, ...] = ("train", "test", "all")
GROUP_COLUMN = "object_id"
_DEFAULTS = LearningConfig()  # the defaults below are the config's


def split_objects(
    object_ids: Iterable[str], test_fraction: float = _DEFAULTS.test_fraction,
    seed: int = _DEFAULTS.seed,
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Split object ids into ``(train, test)``, deterministically and without overlap.

    The unique ids are sorted, then permuted by ``numpy.random.default_rng(seed)``; the first
    ``round(test_fraction * n)`` ids (at least one and at most ``n - 1`` when ``n >= 2``) form the
    test set. The result depends only on the set of ids, ``test_fraction`` and ``seed``, never on
    the order the ids come in. One object alone goes to train. Both tuples come back sorted.

    Raises:
        ValueError: no ids, or ``test_fraction`` outside the open interval (0, 1).
    """
    if not 0.0 < test_fraction < 1.0:
        raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction!r}")
    ids = sorted({str(object_id) for object_id in object_ids})
    if not ids:
        raise ValueError("split_objects needs at least one object id, got none")
    n = len(ids)
    n_test = 0 if n == 1 else min(max(round(test_fraction * n), 1), n - 1)
    order = np.random.default_rng(seed).permutation(n)
    test = sorted(ids[i] for i in order[:n_test])
    train = sorted(ids[i] for i in order[n_test:])
    return tuple(train), tuple(test)


def held_out_objects(
    object_ids: Iterable[str], learning: LearningConfig
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """``(train, test)`` object ids of the study's split: ``learning.test_fraction``, ``.seed``."""
    return split_objects(object_ids, learning.test_fraction, learning.seed)


def split_table(
    table: pd.DataFrame, learning: LearningConfig
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The grips of the training objects and of the held-out objects of :func:`held_out_objects`."""
    ids = table[GROUP_COLUMN].astype(str)
    _, test = held_out_objects(ids, learning)
    held_out = ids.isin(test).to_numpy()
    return table[~held_out], table[held_out]


def objects_in_split(
    object_ids: Iterable[str], split: str, test_fraction: float = _DEFAULTS.test_fraction,
    seed: int = _DEFAULTS.seed,
) -> tuple[str, ...]:
    """The ids of ``split`` ("train", "test" or "all") as given by :func:`split_objects`.

    Raises:
        ValueError: unknown ``split``, or a split that holds no object.
    """
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
    ids = tuple(object_ids)
    train, test = split_objects(ids, test_fraction, seed)
    chosen = {"train": train, "test": test, "all": tuple(sorted(train + test))}[split]
    if not chosen:
        raise ValueError(
            f"split {split!r} holds no object ({len(train) + len(test)} objects, "
            f"test_fraction={test_fraction})"
        )
    return chosen
